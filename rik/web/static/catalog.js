// The catalog pages of rik serve: handle and base-unit cards from /api/catalog/*, filters (type, size, finish,
// text) applied in the page, a side panel with one entry, and a pairing picker that links to /teleop/<variant id>
// (the variant ids come from the server, made by rik.registry.ids). Plain JavaScript, no build step.
"use strict";

const TYPE_LABEL = {knob: "Knob", two_point: "Two-point", finger_pull: "Finger pull"};
const state = {handles: [], bases: [], byId: {}, baseById: {}, robots: {default: "hand-e", robots: []}};
const $ = (selector) => document.querySelector(selector);
const path = (id) => id.split("/").map(encodeURIComponent).join("/");

function el(tag, attrs = {}, ...children) {
  const node = document.createElement(tag);
  for (const [key, value] of Object.entries(attrs)) {
    if (value === null || value === undefined) continue;
    if (key === "class") node.className = value;
    else if (key.startsWith("on")) node.addEventListener(key.slice(2), value);
    else node.setAttribute(key, value);
  }
  for (const child of children.flat()) {
    if (child !== null && child !== undefined) node.append(child instanceof Node ? child : String(child));
  }
  return node;
}

async function getJSON(url) {
  const response = await fetch(url);
  const body = await response.json();
  if (!response.ok) throw new Error(body.detail || response.statusText);
  return body;
}

function fmt(value, digits = 2) {
  if (value === null || value === undefined) return "–";
  if (typeof value === "boolean") return value ? "yes" : "no";
  return Number.isInteger(value) ? String(value) : value.toFixed(digits);
}

function table(rows, headers = null) {
  const head = headers ? el("thead", {}, el("tr", {}, headers.map((h, i) => el("th", {class: i ? "num" : ""}, h))))
    : null;
  return el("table", {}, head, el("tbody", {}, rows.map(
    (cells) => el("tr", {}, cells.map((c, i) => el(i ? "td" : "th", {class: i ? "num" : ""}, c))))));
}

// ---- handles grid and filters ---------------------------------------------------------------------------
function handleCard(h) {
  const card = el("a", {class: "card handle", href: `/catalog/handle/${path(h.id)}`, "data-id": h.id,
                        onclick: (e) => { e.preventDefault(); openHandle(h.id, true).catch(fail); }},
    el("img", {class: "thumb", src: `/catalog/img/${path(h.id)}/thumbnail.png`, alt: `thumbnail of ${h.id}`,
               width: 120, height: 120}),
    el("div", {class: "title"}, h.id),
    el("div", {class: "meta"}, `${TYPE_LABEL[h.type]} · ${fmt(h.dimensions_mm.length, 0)} mm`),
    el("div", {class: "meta"}, el("span", {class: "swatch", style: `background:${h.finish_color}`}), h.finish_name));
  card.handle = h;
  return card;
}

function sizeFilter() {
  const min = parseFloat($("#f-min").value);
  const max = parseFloat($("#f-max").value);
  return [Number.isNaN(min) ? -Infinity : min, Number.isNaN(max) ? Infinity : max];
}

function applyFilters() {
  const type = $("#f-type").value;
  const finish = $("#f-finish").value;
  const [min, max] = sizeFilter();
  const words = $("#f-text").value.toLowerCase().split(/\s+/).filter(Boolean);
  let shown = 0;
  for (const card of document.querySelectorAll("#handle-grid .card")) {
    const h = card.handle;
    const text = [h.id, h.design_name, h.finish, h.finish_name, h.type, TYPE_LABEL[h.type], h.split,
                  h.display.mount].join(" ").toLowerCase();
    const length = h.dimensions_mm.length;
    const visible = (!type || h.type === type) && (!finish || h.finish === finish)
      && length >= min && length <= max && words.every((w) => text.includes(w));
    card.hidden = !visible;
    shown += visible;
  }
  $("#count").textContent = `${shown} of ${state.handles.length} handles`;
}

