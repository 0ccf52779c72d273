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
from typing import Annotated, Literal

from pydantic import Field, ValidationInfo, field_validator

from rik.schemas.common import CatalogId, Frozen, Provenance, Real, Vec3

NonNeg = Annotated[float, Field(ge=0, allow_inf_nan=False)]
Positive = Annotated[float, Field(gt=0, allow_inf_nan=False)]


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


class Stiction(Frozen):
    """Static friction above the Coulomb level, fading with speed (Stribeck): an extra friction force of
    ``breakaway * exp(-(v / stribeck_velocity)^2)`` against the motion."""

    kind: Literal["stiction"] = "stiction"
    breakaway: NonNeg
    """Static minus kinetic friction at rest: N (slide) or N·m (hinge)."""
    stribeck_velocity: Positive
    """Speed over which the extra friction fades: m/s or rad/s."""


class SoftClose(Frozen):
    """A soft-close damper: viscous damping acting only within ``zone`` of the closed position (and, by default,
    only while closing): force ``-damping * v`` there."""

    kind: Literal["soft_close"] = "soft_close"
    zone: Positive
    """Length of the zone from closed: m or rad."""
    damping: NonNeg
    """N·s/m or N·m·s/rad."""
    closing_only: bool = True
    """True: the damper acts only while closing (v < 0), as real soft-close pistons do."""


class SelfClose(Frozen):
    """A self-closing (pull-in) spring in the last ``zone`` before closed: force ``-stiffness * (zone - q)``
    for q < zone, pulling closed, in both directions of motion and at rest (it also holds the front shut)."""

    kind: Literal["self_close"] = "self_close"
    zone: Positive
    """Length of the zone from closed: m or rad."""
    stiffness: NonNeg
    """N/m or N·m/rad; the pull at closed is ``stiffness * zone``."""


class MagneticCatch(Frozen):
    """A magnetic catch: an attraction towards closed, ``-force / (1 + q / decay)^2``."""

    kind: Literal["magnetic_catch"] = "magnetic_catch"
    force: NonNeg
    """Pull at contact (q = 0): N or N·m."""
    decay: Positive
    """Distance over which the pull falls to a quarter: m or rad."""


class Tilt(Frozen):
    """Gravity along the joint: a tilted drawer runner (a constant ``force``) or an out-of-plumb hinge
    (``force * cos q + sine * sin q``). Positive values push the front open."""

    kind: Literal["tilt"] = "tilt"
    force: Real
    """Force at closed: N (slide) or N·m (hinge)."""
    sine: Real = 0.0
    """Hinges only: the coefficient of sin q, N·m (0 for slides)."""


class DirectionFriction(Frozen):
    """Friction that differs with the direction of motion: ``extra`` on top of the Coulomb friction in one
    direction only."""

    kind: Literal["direction_friction"] = "direction_friction"
    extra: NonNeg
    """Additional friction in ``direction``: N or N·m."""
    direction: Literal["opening", "closing"] = "closing"


class QuadraticDamping(Frozen):
    """Fluid-like damping growing with the square of speed: force ``-coefficient * v * |v|``."""

    kind: Literal["quadratic_damping"] = "quadratic_damping"
    coefficient: NonNeg
    """N·s²/m² (slide) or N·m·s²/rad² (hinge)."""


class LoadFriction(Frozen):
    """Friction growing with the extension (a cantilevered drawer loads its runners more the further it is out):
    ``per_extension * q`` on top of the Coulomb friction."""

    kind: Literal["load_friction"] = "load_friction"
    per_extension: NonNeg
    """Additional friction per unit of joint position: N/m (slide) or N·m/rad (hinge)."""


JointEffect = Annotated[Stiction | SoftClose | SelfClose | MagneticCatch | Tilt | DirectionFriction
                        | QuadraticDamping | LoadFriction, Field(discriminator="kind")]
"""An effect beyond damping, Coulomb friction and a linear spring, as identified by ``rik sysid`` (the closer
spring of the library is :class:`Spring`)."""


class JointResistance(Frozen):
    """Passive resistance of one joint type, in MuJoCo's terms (``damping``, ``frictionloss``, ``armature``)."""

    damping: NonNeg
    """Viscous damping: N·s/m (slide) or N·m·s/rad (hinge)."""
    frictionloss: NonNeg
    """Dry (Coulomb) friction: N (slide) or N·m (hinge)."""
    armature: NonNeg = 0.0
    """Added inertia of the mechanism: kg (slide) or kg·m² (hinge)."""
    spring: Spring | None = None
    effects: tuple[JointEffect, ...] = ()
    """Effects beyond damping, friction and the spring (at most one of each kind), e.g. from ``rik sysid``."""
    provenance: Provenance
    notes: str = ""
    """Source, or the derivation of the values."""


    @field_validator("effects")
    @classmethod
    def _one_of_each(cls, effects: tuple) -> tuple:
        kinds = [e.kind for e in effects]
        repeated = sorted({k for k in kinds if kinds.count(k) > 1})
        if repeated:
            raise ValueError(f"at most one effect of each kind, got {', '.join(repeated)} more than once")
        return effects


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
