"""The mapping file of a base-unit import: which node of a GLB is which rigid part, and how each front moves.

Example (``parts.yaml``)::

    units: m            # m | cm | mm | in
    up: +y              # the file's up axis (glTF files: +y)
    front: +z           # the file's axis out of the furniture's front (glTF files: +z)
    install: floor
    carcass: {node: Carcass, finish: wood/oak}
    fronts:
      - {id: drawer, node: Drawer, kind: drawer, finish: lacquer/white, joint: {type: slide, range: [0, 0.3]}}
      - {id: door, node: Door, kind: door, finish: lacquer/white, joint: {type: hinge, side: left, range: [0, 1.9]}}

Lengths in metres (after ``units``), angles in radians.
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from rik.schemas.common import CatalogId, Frozen, Length, NonNegLength

Axis = Literal["+x", "-x", "+y", "-y", "+z", "-z"]


class MappedCarcass(Frozen):
    node: str = Field(min_length=1)
    """Name of the GLB node holding the carcass (its mesh and those of its children)."""
    finish: CatalogId
    panel_thickness: Length = 0.018
    """Thickness of the carcass's boards, m (recorded in the catalog entry)."""


class MappedJoint(Frozen):
    type: Literal["slide", "hinge"]
    range: tuple[float, float]
    """Travel, m (slide) or rad (hinge), from closed (0) to open."""
    side: Literal["left", "right", "top", "bottom"] | None = None
    """Hinges: the edge of the front the hinge is on, seen from the front. Slides move along +y."""


class MappedFront(Frozen):
    id: CatalogId
    node: str = Field(min_length=1)
    kind: Literal["drawer", "door", "flap"]
    finish: CatalogId
    joint: MappedJoint
    panel_thickness: Length = 0.018
    """Thickness of the front panel, m (the mesh's depth includes a drawer's box)."""
    mount_margin: NonNegLength = 0.015
    """Distance kept between a handle and the front's edges, m."""


class BaseUnitMapping(Frozen):
    units: Literal["m", "cm", "mm", "in"] = "m"
    up: Axis = "+y"
    front: Axis = "+z"
    name: str | None = None
    description: str = ""
    install: Literal["floor", "wall"] = "floor"
    install_height: NonNegLength = 0.0
    carcass: MappedCarcass
    fronts: tuple[MappedFront, ...] = Field(min_length=1)
