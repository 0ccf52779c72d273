"""Ground-truth generator for ``rik sysid``: "measured" trials of a furniture joint simulated from a hidden truth.

A :class:`GroundTruth` is a 1-DOF joint (slide: m, N, kg; hinge: rad, N·m, kg·m²) with inertia, viscous damping,
Coulomb friction, a range and up to two effects beyond them (each a :data:`~rik.schemas.joints.JointEffect` or a
closer :class:`~rik.schemas.joints.Spring`, of different kinds; two act together, their forces and extra frictions
add up, e.g. the damper and the pull-in spring of a soft-close runner). Its parameters are in the library's form,
so a fit can be compared with them, but the force the simulation applies has a slightly different shape from the
library law (no "inverse crime"):

==================  ========================================================================================
effect              truth's force law (library parameters keep their meaning)
==================  ========================================================================================
stiction            extra friction ``breakaway * exp(-(|v|/stribeck_velocity)^1.5)`` (library: exponent 2)
soft_close          ``-damping * g(q) * v_ref * (|v|/v_ref)^1.1 * sign(v)`` (only while closing), g a tanh
                    edge at ``zone`` about 10 % of the zone wide; equals ``-damping * v`` at ``|v| = v_ref``
                    (0.1 m/s or 0.25 rad/s) inside the zone
self_close          ``-stiffness * s * softplus((zone - q) / s)``, s = 5 % of the zone: the ramp, rounded at
                    its edge; the pull at closed is ``stiffness * zone``
magnetic_catch      ``-force * exp(-q / (decay * k))``, k so that its impulse over [0, upper] equals the
                    library law's ``-force / (1 + q/decay)^2``; same pull at contact
tilt, spring        exact
direction_friction  extra friction ``extra * (1 + tanh(±v / v_eps)) / 2`` (v_eps 5 mm/s or 0.0125 rad/s);
                    at rest the direction the hand pushes in (see :func:`direction_share`)
quadratic_damping   ``-coefficient * (v|v| + 0.1 v^3 / v_ref)`` (v_ref 0.3 m/s or 1 rad/s)
load_friction       extra friction ``per_extension * q_mid * (q / q_mid)^1.1``, q_mid = upper / 2
==================  ========================================================================================

Friction-type forces (Coulomb, stiction, direction and load friction) stay a MuJoCo constraint: the Coulomb part
is the joint's ``frictionloss`` and the extra friction is written into ``model.dof_frictionloss`` every step, with
``solimpfriction`` d0 = 0.9999 so that a sub-threshold load does not creep (< 0.01 mm/s). The other effects are
``data.qfrc_applied``. Effects are evaluated at ``max(q, 0)``.

The joint is driven by a human-like impedance "hand", ``kp (target - q) + kd (target_vel - v)`` clipped to
60 N or 15 N·m, tracking an :class:`ExcitationPlan`: strokes of varied speed (minimum-jerk), a slow
constant-speed stroke, holds, a stroke into the closed end, one near the far stop, a push towards closed let go
at 15-30 mm (3-9°) from closed and a release from rest at mid-range (hand force exactly 0). The hand force is the
measured force. :func:`measure` samples it with noise, optional quantisation and a delay: the position sample at
time t is the true position at t - ``delay_s``, i.e. the position is recorded ``delay_s`` later than the force
(positive delay in :mod:`rik.sysid.preprocess`).
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal, overload

import numpy as np

from rik.errors import RikError
from rik.joints.kinds import KINDS, SCHEMAS
from rik.paths import write_atomic
from rik.schemas.joints import (
    DirectionFriction,
    JointEffect,
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
from rik.schemas.trajectory import TrialColumns, TrialMeta, TrialUnits
from rik.sysid.trials import Trial

EFFECT_KINDS: tuple[str, ...] = (*KINDS, "spring")
"""Effect kinds :func:`random_truth` can draw: the library's (:data:`rik.joints.kinds.KINDS`) and ``spring``, its
closer :class:`Spring`."""
JOINT_KINDS = {JointType.slide: EFFECT_KINDS, JointType.hinge: EFFECT_KINDS}
"""Effect kinds valid per joint type (every kind has a drawer and a door form)."""
TRUTH_FILE = "truth.json"
"""Name of the ground-truth file :func:`write_trials` writes next to the trial CSVs."""
SOURCE = "simulated"
"""``TrialMeta.source`` of simulated trials."""

GRAVITY = 9.81
"""m/s²."""
SOLIMP_FRICTION = (0.9999, 0.9999, 0.001, 0.5, 2.0)
"""``solimpfriction`` of the truth's joint: nearly hard friction, so that a held joint does not creep."""
SOLREF_LIMIT = (0.005, 1.0)
"""``solreflimit``: a firm end stop (about 1.5 mm penetration at 0.3 m/s)."""

# Per-joint constants of the shapes, the hand and the sensors: slide (SI m, N), hinge (rad, N·m).
SOFT_CLOSE_VREF = {JointType.slide: 0.1, JointType.hinge: 0.25}
"""Speed at which the truth's soft-close force equals ``damping * v``: m/s or rad/s."""
SOFT_CLOSE_EXPONENT = 1.1
EDGE_FRACTION = 0.05
"""tanh half-width (soft-close) and softplus width (self-close) as a fraction of the zone."""
STRIBECK_EXPONENT = 1.5
DIRECTION_VEPS = {JointType.slide: 0.005, JointType.hinge: 0.0125}
"""Regularisation speed of the direction friction: m/s or rad/s."""
DIRECTION_FEPS = 0.01
"""Width of the direction friction's step in the hand force at rest, as a fraction of the total friction."""
CUBIC_VREF = {JointType.slide: 0.3, JointType.hinge: 1.0}
"""Speed at which the cubic damping term is 10 % of the quadratic one: m/s or rad/s."""
CUBIC_FRACTION = 0.1
LOAD_EXPONENT = 1.1

