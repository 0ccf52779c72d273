"""Small mesh toolkit shared by the generators: tessellation density, booleans, placement and solidity checks.

Everything is in metres. Generators build with trimesh's own creation functions (``revolve``,
``sweep_polygon``, ``extrude_polygon``, ``box``, ``cylinder``, ``capsule``, ``torus``) and combine parts with
:func:`union` / :func:`difference`, which run on manifold3d so the result is watertight.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING

from rik.errors import RikError

if TYPE_CHECKING:
    import numpy as np
    import trimesh

CHORD_TOLERANCE = 0.05e-3
"""Largest distance between a tessellated arc and the true arc, m (0.05 mm)."""

MIN_SEGMENTS = 24
MAX_SEGMENTS = 192


def segments(radius: float, arc_rad: float = 2 * math.pi) -> int:
    """Number of straight segments for an arc of ``radius`` (m) and angle ``arc_rad`` (rad).

    Chosen so that the chord error stays under :data:`CHORD_TOLERANCE`: small radii (tight curvature) get
    as many segments per radian as the bound needs, so curved regions are finely tessellated.
    """
    if radius <= 0:
        return MIN_SEGMENTS
    ratio = max(-1.0, min(1.0, 1.0 - CHORD_TOLERANCE / radius))
    step = 2.0 * math.acos(ratio)  # angle per segment that keeps the sagitta under the tolerance
    full = math.ceil(2 * math.pi / step) if step > 0 else MAX_SEGMENTS
    full = max(MIN_SEGMENTS, min(MAX_SEGMENTS, full))
    return max(2, math.ceil(full * arc_rad / (2 * math.pi)))


def union(meshes: Sequence[trimesh.Trimesh]) -> trimesh.Trimesh:
    """Boolean union of closed meshes (manifold3d); the result is watertight."""
    import trimesh

    if len(meshes) == 1:
        return meshes[0]
    return trimesh.boolean.union(list(meshes), engine="manifold")


def difference(base: trimesh.Trimesh, cutters: Sequence[trimesh.Trimesh]) -> trimesh.Trimesh:
    """``base`` minus every cutter (manifold3d)."""
    import trimesh

    return trimesh.boolean.difference([base, *cutters], engine="manifold")


def translated(mesh: trimesh.Trimesh, offset: Sequence[float]) -> trimesh.Trimesh:
    """A copy of ``mesh`` moved by ``offset`` (m)."""
    out = mesh.copy()
    out.apply_translation(offset)
    return out


def rotated(mesh: trimesh.Trimesh, angle_rad: float, axis: Sequence[float]) -> trimesh.Trimesh:
    """A copy of ``mesh`` rotated by ``angle_rad`` about ``axis`` through the origin."""
    import trimesh

    out = mesh.copy()
    out.apply_transform(trimesh.transformations.rotation_matrix(angle_rad, axis))
    return out


def bounds(mesh: trimesh.Trimesh) -> np.ndarray:
    """Axis-aligned bounds ``[[xmin, ymin, zmin], [xmax, ymax, zmax]]``, m."""
    return mesh.bounds


def require_solid(mesh: trimesh.Trimesh, what: str) -> trimesh.Trimesh:
    """Return ``mesh`` cleaned, or raise :class:`RikError` naming ``what`` if it is not a closed solid."""
    mesh.merge_vertices()
    mesh.update_faces(mesh.nondegenerate_faces())
    mesh.remove_unreferenced_vertices()
    if len(mesh.faces) == 0:
        raise RikError(f"{what}: the mesh is empty")
    if not mesh.is_watertight:
        raise RikError(f"{what}: the mesh is not watertight")
    if not mesh.is_winding_consistent:
        raise RikError(f"{what}: the mesh's faces have inconsistent winding")
    if mesh.volume <= 0:
        mesh.invert()
    return mesh
