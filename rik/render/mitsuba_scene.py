"""A Mitsuba 3 scene made from a compiled MuJoCo model, built once and posed in place for every frame.

Geoms that MuJoCo draws (groups 0-2, not transparent) become triangle meshes in their geom frame: mesh geoms
with MuJoCo's own vertex normals (so smooth and sharp edges shade as in MuJoCo), boxes with per-face metric
texture coordinates (so wood grain has the same density on every board), other primitives from trimesh.
Geoms welded to the world are placed once; every other geom is a ``shapegroup`` with an ``instance`` whose
``to_world`` is set from ``geom_xpos``/``geom_xmat`` each frame (no reload, a few ms per update). Cameras copy
MuJoCo's: the same pose (MuJoCo looks along -z with x right, Mitsuba along +z with x left), the same vertical
field of view, the same image size.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from rik.render.geoms import drawn_geoms, geom_triangles, rigid
from rik.render.materials import finish_bsdf, lighting, plastic_bsdf
from rik.schemas.finishes import Finish

if TYPE_CHECKING:
    import mitsuba as mi
    import mujoco

FLOOR_HALF_SIZE_M = 5.0
"""Half-size of the rectangle that stands in for an infinite MuJoCo plane, m."""
MAX_DEPTH = 6
"""Longest light path of the path tracer (bounces + 1)."""
MJ_TO_MI_CAMERA = np.diag([-1.0, 1.0, -1.0])
PATH_TRACER = {"type": "path", "max_depth": MAX_DEPTH}
DENOISER_GUIDES = {"type": "aov", "aovs": "albedo:albedo,normal:sh_normal"}
"""Albedo and shading normals, the guides of the denoiser. A pass of their own at a few samples per pixel costs
far less than wrapping the path tracer in the AOV integrator (measured: about twice the path tracer alone)."""


@dataclass
class PosedScene:
    """A loaded Mitsuba scene plus what is needed to pose it from MuJoCo data."""

    scene: mi.Scene
    params: mi.SceneParameters
    moving_geoms: list[int]
    """MuJoCo ids of the geoms drawn as instances, posed every frame."""
    cameras: dict[str, int]
    """MuJoCo camera name -> index of its Mitsuba sensor."""
    size: tuple[int, int]
    """Image (width, height), px."""
    geoms: list[int] = field(default_factory=list)
    """MuJoCo ids of every geom drawn."""
    sensor_ids: dict[str, str] = field(default_factory=dict)
    """MuJoCo camera name -> Mitsuba id of its sensor (the key of its parameters)."""


def _mi_mesh(name: str, v: np.ndarray, f: np.ndarray, n: np.ndarray | None, uv: np.ndarray,
             bsdf: mi.BSDF) -> mi.Mesh:
    import mitsuba as mi

    props = mi.Properties()
    props["bsdf"] = bsdf
    mesh = mi.Mesh(name, len(v), len(f), has_vertex_normals=n is not None, has_vertex_texcoords=True, props=props)
    p = mi.traverse(mesh)

    def put(key: str, values: np.ndarray, dtype: type[np.generic]) -> None:
        p[key] = type(p[key])(np.ascontiguousarray(values, dtype).ravel())  # Dr.Jit's array type of this variant

    put("vertex_positions", v, np.float32)
    put("faces", f, np.uint32)
    put("vertex_texcoords", uv, np.float32)
    if n is not None:
        put("vertex_normals", n, np.float32)
    p.update()
    return mesh


def geom_bsdf(model: mujoco.MjModel, g: int, finishes: Mapping[str, Finish]) -> dict[str, object]:
    """The BSDF of a geom: its material's catalog finish (materials are named by finish id), else a plastic of
    its MuJoCo colour."""
    import mujoco

    mat = int(model.geom_matid[g])
    if mat >= 0:
        name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_MATERIAL, mat)
        if name in finishes:
            return finish_bsdf(finishes[name])
        return plastic_bsdf(np.asarray(model.mat_rgba[mat]))
    return plastic_bsdf(np.asarray(model.geom_rgba[g]))


def _sensor(model: mujoco.MjModel, cam: int, width: int, height: int, sampler: dict[str, object]) -> dict[str, object]:
    return {"type": "perspective", "fov_axis": "y", "fov": float(model.cam_fovy[cam]),
            "near_clip": 0.005, "far_clip": 100.0, "to_world": _camera_to_world(np.eye(4)),
            "film": {"type": "hdrfilm", "width": width, "height": height, "rfilter": {"type": "box"},
                     "pixel_format": "rgb", "sample_border": False},
            "sampler": sampler}


def _camera_to_world(pose: np.ndarray) -> mi.ScalarTransform4f:
    import mitsuba as mi

    m = pose.copy()
    m[:3, :3] = m[:3, :3] @ MJ_TO_MI_CAMERA
    return mi.ScalarTransform4f(m.tolist())


def _key_light_direction(model: mujoco.MjModel) -> np.ndarray:
    """Direction of the scene's brightest directional light (MuJoCo's ``key``), or straight down."""
    best, direction = -1.0, np.array([0.0, 0.0, -1.0])
    for i in range(model.nlight):
        strength = float(np.sum(model.light_diffuse[i]))
        if strength > best:
            best, direction = strength, np.asarray(model.light_dir[i], np.float64)
    return direction


def build_posed_scene(model: mujoco.MjModel, data: mujoco.MjData, finishes: Mapping[str, Finish], cameras: list[str],
                      width: int, height: int, spp: int = 16, *, integrator: Mapping[str, object] | None = None,
                      floor: bool = True, lights: bool = True, pixel_centres: bool = False) -> PosedScene:
    """Load the Mitsuba scene of ``model`` posed as in ``data`` (after ``mj_forward``), with one sensor per
    MuJoCo camera in ``cameras``, rendered by ``integrator`` (default :data:`PATH_TRACER`). With
    ``pixel_centres``, one ray through the centre of each pixel (as MuJoCo's rasteriser samples)."""
    import mitsuba as mi
    import mujoco

    scene: dict[str, object] = {"type": "scene"}
    scene["integrator"] = integrator or PATH_TRACER
    if lights:
        scene.update(lighting(_key_light_direction(model)))
    moving: list[int] = []
    drawn = drawn_geoms(model)
    bsdfs: dict[str, mi.BSDF] = {}  # one instance per material: Dr.Jit traces every BSDF instance into the kernel
    for g in drawn:
        recipe = geom_bsdf(model, g, finishes)
        key = repr(recipe)
        if key not in bsdfs:
            bsdfs[key] = mi.load_dict(recipe)
        bsdf = bsdfs[key]
        name = f"g{g}"
        static = int(model.body_weldid[model.geom_bodyid[g]]) == 0
        if int(model.geom_type[g]) == mujoco.mjtGeom.mjGEOM_PLANE:
            if not floor:
                continue
            half = [float(s) if s > 0 else FLOOR_HALF_SIZE_M for s in model.geom_size[g][:2]]
            pose = rigid(data.geom_xpos[g], data.geom_xmat[g]) @ np.diag([*half, 1.0, 1.0])
            scene[name] = {"type": "rectangle", "to_world": mi.ScalarTransform4f(pose.tolist()), "bsdf": bsdf}
            continue
        v, f, n, uv = geom_triangles(model, g)
        if static:
            pose = rigid(data.geom_xpos[g], data.geom_xmat[g])
            v = v @ pose[:3, :3].T + pose[:3, 3]
            n = None if n is None else n @ pose[:3, :3].T
            scene[name] = _mi_mesh(name, v, f, n, uv, bsdf)
        else:
            scene[f"{name}_shape"] = {"type": "shapegroup", "mesh": _mi_mesh(name, v, f, n, uv, bsdf)}
            scene[name] = {"type": "instance", "shapegroup": {"type": "ref", "id": f"{name}_shape"}}
            moving.append(g)
    sampler = ({"type": "stratified", "sample_count": 1, "jitter": False} if pixel_centres
               else {"type": "independent", "sample_count": spp})
    sensor_ids: dict[str, str] = {}
    for i, cam in enumerate(cameras):
        cid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, cam)
        sensor_ids[cam] = f"cam_{i:02d}"
        scene[sensor_ids[cam]] = _sensor(model, cid, width, height, sampler)
    loaded = mi.load_dict(scene)
    order = [s.id() for s in loaded.sensors()]  # the scene's sensor list need not follow the dict's order
    posed = PosedScene(loaded, mi.traverse(loaded), moving, {cam: order.index(sid) for cam, sid in sensor_ids.items()},
                       (width, height), drawn, sensor_ids)
    pose_scene(posed, model, data)
    return posed


def pose_scene(posed: PosedScene, model: mujoco.MjModel, data: mujoco.MjData) -> None:
    """Move every instance and camera to its pose in ``data`` (after ``mj_forward``)."""
    import mujoco

    params = posed.params
    for g in posed.moving_geoms:
        params[f"g{g}.to_world"] = _rigid_transform(data.geom_xpos[g], data.geom_xmat[g])
    for cam in posed.cameras:
        cid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, cam)
        params[f"{posed.sensor_ids[cam]}.to_world"] = _camera_to_world(rigid(data.cam_xpos[cid], data.cam_xmat[cid]))
    params.update()


def _rigid_transform(pos: np.ndarray, mat: np.ndarray) -> mi.ScalarTransform4f:
    import mitsuba as mi

    return mi.ScalarTransform4f(rigid(pos, mat).tolist())