HAND_OMEGA = math.sqrt(400.0 / 6.0)
"""Natural frequency of the hand on the truth's inertia, rad/s (kp 400 N/m on 6 kg)."""
HAND_ZETA = 0.6
"""Damping ratio of the hand (kd 59 N·s/m on 6 kg): settled before a release from rest."""
HAND_DEADBAND = {JointType.slide: 0.01, JointType.hinge: 0.03}
"""kp is at least the static friction (Coulomb plus the effect's extra friction at rest) over this error, and
at least that friction plus the largest effect force at rest over the outer half of the range over twice this
error: m or rad."""
HAND_MAX = {JointType.slide: 60.0, JointType.hinge: 15.0}
"""Largest hand force, N or N·m."""
POSITION_NOISE = {JointType.slide: 2e-4, JointType.hinge: math.radians(0.2)}
"""Default position noise (standard deviation): m (0.2 mm) or rad (0.2°)."""
FORCE_NOISE = {JointType.slide: 0.3, JointType.hinge: 0.03}
"""Default force noise (standard deviation): N or N·m."""


@dataclass(frozen=True)
class _Excite:
    """Excitation constants of a joint type (m, m/s or rad, rad/s)."""

    speed: tuple[float, float]
    """Peak speeds of ordinary strokes."""
    block_speed: tuple[float, float]
    """Peak speeds of the strokes inside the required blocks (faster, to fit the trial)."""
    slow: tuple[float, float]
    """Speed of the slow constant-speed stroke."""
    throw: tuple[float, float]
    """Peak speed of the push towards closed that is let go."""
    near_closed: tuple[float, float]
    """Distance from closed at which that push is let go."""
    push: tuple[float, float]
    """How far beyond a stop the target goes when the front is pushed against it and held there (the hand
    presses with about kp times this)."""
    creep: tuple[float, float]
    """Speed of the creep from rest at closed (a slow constant-speed pull with a stiff hand, as a robot or a
    force gauge would make)."""
    creep_length: tuple[float, float]
    """Length of that creep."""


EXCITE = {
    JointType.slide: _Excite(speed=(0.05, 0.5), block_speed=(0.1, 0.5), slow=(0.01, 0.02), throw=(0.12, 0.3),
                             near_closed=(0.015, 0.03), push=(0.01, 0.025), creep=(0.004, 0.006),
                             creep_length=(0.006, 0.01)),
    JointType.hinge: _Excite(speed=(0.2, 2.0), block_speed=(0.4, 2.0), slow=(0.025, 0.05), throw=(0.5, 1.2),
                             near_closed=(0.05, 0.15), push=(math.radians(3.0), math.radians(8.0)),
                             creep=(0.02, 0.03), creep_length=(0.025, 0.04)),
}
CREEP_STIFFNESS = 10.0
"""The hand's stiffness during a creep, as a multiple of its usual kp (its damping scales with the square root):
the force builds at about 10·kp·speed until the front breaks away."""
MOVE_TIME = (0.25, 2.0)
"""Shortest and longest minimum-jerk stroke, s (the peak speed is raised where a stroke would take longer)."""
BLOCK_MOVE_TIME = 1.2
"""Longest stroke inside a required block, s."""
SLOW_RAMP = 0.2
"""Acceleration time of the slow stroke, s."""

# ------------------------------------------------------------------------------------------ parameter ranges

Range = tuple[float, float]
BASE_RANGES: dict[JointType, dict[str, Range]] = {
    JointType.slide: {"mass": (2.0, 15.0), "damping": (1.0, 10.0), "frictionloss": (1.0, 8.0),
                      "upper": (0.35, 0.5)},
    JointType.hinge: {"mass": (0.2, 2.0), "damping": (0.05, 0.5), "frictionloss": (0.1, 1.0),
                      "upper": (1.5, 1.9)},
}
"""Ranges of :func:`random_truth`'s base parameters: mass kg or kg·m², damping N·s/m or N·m·s/rad, frictionloss
N or N·m, upper (the range's upper end; the lower is 0) m or rad. ``mass=`` may be given outside them."""

EFFECT_RANGES: dict[JointType, dict[str, dict[str, Range]]] = {
    JointType.slide: {
        "stiction": {"frictionloss": (3.0, 8.0), "ratio": (1.4, 2.0), "breakaway": (1.2, 8.0),
                     "stribeck_velocity": (0.01, 0.03)},
        "soft_close": {"zone": (0.03, 0.06), "damping": (50.0, 150.0)},
        "self_close": {"zone": (0.02, 0.04), "pull": (5.0, 15.0)},
        "magnetic_catch": {"force": (5.0, 30.0), "decay": (0.002, 0.008)},
        "tilt": {"abs_force": (2.0, 7.8), "angle_deg": (1.0, 6.0), "over_friction": (1.2, 2.5)},
        "direction_friction": {"extra": (1.5, 4.0)},
        "quadratic_damping": {"coefficient": (15.0, 40.0)},
        "load_friction": {"per_extension": (8.0, 25.0)},
        "spring": {"stiffness": (10.0, 40.0), "reference": (-0.1, 0.0)},
    },
    JointType.hinge: {
        "stiction": {"frictionloss": (0.3, 1.0), "ratio": (1.4, 2.0), "breakaway": (0.12, 1.0),
                     "stribeck_velocity": (0.03, 0.08)},
        "soft_close": {"zone": (math.radians(10), math.radians(25)), "damping": (1.0, 3.0)},
        "self_close": {"zone": (math.radians(20), math.radians(30)), "pull": (0.5, 2.0)},
        "magnetic_catch": {"force": (1.5, 6.0), "decay": (0.005, 0.02)},
        "tilt": {"amplitude": (0.4, 1.5), "abs_force": (0.12, 1.5), "abs_sine": (0.12, 1.5),
                 "over_friction": (1.2, 2.5)},
        "direction_friction": {"extra": (0.15, 0.5)},
        "quadratic_damping": {"coefficient": (0.2, 0.6)},
        "load_friction": {"per_extension": (0.2, 0.6)},
        "spring": {"stiffness": (0.5, 2.0), "reference": (-0.3, 0.0)},
    },
}
"""Ranges of the effect parameters :func:`random_truth` draws, per joint and kind (library units). Derived
quantities (see :func:`truth_parameters`): stiction ``ratio`` = static / kinetic friction and its own
``frictionloss`` range; self-close ``pull`` = stiffness * zone; tilt ``abs_force`` = |force|, ``angle_deg`` the
runner's tilt (slide), ``amplitude`` = hypot(force, sine) (hinge, with |force| and |sine| each at least 30 % of
it) and ``over_friction`` = the largest tilt force over the range / frictionloss (> 1: a released front drifts,
which tells tilt from direction friction)."""


