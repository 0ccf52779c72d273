"""Does a handle fit a front? Footprint of a handle against a front's allowed mount rectangle."""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:  # annotations only: rik.registry.index imports this module on its fast path, without pydantic
    from rik.schemas import BaseUnit, Front, Handle

#: Rotations (degrees about the site's z axis) a handle may be mounted at: along the site's x, or across it.
ROTATIONS = (0, 90)


def footprint(handle: Handle, rotation: int) -> tuple[float, float]:
    """Extents (m) of the handle along the site's x and y when mounted at ``rotation`` degrees."""
    g = handle.geometry
    return (g.length, g.width) if rotation % 180 == 0 else (g.width, g.length)


def fits(handle: Handle, front: Front, rotation: int) -> bool:
    """True when the handle's footprint lies within the front's mount rectangle at this rotation."""
    ex, ey = footprint(handle, rotation)
    sx, sy = front.mount.size
    return ex <= sx + 1e-9 and ey <= sy + 1e-9


def fitting_rotations(handle: Handle, front: Front) -> tuple[int, ...]:
    """Rotations (of :data:`ROTATIONS`) at which the handle fits the front."""
    return tuple(r for r in ROTATIONS if fits(handle, front, r))


def fits_base_unit(handle: Handle, base: BaseUnit) -> bool:
    """True when the handle fits every front of the base unit (at some rotation each): the pairing is a variant."""
    return all(fitting_rotations(handle, f) for f in base.fronts)
