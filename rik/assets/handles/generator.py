"""The shape of a handle generator: (the design's parameters, the handle's size, its mount) -> a closed mesh in metres
in the handle's mount frame."""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import trimesh

    from rik.schemas.handles import HandleGeometry, Mount

Generator = Callable[[Any, "HandleGeometry", "Mount"], "trimesh.Trimesh"]