# -------------------------------------------------------------------------------------------- ground truth

Effect = JointEffect | Spring


@dataclass(frozen=True)
class GroundTruth:
    """The hidden joint behind simulated trials; SI units of the joint (see the module docstring)."""

    joint: JointType
    mass: float
    """Total moving inertia: kg (slide) or kg·m² (hinge)."""
    damping: float
    """Viscous damping, N·s/m or N·m·s/rad."""
    frictionloss: float
    """Coulomb friction, N or N·m."""
    range: tuple[float, float]
    """(lower, upper) joint limits, m or rad; lower ≤ 0 < upper."""
    effect: Effect | None = None
    """The (first) effect beyond the baseline, in library form (the simulated shape differs slightly)."""
    second: Effect | None = None
    """A second effect acting together with ``effect``, e.g. the pull-in spring of a soft-close runner; of
    another kind than ``effect``, and only with one."""

    def __post_init__(self) -> None:
        object.__setattr__(self, "joint", _joint(self.joint))
        for name, low in (("mass", None), ("damping", 0.0), ("frictionloss", 0.0)):
            value = getattr(self, name)
            ok = isinstance(value, (int, float)) and math.isfinite(value) and (value > 0 if low is None else
                                                                                value >= low)
            if not ok:
                raise RikError(f"GroundTruth {name} must be a finite number {'> 0' if low is None else '≥ 0'}, "
                               f"got {value!r}")
            object.__setattr__(self, name, float(value))
        try:
            lower, upper = (float(x) for x in self.range)
        except (TypeError, ValueError):
            raise RikError(f"GroundTruth range must be (lower, upper), got {self.range!r}") from None
        if not (math.isfinite(lower) and math.isfinite(upper) and lower <= 0.0 < upper):
            raise RikError(f"GroundTruth range must be (lower, upper) with lower ≤ 0 < upper, got {self.range!r}")
        object.__setattr__(self, "range", (lower, upper))
        _check_effect("effect", self.effect, self.joint, upper)
        _check_effect("second", self.second, self.joint, upper)
        if self.second is not None:
            if self.effect is None:
                raise RikError(f"GroundTruth second ({_kind(self.second)}) needs a first effect: give it as effect "
                               "(second only acts together with effect)")
            if _kind(self.second) == _kind(self.effect):
                raise RikError(f"GroundTruth second is a {_kind(self.second)}, the same kind as effect; the two "
                               "effects must be of different kinds")

    @property
    def kind(self) -> str | None:
        """The (first) effect's kind (``spring`` for a :class:`Spring`), or None."""
        return _kind(self.effect)

    @property
    def effects(self) -> tuple[Effect, ...]:
        """The effects present, in order (``effect``, then ``second``)."""
        return tuple(e for e in (self.effect, self.second) if e is not None)

    @property
    def kinds(self) -> tuple[str, ...]:
        """The kinds of the effects present, in order (empty for none)."""
        return tuple(_kind(e) or "" for e in self.effects)

    def to_json(self) -> dict[str, Any]:
        """A JSON-ready dict; each effect carries its ``kind`` (``spring`` for a Spring). ``second`` is written
        only when there is one (so a one-effect truth's file is as before)."""
        out = {"joint": self.joint.value, "mass": self.mass, "damping": self.damping,
               "frictionloss": self.frictionloss, "range": list(self.range), "effect": _effect_json(self.effect)}
        if self.second is not None:
            out["second"] = _effect_json(self.second)
        return out

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> GroundTruth:
        """The inverse of :meth:`to_json`; ``effect`` and ``second`` may be absent (None; files written before
        ``second`` existed load). A malformed dict is a :class:`RikError`."""
        if not isinstance(data, dict):
            raise RikError(f"ground truth must be a JSON object, got {type(data).__name__}")
        keys = {"joint", "mass", "damping", "frictionloss", "range", "effect", "second"}
        if missing := sorted(keys - {"effect", "second"} - set(data)):
            raise RikError(f"ground truth lacks {', '.join(missing)}")
        if extra := sorted(set(data) - keys):
            raise RikError(f"ground truth has unknown field(s) {', '.join(extra)}")
        return cls(joint=data["joint"], mass=data["mass"], damping=data["damping"],
                   frictionloss=data["frictionloss"], range=data["range"],
                   effect=_effect_from_json("effect", data.get("effect")),
                   second=_effect_from_json("second", data.get("second")))


_EFFECT_TYPES: tuple[type, ...] = (Spring, *SCHEMAS)


def _check_effect(name: str, effect: object, joint: JointType, upper: float) -> None:
    """Refuse an effect (field ``name`` of a :class:`GroundTruth`) that is not one or does not fit the joint."""
    if effect is None:
        return
    if not isinstance(effect, _EFFECT_TYPES):
        raise RikError(f"GroundTruth {name} must be a JointEffect, a Spring or None, got {type(effect).__name__}")
    if isinstance(effect, Tilt) and joint is JointType.slide and effect.sine != 0.0:
        raise RikError(f"GroundTruth {name}: a slide's tilt has no sine term (got sine={effect.sine}); "
                       "sine is for hinges")
    zone = getattr(effect, "zone", None)
    if zone is not None and zone >= upper:
        raise RikError(f"GroundTruth {name} zone {zone:g} must be inside the range (upper {upper:g})")


def _effect_json(effect: Effect | None) -> dict[str, Any] | None:
    if effect is None:
        return None
    out = effect.model_dump(mode="json")
    out.setdefault("kind", "spring")
    return out


def _effect_from_json(name: str, raw: object) -> Effect | None:
    from pydantic import TypeAdapter, ValidationError

    if raw is None:
        return None
    try:
        if isinstance(raw, dict) and raw.get("kind") == "spring":
            return Spring(**{k: v for k, v in raw.items() if k != "kind"})
        return TypeAdapter(JointEffect).validate_python(raw)
    except (ValidationError, TypeError) as exc:
        first = str(exc).splitlines()
        raise RikError(f"ground truth {name} is malformed: {' '.join(first[:3])}") from None


def _kind(effect: Effect | None) -> str | None:
    if effect is None:
        return None
    return "spring" if isinstance(effect, Spring) else effect.kind


