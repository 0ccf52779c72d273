"""MuJoCo's drawn geoms as triangle meshes: which geoms its renderer shows (groups 0-2, not transparent) and each
one's triangles in its geom frame, shared by the Mitsuba scene (:mod:`rik.render.mitsuba_scene`) and the web app's 3D
view (:mod:`rik.web.meshes`). Lengths in m, as the model's.

Mesh geoms keep MuJoCo's own vertex normals (so smooth and sharp edges shade as in MuJoCo); boxes get per-face metric
texture coordinates (so wood grain has the same density on every board); other primitives come from trimesh.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    import mujoco

VISIBLE_GROUPS = (0, 1, 2)
"""Geom groups MuJoCo's renderer shows by default (``mjvOption.geomgroup``)."""
Triangles = tuple[np.ndarray, np.ndarray, "np.ndarray | None", np.ndarray]
"""Vertices (n, 3) m, faces (k, 3), vertex normals (n, 3) or None (let the renderer compute them), texture
coordinates (n, 2) m."""


def rigid(pos: np.ndarray, mat: np.ndarray) -> np.ndarray:
    """The 4x4 rigid transform of a position (m) and a 3x3 rotation (flat or not), as MuJoCo's ``*_xpos``/``*_xmat``."""
    m = np.eye(4)
    m[:3, :3] = np.asarray(mat).reshape(3, 3)
    m[:3, 3] = pos
    return m


def _box(half: np.ndarray) -> Triangles:
    """A box of half-sizes ``half``: 4 vertices per face (flat shading), texture coordinates in metres with u
    along the box's longest side wherever that lies in the face (the grain of a board), else the longer side."""
    longest = int(np.argmax(half))
    verts: list[np.ndarray] = []
    faces: list[tuple[int, int, int]] = []
    uvs: list[tuple[float, float]] = []
    for axis in range(3):
        others = [a for a in range(3) if a != axis]
        u_ax = longest if longest in others else max(others, key=lambda a: half[a])
        v_ax = others[0] if others[1] == u_ax else others[1]
        for sign in (1.0, -1.0):
            base = len(verts)
            corners = [(-1, -1), (1, -1), (1, 1), (-1, 1)]
            for cu, cv in corners:
                p = np.zeros(3)
                p[axis] = sign * half[axis]
                p[u_ax] = cu * half[u_ax]
                p[v_ax] = cv * half[v_ax]
                verts.append(p)
                uvs.append((p[u_ax], p[v_ax]))
            # Counter-clockwise seen from outside: the face normal points along sign * axis.
            n = np.zeros(3)
            n[axis] = sign
            e1 = verts[base + 1] - verts[base]
            e2 = verts[base + 2] - verts[base]
            tri = [(0, 1, 2), (0, 2, 3)] if np.dot(np.cross(e1, e2), n) > 0 else [(0, 2, 1), (0, 3, 2)]
            faces += [(base + a, base + b, base + c) for a, b, c in tri]
    return np.array(verts), np.array(faces), None, np.array(uvs)


def _planar_uv(v: np.ndarray) -> np.ndarray:
    """Texture coordinates in metres: u along the part's longest extent, v along the second."""
    order = np.argsort(np.ptp(v, axis=0))[::-1]
    return v[:, order[:2]]


def _mesh_geom(model: mujoco.MjModel, g: int) -> Triangles:
    """A mesh geom's triangles in its geom frame, one vertex per face corner with MuJoCo's normals."""
    m = int(model.geom_dataid[g])
    va, fa, fn = int(model.mesh_vertadr[m]), int(model.mesh_faceadr[m]), int(model.mesh_facenum[m])
    faces = model.mesh_face[fa:fa + fn]
    verts = model.mesh_vert[va + faces].reshape(-1, 3).astype(np.float64)
    na = int(model.mesh_normaladr[m])
    normals = model.mesh_normal[na + model.mesh_facenormal[fa:fa + fn]].reshape(-1, 3).astype(np.float64)
    return verts, np.arange(3 * fn).reshape(fn, 3), normals, _planar_uv(verts)


def _primitive(model: mujoco.MjModel, g: int) -> Triangles:
    import mujoco
    import trimesh

    kind, size = int(model.geom_type[g]), np.asarray(model.geom_size[g], np.float64)
    t = mujoco.mjtGeom
    if kind == t.mjGEOM_BOX:
        return _box(size)
    if kind == t.mjGEOM_SPHERE:
        mesh = trimesh.creation.icosphere(subdivisions=3, radius=size[0])
    elif kind == t.mjGEOM_ELLIPSOID:
        mesh = trimesh.creation.icosphere(subdivisions=3, radius=1.0)
        mesh.apply_scale(size)
    elif kind == t.mjGEOM_CAPSULE:
        mesh = trimesh.creation.capsule(height=2 * size[1], radius=size[0], count=[24, 24])
    elif kind == t.mjGEOM_CYLINDER:
        mesh = trimesh.creation.cylinder(radius=size[0], height=2 * size[1], sections=48)
        v = np.asarray(mesh.vertices)
        return v, np.asarray(mesh.faces), None, _planar_uv(v)
    else:
        raise ValueError(f"geom type {kind} is not drawn by rik's Mitsuba scene")
    v = np.asarray(mesh.vertices)
    return v, np.asarray(mesh.faces), np.asarray(mesh.vertex_normals), _planar_uv(v)


def drawn_geoms(model: mujoco.MjModel) -> list[int]:
    """Ids of the geoms MuJoCo's renderer draws by default: groups 0-2, not fully transparent."""
    out = []
    for g in range(model.ngeom):
        mat = int(model.geom_matid[g])
        alpha = float(model.mat_rgba[mat][3]) if mat >= 0 else float(model.geom_rgba[g][3])
        if int(model.geom_group[g]) in VISIBLE_GROUPS and alpha > 0.0:
            out.append(g)
    return out

def geom_triangles(model: mujoco.MjModel, g: int) -> Triangles:
    """Geom ``g``'s triangles in its geom frame (a mesh or a primitive; a plane raises ValueError)."""
    import mujoco

    if int(model.geom_type[g]) == mujoco.mjtGeom.mjGEOM_MESH:
        return _mesh_geom(model, g)
    return _primitive(model, g)
