"""Parametric handle generators: one function per generator name, each building a visual mesh.

A generator takes the design's parameters (:mod:`rik.schemas.generators`), the handle's size
(:class:`~rik.schemas.handles.HandleGeometry`) and its mount, and returns one closed triangle mesh in metres in
the handle's mount frame: origin at the mount point on the front's outer surface, +z out of the front, x along the
handle's long axis (see :mod:`rik.schemas.handles`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from rik.assets.handles.generator import Generator
from rik.assets.meshkit import require_solid

if TYPE_CHECKING:
    import trimesh

    from rik.schemas.handles import Handle, HandleDesign


def generators() -> dict[str, Generator]:
    """Every generator by name (the ``name`` field of a design's ``generator``)."""
    from rik.assets.handles import finger_pulls, knobs, two_point

    return {**knobs.GENERATORS, **two_point.GENERATORS, **finger_pulls.GENERATORS}


def generate_handle(handle: Handle, design: HandleDesign) -> trimesh.Trimesh:
    """Build the visual mesh of ``handle`` (a closed solid, metres, mount frame)."""
    build = generators()[design.generator.name]
    mesh = build(design.generator, handle.geometry, handle.mount)
    return require_solid(mesh, f"handle {handle.id}")