def _joint(joint: JointType | str) -> JointType:
    try:
        return JointType(joint)
    except ValueError:
        raise RikError(f"joint '{joint}' is not a joint type; use 'slide' or 'hinge'") from None


def read_truth(path: str | Path) -> GroundTruth:
    """The :class:`GroundTruth` in ``path``: a ``truth.json`` file or a folder holding one."""
    path = Path(path)
    if path.is_dir():
        path = path / TRUTH_FILE
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, json.JSONDecodeError) as exc:
        raise RikError(f"{path}: cannot read the ground truth ({str(exc).splitlines()[0]})") from None
    return GroundTruth.from_json(data)


# ----------------------------------------------------------------------------------------- random truths

def _uniform(rng: np.random.Generator, bounds: Range) -> float:
    return float(rng.uniform(*bounds))


def _log_uniform(rng: np.random.Generator, bounds: Range) -> float:
    return float(math.exp(rng.uniform(math.log(bounds[0]), math.log(bounds[1]))))


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
            while True:
                phase = float(rng.uniform(0.0, 2 * math.pi))
                if min(abs(math.cos(phase)), abs(math.sin(phase))) >= 0.3:
                    break
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


# ----------------------------------------------------------------------------------------- force laws

def magnet_scale(decay: float, upper: float) -> float:
    """k of the truth's magnet ``exp(-q / (decay k))``: its impulse over [0, ``upper``] equals that of
    ``1 / (1 + q/decay)^2`` (both per unit force; m or rad)."""
    target = upper / (upper + decay)  # library impulse / decay
    k = target
    for _ in range(50):
        k_new = target / (1.0 - math.exp(-upper / (decay * k)))
        if abs(k_new - k) < 1e-15:
            break
        k = k_new
    return k


Law = Callable[[Any, Any], Any]
"""(q, v) → a force: floats or broadcast arrays alike (m or rad, m/s or rad/s → N or N·m)."""
FrictionLaw = Callable[[Any, Any, Any], Any]
"""(q, v, hand force) → an extra friction level (≥ 0), floats or arrays alike."""


@overload
def direction_share(v: float, load: float, sign: float, v_eps: float, f_eps: float) -> float: ...
@overload
def direction_share(v: np.ndarray, load: np.ndarray | float, sign: float, v_eps: float, f_eps: float) -> np.ndarray: ...
def direction_share(v: np.ndarray | float, load: np.ndarray | float, sign: float, v_eps: float,
                    f_eps: float) -> np.ndarray | float:
    """Share (0 to 1) of the direction friction that acts: ``(1 + tanh(sign v / v_eps)) / 2`` when moving,
    blended (weight ``exp(-(v/v_eps)^2)``) into a sharp step in the direction of the ``load`` (the hand force)
    at rest, so that a front at rest has the static friction of the direction it is pushed in and never creeps."""
    xp = np if isinstance(v, np.ndarray) or isinstance(load, np.ndarray) else math
    moving = 0.5 * (1.0 + xp.tanh(sign * v / v_eps))
    resting = 0.5 * (1.0 + xp.tanh(sign * load / f_eps))
    w = xp.exp(-((v / v_eps) ** 2))
    return (1.0 - w) * moving + w * resting


class _Scalar:
    """The functions the truth's laws use (:func:`_law_of`), on Python floats: what numpy's ufuncs do on arrays,
    several times faster for the step loop of :func:`simulate`."""

    abs = staticmethod(abs)
    maximum = staticmethod(max)
    exp = staticmethod(math.exp)
    log1p = staticmethod(math.log1p)
    tanh = staticmethod(math.tanh)
    cos = staticmethod(math.cos)
    sin = staticmethod(math.sin)

    @staticmethod
    def sign(x: float) -> float:
        return 1.0 if x > 0.0 else -1.0 if x < 0.0 else 0.0

    @staticmethod
    def where(condition: bool, a: float, b: float) -> float:
        return a if condition else b


def _scalar_laws(truth: GroundTruth) -> tuple[Law | None, FrictionLaw | None]:
    """(applied force law of (q, v), extra friction law of (q, v, hand force)) of the truth's effects as scalar
    functions, for the step loop: the sum over the effects; None where no effect has such a part."""
    applied: Law | None = None
    friction: FrictionLaw | None = None
    for e in truth.effects:
        a, f = _law_of(e, truth, _Scalar)
        if a is not None:
            applied = a if applied is None else _add_laws(applied, a)
        if f is not None:
            friction = f if friction is None else _add_friction_laws(friction, f)
    return applied, friction


def _add_laws(a: Law, b: Law) -> Law:
    return lambda q, v: a(q, v) + b(q, v)


def _add_friction_laws(a: FrictionLaw, b: FrictionLaw) -> FrictionLaw:
    return lambda q, v, f: a(q, v, f) + b(q, v, f)


