"""Base units: carcasses with moving fronts (drawers, doors, flaps), each front with its joint and mount site.

Frame of a base unit: origin at the bottom edge of the carcass's front plane, centred left-right; +x to the
left as seen by a person facing the front (x = y cross z), +y out of the front towards that person, +z up.
"Left" and "right" in ids and names are as that person sees them: a door hinged on the left turns about
an axis at +x. The carcass fills
x in [-width/2, width/2], y in [-depth, 0], z in [0, height]; fronts sit in front of it (y > 0).
All lengths in metres.
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from rik.schemas.common import CatalogId, Frozen, Length, MeshFile, NonNegLength, Quat, Real, Vec3
from rik.schemas.handles import HandleType
from rik.schemas.joints import JointSpec


class Carcass(Frozen):
    """The fixed box of a base unit."""

    width: Length
    height: Length
    depth: Length
    panel_thickness: Length
    """Thickness of sides, top and bottom, m."""
    finish: CatalogId
    """Id of the carcass's finish."""


class MountSite(Frozen):
    """Where a handle may go on a front: a frame on the front's outer face and an allowed rectangle.

    The site frame has +z out of the front and x along the front's width (horizontal on upright fronts).
    """

    pos: Vec3
    """Centre of the allowed rectangle on the front's outer surface, base-unit frame, front closed (m)."""
    quat: Quat = (0.7071067811865476, -0.7071067811865476, 0.0, 0.0)
    """Rotation from the base-unit frame to the site frame (w, x, y, z). The default turns +z to +y (out of
    an upright front) with x unchanged."""
    size: tuple[Length, Length]
    """Extents of the allowed rectangle along the site's x and y, m; a handle's whole footprint must lie in it."""


class Placement(Frozen):
    """Where handles go on one front, overriding the combinator's rule for the front's kind.

    Positions are in the mount site's frame (x along the front's width, y down on upright fronts, metres),
    relative to the centre of the mount rectangle.
    """

    at: tuple[Real, Real]
    """Site-frame (x, y) of the handle's mount point, relative to the mount rectangle's centre, m. For edge
    pulls: x along the edge (the point on the edge is the combinator's)."""
    rotation: Literal[0, 90] | None = None
    """Degrees about the site's z: 0 puts the handle's long axis along the site's x (horizontal on upright
    fronts), 90 across it. Absent: the rule's rotation."""
    handle_types: tuple[HandleType, ...] = (HandleType.knob, HandleType.two_point, HandleType.finger_pull)
    """Handle types this placement applies to; the first placement of a front that lists a type wins."""


class DrawerBox(Frozen):
    """The box behind a drawer front that travels with it."""

    width: Length
    height: Length
    depth: Length
    wall_thickness: Length


class Front(Frozen):
    """A moving front: a drawer front, a door or a flap, with its joint and its handle mount site."""

    id: CatalogId
    """Unique within the base unit, for example ``drawer-1`` or ``door``."""
    kind: Literal["drawer", "door", "flap"]
    size: tuple[Length, Length, Length]
    """Panel width (x), height (z) and thickness (y), m."""
    center: Vec3
    """Centre of the front panel with the front closed, base-unit frame, m."""
    joint: JointSpec
    mount: MountSite
    drawer_box: DrawerBox | None = None
    """For drawers: the box behind the front."""
    finish: CatalogId
    placements: tuple[Placement, ...] = ()
    """Overrides of the combinator's placement rule, per handle type (see :class:`Placement`)."""

    @property
    def layout(self) -> str:
        """What the front is, as tables split it: ``drawer``; ``door-right`` (hinge axis up, as the catalog's
        ``*-right`` doors) or ``door-left``; ``flap-lift-up`` (hinge above the panel's centre) or
        ``flap-drop-down``."""
        if self.kind == "drawer":
            return "drawer"
        if self.kind == "door":
            return "door-right" if self.joint.axis[2] > 0 else "door-left"
        return "flap-lift-up" if self.joint.anchor[2] > self.center[2] else "flap-drop-down"


class BaseUnit(Frozen):
    """A piece of furniture that handles are paired with."""

    id: CatalogId
    """``<category>/<name>``, for example ``drawer/chest-80``."""
    name: str = Field(min_length=1)
    description: str = ""
    install: Literal["floor", "wall"]
    """Stands on the floor, or hangs on a wall."""
    install_height: NonNegLength = 0.0
    """Height of the carcass's bottom above the floor, m."""
    carcass: Carcass
    fronts: tuple[Front, ...] = Field(min_length=1)
    default_preset: CatalogId = "normal"
    """Resistance preset used when none is asked for."""
    licence: str = Field(default="CC-BY-4.0", pattern=r"^[A-Za-z0-9.\-+]+$")
    """SPDX licence identifier."""
    meshes: dict[str, MeshFile] | None = None
    """Imported base units (``rik assets import --base-unit``): one mesh per rigid part, keyed ``carcass`` and
    each front's id, in the base unit's frame with the fronts closed. Absent: rik builds the parts from boards
    with the carcass's and fronts' dimensions."""
