"""Random realistic truths (:func:`random_truth`) and the parameters a fit is compared with
(:func:`truth_parameters`)."""

from __future__ import annotations

import math

import numpy as np

from rik.errors import RikError
from rik.schemas.joints import (
    DirectionFriction,
    JointType,
    LoadFriction,
    MagneticCatch,
    QuadraticDamping,
    SelfClose,
    SoftClose,
    Spring,
    Stiction,
    Tilt,
)
from rik.sysid.synthetic.draws import joint_type as _joint
from rik.sysid.synthetic.draws import log_uniform as _log_uniform
from rik.sysid.synthetic.draws import tilt_phase
from rik.sysid.synthetic.draws import uniform as _uniform
from rik.sysid.synthetic.generate.constants import BASE_RANGES, EFFECT_KINDS, EFFECT_RANGES, GRAVITY, JOINT_KINDS
from rik.sysid.synthetic.generate.truth import Effect, GroundTruth

SECOND_CONFLICTS = {frozenset({"tilt", "stiction"}): "both set the Coulomb friction (tilt from its over_friction, "
                                                    "stiction from its own frictionloss range)"}
"""Pairs of kinds :func:`random_truth` cannot draw together, with the reason."""


def _check_kind(name: str, kind: str, joint: JointType) -> None:
    if kind not in EFFECT_KINDS:
        raise RikError(f"{name} '{kind}' is not an effect kind; use one of {', '.join(EFFECT_KINDS)}"
                       + (" or None" if name == "kind" else ""))
    if kind not in JOINT_KINDS[joint]:
        raise RikError(f"{name} '{kind}' is not valid for a {joint.value} joint; use one of "
                       f"{', '.join(JOINT_KINDS[joint])}")


def random_truth(kind: str | None, joint: JointType | str, rng: np.random.Generator, *,
                 mass: float | None = None, second: str | None = None) -> GroundTruth:
    """A realistic truth with effect ``kind`` (one of :data:`EFFECT_KINDS`, or None for none), base and effect
    parameters drawn from :data:`BASE_RANGES` and :data:`EFFECT_RANGES`, large enough to identify (the effect's
    RMS force where active is several times the default force noise). ``mass`` (kg or kg·m²) fixes the inertia.

    ``second`` (a kind other than ``kind``) adds a second effect acting together with the first, drawn the same
    way after all of the first's draws (so a truth without ``second`` is the same for a seed); its base rules
    apply on top (a second ``stiction`` redraws the Coulomb friction from its range, a second ``tilt`` sets it
    from its over_friction and, on a slide without ``mass``, redraws a heavier mass). Pairs in
    :data:`SECOND_CONFLICTS` are refused."""
    joint = _joint(joint)
    if kind is not None:
        _check_kind("kind", kind, joint)
    if second is not None:
        _check_kind("second", second, joint)
        if kind is None:
            raise RikError(f"second '{second}' needs a first effect kind; give kind")
        if second == kind:
            raise RikError(f"second '{second}' is the same kind as kind; the two effects must differ")
        if reason := SECOND_CONFLICTS.get(frozenset({kind, second})):
            raise RikError(f"kind '{kind}' and second '{second}' cannot be drawn together: {reason}")
    if not isinstance(rng, np.random.Generator):
        raise RikError(f"rng must be a numpy.random.Generator, got {type(rng).__name__}")
    if mass is not None and not (isinstance(mass, (int, float)) and math.isfinite(mass) and mass > 0):
        raise RikError(f"mass must be a finite number > 0, got {mass!r}")
    base = BASE_RANGES[joint]
    slide = joint is JointType.slide
    m = float(mass) if mass is not None else _log_uniform(rng, base["mass"])
    if kind == "tilt" and slide and mass is None:
        m = _log_uniform(rng, (4.0, base["mass"][1]))  # heavy enough for a 2 N pull at ≤ 3°
    damping = _log_uniform(rng, base["damping"])
    friction = _log_uniform(rng, base["frictionloss"])
    upper = _uniform(rng, base["upper"])
    effect, friction = _draw_effect(kind, joint, rng, m=m, friction=friction, upper=upper)
    other: Effect | None = None
    if second is not None:
        if second == "tilt" and slide and mass is None:
            m = _log_uniform(rng, (4.0, base["mass"][1]))
        other, friction = _draw_effect(second, joint, rng, m=m, friction=friction, upper=upper)
    return GroundTruth(joint=joint, mass=m, damping=damping, frictionloss=friction, range=(0.0, upper),
                       effect=effect, second=other)