def _law_of(e: Effect, truth: GroundTruth, xp: Any) -> tuple[Law | None, FrictionLaw | None]:
    """(applied force law of (q, v), extra friction law (≥ 0) of (q, v, hand force)) of one effect ``e`` of
    ``truth`` (the shapes of the module docstring), None for a part it lacks. The one implementation of each
    truth law: ``xp`` is :class:`_Scalar` for floats (:func:`_scalar_laws`) or numpy for arrays
    (:func:`effect_laws`)."""
    joint, upper = truth.joint, truth.range[1]
    if isinstance(e, Stiction):
        b, vs, p = e.breakaway, e.stribeck_velocity, STRIBECK_EXPONENT
        return None, lambda q, v, f: b * xp.exp(-((xp.abs(v) / vs) ** p))
    if isinstance(e, DirectionFriction):
        extra, s, eps = e.extra, (1.0 if e.direction == "opening" else -1.0), DIRECTION_VEPS[joint]
        f_eps = DIRECTION_FEPS * (truth.frictionloss + extra)
        return None, lambda q, v, f: extra * direction_share(v, f, s, eps, f_eps)
    if isinstance(e, LoadFriction):
        mid = 0.5 * upper
        c = e.per_extension * mid
        return None, lambda q, v, f: c * (xp.maximum(q, 0.0) / mid) ** LOAD_EXPONENT
    if isinstance(e, SoftClose):
        c, zone, w, vref = e.damping, e.zone, EDGE_FRACTION * e.zone, SOFT_CLOSE_VREF[joint]
        one_way, n = e.closing_only, SOFT_CLOSE_EXPONENT

        def soft_close(q: Any, v: Any) -> Any:
            gate = 0.5 * (1.0 - xp.tanh((xp.maximum(q, 0.0) - zone) / w))
            force = -xp.sign(v) * (c * gate * vref * (xp.abs(v) / vref) ** n)
            return xp.where(v < 0.0, force, 0.0) if one_way else force

        return soft_close, None
    if isinstance(e, SelfClose):
        k, zone, s = e.stiffness, e.zone, EDGE_FRACTION * e.zone

        def self_close(q: Any, v: Any) -> Any:
            x = (zone - xp.maximum(q, 0.0)) / s  # softplus(x), rounding the ramp's edge
            return -k * s * (xp.maximum(x, 0.0) + xp.log1p(xp.exp(-xp.abs(x))))

        return self_close, None
    if isinstance(e, MagneticCatch):
        a, length = e.force, e.decay * magnet_scale(e.decay, upper)
        return (lambda q, v: -a * xp.exp(-xp.maximum(q, 0.0) / length)), None
    if isinstance(e, Tilt):
        if joint is JointType.slide:
            f = e.force
            return (lambda q, v: f + 0.0 * q), None
        fc, fs = e.force, e.sine
        return (lambda q, v: fc * xp.cos(q) + fs * xp.sin(q)), None
    if isinstance(e, QuadraticDamping):
        c, c3 = e.coefficient, e.coefficient * CUBIC_FRACTION / CUBIC_VREF[joint]
        return (lambda q, v: -(c * v * xp.abs(v) + c3 * v * v * v)), None
    if isinstance(e, Spring):
        k, ref = e.stiffness, e.reference
        return (lambda q, v: -k * (q - ref)), None
    raise AssertionError(f"no law for {type(e).__name__}")  # pragma: no cover


def effect_laws(truth: GroundTruth, q: np.ndarray, v: np.ndarray,
                load: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(applied force, extra friction level) of the truth's effects (summed over both where there are two) at
    positions ``q`` and velocities ``v`` (arrays, m or rad and m/s or rad/s), N or N·m. The friction level is ≥ 0
    and acts against the motion (at rest it is the extra static friction the joint can hold). ``load`` (N or N·m,
    default 0) is the hand force, which only the direction friction at rest depends on (see
    :func:`direction_share`)."""
    q = np.asarray(q, dtype=np.float64)
    v = np.asarray(v, dtype=np.float64)
    load = np.zeros(1) if load is None else np.asarray(load, dtype=np.float64)
    q, v, load = np.broadcast_arrays(q, v, load)
    applied, friction = np.zeros(q.shape), np.zeros(q.shape)
    for e in truth.effects:
        a, f = _law_of(e, truth, np)
        if a is not None:
            applied = applied + a(q, v)
        if f is not None:
            friction = friction + f(q, v, load)
    return applied, friction


def ground_truth_force(truth: GroundTruth, q: np.ndarray, v: np.ndarray, load: np.ndarray | None = None) -> np.ndarray:
    """The truth's effect force (the sum of both where there are two; not the baseline's) at positions ``q`` and
    velocities ``v``, N or N·m, positive opening. Friction-type effects give ``-level * sign(v)``: 0 at v = 0, where
    friction is indeterminate. ``load``: the hand force, as in :func:`effect_laws` (matters only to direction
    friction below ~2 v_eps)."""
    applied, friction = effect_laws(truth, q, v, load)
    return applied - friction * np.sign(np.asarray(v, dtype=np.float64))


# ----------------------------------------------------------------------------------------- excitation

SegmentKind = Literal["move", "slow", "creep", "hold", "release", "throw"]


@dataclass(frozen=True)
class Segment:
    """One step of an excitation plan (m, m/s or rad, rad/s; s).

    - ``move``: minimum-jerk stroke from the current target (or, after a release, the position) to ``goal`` at
      peak speed ``speed``, lasting 1.875 |Δ| / speed clipped to ``duration`` (its longest) and 0.25 s;
    - ``slow``: constant-speed stroke at ``speed`` to ``goal`` with 0.2 s smooth ramps;
    - ``creep``: a ``slow`` stroke from the position (not the target: a hand pressing the front on a stop lets
      off first) with a :data:`CREEP_STIFFNESS` times stiffer hand: the force builds slowly from rest until the
      front breaks away, then it follows at constant speed;
    - ``hold``: target fixed for ``duration``;
    - ``release``: hand force exactly 0 for ``duration``;
    - ``throw``: a closing minimum-jerk stroke at peak ``speed`` whose midpoint is ``goal`` (so its end is past
      closed), cut when the position reaches ``goal``; a following ``release`` lets the front go."""

    kind: SegmentKind
    goal: float = 0.0
    speed: float = 0.0
    duration: float = 0.0


@dataclass(frozen=True)
class ExcitationPlan:
    """Where a trial starts (m or rad, at rest) and what the hand does."""

    start: float
    segments: tuple[Segment, ...]

    def nominal_duration(self) -> float:
        """Duration of the plan, s, were every target reached (a let-go front taken to stop at closed)."""
        total, at = 0.0, self.start
        for seg in self.segments:
            if seg.kind == "move":
                total += _move_time(abs(seg.goal - at), seg.speed, seg.duration)
                at = seg.goal
            elif seg.kind in ("slow", "creep"):
                total += abs(seg.goal - (0.0 if seg.kind == "creep" and at < 0 else at)) / seg.speed + SLOW_RAMP
                at = seg.goal
            elif seg.kind == "throw":
                total += _move_time(2 * abs(seg.goal - at), seg.speed, math.inf) / 2 + 0.2  # + the lag
                at = 0.0
            else:
                total += seg.duration
        return total


def _move_time(distance: float, speed: float, longest: float) -> float:
    return min(max(1.875 * distance / speed, MOVE_TIME[0]), max(longest, MOVE_TIME[0]))


def excitation_plan(joint: JointType | str, upper: float, rng: np.random.Generator, *, duration_s: float = 12.0,
                    start: float | None = None) -> ExcitationPlan:
    """A random excitation for a joint with range (0, ``upper``) (m or rad) filling ``duration_s`` s: in random
    order a push held against the closed stop then a creep open from rest there, a push towards closed let go
    near closed, a hold and release from rest at mid-range, a hold then a slow stroke, a push held against the far
    stop; then
    strokes of random speed (and short holds) to the end. The required blocks are redrawn (up to 50 times) until
    they fit ``duration_s`` - 0.5 s nominally: always at 12 s, about 97 % at 10 s; shorter trials lose the last
    blocks. ``start`` (default: closed or a random position) is where the front rests at t = 0."""
    joint = _joint(joint)
    x = EXCITE[joint]
    u = float(upper)
    best: ExcitationPlan | None = None
    for _ in range(50):
        if start is None:
            begin = 0.0 if rng.random() < 0.4 else _uniform(rng, (0.1 * u, 0.6 * u))
        else:
            begin = start

        def move(lo: float, hi: float) -> Segment:
            return Segment("move", _uniform(rng, (lo * u, hi * u)), _log_uniform(rng, x.block_speed), BLOCK_MOVE_TIME)

        slow_speed = _uniform(rng, x.slow)
        slow_from = _uniform(rng, (0.25 * u, 0.75 * u))
        slow_length = slow_speed * _uniform(rng, (1.2, 2.0))
        slow_to = slow_from + (slow_length if rng.random() < 0.5 else -slow_length)
        blocks = [
            [Segment("move", -_uniform(rng, x.push), _log_uniform(rng, x.block_speed), BLOCK_MOVE_TIME),
             Segment("hold", duration=_uniform(rng, (0.5, 1.0))),
             Segment("creep", _uniform(rng, x.creep_length), _uniform(rng, x.creep))],
            [move(0.2, 0.45), Segment("throw", _uniform(rng, x.near_closed), _uniform(rng, x.throw)),
             Segment("release", duration=_uniform(rng, (0.5, 0.8)))],
            [move(0.3, 0.7), Segment("hold", duration=_uniform(rng, (0.6, 0.9))),
             Segment("release", duration=_uniform(rng, (0.5, 0.8)))],
            [Segment("move", slow_from, _log_uniform(rng, x.block_speed), BLOCK_MOVE_TIME),
             Segment("hold", duration=0.3), Segment("slow", slow_to, slow_speed)],
            [Segment("move", u + _uniform(rng, x.push), _log_uniform(rng, x.block_speed), BLOCK_MOVE_TIME),
             Segment("hold", duration=_uniform(rng, (0.5, 0.8)))],
        ]
        order = rng.permutation(len(blocks))
        plan = ExcitationPlan(begin, tuple(seg for i in order for seg in blocks[i]))
        if best is None or plan.nominal_duration() < best.nominal_duration():
            best = plan
        if plan.nominal_duration() <= duration_s - 0.5:
            break
    assert best is not None
    segments = list(best.segments)
    while ExcitationPlan(best.start, tuple(segments)).nominal_duration() < duration_s + 1.0:
        segments.append(Segment("move", _uniform(rng, (0.05 * u, 0.95 * u)), _log_uniform(rng, x.speed),
                                MOVE_TIME[1]))
        if rng.random() < 0.3:
            segments.append(Segment("hold", duration=_uniform(rng, (0.3, 0.6))))
    return ExcitationPlan(best.start, tuple(segments))


def _min_jerk(a: float, b: float, n: int, total: int, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Steps 1..n of a minimum-jerk profile from ``a`` to ``b`` over ``total`` steps: (target, target velocity)."""
    s = np.arange(1, n + 1) / total
    shape = s**3 * (10.0 - 15.0 * s + 6.0 * s**2)
    rate = 30.0 * s**2 * (1.0 - s) ** 2
    return a + (b - a) * shape, (b - a) * rate / (total * dt)


