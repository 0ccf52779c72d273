"""The geometric alignment check of the two streams: silhouettes of everything but the floor, from MuJoCo's
segmentation render and from Mitsuba rays through the same pixel centres, same camera and state, compared by
IoU. Both sample each pixel at its centre, so the masks differ only where geometry or cameras differ."""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING

import numpy as np

from rik.render.backend import use_variant
from rik.render.mitsuba_scene import build_posed_scene
from rik.schemas.finishes import Finish

if TYPE_CHECKING:
    import mujoco


def mujoco_silhouette(model: mujoco.MjModel, data: mujoco.MjData, camera: str, width: int, height: int) -> np.ndarray:
    """(H, W) bool: pixels where MuJoCo's renderer draws a geom other than a plane."""
    import mujoco

    renderer = mujoco.Renderer(model, height, width)
    try:
        renderer.enable_segmentation_rendering()
        renderer.update_scene(data, camera=camera)
        seg = renderer.render()
    finally:
        renderer.close()
    ids, types = seg[..., 0], seg[..., 1]
    planes = {g for g in range(model.ngeom) if int(model.geom_type[g]) == mujoco.mjtGeom.mjGEOM_PLANE}
    is_geom = (types == int(mujoco.mjtObj.mjOBJ_GEOM)) & (ids >= 0)
    return is_geom & ~np.isin(ids, list(planes))


def mitsuba_silhouette(model: mujoco.MjModel, data: mujoco.MjData, camera: str, width: int, height: int,
                       finishes: Mapping[str, Finish] | None = None, variant: str = "auto") -> np.ndarray:
    """(H, W) bool: pixels whose centre ray hits a shape of rik's Mitsuba scene (floor left out): the depth
    AOV of one unjittered sample per pixel is positive."""
    import mitsuba as mi


    use_variant(variant)
    posed = build_posed_scene(model, data, finishes or {}, [camera], width, height, 1,
                              integrator={"type": "aov", "aovs": "depth:depth"}, floor=False, lights=False,
                              pixel_centres=True)
    # the ignore: mitsuba's stub types seed as UInt32; every variant takes a Python int (scalar_rgb only that)
    depth = np.array(mi.render(posed.scene, sensor=0, spp=1, seed=0))[..., 0]  # type: ignore[arg-type]
    return depth > 0.0


def iou(a: np.ndarray, b: np.ndarray) -> float:
    """Intersection over union of two boolean masks (1 when both are empty)."""
    union = np.logical_or(a, b).sum()
    return float(np.logical_and(a, b).sum() / union) if union else 1.0


def silhouette_iou(model: mujoco.MjModel, data: mujoco.MjData, camera: str, width: int, height: int,
                   finishes: Mapping[str, Finish] | None = None, variant: str = "auto") -> float:
    """IoU of the MuJoCo and Mitsuba silhouettes of the state in ``data`` seen by ``camera``."""
    return iou(mujoco_silhouette(model, data, camera, width, height),
               mitsuba_silhouette(model, data, camera, width, height, finishes, variant))
