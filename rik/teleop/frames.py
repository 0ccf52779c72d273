"""The browser station's camera images: the operator's follow view (``front``, :mod:`rik.teleop.view`) and the
wrist camera, rendered offscreen per stream size with shadows and reflections off, jaws and handle painted, from
the scene's view model (:mod:`rik.teleop.view_model`: an arm's visual meshes decimated to a triangle budget).

Anti-aliasing (MuJoCo's 4x multisampled offscreen buffer) is kept where the machine affords it: on a CPU
rasteriser (Mesa llvmpipe) it costs 1.5-2.5x per render, so a station whose first renders take longer than
:data:`ANTIALIAS_BUDGET` each renders without it from then on (edges are stair-stepped, nothing else changes).

Only what the operator sees: every recorded stream is rendered later from the episode's states with the scene's
fixed cameras and materials."""

from __future__ import annotations

import copy
import statistics
import time
from typing import TYPE_CHECKING, Any

from rik.teleop.view import FOLLOWED, FollowView, paint_for_contrast
from rik.teleop.view_model import TRIANGLE_BUDGET, ViewModel

if TYPE_CHECKING:
    import mujoco
    import numpy as np

    from rik.sim.scene import SimScene


ANTIALIAS_TRIAL = 20
"""Camera renders timed with anti-aliasing before a station decides whether to keep it."""
ANTIALIAS_BUDGET = 0.02
"""Median time of a camera render (s) above which anti-aliasing is turned off: two cameras per 50 ms control
period leave 25 ms each, JPEG and the step included."""


def keep_antialiasing(render_s: list[float], budget: float = ANTIALIAS_BUDGET) -> bool:
    """Whether renders that took ``render_s`` (s each, anti-aliased) leave room to keep anti-aliasing."""
    return statistics.median(render_s) <= budget


class StationFrames:
    """Offscreen renderers of a station's scene, one per stream size (width, height px), made on first use. Use it
    from one thread only (a MuJoCo GL context belongs to the thread that made it). ``antialias``: True or False
    for good, or None to decide after the first :data:`ANTIALIAS_TRIAL` renders (:func:`keep_antialiasing`)."""

    def __init__(self, scene: SimScene, budget: int = TRIANGLE_BUDGET, antialias: bool | None = None) -> None:
        self.scene = scene
        self.follow = FollowView(scene)
        self.view = ViewModel.of(scene, budget)
        self.antialias = antialias is not False
        self._trial: list[float] | None = [] if antialias is None else None
        self._plain: mujoco.MjModel | None = None
        self._renderers: dict[tuple[int, int], Any] = {}

    def _model(self) -> mujoco.MjModel:
        """The model the renderers are made from: the view model, or a copy of it without multisampling."""
        if self.antialias:
            return self.view.model
        if self._plain is None:
            self._plain = copy.copy(self.view.model)  # the physics model itself for a scene drawn in full
            self._plain.vis.quality.offsamples = 0
        return self._plain

    def renderer(self, size: tuple[int, int]) -> mujoco.Renderer:
        """The renderer of ``size`` (width, height px), shadows and reflections off."""
        import mujoco

        if size not in self._renderers:
            r = mujoco.Renderer(self._model(), size[1], size[0])
            r.scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = 0
            r.scene.flags[mujoco.mjtRndFlag.mjRND_REFLECTION] = 0
            self._renderers[size] = r
        return self._renderers[size]

    def render(self, data: mujoco.MjData, camera: str, size: tuple[int, int],
               turn: tuple[float, float] = (0.0, 0.0)) -> np.ndarray:
        """The image (height x width x 3 RGB) of ``camera`` in the physics state ``data`` (after ``mj_forward``),
        drawn from the view model: the follow view for :data:`FOLLOWED` (orbited by ``turn``: azimuth, elevation
        degrees), else the scene's camera."""
        renderer = self.renderer(size)
        start = time.perf_counter()
        data = self.view.sync(data)
        renderer.update_scene(data, camera=self.follow.at(data, turn) if camera == FOLLOWED else camera)
        paint_for_contrast(renderer.scene, self.scene)
        image = renderer.render()
        if self._trial is not None:
            self._trial.append(time.perf_counter() - start)
            if len(self._trial) >= ANTIALIAS_TRIAL:
                if not keep_antialiasing(self._trial):
                    self.close()  # made again, from the copy without multisampling
                    self.antialias = False
                self._trial = None
        return image

    def close(self) -> None:
        for r in self._renderers.values():
            r.close()
        self._renderers = {}
