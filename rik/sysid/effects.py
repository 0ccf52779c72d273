"""The effect library: every candidate cause of what damping and Coulomb friction miss, as regressors.

The equation the fit solves on moving samples (SI units of the joint: m or rad, N or N·m, s)::

    F_applied = M·a + b·v + Fc·sign(v) + Σ θ_j·φ_j(q, v; h)

``M`` inertia (kg or kg·m²), ``b`` damping, ``Fc`` Coulomb friction (the baseline: rik's current joint model),
and one effect: its regressors ``φ_j`` (the resistance it adds, i.e. minus its force on the joint), linear in
the coefficients ``θ_j`` and shaped by at most one nonlinear hyperparameter ``h`` (a zone length, a decay
length, a Stribeck speed) searched on a grid and refined. Each :class:`Family` turns its coefficients into the
physical parameters of a :data:`rik.schemas.joints.JointEffect` (or a :class:`~rik.schemas.joints.Spring`) and
says when they are unphysical (a damper that pushes, a magnet that repels).

The families follow ../shared/notes/research-sysid.md, section 2. Not in the library, and why:

- end stops and bumpers: they act at the range's ends only; samples there are excluded from the fit and the
  range is reported instead;
- gas struts (lift-up flaps): their torque depends on the strut's mounting geometry, which joint data alone
  cannot give; a strut shows up as a spring plus direction-dependent friction;
- push-to-open latches: a one-shot mechanism, not a force law of the joint;
- friction proportional to the applied force (racking): the force is on both sides of the equation, which
  biases any fit (errors in variables); friction growing with extension (``load_friction``) is in.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from rik.joints.laws import effect_force
from rik.schemas import joints as j
from rik.schemas.joints import JointEffect, JointType, Spring

Effect = JointEffect | Spring
"""An effect of the library (:data:`rik.joints.kinds.KINDS`) or the closer spring."""


@dataclass(frozen=True)
class Motion:
    """Samples of a joint's motion the regressors are evaluated at (SI, equal-length arrays)."""

    q: np.ndarray
    """Position, m or rad."""
    qd: np.ndarray
    """Velocity, m/s or rad/s."""


@dataclass(frozen=True)
class Baseline:
    """The baseline joint model: inertia, viscous damping and Coulomb friction."""

    inertia: float
    """Moving mass (slide, kg) or moment of inertia about the axis (hinge, kg·m²): body plus armature."""
    damping: float
    """N·s/m or N·m·s/rad."""
    friction: float
    """N or N·m."""
    damping_se: float = 0.0
    """Standard error of ``damping`` (inflated for the residuals' correlation), N·s/m or N·m·s/rad."""


@dataclass(frozen=True)
class Family:
    """One effect of the library: its regressors, hyperparameter grid and physical reading."""

    kind: str
    """The effect's ``kind`` (as in :mod:`rik.schemas.joints`), or ``spring``."""
    title: str
    """Short human name."""
    coefficients: tuple[str, ...]
    """Names of the linear coefficients θ (tilt's ``sine`` only for hinges)."""
    features: Callable[[Motion, float | None, JointType], np.ndarray]
    """(motion, h, joint) → regressors, shape (n, len(coefficients))."""
    reading: Callable[[np.ndarray, float | None, Baseline, JointType], tuple[Effect, Baseline, str | None]]
    """(θ, h, baseline, joint) → (effect, baseline adjusted by the effect, why unphysical or None)."""
    hyper: str | None = None
    """Name of the hyperparameter (``zone``, ``decay``, ``stribeck_velocity``), None if the family has none."""
    grid: Callable[[JointType], np.ndarray] | None = None
    """Hyperparameter values to search, SI."""
    cause: str = ""
    """What the effect is, as a clause for the report's sentence."""


# --------------------------------------------------------------------------------------------------- helpers

def _scale(joint: JointType, slide: float, hinge: float) -> float:
    return slide if joint is JointType.slide else hinge


def _log_grid(lo: float, hi: float, n: int = 32) -> np.ndarray:
    return np.geomspace(lo, hi, n)


def _given(hyper: float | None) -> float:
    """The hyperparameter of a family that has one (its grid gives it)."""
    if hyper is None:
        raise ValueError("this effect family needs its hyperparameter")
    return float(hyper)


def _negative(name: str, value: float, unit: str) -> str | None:
    return f"{name} {value:.3g} {unit} is negative" if value < 0 else None


_FORCE = {JointType.slide: "N", JointType.hinge: "N·m"}

DAMPING_TOLERANCE = {JointType.slide: 0.2, JointType.hinge: 0.02}
"""How far below 0 a fitted damping may come out before it counts as unphysical (noise around a joint with
almost no damping), N·s/m or N·m·s/rad: at least this, or 3 standard errors of the fitted damping."""