function setupFilters(finishes) {
  const counts = {};
  for (const h of state.handles) counts[h.type] = (counts[h.type] || 0) + 1;
  for (const [type, label] of Object.entries(TYPE_LABEL)) {
    if (counts[type]) $("#f-type").append(el("option", {value: type}, `${label} (${counts[type]})`));
  }
  const used = new Set(state.handles.map((h) => h.finish));
  for (const f of finishes.filter((f) => used.has(f.id))) {
    const n = state.handles.filter((h) => h.finish === f.id).length;
    $("#f-finish").append(el("option", {value: f.id}, `${f.name} (${n})`));
  }
  $("#f-size").addEventListener("change", () => {
    const [lo, hi] = $("#f-size").value.split("-");
    $("#f-min").value = lo || "";
    $("#f-max").value = hi || "";
    applyFilters();
  });
  for (const id of ["#f-type", "#f-finish"]) $(id).addEventListener("change", applyFilters);
  for (const id of ["#f-min", "#f-max", "#f-text"]) $(id).addEventListener("input", () => {
    if (id !== "#f-text") $("#f-size").value = "";
    applyFilters();
  });
  $("#f-reset").addEventListener("click", () => {
    $("#filters").reset();
    applyFilters();
  });
}

// ---- pairing picker ---------------------------------------------------------------------------------------
function picker(pairings, noun, grouped) {
  // pairings: [{id, label, type, variants: {preset: variant id}}] from the server (only pairings that fit)
  if (!pairings.length) return el("p", {class: "note"}, `No ${noun} fits this entry.`);
  const other = el("select", {id: "pair-other", "aria-label": noun});
  const groups = {};
  for (const [i, p] of pairings.entries()) {
    const option = el("option", {value: i}, p.label === p.id ? p.id : `${p.id} (${p.label})`);
    if (grouped) (groups[p.type] ||= el("optgroup", {label: TYPE_LABEL[p.type] || p.type})).append(option);
    else other.append(option);
  }
  other.append(...Object.values(groups));
  const preset = el("select", {id: "pair-preset", "aria-label": "resistance preset"});
  // the robot that opens it: the station at /teleop/<variant>?robot=<id> (none: the server's --robot)
  const robot = el("select", {id: "pair-robot", "aria-label": "robot"},
                   ...state.robots.robots.map((r) => el("option", {value: r.id}, `${r.id} (${r.name})`)));
  robot.value = pickedRobot || state.robots.default;
  const link = el("a", {id: "teleop-link", class: "go"}, "Build and teleoperate");
  const shownId = el("code", {id: "variant-id"});
  // the chosen variant in 3D, when it is built (the server answers one line naming the command otherwise)
  const viewer = el("div", {id: "viewer-variant", class: "viewer3d", hidden: ""});
  const show3d = el("button", {type: "button", id: "variant-3d", onclick: () => {
    viewer.hidden = false;
    view3d(viewer, `/catalog/variant/${encodeURIComponent(shownId.textContent)}/visual.glb`, VARIANT_VIEW);
  }}, "3D view (built variants)");
  const update = () => {
    const variants = pairings[other.value].variants;
    const chosen = preset.value in variants ? preset.value : Object.keys(variants)[0];
    preset.replaceChildren(...Object.keys(variants).map((p) => el("option", {value: p}, p)));
    preset.value = chosen;
    pickedRobot = robot.value;
    const query = robot.value && robot.value !== state.robots.default ? `?robot=${encodeURIComponent(robot.value)}`
      : "";
    link.href = `/teleop/${encodeURIComponent(variants[chosen])}${query}`;
    shownId.textContent = variants[chosen];
  };
  const changed = () => { update(); if (!viewer.hidden) show3d.click(); };
  other.addEventListener("change", changed);
  preset.addEventListener("change", changed);
  robot.addEventListener("change", update);
  update();
  return el("div", {class: "pairing"}, el("label", {}, `${noun} `, other), el("label", {}, "preset ", preset),
            state.robots.robots.length ? el("label", {}, "robot ", robot) : null, link, show3d, shownId, viewer);
}
let pickedRobot = null; // the robot last picked, kept from one entry to the next

// ---- 3D view ----------------------------------------------------------------------------------------------
// three.js is loaded only when a panel shows a model (a module import from this classic script).
const HANDLE_VIEW = {up: [0, 1, 0], view: [0.6, 0.5, 1]}; // mount frame: +z out of the front, y up
const VARIANT_VIEW = {up: [0, 0, 1], view: [-0.6, 1.2, 0.7]}; // MuJoCo's frame: z up, the fronts face +y
function view3d(element, url, options) {
  element.dataset.ready = "0";
  import("/static/viewer3d.js").then((m) => m.mount(element, url, options)).catch((err) => {
    element.textContent = `rik: the 3D view failed: ${err.message}`;
    element.dataset.ready = "error";
  });
}

