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

from pydantic import Field, ValidationInfo, field_validator, model_validator

from rik.schemas.common import CatalogId, FieldError, Frozen, Provenance, Real, Vec3

NonNeg = Annotated[float, Field(ge=0, allow_inf_nan=False)]
Positive = Annotated[float, Field(gt=0, allow_inf_nan=False)]

CATALOG_LEVER_ARM = 0.40
"""The lever arm at which the catalog states hinge values, m: the handle's distance from the hinge axis (a handle
near the opening edge of a 40-45 cm door; ``presets.yaml``'s header). A force F at the handle is a torque
F × 0.40 m about the hinge, and a hinge torque T is felt as T / 0.40 m at the handle."""


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

    def hold_terms(self) -> list[tuple[str, float]]:
        """What it takes to start the front opening from rest at closed (q = 0), term by term: (the field, its
        share) in N (slide) or N·m (hinge), positive holding the front shut. The Coulomb friction
        (``frictionloss``), the friction effects at rest when opening (stiction's ``breakaway``, a
        ``direction_friction`` that acts opening), the pulls towards closed at q = 0 (a magnetic catch's
        ``force``, a self-closing spring's ``stiffness × zone``), and minus what pushes the front open there (a
        tilt's ``force``, a spring's ``stiffness × reference``). Terms that are zero at rest or at closed (damping,
        soft close, quadratic damping, load friction) are left out."""
        terms = [("frictionloss", self.frictionloss)]
        for i, e in enumerate(self.effects):
            match e:
                case Stiction():
                    terms.append((f"effects.{i}.breakaway", e.breakaway))
                case DirectionFriction(direction="opening"):
                    terms.append((f"effects.{i}.extra", e.extra))
                case MagneticCatch():
                    terms.append((f"effects.{i}.force", e.force))
                case SelfClose():
                    terms.append((f"effects.{i}.stiffness", e.stiffness * e.zone))
                case Tilt():
                    terms.append((f"effects.{i}.force", -e.force))
        if self.spring is not None and self.spring.stiffness * self.spring.reference != 0:
            terms.append(("spring.reference", -self.spring.stiffness * self.spring.reference))
        return terms

    def mechanism(self) -> str:
        """The joint's class (:data:`MECHANISMS`): ``catch`` with a magnetic catch, else ``self-closing`` with a
        self-closing spring, else ``tilted`` with a tilt whose force or sine term reaches :data:`TILTED`, else
        ``plain`` (friction and damping). Splits hold each class of real door in every split."""
        kinds = {e.kind: e for e in self.effects}
        if "magnetic_catch" in kinds:
            return "catch"
        if "self_close" in kinds:
            return "self-closing"
        tilt = kinds.get("tilt")
        if isinstance(tilt, Tilt) and max(abs(tilt.force), abs(tilt.sine)) >= TILTED:
            return "tilted"
        return "plain"

    def hold_at_closed(self) -> float:
        """The force (N, slide) or torque (N·m, hinge) it takes to start the front opening from rest at closed:
        the sum of :meth:`hold_terms`, 0 when the front would open by itself."""
        return max(0.0, sum(v for _, v in self.hold_terms()))


MECHANISMS = ("catch", "self-closing", "tilted", "plain")
"""The classes of a joint's mechanism (:meth:`JointResistance.mechanism`), in the order they are tested."""
TILTED = 1.0
"""N·m (hinge) or N (slide): the largest term of a tilt from which a joint counts as ``tilted`` (2.5 N at the
catalog's lever arm of 0.40 m; the level kitchen cabinets of the real data fit tilts of 0.4-0.5 N·m)."""


class PresetSource(Frozen):
    """Where a preset's values come from: the paper, a fit to measured data, the literature or an assumption.

    A measured source names its data: the file, the mechanism in it, the trials fitted and held out, and the
    preset's error against them (forces in N; a hinge's at the handle, at ``lever_arm_m``)."""

    kind: Provenance
    """``paper`` (the Real-IKEA paper), ``literature``, ``measured`` (fitted to data) or ``assumed``."""
    reference: str = Field(min_length=1)
    """The publication, study or derivation the values come from."""
    data: str | None = Field(default=None, min_length=1)
    """Measured: the data file fitted, by its published name."""
    mechanism: str | None = Field(default=None, min_length=1)
    """Measured: the mechanism (door, drawer) of the data file fitted, as the file names it."""
    trials_fitted: int | None = Field(default=None, ge=1)
    """Measured: how many trials (openings) were fitted."""
    trials_heldout: tuple[str, ...] = ()
    """Measured: the trials held out of the fit (to test it on), as the file names them."""
    fit_rms_n: NonNeg | None = None
    """Measured: RMS difference between the preset's force and the measured one over the fitted trials, N (a
    hinge's at the handle, at ``lever_arm_m``)."""
    heldout_rms_n: NonNeg | None = None
    """Measured: the same over the held-out trials, N."""
    lever_arm_m: Positive | None = None
    """The lever arm at which forces at the handle became hinge torques (torque = force × lever arm), m."""

    @model_validator(mode="after")
    def _measured_fields(self) -> PresetSource:
        measured = ("data", "mechanism", "trials_fitted", "trials_heldout", "fit_rms_n", "heldout_rms_n")
        if self.kind is not Provenance.measured:
            given = next((f for f in measured if getattr(self, f) not in (None, ())), None)
            if given is not None:
                raise FieldError((given,), f"only a measured source names its {given.replace('_', ' ')} "
                                           f"(this one is {self.kind.value})")
            return self
        if self.data is None:
            raise FieldError(("data",), "a measured source names the data file it was fitted to")
        if self.trials_heldout and self.heldout_rms_n is None:
            raise FieldError(("heldout_rms_n",), "held-out trials need the preset's RMS error over them, N")
        if self.heldout_rms_n is not None and not self.trials_heldout:
            raise FieldError(("trials_heldout",), "an RMS error over held-out trials needs the trials it was taken "
                                                  "over")
        if self.fit_rms_n is not None and self.trials_fitted is None:
            raise FieldError(("trials_fitted",), "a fit's RMS error needs the number of trials fitted")
        return self


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
    source: PresetSource | None = None
    """Where the values come from (None: not stated, as in older user catalogs)."""

    @property
    def in_default_set(self) -> bool:
        """Whether variants are built with this preset when no preset is named (``rik variants build --all``,
        :func:`rik.registry.ids.select_variants`, datasets): every preset except measured ones, which are built
        when named (``--preset real-hai-refrigerator``). The one rule; :attr:`rik.registry.catalog.Catalog.
        default_presets` applies it."""
        return self.source is None or self.source.kind is not Provenance.measured

    def for_joint(self, joint_type: JointType) -> JointResistance:
        """The resistance that applies to a joint of this type."""
        return self.slide if joint_type is JointType.slide else self.hinge