def _unphysical_baseline(base: Baseline, joint: JointType) -> str | None:
    if base.damping < -max(DAMPING_TOLERANCE[joint], 3.0 * base.damping_se):
        unit = "N·s/m" if joint is JointType.slide else "N·m·s/rad"
        return f"the viscous damping comes out negative ({base.damping:.3g} {unit})"
    if base.inertia <= 0:
        return f"the inertia comes out non-positive ({base.inertia:.3g})"
    if base.friction < 0:
        return f"the Coulomb friction comes out negative ({base.friction:.3g} {_FORCE[joint]})"
    return None


def _first(*problems: str | None) -> str | None:
    return next((p for p in problems if p), None)


# ------------------------------------------------------------------------------------------------ families

UnitEffects = Callable[[float | None, JointType], tuple[j.JointEffect, ...]]
"""(h, joint) → the family's effect with each linear coefficient set to 1 in turn (the others 0)."""


def _law_features(unit: UnitEffects) -> Callable[[Motion, float | None, JointType], np.ndarray]:
    """Regressors from the library's one force law (:func:`rik.joints.laws.effect_force`, what rik's simulator
    applies): the resistance of each unit effect, i.e. minus its force, so a fitted effect is exactly the law the
    extended joint is simulated with."""

    def features(m: Motion, h: float | None, joint: JointType) -> np.ndarray:
        return -np.column_stack([effect_force(e, m.q, m.qd, joint) for e in unit(h, joint)])

    return features


_UNITS = {
    "breakaway": {JointType.slide: "N", JointType.hinge: "N·m"},
    "damping": {JointType.slide: "N·s/m", JointType.hinge: "N·m·s/rad"},
    "stiffness": {JointType.slide: "N/m", JointType.hinge: "N·m/rad"},
    "coefficient": {JointType.slide: "N·s²/m²", JointType.hinge: "N·m·s²/rad²"},
    "per_extension": {JointType.slide: "N/m", JointType.hinge: "N·m/rad"},
}
"""Units of the single coefficients read by :func:`_coefficient_reading`."""


def _coefficient_reading(build: Callable[[float, float | None], Effect], name: str, field: str):
    """The reading of a family with one coefficient that must not be negative: ``build(value, h)`` makes the
    effect (the value clipped at 0), ``name`` says what it is in the message when it comes out negative."""

    def reading(theta: np.ndarray, h: float | None, base: Baseline, joint: JointType):
        value = float(theta[0])
        return build(max(value, 0.0), h), base, _first(_negative(name, value, _UNITS[field][joint]),
                                                        _unphysical_baseline(base, joint))

    return reading


def _magnet_reading(theta: np.ndarray, decay: float | None, base: Baseline, joint: JointType):
    effect = j.MagneticCatch(force=max(float(theta[0]), 0.0), decay=_given(decay))
    problem = f"the catch repels ({float(theta[0]):.3g} {_FORCE[joint]})" if theta[0] < 0 else None
    return effect, base, _first(problem, _unphysical_baseline(base, joint))


def _tilt_units(h: float | None, joint: JointType) -> tuple[j.JointEffect, ...]:
    if joint is JointType.slide:
        return (j.Tilt(force=1.0),)
    return j.Tilt(force=1.0), j.Tilt(force=0.0, sine=1.0)


def _tilt_reading(theta: np.ndarray, h: float | None, base: Baseline, joint: JointType):
    effect = j.Tilt(force=float(theta[0]), sine=float(theta[1]) if joint is JointType.hinge else 0.0)
    return effect, base, _unphysical_baseline(base, joint)


def _direction_reading(theta: np.ndarray, h: float | None, base: Baseline, joint: JointType):
    extra = float(theta[0])
    if extra >= 0:
        return j.DirectionFriction(extra=extra, direction="closing"), base, _unphysical_baseline(base, joint)
    # more friction opening than closing: the closing level is the baseline's, the opening one adds |extra|
    adjusted = replace(base, friction=base.friction + extra)
    problem = _unphysical_baseline(adjusted, joint)
    return j.DirectionFriction(extra=-extra, direction="opening"), adjusted, problem


def _spring_features(m: Motion, h: float | None, joint: JointType) -> np.ndarray:
    """The closer spring is MuJoCo's own joint stiffness, ``-k (q - reference)``: resistance ``k q - k reference``."""
    return np.column_stack([m.q, -np.ones_like(m.q)])


def _spring_reading(theta: np.ndarray, h: float | None, base: Baseline, joint: JointType):
    stiffness, preload = float(theta[0]), float(theta[1])
    unit = "N/m" if joint is JointType.slide else "N·m/rad"
    reference = preload / stiffness if stiffness > 0 else 0.0
    effect = Spring(stiffness=max(stiffness, 0.0), reference=reference)
    problem = f"the spring pushes the front open (stiffness {stiffness:.3g} {unit})" if stiffness < 0 else None
    return effect, base, _first(problem, _unphysical_baseline(base, joint))


