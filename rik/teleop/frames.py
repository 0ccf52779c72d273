"""The browser station's camera images: the operator's follow view (``front``, :mod:`rik.teleop.view`) and the
wrist camera, rendered offscreen per stream size with shadows and reflections off, jaws and handle painted, from
the scene's view model (:mod:`rik.teleop.view_model`: an arm's visual meshes decimated to a triangle budget).

Only what the operator sees: every recorded stream is rendered later from the episode's states with the scene's
fixed cameras and materials."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from rik.teleop.view import FOLLOWED, FollowView, paint_for_contrast
from rik.teleop.view_model import TRIANGLE_BUDGET, ViewModel

if TYPE_CHECKING:
    import mujoco
    import numpy as np

    from rik.sim.scene import SimScene


class StationFrames:
    """Offscreen renderers of a station's scene, one per stream size (width, height px), made on first use. Use it
    from one thread only (a MuJoCo GL context belongs to the thread that made it)."""

    def __init__(self, scene: SimScene, budget: int = TRIANGLE_BUDGET) -> None:
        self.scene = scene
        self.follow = FollowView(scene)
        self.view = ViewModel.of(scene, budget)
        self._renderers: dict[tuple[int, int], Any] = {}

    def renderer(self, size: tuple[int, int]) -> mujoco.Renderer:
        """The renderer of ``size`` (width, height px), shadows and reflections off."""
        import mujoco

        if size not in self._renderers:
            r = mujoco.Renderer(self.view.model, size[1], size[0])
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
        data = self.view.sync(data)
        renderer.update_scene(data, camera=self.follow.at(data, turn) if camera == FOLLOWED else camera)
        paint_for_contrast(renderer.scene, self.scene)
        return renderer.render()

    def close(self) -> None:
        for r in self._renderers.values():
            r.close()
        self._renderers = {}