def _profile(seg: Segment, at: float, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """(target, target velocity) per fine step of a hand segment starting at target ``at``."""
    if seg.kind == "hold":
        n = max(int(round(seg.duration / dt)), 1)
        return np.full(n, at), np.zeros(n)
    if seg.kind == "move":
        n = max(int(round(_move_time(abs(seg.goal - at), seg.speed, seg.duration) / dt)), 1)
        return _min_jerk(at, seg.goal, n, n, dt)
    if seg.kind == "throw":
        end = seg.goal + (seg.goal - at)
        total = max(int(round(_move_time(abs(end - at), seg.speed, math.inf) / dt)), 2)
        return _min_jerk(at, end, total, total, dt)
    if seg.kind in ("slow", "creep"):
        distance = abs(seg.goal - at)
        n = max(int(round((distance / seg.speed + SLOW_RAMP) / dt)), 2)
        t = (np.arange(n) + 0.5) * dt
        w = np.minimum(np.clip(t / SLOW_RAMP, 0.0, 1.0), np.clip((n * dt - t) / SLOW_RAMP, 0.0, 1.0))
        w = 0.5 * (1.0 - np.cos(np.pi * w))
        vel = np.sign(seg.goal - at) * w
        path = np.cumsum(vel) * dt
        scale = (seg.goal - at) / path[-1] if path[-1] != 0.0 else 0.0
        return at + path * scale, vel * scale
    raise AssertionError(seg.kind)  # pragma: no cover


# ----------------------------------------------------------------------------------------- simulation

@dataclass(frozen=True, eq=False)
class Simulation:
    """A simulated run on the fine grid: state at t, and the hand force applied from t to t + timestep."""

    truth: GroundTruth
    plan: ExcitationPlan
    timestep: float
    t: np.ndarray
    """Time, s (k · timestep)."""
    q: np.ndarray
    """True position, m or rad."""
    v: np.ndarray
    """True velocity, m/s or rad/s."""
    f: np.ndarray
    """Hand force, N or N·m (exactly 0 while released)."""
    released: np.ndarray
    """True where the hand has let go."""
    segments: list[tuple[str, float, float]] = field(default_factory=list)
    """(kind, start s, end s) of each executed plan segment."""


def hand_gains(truth: GroundTruth) -> tuple[float, float]:
    """(kp N/m or N·m/rad, kd N·s/m or N·m·s/rad) of the hand on ``truth``: kp = mass · ω², ω from 400 N/m on
    6 kg, raised for strong friction or effect forces (see :data:`HAND_DEADBAND`); damping ratio
    :data:`HAND_ZETA`."""
    grid = np.linspace(0.0, truth.range[1], 101)
    applied, extra = effect_laws(truth, grid, np.zeros(101))
    static = truth.frictionloss + float(extra.max())
    load = static + float(np.abs(applied[50:]).max())
    deadband = HAND_DEADBAND[truth.joint]
    kp = max(truth.mass * HAND_OMEGA**2, static / deadband, load / (2 * deadband))
    return kp, 2.0 * HAND_ZETA * math.sqrt(kp * truth.mass)


def _model_xml(truth: GroundTruth, timestep: float) -> str:
    lower, upper = truth.range
    if truth.joint is JointType.slide:
        axis, inertial = "1 0 0", f'mass="{truth.mass!r}" diaginertia="0.01 0.01 0.01"'
    else:
        i = repr(truth.mass)
        axis, inertial = "0 0 1", f'mass="1" diaginertia="{i} {i} {i}"'
    solimp = " ".join(repr(x) for x in SOLIMP_FRICTION)
    solref = " ".join(repr(x) for x in SOLREF_LIMIT)
    return f"""<mujoco model="rik-sysid-truth">
  <compiler angle="radian"/>
  <option timestep="{timestep!r}" integrator="implicitfast" gravity="0 0 0"/>
  <worldbody>
    <body name="front">
      <joint name="joint" type="{truth.joint.value}" axis="{axis}" limited="true" range="{lower!r} {upper!r}"
             damping="{truth.damping!r}" frictionloss="{truth.frictionloss!r}" solimpfriction="{solimp}"
             solreflimit="{solref}"/>
      <inertial pos="0 0 0" {inertial}/>
    </body>
  </worldbody>
</mujoco>"""


def simulate(truth: GroundTruth, plan: ExcitationPlan, *, duration_s: float = 12.0,
             timestep: float = 0.0005) -> Simulation:
    """Run ``plan`` on ``truth`` for ``duration_s`` s at ``timestep`` s (MuJoCo, implicitfast); the plan is
    padded with a hold if it ends early."""
    import mujoco

    _positive(duration_s=duration_s, timestep=timestep)
    model = mujoco.MjModel.from_xml_string(_model_xml(truth, timestep))
    data = mujoco.MjData(model)
    lower, upper = truth.range
    data.qpos[0] = min(max(plan.start, lower), upper)
    mujoco.mj_forward(model, data)
    steps = int(math.ceil(duration_s / timestep - 1e-9)) + 1
    qs, vs, fs = [0.0] * steps, [0.0] * steps, [0.0] * steps
    released = np.zeros(steps, dtype=bool)
    kp, kd = hand_gains(truth)
    fmax = HAND_MAX[truth.joint]
    applied, friction = _scalar_laws(truth)
    fc = truth.frictionloss
    qpos, qvel, qfrc, floss = data.qpos, data.qvel, data.qfrc_applied, model.dof_frictionloss
    step = mujoco.mj_step
    segments: list[tuple[str, float, float]] = []
    k = 0
    target = float(qpos[0])
    after_release = False
    queue = list(plan.segments)
    while k < steps:
        seg = queue.pop(0) if queue else Segment("hold", duration=(steps - k) * timestep)
        stop_below = seg.goal if seg.kind == "throw" else -math.inf
        if seg.kind == "release":
            n = max(int(round(seg.duration / timestep)), 1)
            tq, tv, gp, gd = [0.0] * n, [0.0] * n, 0.0, 0.0
            released[k:k + n] = True
            after_release = True
        else:
            if after_release or seg.kind == "creep":
                target = float(qpos[0])
                after_release = False
            profile = _profile(seg, target, timestep)
            target = float(profile[0][-1])
            stiff = CREEP_STIFFNESS if seg.kind == "creep" else 1.0
            tq, tv, gp, gd = profile[0].tolist(), profile[1].tolist(), kp * stiff, kd * math.sqrt(stiff)
            n = len(tq)
        n = min(n, steps - k)
        segments.append((seg.kind, k * timestep, (k + n) * timestep))
        for i in range(n):
            q = qpos.item(0)
            if q < stop_below:
                break
            v = qvel.item(0)
            f = gp * (tq[i] - q) + gd * (tv[i] - v)
            if f > fmax:
                f = fmax
            elif f < -fmax:
                f = -fmax
            qs[k] = q
            vs[k] = v
            fs[k] = f
            qfrc[0] = f if applied is None else f + applied(q, v)
            if friction is not None:
                floss[0] = fc + friction(q, v, f)
            step(model, data)
            k += 1
        segments[-1] = (seg.kind, segments[-1][1], k * timestep)
    t = np.arange(steps) * timestep
    return Simulation(truth, plan, timestep, t, np.asarray(qs), np.asarray(vs), np.asarray(fs), released,
                      segments)


# ---------------------------------------------------------------------------------------------- measuring

def _positive(**values: float) -> None:
    for name, value in values.items():
        if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
            raise RikError(f"{name} must be a finite number > 0, got {value!r}")


def _non_negative(**values: float | None) -> None:
    for name, value in values.items():
        if value is not None and not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0):
            raise RikError(f"{name} must be a finite number ≥ 0, got {value!r}")