def _draw_effect(kind: str | None, joint: JointType, rng: np.random.Generator, *, m: float, friction: float,
                 upper: float) -> tuple[Effect | None, float]:
    """(effect of ``kind`` drawn from :data:`EFFECT_RANGES`, the Coulomb friction: ``friction`` or, for stiction
    and tilt, the one their rule sets) for a joint of mass ``m`` and range (0, ``upper``)."""
    base = BASE_RANGES[joint]
    ranges = EFFECT_RANGES[joint].get(kind or "", {})
    slide = joint is JointType.slide
    effect: Effect | None = None
    if kind == "stiction":
        friction = _uniform(rng, ranges["frictionloss"])
        effect = Stiction(breakaway=friction * (_uniform(rng, ranges["ratio"]) - 1.0),
                          stribeck_velocity=_log_uniform(rng, ranges["stribeck_velocity"]))
    elif kind == "soft_close":
        effect = SoftClose(zone=_uniform(rng, ranges["zone"]), damping=_uniform(rng, ranges["damping"]))
    elif kind == "self_close":
        zone = _uniform(rng, ranges["zone"])
        effect = SelfClose(zone=zone, stiffness=_uniform(rng, ranges["pull"]) / zone)
    elif kind == "magnetic_catch":
        effect = MagneticCatch(force=_uniform(rng, ranges["force"]), decay=_uniform(rng, ranges["decay"]))
    elif kind == "tilt":
        sign = 1.0 if rng.random() < 0.5 else -1.0
        ratio = _uniform(rng, ranges["over_friction"])
        lo_f, hi_f = base["frictionloss"]
        if slide:
            lowest = math.degrees(math.asin(min(1.0, ranges["abs_force"][0] / (m * GRAVITY))))
            angle = max(_uniform(rng, (1.0, 3.0)), lowest)
            if angle > ranges["angle_deg"][1]:
                raise RikError(f"mass {m:g} kg is too light for an identifiable tilt (≥ 2 N within "
                               f"{ranges['angle_deg'][1]:g}°); use mass ≥ 2 kg")
            force = m * GRAVITY * math.sin(math.radians(angle))
            effect = Tilt(force=sign * force)
            friction = min(max(force / ratio, lo_f), hi_f)
        else:
            amplitude = _uniform(rng, ranges["amplitude"])
            phase = tilt_phase(rng)
            effect = Tilt(force=amplitude * math.cos(phase), sine=amplitude * math.sin(phase))
            grid = np.linspace(0.0, upper, 181)
            peak = float(np.max(np.abs(effect.force * np.cos(grid) + effect.sine * np.sin(grid))))
            friction = min(max(peak / ratio, lo_f), hi_f)
    elif kind == "direction_friction":
        effect = DirectionFriction(extra=_uniform(rng, ranges["extra"]),
                                   direction="closing" if rng.random() < 0.5 else "opening")
    elif kind == "quadratic_damping":
        effect = QuadraticDamping(coefficient=_uniform(rng, ranges["coefficient"]))
    elif kind == "load_friction":
        effect = LoadFriction(per_extension=_uniform(rng, ranges["per_extension"]))
    elif kind == "spring":
        effect = Spring(stiffness=_uniform(rng, ranges["stiffness"]), reference=_uniform(rng, ranges["reference"]))
    return effect, friction


def truth_parameters(truth: GroundTruth) -> dict[str, float]:
    """The base parameters (``mass``, ``damping``, ``frictionloss``, ``upper``) and the effect's (``effect.<name>``),
    with the derived quantities named in :data:`EFFECT_RANGES`; a second effect's are ``second.<name>``, derived
    ones included. Library units."""
    out = {"mass": truth.mass, "damping": truth.damping, "frictionloss": truth.frictionloss,
           "upper": truth.range[1]}
    for prefix, effect in (("effect", truth.effect), ("second", truth.second)):
        if effect is None:
            continue
        values = {k: float(v) for k, v in effect.model_dump().items() if isinstance(v, (int, float))
                  and not isinstance(v, bool)}
        out.update({f"{prefix}.{k}": v for k, v in values.items()})
        derived = _derived_parameters(effect, truth)
        out.update(derived if prefix == "effect" else {f"second.{k}": v for k, v in derived.items()})
    return out


def _derived_parameters(effect: Effect, truth: GroundTruth) -> dict[str, float]:
    out: dict[str, float] = {}
    if isinstance(effect, Stiction):
        out["ratio"] = (truth.frictionloss + effect.breakaway) / truth.frictionloss if truth.frictionloss else math.inf
    elif isinstance(effect, SelfClose):
        out["pull"] = effect.stiffness * effect.zone
    elif isinstance(effect, Tilt):
        out["abs_force"] = abs(effect.force)
        if truth.joint is JointType.slide:
            out["angle_deg"] = math.degrees(math.asin(min(1.0, abs(effect.force) / (truth.mass * GRAVITY))))
            peak = abs(effect.force)
        else:
            out["amplitude"] = math.hypot(effect.force, effect.sine)
            out["abs_sine"] = abs(effect.sine)
            grid = np.linspace(0.0, truth.range[1], 181)
            peak = float(np.max(np.abs(effect.force * np.cos(grid) + effect.sine * np.sin(grid))))
        out["over_friction"] = peak / truth.frictionloss if truth.frictionloss else math.inf
    return out