FAMILIES: tuple[Family, ...] = (
    Family("stiction", "stiction (Stribeck)", ("breakaway",),
           _law_features(lambda h, jt: (j.Stiction(breakaway=1.0, stribeck_velocity=h),)),
           _coefficient_reading(lambda v, h: j.Stiction(breakaway=v, stribeck_velocity=_given(h)),
                                "the breakaway friction", "breakaway"),
           hyper="stribeck_velocity", grid=lambda jt: _log_grid(_scale(jt, 0.002, 0.01), _scale(jt, 0.15, 1.0)),
           cause="friction that is higher at low speed than when sliding (stiction, fading by the Stribeck speed)"),
    Family("soft_close", "soft-close damper", ("damping",),
           _law_features(lambda h, jt: (j.SoftClose(zone=h, damping=1.0),)),
           _coefficient_reading(lambda v, h: j.SoftClose(zone=_given(h), damping=v), "the soft-close damping",
                                "damping"),
           hyper="zone", grid=lambda jt: _log_grid(_scale(jt, 0.005, 0.01), _scale(jt, 0.2, 0.8)),
           cause="a soft-close damper: damping that acts only near the closed end and only while closing"),
    Family("self_close", "self-closing spring", ("stiffness",),
           _law_features(lambda h, jt: (j.SelfClose(zone=h, stiffness=1.0),)),
           _coefficient_reading(lambda v, h: j.SelfClose(zone=_given(h), stiffness=v), "the pull-in stiffness",
                                "stiffness"),
           hyper="zone", grid=lambda jt: _log_grid(_scale(jt, 0.003, 0.01), _scale(jt, 0.2, 0.8)),
           cause="a self-closing spring that pulls the front shut over its last stretch"),
    Family("magnetic_catch", "magnetic catch", ("force",),
           _law_features(lambda h, jt: (j.MagneticCatch(force=1.0, decay=h),)), _magnet_reading,
           hyper="decay", grid=lambda jt: _log_grid(_scale(jt, 0.0005, 0.002), _scale(jt, 0.05, 0.3)),
           cause="a magnetic catch: a pull towards closed that fades within millimetres of it"),
    Family("tilt", "tilt (gravity)", ("force", "sine"), _law_features(_tilt_units), _tilt_reading,
           cause="gravity along the joint: a tilted runner or an out-of-plumb hinge"),
    Family("direction_friction", "direction-dependent friction", ("extra",),
           _law_features(lambda h, jt: (j.DirectionFriction(extra=1.0, direction="closing"),)),
           _direction_reading, cause="friction that is higher in one direction of motion than the other"),
    Family("quadratic_damping", "quadratic damping", ("coefficient",),
           _law_features(lambda h, jt: (j.QuadraticDamping(coefficient=1.0),)),
           _coefficient_reading(lambda v, h: j.QuadraticDamping(coefficient=v), "the quadratic damping",
                                "coefficient"),
           cause="damping that grows with the square of speed (fluid drag)"),
    Family("load_friction", "friction growing with extension", ("per_extension",),
           _law_features(lambda h, jt: (j.LoadFriction(per_extension=1.0),)),
           _coefficient_reading(lambda v, h: j.LoadFriction(per_extension=v), "the friction per extension",
                                "per_extension"),
           cause="friction that grows the further the front is open (a cantilevered load)"),
    Family("spring", "closer spring", ("stiffness", "preload"), _spring_features, _spring_reading,
           cause="a spring that pulls the front closed over its whole travel"),
)
"""The library, in the order ties are broken (simplest and most common first is not implied)."""

FAMILY = {f.kind: f for f in FAMILIES}


def baseline_features(q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
    """The baseline's regressors (acceleration, velocity, sign of velocity), shape (n, 3)."""
    return np.column_stack([qdd, qd, np.sign(qd)])


INDISTINGUISHABLE: dict[frozenset[str], str] = {
    frozenset({"tilt", "direction_friction"}): (
        "on moving samples a constant force and friction that differs by direction are the same equation; hold "
        "the front still at a few positions and let go (a tilt needs a holding force or makes it drift, "
        "direction-dependent friction does neither), or measure the breakaway force from rest in both "
        "directions"),
    frozenset({"magnetic_catch", "self_close"}): (
        "both pull the front shut near closed; release it from rest at several distances from closed (a magnet "
        "pulls only within millimetres, a self-closing spring over its whole zone), or pull it open slowly from "
        "closed while measuring the force"),
    frozenset({"tilt", "spring"}): (
        "a constant force and a stiff spring look alike over a short stroke; move the front over its whole "
        "travel and hold it at both ends"),
    frozenset({"stiction", "quadratic_damping"}): (
        "both change the force at low against high speed; drag the front at several constant speeds, "
        "including very slow ones"),
}
"""Pairs of effects that can explain the same data, and the experiment that would tell them apart."""

MAGNET_AMBIGUITY = ("the magnet's pull at contact and its decay length trade off against each other (only the "
                    "impulse near closed is well determined); release the front from rest a few millimetres open, "
                    "or pull it slowly from closed, to pin down the shape")