// ---- detail panel -----------------------------------------------------------------------------------------
function showDetail(...children) {
  $("#detail-body").replaceChildren(...children);
  $("#detail").hidden = false;
  $("#detail").scrollTop = 0;
  document.body.classList.add("with-detail");
}

function closeDetail(push) {
  $("#detail").hidden = true;
  document.body.classList.remove("with-detail");
  for (const c of document.querySelectorAll(".card.selected")) c.classList.remove("selected");
  if (push) history.pushState({}, "", "/catalog" + (activeTab() === "bases" ? "#bases" : ""));
}

function select(card) {
  for (const c of document.querySelectorAll(".card.selected")) c.classList.remove("selected");
  if (card) card.classList.add("selected");
}

async function openHandle(id, push) {
  const h = await getJSON(`/api/catalog/handles/${path(id)}`);
  if (push) history.pushState({}, "", `/catalog/handle/${path(id)}`);
  showTab("handles");
  select(document.querySelector(`#handle-grid .card[data-id="${CSS.escape(id)}"]`));
  const dims = Object.entries(h.display).filter(([k]) => !["id", "type"].includes(k));
  const mesh = h.mesh ? table([
    ["vertices", fmt(h.mesh.vertices)], ["faces", fmt(h.mesh.faces)],
    ["mean edge length, mm", fmt(h.mesh.mean_edge_mm)], ["mean face area, mm²", fmt(h.mesh.mean_face_area_mm2, 3)],
    ["watertight", fmt(h.mesh.watertight)], ["collision hulls (CoACD)", fmt(h.mesh.hulls)],
    ["collision vertices", fmt(h.mesh.collision_vertices)]]) : el("p", {class: "note"}, "No mesh statistics "
    + "(run rik assets stats).");
  const f = h.fidelity;
  const rows = [["mean", "mean"], ["95th percentile", "p95"], ["max", "max"]];
  const fidelity = f ? [
    table([...rows.map(([label, k]) => [`E_Q→P ${label}`, fmt(f.coacd[`eqp_${k}_mm`]), fmt(f.hull[`eqp_${k}_mm`])]),
           ...rows.map(([label, k]) => [`E_P→Q ${label}`, fmt(f.coacd[`epq_${k}_mm`]), fmt(f.hull[`epq_${k}_mm`])])],
          ["distance, mm", `CoACD (${f.hulls} hulls)`, "single convex hull"]),
    el("p", {class: "note"}, `The single hull strays ${fmt(f.hull_over_coacd, 1)}× as far from the visual surface `
       + "as rik's CoACD collision (E_Q→P: collision to visual; E_P→Q: visual to collision)."),
  ] : [el("p", {class: "note"}, "No fidelity numbers (run rik assets fidelity).")];
  showDetail(
    el("h2", {id: "detail-title"}, h.id),
    el("p", {}, `${h.design_name} · ${TYPE_LABEL[h.type]} · `, el("span", {class: "badge"}, `split ${h.split}`),
       h.origin === "overlay" ? el("span", {class: "badge"}, "user catalog") : null),
    el("div", {class: "pictures"},
       el("img", {class: "thumb", src: `/catalog/img/${path(h.id)}/thumbnail.png`, alt: `thumbnail of ${h.id}`}),
       el("div", {id: "viewer-handle", class: "viewer3d", title: "drag to turn, wheel to zoom"})),
    el("h3", {}, "Dimensions"), el("div", {id: "dimensions"}, table(dims)),
    el("h3", {}, "Build and teleoperate"),
    el("p", {class: "note"}, `Fits ${h.pairings.length} of ${state.bases.length} base units.`),
    picker(h.pairings, "base unit", false),
    el("h3", {}, "Collision fidelity"),
    el("img", {id: "fidelity-img", class: "heatmap", src: `/catalog/img/${path(h.id)}/fidelity.png`,
               alt: `collision-error heatmaps of ${h.id}`}),
    el("div", {id: "fidelity"}, fidelity),
    el("h3", {}, "Mesh statistics"), el("div", {id: "mesh-stats"}, mesh));
  view3d($("#viewer-handle"), `/catalog/model/${path(h.id)}/visual.glb`, HANDLE_VIEW);
}

