"""Helpers shared by the generator tests: catalogued handles, their meshes (built once), and an exact
inside/outside test."""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest
import trimesh

from rik.assets.handles import generate_handle
from rik.registry import load_catalog
from rik.schemas.handles import Handle, HandleDesign

CATALOG = load_catalog([])


def handles_of(generators: set[str]) -> list[str]:
    """Ids of the catalogued handles whose design uses one of ``generators``."""
    return [hid for hid, h in CATALOG.handles.items() if CATALOG.designs[h.design].generator.name in generators]


def parts(hid: str) -> tuple[Handle, HandleDesign]:
    """The catalogued handle and its design."""
    handle = CATALOG.handles[hid]
    return handle, CATALOG.designs[handle.design]


@functools.cache
def mesh_of(hid: str):
    """The handle's mesh, built once per test session."""
    return generate_handle(*parts(hid))


def inside(mesh, points: np.ndarray) -> np.ndarray:
    """Generalised winding number of a closed mesh at ``points`` (> 0.5: inside); exact, without ray casting
    (``mesh.contains`` took seconds per 2,000 points)."""
    tri = mesh.vertices[mesh.faces]
    out = np.empty(len(points))
    for i in range(0, len(points), 64):
        p = points[i:i + 64, None, :]
        a, b, c = (tri[None, :, k, :] - p for k in range(3))
        la, lb, lc = (np.linalg.norm(v, axis=-1) for v in (a, b, c))
        num = np.einsum("pfi,pfi->pf", a, np.cross(b, c))
        den = (la * lb * lc + np.einsum("pfi,pfi->pf", a, b) * lc + np.einsum("pfi,pfi->pf", b, c) * la
               + np.einsum("pfi,pfi->pf", c, a) * lb)
        out[i:i + 64] = np.arctan2(num, den).sum(axis=1) / (2 * math.pi)
    return out > 0.5


def assert_catalogued_extents(mesh, geometry, tol: float) -> None:
    """The mesh's overall length (x), width (y) and projection (top z) are the catalog's, within ``tol`` (m)."""
    (x0, y0, _), (x1, y1, z1) = mesh.bounds
    assert x1 - x0 == pytest.approx(geometry.length, abs=tol)
    assert y1 - y0 == pytest.approx(geometry.width, abs=tol)
    assert z1 == pytest.approx(geometry.projection, abs=tol)


def assert_one_closed_body(mesh, min_faces: int, max_faces: int = 40_000) -> None:
    """Watertight, consistently wound, positive volume, a single connected body, a sensible triangle count."""
    assert mesh.is_watertight and mesh.is_winding_consistent
    assert mesh.volume > 0
    bodies = trimesh.graph.connected_components(mesh.face_adjacency, nodes=np.arange(len(mesh.faces)), engine="scipy")
    assert len(bodies) == 1
    assert min_faces <= len(mesh.faces) <= max_faces
