"""The two frame renderers of a scene: MuJoCo's rasteriser (the live ``sim`` stream) and the Mitsuba 3 path
tracer (the offline ``rerendered`` stream). Both take the scene's ``MjData`` after ``mj_forward`` and return one
8-bit sRGB image per camera, so either stream can stand in for the other."""

from __future__ import annotations

import hashlib
import time
from collections import OrderedDict
from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Protocol

import numpy as np

from rik.render.backend import use_variant
from rik.render.materials import linear_to_srgb8
from rik.render.mitsuba_scene import DENOISER_GUIDES, PATH_TRACER, PosedScene, build_posed_scene, pose_scene
from rik.render.streams import StreamSpec
from rik.schemas.finishes import Finish

if TYPE_CHECKING:
    import mitsuba as mi
    import mujoco


GUIDE_SPP = {"cuda_ad_rgb": 4, "llvm_ad_rgb": 4, "scalar_rgb": 1}
"""Samples per pixel of the albedo and normal images that guide the denoiser (they are nearly noise-free), per
Mitsuba variant. Mitsuba's AOV integrator is about 30 times slower than its path tracer per sample in
``scalar_rgb`` (3.9.1; measured: 2 s against 0.06 s for 128 px at 4 spp), so the scalar fallback takes one."""


class FrameRenderer(Protocol):
    def render(self, data: mujoco.MjData, index: int) -> dict[str, np.ndarray]:
        """Every camera's (H, W, 3) uint8 image of the state in ``data``; ``index`` seeds the sampler."""
        ...

    def info(self) -> dict[str, object]:
        """What rendered the frames (library versions, variant, seconds spent since the clock last started)."""
        ...

    def start_clock(self) -> None:
        """Count the seconds of :meth:`info` from now (a renderer reused for another stream)."""
        ...

    def close(self) -> None: ...


RenderFunction = Callable[["mi.Scene", "mi.Sensor", "mi.UInt32 | int"], "mi.TensorXf"]
"""``f(scene, sensor, seed)``: one image (H, W, channels) of ``sensor``."""


def _render_function(variant: str, spp: int) -> RenderFunction:
    """``f(scene, sensor, seed)`` rendering ``spp`` samples per pixel. On the JIT variants the function is frozen
    (``drjit.freeze``): after its first calls Dr.Jit replays the recorded kernels instead of tracing the integrator
    again, which otherwise costs about half a second per call whatever the image size (measured: 0.55 s against
    0.04 s for a 64-pixel image, identical pixels). The scene's changed poses are inputs of the replay. Every input
    is opaque (``auto_opaque=False``): with Dr.Jit's default the seed's change from the first frame to the second
    made it record each camera once more (4 recordings per function instead of 3), about 2 s of a renderer's second
    frame on this 2-core machine, for the same pixels and the same time per frame after."""
    import mitsuba as mi

    def render(scene: mi.Scene, sensor: mi.Sensor, seed: mi.UInt32 | int) -> mi.TensorXf:
        # the ignore: mitsuba's stub types seed as UInt32; scalar_rgb takes a Python int (and only that)
        return mi.render(scene, sensor=sensor, spp=spp, seed=seed)  # type: ignore[arg-type]

    if variant == "scalar_rgb":
        return render
    import drjit as dr

    return dr.freeze(render, auto_opaque=False)


