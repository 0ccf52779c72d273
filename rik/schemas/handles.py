"""Handles and knobs: designs (shape families) and handles (sized, finished instances of a design).

Frames: a handle's mount frame has its origin at the mount point on the front's outer surface, +z out of the
front, x along the handle's long axis. All lengths in metres, masses in kilograms.
"""

from __future__ import annotations

from enum import StrEnum
from typing import Literal

from pydantic import Field

from rik.schemas.common import CatalogId, Frozen, Length, Mass
from rik.schemas.generators import GeneratorSpec


class HandleType(StrEnum):
    """The three handle categories of the paper (Figure 9), by how their geometry is grasped."""

    knob = "knob"  #: a single-point knob or ring pull
    two_point = "two_point"  #: a bar, bow or loop on two screws, with a loop a finger fits through
    finger_pull = "finger_pull"  #: an edge profile, tab, cup or recess: fingertips hook under a lip or hood


class DesignProvenance(Frozen):
    """Where a design's geometry comes from."""

    origin: Literal["parametric", "user_mesh"]
    """``parametric``: built by one of rik's generators; ``user_mesh``: imported from a user's mesh file."""
    reference: str = Field(min_length=1)
    """What the shape and proportions follow (hardware sizing guides, a drawing, a measurement)."""


class HandleDesign(Frozen):
    """A shape family; its handles differ in size and finish only."""

    id: CatalogId
    """``<type>/<design>``, for example ``two_point/bow``."""
    type: HandleType
    subtype: CatalogId
    """Finer shape class within the type, for example ``mushroom``, ``bar``, ``bow``, ``edge_lip``."""
    name: str = Field(min_length=1)
    """Descriptive name (never a product name)."""
    generator: GeneratorSpec
    provenance: DesignProvenance


class Clearance(Frozen):
    """Free space a fingertip or gripper finger can enter: behind a bar, under a hood, lip or knob head."""

    depth: Length
    """How deep a finger can go, m: front face to the grip's underside for loops and knob heads, hook depth
    behind a lip or hood; for inset grips, the depth of the recess behind the front's face."""
    width: Length
    """Free opening, m: along the handle's x axis for loops (between the legs) and lips (along the lip); for
    knobs, the width of the head a finger or gripper reaches behind."""


class HandleGeometry(Frozen):
    """Grasp-relevant dimensions, in metres, in the handle's mount frame."""

    length: Length
    """Overall extent along x (the long axis)."""
    width: Length
    """Overall extent along y."""
    projection: Length
    """Stand-off from the front surface to the outermost point, along +z."""
    grip_diameter: Length
    """Diameter of a knob's head, or thickness of a bar's, bow's or lip's section."""
    hole_spacing: Length | None = None
    """Centre-to-centre distance of the two screws (two-screw mounts only)."""
    clearance: Clearance | None = None
    """Finger clearance of the loop, lip, hood or knob head."""


class Mount(Frozen):
    """How the handle is fixed to a front."""

    kind: Literal["single_screw", "two_screw", "edge_clip", "inset"]
    """``edge_clip``: fixed on an edge of the front; ``inset``: set into a routed recess."""
    edge: Literal["top", "side"] | None = None
    """For edge clips: the edge of the front the profile is made for (top edge, or the opening side)."""
    screw: str | None = None
    """Screw size, for example ``M4``."""


class Handle(Frozen):
    """One catalogued handle: a design at one size, with one finish."""

    id: CatalogId
    """``<design id>-<size>``, for example ``two_point/bow-128``."""
    design: CatalogId
    """Id of the :class:`HandleDesign`."""
    size: str = Field(pattern=r"^[a-z0-9][a-z0-9.\-]*$")
    """Size label, usually the hole spacing or diameter in mm."""
    finish: CatalogId
    """Id of a :class:`rik.schemas.finishes.Finish`."""
    geometry: HandleGeometry
    mount: Mount
    mass: Mass
    """kg."""
    licence: str = Field(pattern=r"^[A-Za-z0-9.\-+]+$")
    """SPDX licence identifier of the handle's data and generated geometry."""
