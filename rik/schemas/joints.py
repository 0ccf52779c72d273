"""Joints and their resistance: the mechanism of a front, and named resistance presets.

Units depend on the joint type:

=============  ==================  ====================
quantity       slide               hinge
=============  ==================  ====================
position       m                   rad
damping        N·s/m               N·m·s/rad
frictionloss   N                   N·m
armature       kg                  kg·m²
spring         N/m                 N·m/rad
=============  ==================  ====================
"""

from __future__ import annotations

import math
from enum import StrEnum
from typing import Annotated

from pydantic import Field, ValidationInfo, field_validator

from rik.schemas.common import CatalogId, Frozen, Provenance, Real, Vec3

NonNeg = Annotated[float, Field(ge=0, allow_inf_nan=False)]


class JointType(StrEnum):
    """Joint mechanisms of furniture fronts."""

    slide = "slide"  #: drawer runners (MuJoCo ``slide``)
    hinge = "hinge"  #: door and flap hinges (MuJoCo ``hinge``)


class JointSpec(Frozen):
    """The joint that moves a front, in the base unit's frame, with 0 the closed position."""

    type: JointType
    axis: Vec3
    """Direction of positive motion (opening); normalised on load."""
    anchor: Vec3
    """A point on the joint axis, m (for hinges: on the hinge line)."""
    range: tuple[Real, Real]
    """(lower, upper) joint position: m for slides, rad for hinges. Must contain 0 (closed)."""

    @field_validator("axis")
    @classmethod
    def _unit_axis(cls, axis: Vec3) -> Vec3:
        norm = math.sqrt(sum(c * c for c in axis))
        if norm < 1e-9:
            raise ValueError("axis must be a non-zero vector")
        return (axis[0] / norm, axis[1] / norm, axis[2] / norm)

    @field_validator("range")
    @classmethod
    def _ordered_range(cls, value: tuple[float, float], info: ValidationInfo) -> tuple[float, float]:
        lower, upper = value
        if not lower < upper:
            raise ValueError(f"must be (lower, upper) with lower < upper, got ({lower}, {upper})")
        if not lower <= 0.0 <= upper:
            raise ValueError(f"({lower}, {upper}) must contain 0, the closed position")
        if info.data.get("type") is JointType.hinge and upper - lower > 2 * math.pi:
            raise ValueError(f"a hinge range may span at most 2π rad (a full turn), got {upper - lower:.3f} rad")
        return value


class Spring(Frozen):
    """A linear spring on the joint (a self-closing runner, a stay)."""

    stiffness: NonNeg
    """N/m for slides, N·m/rad for hinges."""
    reference: Real = 0.0
    """Joint position where the spring exerts no force (m or rad)."""


class JointResistance(Frozen):
    """Passive resistance of one joint type, in MuJoCo's terms (``damping``, ``frictionloss``, ``armature``)."""

    damping: NonNeg
    """Viscous damping: N·s/m (slide) or N·m·s/rad (hinge)."""
    frictionloss: NonNeg
    """Dry (Coulomb) friction: N (slide) or N·m (hinge)."""
    armature: NonNeg = 0.0
    """Added inertia of the mechanism: kg (slide) or kg·m² (hinge)."""
    spring: Spring | None = None
    provenance: Provenance
    notes: str = ""
    """Source, or the derivation of the values."""


class ResistancePreset(Frozen):
    """A named level of joint resistance, with values for slides and for hinges."""

    id: CatalogId
    """For example ``normal``."""
    name: str = Field(min_length=1)
    description: str = ""
    slide: JointResistance
    """Values for drawer slides."""
    hinge: JointResistance
    """Values for door and flap hinges."""

    def for_joint(self, joint_type: JointType) -> JointResistance:
        """The resistance that applies to a joint of this type."""
        return self.slide if joint_type is JointType.slide else self.hinge