class MujocoFrames:
    """MuJoCo's OpenGL renderer (EGL when headless), one camera after another."""

    def __init__(self, model: mujoco.MjModel, cameras: list[str], spec: StreamSpec):
        import mujoco

        self.model, self.cameras, self.spec = model, cameras, spec
        # MuJoCo renders into an offscreen buffer of the model's offwidth x offheight (1280 x 960 in rik's scenes):
        # grow it for larger images (up to MAX_SIDE), leaving it as it is for the sizes it holds
        vis = model.vis.global_
        vis.offwidth, vis.offheight = max(vis.offwidth, spec.width), max(vis.offheight, spec.height)
        # the context takes the shadow map's size and the multisamples when it is made: set them for it, then give
        # the model (shared with the scene and other renderers) its own back
        quality = model.vis.quality
        own = quality.shadowsize, quality.offsamples
        quality.shadowsize, quality.offsamples = spec.sim.shadow_size, spec.sim.multisamples
        try:
            self.renderer = mujoco.Renderer(model, spec.height, spec.width)
        finally:
            quality.shadowsize, quality.offsamples = own
        self.start_clock()

    def start_clock(self) -> None:
        self.seconds = 0.0

    def render(self, data: mujoco.MjData, index: int) -> dict[str, np.ndarray]:
        start = time.perf_counter()
        out = {}
        for cam in self.cameras:
            self.renderer.update_scene(data, camera=cam)
            out[cam] = self.renderer.render().copy()
        self.seconds += time.perf_counter() - start
        return out

    def info(self) -> dict[str, object]:
        import mujoco

        return {"renderer": "mujoco", "versions": {"mujoco": mujoco.__version__}, "render_seconds": self.seconds}

    def close(self) -> None:
        self.renderer.close()


class MitsubaFrames:
    """Mitsuba 3's path tracer on a scene built once and posed per frame; optionally denoised by Intel Open
    Image Denoise, guided by albedo and shading normals, then tone-mapped to 8-bit sRGB."""

    def __init__(self, model: mujoco.MjModel, data: mujoco.MjData, cameras: list[str], spec: StreamSpec,
                 finishes: Mapping[str, Finish]):
        self.variant = use_variant(spec.variant)
        self.model, self.cameras, self.spec = model, cameras, spec
        w, h = spec.width, spec.height
        self.beauty: PosedScene | None = build_posed_scene(model, data, finishes, cameras, w, h, spec.spp,
                                                           integrator=PATH_TRACER)
        self.guide_spp = GUIDE_SPP[self.variant]
        self.guides: PosedScene | None = (build_posed_scene(model, data, finishes, cameras, w, h, self.guide_spp,
                                         integrator=DENOISER_GUIDES) if spec.denoise else None)
        self.start_clock()
        self._beauty_render = _render_function(self.variant, spec.spp)
        self._guides_render = _render_function(self.variant, self.guide_spp)

    def start_clock(self) -> None:
        self.seconds = {"pose": 0.0, "render": 0.0, "denoise": 0.0}

    def render_linear(self, data: mujoco.MjData, index: int) -> dict[str, np.ndarray]:
        """Every camera's linear radiance, (H, W, 3) float32, denoised when the spec says so."""
        import mitsuba as mi


        if self.beauty is None:
            raise RuntimeError("this MitsubaFrames is closed")
        t0 = time.perf_counter()
        pose_scene(self.beauty, self.model, data)
        if self.guides is not None:
            pose_scene(self.guides, self.model, data)
        t1 = time.perf_counter()
        out, denoise = {}, 0.0
        for cam in self.cameras:
            i = self.beauty.cameras[cam]
            seed = mi.UInt32(index) if self.variant != "scalar_rgb" else index
            color = np.array(self._beauty_render(self.beauty.scene, self.beauty.scene.sensors()[i], seed))[..., :3]
            if self.guides is not None:
                aux = np.array(self._guides_render(self.guides.scene, self.guides.scene.sensors()[i], seed))
                t = time.perf_counter()
                color = self._denoise(color, aux)
                denoise += time.perf_counter() - t
            out[cam] = np.ascontiguousarray(color, np.float32)
        t2 = time.perf_counter()
        self.seconds["pose"] += t1 - t0
        self.seconds["render"] += t2 - t1 - denoise
        self.seconds["denoise"] += denoise
        return out

    @staticmethod
    def _denoise(color: np.ndarray, aux: np.ndarray) -> np.ndarray:
        import mitsuba_oidn

        albedo = np.ascontiguousarray(np.clip(aux[..., 0:3], 0.0, 1.0), np.float32)
        normal = np.ascontiguousarray(np.clip(aux[..., 3:6], -1.0, 1.0), np.float32)
        return np.asarray(mitsuba_oidn.denoise(np.ascontiguousarray(color, np.float32), albedo=albedo,
                                               normal=normal, hdr=True))

    def render(self, data: mujoco.MjData, index: int) -> dict[str, np.ndarray]:
        return {cam: linear_to_srgb8(img) for cam, img in self.render_linear(data, index).items()}

    def info(self) -> dict[str, object]:
        import mitsuba

        versions = {"mitsuba": mitsuba.__version__}
        if self.guides is not None:
            import mitsuba_oidn

            versions["mitsuba_oidn"] = mitsuba_oidn.__version__
        return {"renderer": "mitsuba", "mitsuba_variant": self.variant, "versions": versions,
                "render_seconds": sum(self.seconds.values()), "seconds": dict(self.seconds)}

    def close(self) -> None:
        self.beauty = self.guides = None


