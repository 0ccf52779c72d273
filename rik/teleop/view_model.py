"""The teleop station's view model: the scene's model with its largest visible meshes decimated (quadric edge
collapse, ``fast-simplification``) to a triangle budget, for the station's cameras only.

On a CPU rasteriser (Mesa llvmpipe) a frame's cost grows with the triangles drawn: the Panda with the 2F-85 draws
about 192,000 (Menagerie's full-detail visual meshes), which made each camera's render about twice the Hand-E's.
The physics and collision model stay exactly as they are: the view model is a second compiled model, with the
same bodies, joints, geoms, sites and cameras in the same order, whose state is set from the physics state's
joint positions before each render (:class:`ViewModel`). Episodes record states, not pictures, so recording and
replay do not change; every recorded stream renders the full model.

Decimated meshes are cached, content-addressed (a sha256 of the mesh's vertices and faces, the target and the
library's version), under ``<cache>/view-meshes/``: each is made once.
"""

from __future__ import annotations

import hashlib
import io
from dataclasses import dataclass
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from rik.outputs import CACHED, write_bytes
from rik.paths import cache_dir

if TYPE_CHECKING:
    import mujoco

    from rik.sim.scene import SimScene

TRIANGLE_BUDGET = 30_000
"""Triangles of the visible meshes (groups 0-2) the station's view draws at most, whole scene."""
KEEP_FACES = 1_000
"""A mesh with at most this many faces is drawn as it is (a gripper's small parts)."""
MIN_FACES = 200
"""The fewest faces a decimated mesh is given."""
VISIBLE_GROUPS = 3
"""Geom groups 0..2 are drawn by MuJoCo's default visual options; the others (collision shapes) are not."""
DECIMATION_FORMAT = 1
"""Bumped when what a cached mesh holds, or how it is made, changes."""


def _library_version() -> str:
    try:
        return version("fast-simplification")
    except PackageNotFoundError:  # pragma: no cover - a dependency of rik
        return "absent"


def mesh_key(vert: np.ndarray, face: np.ndarray, target: int) -> str:
    """sha256 of everything that decides a decimated mesh: its vertices and faces, the target face count, the
    format, this module's source and the library's version."""
    h = hashlib.sha256()
    h.update(f"rik-view-mesh {DECIMATION_FORMAT} {_library_version()} {target}".encode())
    h.update(Path(__file__).read_bytes())
    for a in (np.ascontiguousarray(vert, np.float64), np.ascontiguousarray(face, np.int64)):
        h.update(str(a.shape).encode())
        h.update(a.tobytes())
    return h.hexdigest()


