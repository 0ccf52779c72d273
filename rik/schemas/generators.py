"""Parameters of the parametric mesh generators, one model per generator.

Every parameter is dimensionless (a ratio of the handle's own dimensions, or an angle in degrees), so one
design serves all its sizes: the absolute size comes from :class:`rik.schemas.handles.HandleGeometry`.
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field

from rik.schemas.common import Frozen, MeshFile, Unit

Ratio = Annotated[float, Field(gt=0, le=4, allow_inf_nan=False)]
"""A positive ratio of two lengths of the same handle."""


class KnobLathe(Frozen):
    """A knob turned on a lathe: a profile revolved about the mount axis (z)."""

    name: Literal["knob_lathe"]
    profile: Literal["mushroom", "cylinder", "disc", "ball", "cone", "bell", "stepped", "dome", "peg", "rosette"]
    """Family of the revolved outline."""
    neck_ratio: Unit
    """Neck diameter / head diameter."""
    head_ratio: Unit
    """Head height / projection."""
    edge_round: Unit = 0.2
    """Fillet radius of the head's edges / head radius."""
    flutes: Annotated[int, Field(ge=0, le=64)] = 0
    """Number of grooves cut around the head (0 = smooth)."""


class KnobPrism(Frozen):
    """A knob whose head is an extruded polygon or outline (square, hexagon, T-bar, oval)."""

    name: Literal["knob_prism"]
    outline: Literal["square", "hexagon", "octagon", "t_bar", "oval"]
    """Outline of the head seen from the front."""
    neck_ratio: Unit
    """Neck diameter / head width."""
    head_ratio: Unit
    """Head height / projection."""
    corner_round: Unit = 0.15
    """Corner radius / half the head width."""
    taper: Unit = 1.0
    """Size of the head's outer face / size of its inner face."""


class KnobRing(Frozen):
    """A drop-ring pull: a ring hanging from a knob-like boss (single screw)."""

    name: Literal["knob_ring"]
    section_ratio: Unit
    """Ring wire diameter / ring outer diameter."""
    boss_ratio: Unit
    """Boss diameter / ring outer diameter."""


class BarPull(Frozen):
    """A straight bar carried by two legs (two-point)."""

    name: Literal["bar_pull"]
    section: Literal["round", "square", "flat", "oval", "hexagon"]
    """Cross-section of the bar."""
    leg: Literal["round", "square", "tapered", "flat"]
    """Shape of the two legs."""
    leg_ratio: Ratio = 1.0
    """Leg diameter / bar section diameter."""
    end_style: Literal["flush", "overhang", "rounded"] = "overhang"
    """How the bar ends beyond the legs."""


class BowPull(Frozen):
    """A bow or loop swept along a curved path between two feet (two-point)."""

    name: Literal["bow_pull"]
    path: Literal["arc", "ellipse", "d_shape", "trapezoid", "bridge", "rectangle"]
    """Path of the bow's centre line, seen from above."""
    section: Literal["round", "flat", "oval", "square", "strap"]
    """Cross-section swept along the path."""
    foot: Literal["plain", "round_boss", "square_boss"] = "plain"
    """What the bow stands on at each screw."""
    foot_ratio: Ratio = 1.0
    """Foot diameter / section diameter."""


class CupPull(Frozen):
    """A cup or shell pull: a hood over a finger pocket, screwed through a flange."""

    name: Literal["cup_pull"]
    hood: Literal["half_moon", "rectangular", "long_hood"]
    """Outline of the hood."""
    flange_ratio: Unit = 0.25
    """Flange width / overall width."""


class EdgeProfile(Frozen):
    """A finger-pull profile fixed on a front's edge, forming a lip to hook fingertips under."""

    name: Literal["edge_profile"]
    section: Literal["lip", "j_hook", "l_angle", "rounded_bead", "bevel"]
    """Cross-section of the profile."""
    lip_angle_deg: Annotated[float, Field(ge=0, le=90, allow_inf_nan=False)] = 90.0
    """Angle of the lip to the front's face, degrees (90 = perpendicular)."""
    wall_ratio: Unit = 0.15
    """Wall thickness / projection."""


class TabPull(Frozen):
    """A tab screwed behind the top edge and standing over it."""

    name: Literal["tab_pull"]
    outline: Literal["rectangle", "rounded", "trapezoid"]
    """Outline of the tab seen from the front."""
    overhang_ratio: Unit = 0.5
    """Part of the tab's width that stands above the edge / width."""


class RecessLip(Frozen):
    """A grip set into a routed recess of the front, with a short lip standing proud of the face."""

    name: Literal["recess_lip"]
    lip_ratio: Unit
    """Lip height above the face / projection."""


class UserMesh(MeshFile):
    """Not a generator: the design's mesh is a user's file (in the mount frame), imported with
    ``rik assets import``."""

    name: Literal["user_mesh"]


GeneratorSpec = Annotated[
    KnobLathe | KnobPrism | KnobRing | BarPull | BowPull | CupPull | EdgeProfile | TabPull | RecessLip | UserMesh,
    Field(discriminator="name"),
]
"""Which generator builds a design, and its parameters."""
