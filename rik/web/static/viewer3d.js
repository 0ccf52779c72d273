// The catalog's 3D view: a GLB from /catalog/model/<handle>/visual.glb or /catalog/variant/<id>/visual.glb drawn
// with three.js (vendored under vendor/three/, see its SOURCE.txt) and turned with the mouse (OrbitControls: drag
// to orbit, wheel to zoom, right-drag to pan). Lit by three's RoomEnvironment through a PMREM, so metal finishes
// (glTF metallic 1) reflect a room instead of rendering black. Renders on demand (on a turn), no animation loop.
// catalog.js imports this module only when a detail panel opens a view (lazy: the grid loads without it).
import * as THREE from "./vendor/three/three.module.js";
import {OrbitControls} from "./vendor/three/addons/controls/OrbitControls.js";
import {GLTFLoader} from "./vendor/three/addons/loaders/GLTFLoader.js";
import {RoomEnvironment} from "./vendor/three/addons/environments/RoomEnvironment.js";

const BACKGROUND = 0xd5dde3; // a light grey-blue that white lacquer and chrome both stand out from
const live = new Set(); // mounted views: a view whose element left the page is disposed (browsers cap WebGL contexts)

function dispose(view) {
  view.controls.dispose();
  view.renderer.dispose();
  view.renderer.forceContextLoss();
  live.delete(view);
}

export function unmount(element) {
  for (const view of [...live]) if (view.element === element || !view.element.isConnected) dispose(view);
}

function message(element, text) {
  const p = document.createElement("p");
  p.className = "viewer3d-error";
  p.textContent = text; // the server's one line (textContent: never parsed as HTML)
  element.replaceChildren(p);
}

// Draw the GLB at `url` in `element` (which sets the size). Options: up (the model's up axis) and view (the
// direction from the model's centre to the camera), both in the model's frame. element.dataset.ready becomes "1"
// once drawn, "error" when the server refused (its one-line reason is shown).
export async function mount(element, url, {up = [0, 0, 1], view = [-0.6, 1.2, 0.7]} = {}) {
  unmount(element);
  element.dataset.ready = "0";
  element.replaceChildren();
  const response = await fetch(url);
  if (!response.ok) {
    let detail = response.statusText;
    try { detail = (await response.json()).detail || detail; } catch { /* not JSON: the status text */ }
    message(element, `rik: ${detail}`);
    element.dataset.ready = "error";
    return null;
  }
  const gltf = await new GLTFLoader().parseAsync(await response.arrayBuffer(), "");
  if (!element.isConnected) return null; // the panel moved on while the model loaded
  const width = element.clientWidth || 480;
  const height = element.clientHeight || 320;
  // preserveDrawingBuffer: the picture stays readable after it is shown (tests read its pixels back)
  const renderer = new THREE.WebGLRenderer({antialias: true, preserveDrawingBuffer: true});
  renderer.setPixelRatio(Math.min(window.devicePixelRatio || 1, 2));
  renderer.setSize(width, height);
  renderer.setClearColor(BACKGROUND);
  renderer.toneMapping = THREE.NeutralToneMapping;
  renderer.toneMappingExposure = 0.85;
  const scene = new THREE.Scene();
  const pmrem = new THREE.PMREMGenerator(renderer);
  scene.environment = pmrem.fromScene(new RoomEnvironment(), 0.04).texture;
  pmrem.dispose();
  const key = new THREE.DirectionalLight(0xffffff, 0.8);
  scene.add(key, gltf.scene);

  const box = new THREE.Box3().setFromObject(gltf.scene);
  const centre = box.getCenter(new THREE.Vector3());
  const radius = Math.max(box.getSize(new THREE.Vector3()).length() / 2, 1e-3);
  const camera = new THREE.PerspectiveCamera(35, width / height, radius / 100, radius * 100);
  camera.up.set(...up); // before the controls: they orbit about the camera's up
  const direction = new THREE.Vector3(...view).normalize();
  const distance = radius / Math.sin(THREE.MathUtils.degToRad(35 / 2)) * 1.05;
  camera.position.copy(centre).addScaledVector(direction, distance);
  key.position.copy(camera.position).add(new THREE.Vector3(...up).multiplyScalar(distance));
  key.target.position.copy(centre);
  scene.add(key.target);

  const controls = new OrbitControls(camera, renderer.domElement);
  controls.target.copy(centre);
  const draw = () => renderer.render(scene, camera);
  controls.addEventListener("change", draw);
  controls.update();
  element.replaceChildren(renderer.domElement);
  draw();
  const mounted = {element, renderer, controls, camera};
  live.add(mounted);
  // for tests and the curious: the camera's angles about the target, radians
  element.angles = () => ({azimuth: controls.getAzimuthalAngle(), polar: controls.getPolarAngle()});
  element.dataset.ready = "1";
  return mounted;
}