def trial_units(joint: JointType) -> tuple[TrialUnits, TrialColumns]:
    """The SI units and CSV headers of a simulated trial of ``joint``."""
    joint = _joint(joint)
    position, force = ("m", "N") if joint is JointType.slide else ("rad", "N·m")
    word = "force" if joint is JointType.slide else "torque"
    return (TrialUnits(time="s", position=position, force=force),
            TrialColumns(time="time [s]", position=f"position [{position}]", force=f"{word} [{force}]"))


def measure(sim: Simulation, rng: np.random.Generator, *, name: str = "trial_1", duration_s: float | None = None,
            rate_hz: float = 200.0, position_noise: float | None = None, force_noise: float | None = None,
            delay_s: float = 0.01, quantum: float | None = None) -> Trial:
    """Sample ``sim`` at ``rate_hz`` Hz for ``duration_s`` s (default: as long as it lasts), times from 0: force
    (zero-order hold) + N(0, ``force_noise``), position (interpolated) at ``delay_s`` s earlier +
    N(0, ``position_noise``), then rounded to multiples of ``quantum`` (m or rad) if given. Noise defaults per joint:
    :data:`POSITION_NOISE`, :data:`FORCE_NOISE`. The simulation must cover ``duration_s + |delay_s|``."""
    joint = sim.truth.joint
    position_noise = POSITION_NOISE[joint] if position_noise is None else position_noise
    force_noise = FORCE_NOISE[joint] if force_noise is None else force_noise
    _positive(rate_hz=rate_hz)
    _non_negative(position_noise=position_noise, force_noise=force_noise)
    if quantum is not None:
        _positive(quantum=quantum)
    if not (isinstance(delay_s, (int, float)) and math.isfinite(delay_s)):
        raise RikError(f"delay_s must be a finite number, got {delay_s!r}")
    span = float(sim.t[-1])
    available = span - abs(delay_s)
    duration = available if duration_s is None else float(duration_s)
    if duration_s is not None:
        _positive(duration_s=duration_s)
    if duration > available + 1e-9:
        raise RikError(f"duration_s {duration:g} s plus |delay_s| {abs(delay_s):g} s exceeds the simulation "
                       f"({span:g} s)")
    samples = int(math.floor(duration * rate_hz + 1e-9)) + 1
    t = np.arange(samples) / rate_hz
    offset = max(delay_s, 0.0)
    force_index = np.minimum(np.floor((t + offset) / sim.timestep + 1e-6).astype(np.int64), len(sim.f) - 1)
    f = sim.f[force_index] + rng.normal(0.0, force_noise, samples)
    q = np.interp(t + offset - delay_s, sim.t, sim.q) + rng.normal(0.0, position_noise, samples)
    if quantum is not None:
        q = np.round(q / quantum) * quantum
    si_units, columns = trial_units(joint)
    meta = TrialMeta(name=name, source=SOURCE, joint=joint, units=si_units, columns=columns, samples=samples,
                     duration=float(t[-1]))
    return Trial(meta, t, q, f)