async function openBase(id, push) {
  const b = await getJSON(`/api/catalog/bases/${path(id)}`);
  if (push) history.pushState({}, "", `/catalog/base/${path(id)}`);
  showTab("bases");
  select(document.querySelector(`#base-grid .card[data-id="${CSS.escape(id)}"]`));
  const dims = Object.entries(b.display).filter(([k]) => k !== "id");
  showDetail(
    el("h2", {id: "detail-title"}, b.id),
    el("p", {}, b.description),
    el("img", {class: "front", src: `/catalog/img/${path(b.id)}/front.svg`, alt: `front view of ${b.id}`}),
    el("h3", {}, "Dimensions"), el("div", {id: "dimensions"}, table(dims)),
    el("h3", {}, "Fronts"),
    table(b.fronts_mm.map((f) => [f.id, f.kind, f.joint, `${fmt(f.size[0], 0)} × ${fmt(f.size[1], 0)}`,
                                  `${fmt(f.mount[0], 0)} × ${fmt(f.mount[1], 0)}`]),
          ["front", "kind", "joint", "size mm", "mount area mm"]),
    el("h3", {}, "Build and teleoperate"),
    el("p", {class: "note"}, `${b.pairings.length} of ${state.handles.length} handles fit; default preset `
       + `${b.default_preset}.`),
    picker(b.pairings, "handle", true));
}

// ---- tabs, routes, start ----------------------------------------------------------------------------------
function activeTab() { return $("#bases-tab").hidden ? "handles" : "bases"; }

function showTab(tab) {
  $("#handles-tab").hidden = tab !== "handles";
  $("#bases-tab").hidden = tab !== "bases";
  for (const b of document.querySelectorAll("#tabs button")) b.classList.toggle("active", b.dataset.tab === tab);
}

async function route() {
  const match = location.pathname.match(/^\/catalog\/(handle|base)\/(.+)$/);
  try {
    if (!match) {
      $("#detail").hidden = true;
      document.body.classList.remove("with-detail");
      showTab(location.hash === "#bases" ? "bases" : "handles");
    } else {
      const id = match[2].split("/").map(decodeURIComponent).join("/");
      await (match[1] === "handle" ? openHandle(id, false) : openBase(id, false));
    }
  } catch (err) {
    fail(err);
  }
}

function fail(err) {
  $("#error").textContent = `rik: ${err.message}`;
  $("#error").hidden = false;
}

async function start() {
  const [h, b, r] = await Promise.all([getJSON("/api/catalog/handles"), getJSON("/api/catalog/bases"),
                                       getJSON("/teleop/robots.json")]);
  state.robots = r;
  state.handles = h.handles;
  state.bases = b.bases;
  $("#n-handles").textContent = `(${h.count})`;
  $("#n-bases").textContent = `(${b.count})`;
  $("#summary").textContent = `${h.count} handles, ${b.count} base units; ${h.pairings.fit} of `
    + `${h.pairings.total} pairings fit`;
  $("#handle-grid").replaceChildren(...state.handles.map(handleCard));
  $("#base-grid").replaceChildren(...state.bases.map((base) => el("a", {
    class: "card base", href: `/catalog/base/${path(base.id)}`, "data-id": base.id,
    onclick: (e) => { e.preventDefault(); openBase(base.id, true).catch(fail); }},
    el("img", {src: `/catalog/img/${path(base.id)}/front.svg`, alt: `front view of ${base.id}`}),
    el("div", {class: "title"}, base.id),
    el("div", {class: "meta"}, base.name),
    el("div", {class: "meta"}, `${base.display.fronts} · ${base.joint_types.join(", ")}`))));
  $("#bases-count").textContent = `${b.count} base units; each pairs with the handles that fit every one of its `
    + "fronts.";
  setupFilters(h.finishes);
  applyFilters();
  for (const button of document.querySelectorAll("#tabs button")) {
    button.addEventListener("click", () => { showTab(button.dataset.tab); closeDetail(true); });
  }
  $("#detail-close").addEventListener("click", () => closeDetail(true));
  document.addEventListener("keydown", (e) => { if (e.key === "Escape" && !$("#detail").hidden) closeDetail(true); });
  window.addEventListener("popstate", route);
  await route();
  document.body.dataset.ready = "1";
}

start().catch(fail);