RendererFactory = Callable[["mujoco.MjModel", "mujoco.MjData", list[str], StreamSpec, Mapping[str, Finish]],
                           FrameRenderer]
"""``(model, data, cameras, spec, finishes)`` → a renderer."""

RENDERERS: dict[str, RendererFactory] = {
    "sim": lambda model, data, cameras, spec, finishes: MujocoFrames(model, cameras, spec),
    "rerendered": MitsubaFrames,
}
"""Stream kind -> renderer factory ``(model, data, cameras, spec, finishes)``."""


def make_renderer(model: mujoco.MjModel, data: mujoco.MjData, cameras: list[str], spec: StreamSpec,
                  finishes: Mapping[str, Finish]) -> FrameRenderer:
    """The renderer of ``spec.kind``."""
    return RENDERERS[spec.kind](model, data, cameras, spec, finishes)


KEPT_RENDERERS = 2
"""How many renderers :func:`reused_renderer` keeps in a process (the last used first): one per stream kind of the
variant whose episodes are being rendered."""
_kept: OrderedDict[tuple[str, ...], FrameRenderer] = OrderedDict()


def reused_renderer(model: mujoco.MjModel, data: mujoco.MjData, cameras: list[str], spec: StreamSpec,
                    finishes: Mapping[str, Finish]) -> FrameRenderer:
    """The renderer of ``spec.kind`` for this model (by content: another episode of the same variant has its own
    ``MjModel`` of the same bytes), cameras and finishes, kept from an earlier stream of this process when there is
    one, its clock restarted; otherwise a new one, kept in place of the least recently used. A Mitsuba renderer
    traces its integrator and compiles its kernels on its first frames (measured: 13 s of the demo's second episode,
    37 s fresh against 24 s reused, identical pixels); a kept one replays them. The caller does not close it."""
    key = (model_digest(model), repr(spec), *cameras,
           hashlib.sha256("".join(f.model_dump_json() for f in finishes.values()).encode()).hexdigest())
    renderer = _kept.pop(key, None)
    if renderer is None:
        renderer = make_renderer(model, data, cameras, spec, finishes)
        while len(_kept) >= KEPT_RENDERERS:
            _kept.popitem(last=False)[1].close()
    else:
        renderer.start_clock()
    _kept[key] = renderer
    return renderer


def drop_renderers() -> None:
    """Close every renderer :func:`reused_renderer` keeps (their GL contexts, Mitsuba scenes and kernels)."""
    while _kept:
        _kept.popitem()[1].close()


def model_digest(model: mujoco.MjModel) -> str:
    """sha256 of the compiled model's bytes (``mj_saveModel``; about 5 ms for a variant's scene)."""
    import mujoco

    buffer = np.empty(mujoco.mj_sizeModel(model), np.uint8)
    mujoco.mj_saveModel(model, None, buffer)
    return hashlib.sha256(buffer).hexdigest()