def _weld(vert: np.ndarray, face: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Vertices at the same position merged (a flat-shaded OBJ stores each corner apart: nothing to collapse), and
    faces that lost an edge or repeat another dropped."""
    unique, inverse = np.unique(np.asarray(vert, np.float64), axis=0, return_inverse=True)
    return unique, _degenerate(inverse.reshape(-1)[np.asarray(face, np.int64)])


def _degenerate(f: np.ndarray) -> np.ndarray:
    """Faces that lost an edge (two equal corners) dropped, and every face that repeats another's corners."""
    f = f[(f[:, 0] != f[:, 1]) & (f[:, 1] != f[:, 2]) & (f[:, 0] != f[:, 2])]
    _, first = np.unique(np.sort(f, axis=1), axis=0, return_index=True)
    return f[np.sort(first)]


def _cluster(v: np.ndarray, f: np.ndarray, target: int) -> tuple[np.ndarray, np.ndarray]:
    """Vertex clustering on a grid, coarser until at most ``target`` faces are left: each cell's vertices become
    their mean. What a mesh whose quadric collapse stops short (locked borders, slivers) is brought down with."""
    extent = float(np.ptp(v, axis=0).max()) or 1.0
    cells = 128
    while len(f) > target and cells >= 2:
        cell = np.floor((v - v.min(axis=0)) / (extent / cells)).astype(np.int64)
        _, inverse = np.unique(cell, axis=0, return_inverse=True)
        inverse = inverse.reshape(-1)
        n = int(inverse.max()) + 1
        mean = np.zeros((n, 3))
        np.add.at(mean, inverse, v)
        mean /= np.bincount(inverse, minlength=n)[:, None]
        v, f = mean, _degenerate(inverse[f])
        cells = cells * 3 // 4
    return v, f


def _simplify(vert: np.ndarray, face: np.ndarray, target: int) -> tuple[np.ndarray, np.ndarray]:
    """The mesh welded and decimated to at most ``target`` faces (quadric edge collapse; vertex clustering after
    it where the collapse stops short); unused vertices removed."""
    import fast_simplification  # type: ignore[import-untyped]  # ships no type hints

    v, f = _weld(vert, face)
    if len(f) > target:
        v, f = fast_simplification.simplify(v, f.astype(np.int32), target_count=int(target))
        v, f = _cluster(np.asarray(v, np.float64), _degenerate(np.asarray(f, np.int64)), target)
    used, f = np.unique(f, return_inverse=True)
    return np.asarray(v, np.float64)[used], f.reshape(-1, 3).astype(np.int32)


def decimate(vert: np.ndarray, face: np.ndarray, target: int, cache: Path | None = None
             ) -> tuple[np.ndarray, np.ndarray]:
    """``vert`` (n x 3, m) and ``face`` (k x 3 indices) decimated to at most about ``target`` faces: from the cache
    (``cache``, default ``<cache>/view-meshes``) when it holds this mesh, else made and stored there. Deterministic:
    the same input gives the same bytes."""
    key = mesh_key(vert, face, target)
    folder = (cache_dir() / "view-meshes" if cache is None else Path(cache)) / key[:2]
    path = folder / f"{key}.npy"
    if path.is_file():
        try:
            with path.open("rb") as fh:
                v, f = np.load(fh, allow_pickle=False), np.load(fh, allow_pickle=False)
            if v.ndim == 2 and v.shape[1] == 3 and f.ndim == 2 and f.shape[1] == 3 and len(f) and \
                    int(f.min()) >= 0 and int(f.max()) < len(v):
                return v.astype(np.float64), f.astype(np.int32)
        except (OSError, ValueError):
            pass  # a damaged entry is made again
    v, f = _simplify(vert, face, target)
    buf = io.BytesIO()
    np.save(buf, v, allow_pickle=False)
    np.save(buf, f, allow_pickle=False)
    try:
        folder.mkdir(parents=True, exist_ok=True)
        write_bytes(path, buf.getvalue(), CACHED)
    except OSError:
        pass  # a read-only or full cache: the mesh is made again next time
    return v, f


def visible_meshes(model: mujoco.MjModel) -> dict[int, int]:
    """Faces drawn of each mesh that visible geoms (groups 0..2) draw, by mesh id: its face count times the geoms
    drawing it."""
    import mujoco

    out: dict[int, int] = {}
    for g in range(model.ngeom):
        if model.geom_type[g] == mujoco.mjtGeom.mjGEOM_MESH and model.geom_group[g] < VISIBLE_GROUPS:
            mesh = int(model.geom_dataid[g])
            out[mesh] = out.get(mesh, 0) + int(model.mesh_facenum[mesh])
    return out


def face_targets(model: mujoco.MjModel, budget: int = TRIANGLE_BUDGET) -> dict[int, int]:
    """Target face count of each visible mesh to decimate (by mesh id), so that the visible meshes hold at most
    about ``budget`` faces: the robot's meshes (named ``robot/...``) of more than :data:`KEEP_FACES` shrink in
    proportion, none below :data:`MIN_FACES`; the furniture's (the handle the operator aims at) stay as they are.
    Empty when the scene is within budget."""
    from rik.sim.robots.arm import ROBOT_PREFIX

    faces = visible_meshes(model)
    total = sum(faces.values())
    large = {m: n for m, n in faces.items()
             if model.mesh_facenum[m] > KEEP_FACES and model.mesh(m).name.startswith(ROBOT_PREFIX)}
    if total <= budget or not large:
        return {}
    room = budget - (total - sum(large.values()))  # faces left for the large meshes, each drawing counted
    floor: dict[int, int] = {}  # meshes held at MIN_FACES; the others share what is left in proportion
    while True:
        rest = {m: n for m, n in large.items() if m not in floor}
        left = room - sum(MIN_FACES * (large[m] // int(model.mesh_facenum[m])) for m in floor)
        scale = max(left, 0) / max(sum(rest.values()), 1)
        low = {m for m in rest if model.mesh_facenum[m] * scale < MIN_FACES}
        if not low:
            break
        floor.update(dict.fromkeys(low, MIN_FACES))
    return {**{m: int(model.mesh_facenum[m] * scale) for m in rest}, **floor}


def _mesh_arrays(model: mujoco.MjModel, mesh: int) -> tuple[np.ndarray, np.ndarray]:
    """A compiled mesh's vertices (in its geoms' frame, scaled, m) and faces."""
    v0, nv = int(model.mesh_vertadr[mesh]), int(model.mesh_vertnum[mesh])
    f0, nf = int(model.mesh_faceadr[mesh]), int(model.mesh_facenum[mesh])
    return model.mesh_vert[v0:v0 + nv].astype(np.float64), model.mesh_face[f0:f0 + nf].astype(np.int64)


def build_view_model(scene: SimScene, budget: int = TRIANGLE_BUDGET, cache: Path | None = None) -> mujoco.MjModel:
    """The view model of ``scene`` (see the module docstring); the scene's own model when its visible meshes are
    within ``budget``, it was not built from a spec (``scene.spec``), or a view model cannot be made from it (a
    robot model that MuJoCo will not compile with user meshes, a spec that does not match: the station then draws
    the full model, slower, rather than nothing)."""
    model = scene.model
    targets = face_targets(model, budget)
    if not targets or scene.spec is None:
        return model
    try:
        return _decimated_model(scene, targets, cache)
    except (ValueError, AssertionError, KeyError, IndexError):
        return model


def _decimated_model(scene: SimScene, targets: dict[int, int], cache: Path | None) -> mujoco.MjModel:
    import mujoco

    model = scene.model
    assert scene.spec is not None
    spec = scene.spec.copy()  # the same elements in the same order; ``id``: an element's index once compiled
    geoms = {int(sg.id): copied for sg, copied in zip(scene.spec.geoms, spec.geoms, strict=True)}
    meshes = {int(sm.id): copied for sm, copied in zip(scene.spec.meshes, spec.meshes, strict=True)}
    for mesh_id, target in targets.items():
        v, f = decimate(*_mesh_arrays(model, mesh_id), target, cache)
        old = meshes[mesh_id]  # replaced by a mesh of the same name (MuJoCo keeps a file's normals apart)
        name, material = old.name, old.material
        spec.delete(old)
        mesh = spec.add_mesh(name=name, material=material, uservert=v.reshape(-1).tolist(),
                             userface=f.reshape(-1).tolist())
        mesh.inertia = mujoco.mjtMeshInertia.mjMESH_INERTIA_SHELL  # decimated surfaces need not be closed
        # the vertices are in the compiled geoms' frame: each geom drawing the mesh takes its compiled placement
        for g in np.flatnonzero((model.geom_type == mujoco.mjtGeom.mjGEOM_MESH) & (model.geom_dataid == mesh_id)):
            sg = geoms[int(g)]
            sg.pos = model.geom_pos[g].tolist()
            sg.quat = model.geom_quat[g].tolist()
            sg.alt.type = mujoco.mjtOrientation.mjORIENTATION_QUAT
    view = spec.compile()
    check_same_structure(model, view)
    return view


def check_same_structure(model: mujoco.MjModel, view: mujoco.MjModel) -> None:
    """The view model must hold the physics model's elements in the same order (a geom id, a camera name or a
    joint address means the same in both); else an AssertionError."""
    for size in ("nq", "nbody", "njnt", "ngeom", "nsite", "ncam", "nlight", "nmesh", "nmat", "nmocap"):
        assert getattr(model, size) == getattr(view, size), f"view model differs in {size}"
    assert np.array_equal(model.geom_bodyid, view.geom_bodyid) and np.array_equal(model.geom_type, view.geom_type)
    assert np.array_equal(model.jnt_qposadr, view.jnt_qposadr)


@dataclass
class ViewModel:
    """What the station's renderers draw: ``model`` (the view model) in ``data``, its state set from a physics
    state by :meth:`sync`. When the view model is the physics model itself, :meth:`sync` returns the physics data."""

    physics: mujoco.MjModel
    model: mujoco.MjModel
    data: mujoco.MjData

    @classmethod
    def of(cls, scene: SimScene, budget: int = TRIANGLE_BUDGET, cache: Path | None = None) -> ViewModel:
        import mujoco

        model = build_view_model(scene, budget, cache)
        return cls(scene.model, model, mujoco.MjData(model))

    @property
    def decimated(self) -> bool:
        return self.model is not self.physics

    def sync(self, data: mujoco.MjData) -> mujoco.MjData:
        """The view's data posed as the physics ``data`` (joint positions, mocap bodies, time): kinematics, centres
        of mass and cameras computed; the physics ``data`` itself when nothing is decimated."""
        import mujoco

        if not self.decimated:
            return data
        d = self.data
        d.qpos[:] = data.qpos
        d.mocap_pos[:] = data.mocap_pos
        d.mocap_quat[:] = data.mocap_quat
        d.time = data.time
        mujoco.mj_kinematics(self.model, d)
        mujoco.mj_comPos(self.model, d)
        mujoco.mj_camlight(self.model, d)
        return d


def visible_faces(model: mujoco.MjModel) -> int:
    """Faces of the meshes the visible geoms (groups 0..2) draw, each geom counted."""
    return sum(visible_meshes(model).values())