def simulate_trials(truth: GroundTruth, *, n_trials: int = 4, seed: int = 0, duration_s: float = 12.0,
                    rate_hz: float = 200.0, timestep: float = 0.0005, position_noise: float | None = None,
                    force_noise: float | None = None, delay_s: float = 0.01,
                    quantum: float | None = None) -> list[Trial]:
    """``n_trials`` measured trials ``trial_1`` … of ``truth``, each with its own excitation plan, deterministic
    for ``seed``: ``duration_s`` s at ``rate_hz`` Hz simulated at ``timestep`` s; noise, delay (s, position later
    than force) and quantum as in :func:`measure`."""
    if not isinstance(truth, GroundTruth):
        raise RikError(f"truth must be a GroundTruth, got {type(truth).__name__}")
    if not isinstance(n_trials, int) or isinstance(n_trials, bool) or n_trials < 1:
        raise RikError(f"n_trials must be an integer ≥ 1, got {n_trials!r}")
    if not isinstance(seed, int) or isinstance(seed, bool) or seed < 0:
        raise RikError(f"seed must be an integer ≥ 0, got {seed!r}")
    _positive(duration_s=duration_s, rate_hz=rate_hz, timestep=timestep)
    if timestep > 0.5 / rate_hz:
        raise RikError(f"timestep {timestep:g} s must be at most half the sample interval ({0.5 / rate_hz:g} s)")
    _non_negative(position_noise=position_noise, force_noise=force_noise)
    if quantum is not None:
        _positive(quantum=quantum)
    if not (isinstance(delay_s, (int, float)) and math.isfinite(delay_s) and abs(delay_s) < duration_s):
        raise RikError(f"delay_s must be a finite number smaller than duration_s in size, got {delay_s!r}")
    trials = []
    for i, child in enumerate(np.random.SeedSequence(seed).spawn(n_trials)):
        plan_rng, noise_rng = (np.random.default_rng(s) for s in child.spawn(2))
        start = 0.0 if i == 0 else None
        plan = excitation_plan(truth.joint, truth.range[1], plan_rng, duration_s=duration_s, start=start)
        sim = simulate(truth, plan, duration_s=duration_s + abs(delay_s) + timestep, timestep=timestep)
        trials.append(measure(sim, noise_rng, name=f"trial_{i + 1}", duration_s=duration_s, rate_hz=rate_hz,
                              position_noise=position_noise, force_noise=force_noise, delay_s=delay_s,
                              quantum=quantum))
    return trials


def write_trials(trials: Sequence[Trial], directory: str | Path, truth: GroundTruth) -> list[Path]:
    """Write each trial to ``directory/<name>.csv`` (headers ``time [s]``, ``position [m|rad]``,
    ``force [N]`` or ``torque [N·m]``, values printed to round-trip exactly) and the truth to
    ``directory/truth.json``, each atomically; returns the CSV paths (for :func:`rik.sysid.trials.load_trials`)."""
    if not trials:
        raise RikError("trials is empty; nothing to write")
    if not isinstance(truth, GroundTruth):
        raise RikError(f"truth must be a GroundTruth, got {type(truth).__name__}")
    names = [t.name for t in trials]
    if len(set(names)) != len(names):
        raise RikError(f"trials have repeated names ({', '.join(sorted({n for n in names if names.count(n) > 1}))})")
    for trial in trials:
        if trial.joint is not truth.joint:
            raise RikError(f"trials: '{trial.name}' is a {trial.joint.value} trial but the truth is a "
                           f"{truth.joint.value}")
        if "/" in trial.name or "\\" in trial.name or trial.name.startswith("."):
            raise RikError(f"trials: name '{trial.name}' cannot be a file name")
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    _, columns = trial_units(truth.joint)
    header = f"{columns.time},{columns.position},{columns.force}\n"
    paths = []
    for trial in trials:
        rows = zip(trial.t.tolist(), trial.q.tolist(), trial.f.tolist(), strict=True)
        text = header + "".join(f"{a!r},{b!r},{c!r}\n" for a, b, c in rows)
        path = directory / f"{trial.name}.csv"
        write_atomic(path, text)
        paths.append(path)
    write_atomic(directory / TRUTH_FILE, json.dumps(truth.to_json(), indent=2) + "\n")
    return paths
