"""A foreign generator of "measured" drawer and door trials: a second source of test data for ``rik sysid``, with
force laws written independently of rik's effect library (nothing here imports :mod:`rik.joints`,
:mod:`rik.sysid.effects`, :mod:`rik.combinator` or the laws of :mod:`rik.sysid.synthetic.generate`).

A :class:`ForeignTruth` is a 1-DOF joint (slide: m, N, kg; hinge: rad, N·m, kg·m²) integrated here in plain
Python (semi-implicit Euler at :data:`TIMESTEP` = 0.1 ms; the LuGre bristle state implicitly, so it stays stable
at any speed). Its base, present in every case:

- inertia and viscous damping;
- friction as a LuGre model: bristle state ``z``, ``dz/dt = v - σ0 |v| z / g(v)``, friction
  ``σ0 z + σ1 dz/dt``; ``g`` is the Coulomb level, or a Stribeck curve for stiction. A front at rest under a load
  below ``g(0)`` deflects the bristles (presliding, a fraction of a millimetre) and does not slide;
- compliant end stops at both ends of the range: a unilateral penalty contact ``k·pen + c·v`` (never pulling).

One hidden effect per case, keyed by rik's kind names (other shapes than rik's library on purpose):

==================  =============================================================================================
kind                force on the joint (positive opens; q ≥ 0 from closed)
==================  =============================================================================================
stiction            LuGre ``g(v) = Fc + (Fs - Fc) / (1 + (v / vs)^2)`` (a Lorentzian Stribeck curve: flat at
                    rest, a long tail), Fs = 1.4-2 Fc
magnetic_catch      ``-F0 / (1 + q/d)^3`` (a cubic falloff)
self_close          ``-(preload + k (zone - q)) · clip((zone - q) / play, 0, 1)`` inside the zone: a preloaded
                    spring picked up over a few millimetres of play
soft_close          ``+c |v|^0.8`` while closing inside the zone, taken up over the first 3 mm (1° on a hinge)
quadratic_damping   ``-c v_ref² sign(v) (|v| / v_ref)^1.8`` (fluid drag)
load_friction       Coulomb and static friction grow by ``W q / (L - q)``, L = 1.5 upper (a cantilevered load
                    whose lever grows as the runners' overlap shrinks)
tilt                slide: ``-m g sin(a (1 + 0.2 q / upper))`` (a tilted runner that sags when extended);
                    hinge: ``-A sin(q + φ)`` (gravity about a tilted axis)
none                the base only
==================  =============================================================================================

A simulated hand (PID on a target with a clamped integral, force-limited like a person) runs an excitation
written here: strokes at several speeds, a creep at constant slow speed, pushes held against both stops (target
5-15 mm or 0.8-2.5° beyond the stop), holds and releases (hand force exactly 0) at several positions and a throw
towards closed let go near closed. :func:`simulate_foreign` samples it at 200 Hz with noise and a 10 ms
force-to-position delay (the position sample at time t is the true position at t - delay) and returns
:class:`rik.sysid.trials.Trial` objects; :class:`ForeignTruth` ``.to_json()`` is the truth record.

The hand's kp is set from the largest force it must hold (friction plus the effect anywhere in the range), so a
front near a strong magnet is held firmly and a push held 15 mm beyond a stop can reach 40-60 N there.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from rik.errors import RikError
from rik.schemas.joints import JointType
from rik.schemas.trajectory import TrialColumns, TrialMeta, TrialUnits
from rik.sysid.synthetic.draws import joint_type as _joint
from rik.sysid.synthetic.draws import log_uniform as _log_uniform
from rik.sysid.synthetic.draws import tilt_phase
from rik.sysid.synthetic.draws import uniform as _uniform
from rik.sysid.trials import Trial, si_columns, write_simulated

FOREIGN_KINDS = ("none", "stiction", "magnetic_catch", "self_close", "soft_close", "quadratic_damping",
                 "load_friction", "tilt")
"""Hidden-effect kinds of the foreign generator (rik's kind names; ``none`` for the base only)."""
SOURCE = "foreign"
"""``TrialMeta.source`` of foreign trials."""
TRUTH_FILE = "truth.json"
TIMESTEP = 1e-4
"""Integration step, s."""
GRAVITY = 9.81
"""m/s²."""
LEVER = 0.35
"""Door: handle distance from the hinge axis, m (turns the stop's N/m into N·m/rad and mm into rad)."""

Range = tuple[float, float]


@dataclass(frozen=True)
class _Joint:
    """Constants of a joint type: slide (m, N, kg) or hinge (rad, N·m, kg·m²)."""

    mass: Range
    damping: Range
    coulomb: Range
    upper: Range
    presliding: Range
    """Bristle deflection at the static friction, Fs / σ0: m or rad."""
    stop_stiffness: Range
    """N/m or N·m/rad."""
    hand_max: float
    """Largest hand force, N or N·m."""
    deadband: float
    """The hand's kp is at least the static friction over this error, m or rad."""
    stroke_speed: Range
    creep_speed: Range
    throw_speed: Range
    release_near_closed: Range
    """Distance from closed at which the throw is let go, m or rad."""
    beyond: Range
    """How far beyond a stop the hand's target goes in a held push, m or rad."""
    position_noise: float
    force_noise: float
    effects: dict[str, dict[str, Range]] = field(default_factory=dict)


SLIDE = _Joint(
    mass=(2.0, 15.0), damping=(1.0, 10.0), coulomb=(1.0, 8.0), upper=(0.35, 0.5), presliding=(1e-4, 3e-4),
    stop_stiffness=(1e5, 1e6), hand_max=60.0, deadband=0.01, stroke_speed=(0.05, 0.5), creep_speed=(0.002, 0.01),
    throw_speed=(0.15, 0.35), release_near_closed=(0.015, 0.03), beyond=(0.005, 0.015), position_noise=2e-4,
    force_noise=0.3,
    effects={
        "stiction": {"coulomb": (3.0, 8.0), "ratio": (1.4, 2.0), "stribeck_velocity": (0.01, 0.03)},
        "magnetic_catch": {"force": (5.0, 30.0), "decay": (0.003, 0.01)},
        "self_close": {"zone": (0.02, 0.04), "pull": (5.0, 15.0), "preload_share": (0.3, 0.6),
                       "play": (0.002, 0.005)},
        "soft_close": {"zone": (0.03, 0.06), "damping": (50.0, 150.0), "v_ref": (0.1, 0.1),
                       "take_up": (0.003, 0.003)},
        "quadratic_damping": {"coefficient": (15.0, 40.0), "v_ref": (0.3, 0.3)},
        "load_friction": {"per_extension": (8.0, 25.0)},
        "tilt": {"angle_deg": (1.0, 3.0), "over_friction": (1.2, 2.5), "sag": (0.2, 0.2)},
    })
HINGE = _Joint(
    mass=(0.2, 2.0), damping=(0.05, 0.5), coulomb=(0.1, 1.0), upper=(1.5, 1.9), presliding=(3e-4, 1e-3),
    stop_stiffness=(1e5 * LEVER**2, 1e6 * LEVER**2), hand_max=15.0, deadband=0.03, stroke_speed=(0.2, 2.0),
    creep_speed=(0.006, 0.03), throw_speed=(0.5, 1.2), release_near_closed=(0.05, 0.15),
    beyond=(0.005 / LEVER, 0.015 / LEVER), position_noise=math.radians(0.2), force_noise=0.03,
    effects={
        "stiction": {"coulomb": (0.3, 1.0), "ratio": (1.4, 2.0), "stribeck_velocity": (0.03, 0.08)},
        "magnetic_catch": {"force": (1.5, 6.0), "decay": (0.008, 0.025)},
        "self_close": {"zone": (math.radians(20), math.radians(30)), "pull": (0.5, 2.0),
                       "preload_share": (0.3, 0.6), "play": (math.radians(1), math.radians(3))},
        "soft_close": {"zone": (math.radians(10), math.radians(25)), "damping": (1.0, 3.0), "v_ref": (0.25, 0.25),
                       "take_up": (math.radians(1), math.radians(1))},
        "quadratic_damping": {"coefficient": (0.2, 0.6), "v_ref": (1.0, 1.0)},
        "load_friction": {"per_extension": (0.2, 0.6)},
        "tilt": {"amplitude": (0.4, 1.5), "over_friction": (1.2, 2.5)},
    })
JOINTS = {JointType.slide: SLIDE, JointType.hinge: HINGE}
SOFT_CLOSE_EXPONENT = 0.8
DRAG_EXPONENT = 1.8
LOAD_LEVER = 1.5
"""L / upper of the load friction's lever."""
STOP_ZETA = (0.3, 0.7)
"""Damping ratio of the end stops' contact on the moving mass."""
BRISTLE_ZETA = 0.7
"""Damping ratio of the bristles (σ1 = 2 ζ sqrt(σ0 m))."""
HAND_OMEGA2 = 400.0 / 6.0
"""kp / mass of the hand at least, 1/s² (400 N/m on 6 kg)."""
HAND_ZETA = 0.6
HAND_INTEGRAL_S = 0.3
"""Integral time of the hand (ki = kp / this), s: a person corrects a lasting error within a few tenths of a
second, so a held front settles at its target against a closer or a magnet."""
HAND_INTEGRAL_SHARE = 0.25
"""The integral term is clamped to this share of the largest hand force (a push held against a stop is not
wound up to the limit)."""
FORCE_RAMP = 0.2
"""A ``force`` segment reaches its force over this time (a raised cosine), s."""


# -------------------------------------------------------------------------------------------------- truth

@dataclass(frozen=True)
class ForeignTruth:
    """The hidden joint of a foreign case; SI units of the joint (see the module docstring)."""

    joint: JointType
    kind: str
    """One of :data:`FOREIGN_KINDS`."""
    mass: float
    """kg or kg·m²."""
    damping: float
    """Viscous damping, N·s/m or N·m·s/rad."""
    coulomb: float
    """Sliding (Coulomb) friction level Fc, N or N·m."""
    static: float
    """Static friction level Fs (= Fc unless stiction), N or N·m."""
    stribeck_velocity: float
    """vs of the Stribeck curve, m/s or rad/s (unused when Fs = Fc)."""
    bristle_stiffness: float
    """σ0, N/m or N·m/rad."""
    bristle_damping: float
    """σ1, N·s/m or N·m·s/rad."""
    range: tuple[float, float]
    """(lower, upper) stops, m or rad."""
    stop_stiffness: float
    """N/m or N·m/rad."""
    stop_damping: float
    """N·s/m or N·m·s/rad."""
    params: dict[str, float] = field(default_factory=dict)
    """The effect's parameters (see :func:`effect_force`), SI."""

    def to_json(self) -> dict[str, Any]:
        """A JSON-ready dict (``generator: foreign``)."""
        return {"generator": "foreign", "joint": self.joint.value, "kind": self.kind, "mass": self.mass,
                "damping": self.damping, "coulomb": self.coulomb, "static": self.static,
                "stribeck_velocity": self.stribeck_velocity, "bristle_stiffness": self.bristle_stiffness,
                "bristle_damping": self.bristle_damping, "range": list(self.range),
                "stop_stiffness": self.stop_stiffness, "stop_damping": self.stop_damping,
                "params": dict(self.params)}


def foreign_truth(kind: str | None, joint: JointType | str, rng: np.random.Generator) -> ForeignTruth:
    """A realistic foreign truth with hidden effect ``kind`` (one of :data:`FOREIGN_KINDS`; None is ``none``), all
    parameters drawn from ``rng`` within the ranges of :data:`SLIDE` or :data:`HINGE`."""
    joint = _joint(joint)
    kind = "none" if kind is None else kind
    if kind not in FOREIGN_KINDS:
        raise RikError(f"kind '{kind}' is not a foreign effect kind; use one of {', '.join(FOREIGN_KINDS)}")
    if not isinstance(rng, np.random.Generator):
        raise RikError(f"rng must be a numpy.random.Generator, got {type(rng).__name__}")
    c = JOINTS[joint]
    slide = joint is JointType.slide
    mass = _log_uniform(rng, c.mass)
    damping = _log_uniform(rng, c.damping)
    coulomb = _log_uniform(rng, c.coulomb)
    upper = _uniform(rng, c.upper)
    presliding = _uniform(rng, c.presliding)
    stop_k = _log_uniform(rng, c.stop_stiffness)
    stop_zeta = _uniform(rng, STOP_ZETA)
    ranges = c.effects.get(kind, {})
    params: dict[str, float] = {}
    static, vs = coulomb, 1.0
    if kind == "stiction":
        coulomb = _uniform(rng, ranges["coulomb"])
        static = coulomb * _uniform(rng, ranges["ratio"])
        vs = _log_uniform(rng, ranges["stribeck_velocity"])
        params = {"ratio": static / coulomb}
    elif kind == "magnetic_catch":
        params = {"force": _uniform(rng, ranges["force"]), "decay": _uniform(rng, ranges["decay"])}
    elif kind == "self_close":
        zone, pull = _uniform(rng, ranges["zone"]), _uniform(rng, ranges["pull"])
        preload = pull * _uniform(rng, ranges["preload_share"])
        params = {"zone": zone, "pull": pull, "preload": preload, "stiffness": (pull - preload) / zone,
                  "play": _uniform(rng, ranges["play"])}
    elif kind == "soft_close":
        v_ref, equivalent = ranges["v_ref"][0], _uniform(rng, ranges["damping"])
        params = {"zone": _uniform(rng, ranges["zone"]), "damping_at_vref": equivalent, "v_ref": v_ref,
                  "coefficient": equivalent * v_ref ** (1.0 - SOFT_CLOSE_EXPONENT), "take_up": ranges["take_up"][0]}
    elif kind == "quadratic_damping":
        params = {"coefficient": _uniform(rng, ranges["coefficient"]), "v_ref": ranges["v_ref"][0]}
    elif kind == "load_friction":
        slope = _uniform(rng, ranges["per_extension"])
        lever = LOAD_LEVER * upper
        # W q / (L - q) reaches slope * upper at the open end
        params = {"per_extension": slope, "lever": lever, "load": slope * (lever - upper)}
    elif kind == "tilt":
        sign = 1.0 if rng.random() < 0.5 else -1.0
        ratio = _uniform(rng, ranges["over_friction"])
        if slide:
            mass = _log_uniform(rng, (4.0, c.mass[1]))  # heavy enough for a pull of 2 N at ≤ 3°
            angle = max(_uniform(rng, ranges["angle_deg"]), math.degrees(math.asin(min(1.0, 2.0 / (mass * GRAVITY)))))
            params = {"angle_deg": sign * angle, "sag": ranges["sag"][0]}
            peak = mass * GRAVITY * math.sin(math.radians(angle * (1.0 + ranges["sag"][0])))
        else:
            amplitude = _uniform(rng, ranges["amplitude"])
            phase = tilt_phase(rng)
            params = {"amplitude": amplitude, "phase": phase}
            grid = np.linspace(0.0, upper, 181)
            peak = float(np.max(np.abs(amplitude * np.sin(grid + phase))))
        coulomb = min(max(peak / ratio, c.coulomb[0]), c.coulomb[1])
        static = coulomb
        params["over_friction"] = peak / coulomb
    sigma0 = static / presliding
    return ForeignTruth(joint=joint, kind=kind, mass=mass, damping=damping, coulomb=coulomb, static=static,
                        stribeck_velocity=vs, bristle_stiffness=sigma0,
                        bristle_damping=2.0 * BRISTLE_ZETA * math.sqrt(sigma0 * mass), range=(0.0, upper),
                        stop_stiffness=stop_k, stop_damping=2.0 * stop_zeta * math.sqrt(stop_k * mass),
                        params=params)


# ------------------------------------------------------------------------------------------------- laws

Law = Callable[[float, float], float]


def effect_law(truth: ForeignTruth) -> Law | None:
    """The hidden effect's force on the joint as a scalar function of (q, v) (N or N·m, positive opens), for
    the effects that are a force (not the friction-level ones: stiction and load friction, see
    :func:`friction_levels`); None when there is none."""
    p, slide, upper = truth.params, truth.joint is JointType.slide, truth.range[1]
    kind = truth.kind
    if kind == "magnetic_catch":
        f0, d = p["force"], p["decay"]

        def law(q: float, v: float) -> float:
            x = 1.0 + (q if q > 0.0 else 0.0) / d
            return -f0 / (x * x * x)
    elif kind == "self_close":
        zone, pre, k, play = p["zone"], p["preload"], p["stiffness"], p["play"]

        def law(q: float, v: float) -> float:
            s = zone - (q if q > 0.0 else 0.0)
            if s <= 0.0:
                return 0.0
            return -(pre + k * s) * (s / play if s < play else 1.0)
    elif kind == "soft_close":
        zone, coef, take = p["zone"], p["coefficient"], p["take_up"]

        def law(q: float, v: float) -> float:
            s = zone - (q if q > 0.0 else 0.0)
            if s <= 0.0 or v >= 0.0:
                return 0.0
            return coef * (-v) ** SOFT_CLOSE_EXPONENT * (s / take if s < take else 1.0)
    elif kind == "quadratic_damping":
        cv = p["coefficient"] * p["v_ref"] ** 2
        vref = p["v_ref"]

        def law(q: float, v: float) -> float:
            if v == 0.0:
                return 0.0
            return -math.copysign(cv * (abs(v) / vref) ** DRAG_EXPONENT, v)
    elif kind == "tilt" and slide:
        a0, sag, w = math.radians(p["angle_deg"]), p["sag"], truth.mass * GRAVITY

        def law(q: float, v: float) -> float:
            return -w * math.sin(a0 * (1.0 + sag * min(max(q, 0.0), upper) / upper))
    elif kind == "tilt":
        amp, phase = p["amplitude"], p["phase"]

        def law(q: float, v: float) -> float:
            return -amp * math.sin(q + phase)
    else:
        return None
    return law


def friction_levels(truth: ForeignTruth) -> Callable[[float], float]:
    """Extra friction (added to both Fc and Fs) as a function of q, N or N·m: the load friction's
    ``W q / (L - q)``; zero otherwise."""
    if truth.kind != "load_friction":
        return lambda q: 0.0
    w, lever, upper = truth.params["load"], truth.params["lever"], truth.range[1]

    def extra(q: float) -> float:
        x = min(max(q, 0.0), upper)
        return w * x / (lever - x)
    return extra


def effect_force(truth: ForeignTruth, q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """The force-type effect's force at each (q, v), N or N·m (zeros without one); for comparisons in tests."""
    law = effect_law(truth)
    q, v = np.broadcast_arrays(np.asarray(q, float), np.asarray(v, float))
    if law is None:
        return np.zeros(q.shape)
    return np.array([law(a, b) for a, b in zip(q.ravel().tolist(), v.ravel().tolist(), strict=True)]).reshape(q.shape)


def hand_gains(truth: ForeignTruth) -> tuple[float, float]:
    """(kp, kd) of the hand: kp = mass · 400/6 at least, raised so that the static friction plus the largest
    effect force at rest anywhere in the range is met within the joint's deadband (a person holds a drawer
    firmly: 1 cm for the pull of a closer)."""
    c = JOINTS[truth.joint]
    upper = truth.range[1]
    law, extra = effect_law(truth), friction_levels(truth)
    grid = np.linspace(0.0, upper, 101).tolist()
    static = truth.static + max(extra(q) for q in grid)
    load = static + (max(abs(law(q, 0.0)) for q in grid) if law else 0.0)
    kp = max(truth.mass * HAND_OMEGA2, load / c.deadband)
    return kp, 2.0 * HAND_ZETA * math.sqrt(kp * truth.mass)


# ------------------------------------------------------------------------------------------- excitation

@dataclass(frozen=True)
class Segment:
    """One piece of the hand's plan. ``move``: minimum-jerk to ``goal`` at peak speed ``speed``; ``creep``:
    constant ``speed`` to ``goal``; ``hold``: keep the target for ``duration`` s; ``release``: hand force exactly 0
    for ``duration`` s; ``throw``: minimum-jerk towards closed at peak ``speed``, let go once q < ``goal``;
    ``force``: a hand force ``force`` (N or N·m) for ``duration`` s, reached over :data:`FORCE_RAMP` s from 0.
    Units m, m/s or rad, rad/s."""

    kind: str
    goal: float = 0.0
    speed: float = 0.0
    duration: float = 0.0
    force: float = 0.0


def _move_time(distance: float, speed: float) -> float:
    return min(max(1.875 * distance / speed, 0.25), 2.0) if distance > 0.0 else 0.25


def nominal_duration(segments: Sequence[Segment], start: float) -> float:
    """The plan's length, s, if the hand tracked its targets exactly (a throw counted to its let-go point)."""
    at, total = start, 0.0
    for s in segments:
        if s.kind == "move":
            total += _move_time(abs(s.goal - at), s.speed)
            at = s.goal
        elif s.kind == "creep":
            total += abs(s.goal - at) / s.speed + CREEP_RAMP
            at = s.goal
        elif s.kind == "throw":
            total += 0.5 * _move_time(2 * abs(at - s.goal), s.speed)
            at = s.goal
        else:
            total += s.duration
    return total


CREEP_RAMP = 0.1
"""Acceleration time at each end of a creep, s."""


def excitation(joint: JointType | str, upper: float, rng: np.random.Generator, *, duration_s: float = 12.0,
               start: float | None = None) -> tuple[float, list[Segment]]:
    """(start position, segments) of one trial: pushes held 0.5-1.2 s against both stops, a creep at constant
    slow speed, holds and releases at two positions (one near closed), a throw towards closed let go near closed,
    in random order, with moves between them at random speeds (the slowest sped up until the blocks fit in
    ``duration_s`` s; of :data:`ORDER_TRIES` random block orders the first that fits, else the shortest, so in
    rare plans the last block is cut), then strokes of random speed until ``duration_s`` s are filled."""
    c = JOINTS[_joint(joint)]
    at = _uniform(rng, (0.1 * upper, 0.9 * upper)) if start is None else float(start)
    blocks: list[list[Segment]] = [
        [Segment("move", -_uniform(rng, c.beyond), _log_uniform(rng, c.stroke_speed)),
         Segment("hold", duration=_uniform(rng, (0.5, 1.2)))],
        [Segment("move", upper + _uniform(rng, c.beyond), _log_uniform(rng, c.stroke_speed)),
         Segment("hold", duration=_uniform(rng, (0.5, 1.2)))],
    ]
    speed, span = _log_uniform(rng, c.creep_speed), _uniform(rng, (1.0, 2.0))
    a = _uniform(rng, (0.05 * upper, 0.95 * upper - speed * span))
    ends = (a, a + speed * span) if rng.random() < 0.5 else (a + speed * span, a)
    blocks.append([Segment("move", ends[0], _log_uniform(rng, c.stroke_speed)), Segment("creep", ends[1], speed)])
    near = _uniform(rng, (c.release_near_closed[0] * 0.3, c.release_near_closed[1] * 1.5))
    for where in (near, _uniform(rng, (0.2 * upper, 0.9 * upper))):
        blocks.append([Segment("move", where, _log_uniform(rng, c.stroke_speed)),
                       Segment("hold", duration=_uniform(rng, (0.3, 0.5))),
                       Segment("release", duration=_uniform(rng, (0.4, 0.8)))])
    blocks.append([Segment("move", _uniform(rng, (0.4 * upper, 0.7 * upper)), _log_uniform(rng, c.stroke_speed)),
                   Segment("throw", _uniform(rng, c.release_near_closed), _uniform(rng, c.throw_speed)),
                   Segment("release", duration=_uniform(rng, (0.5, 0.9)))])
    best: list[Segment] = []
    for _ in range(ORDER_TRIES):  # the first order that fits, else the shortest
        order = rng.permutation(len(blocks))
        segments = _fit_moves([s for i in order for s in blocks[int(i)]], at, duration_s - 0.3, c.stroke_speed[1])
        if not best or nominal_duration(segments, at) < nominal_duration(best, at):
            best = segments
        if nominal_duration(best, at) <= duration_s - 0.3:
            break
    segments = best
    while nominal_duration(segments, at) < duration_s + 0.5:
        segments.append(Segment("move", _uniform(rng, (0.05 * upper, 0.95 * upper)),
                                _log_uniform(rng, c.stroke_speed)))
    return at, segments


ORDER_TRIES = 20
"""Block orders :func:`excitation` tries before it takes the shortest."""


def _fit_moves(segments: list[Segment], at: float, budget: float, fast: float) -> list[Segment]:
    """``segments`` with the longest moves sped up (doubled, at most to ``fast``) until the plan lasts at most
    ``budget`` s or no move can be shortened."""
    segments = list(segments)
    while nominal_duration(segments, at) > budget:
        times, here = [], at
        for s in segments:
            times.append(_move_time(abs(s.goal - here), s.speed) if s.kind == "move" and s.speed < fast else 0.0)
            here = s.goal if s.kind in ("move", "creep", "throw") else here
        longest = int(np.argmax(times))
        if times[longest] <= 0.25 + 1e-9:
            break  # every move is as short or as fast as it gets
        segments[longest] = dataclasses.replace(segments[longest], speed=min(2.0 * segments[longest].speed, fast))
    return segments


def _profile(seg: Segment, at: float, dt: float) -> tuple[list[float], list[float]]:
    """(target, target velocity) per step of a ``move``, ``creep``, ``hold`` or ``throw`` from target ``at``."""
    if seg.kind == "hold":
        n = max(int(round(seg.duration / dt)), 1)
        return [at] * n, [0.0] * n
    if seg.kind in ("move", "throw"):
        end = seg.goal if seg.kind == "move" else seg.goal - (at - seg.goal)
        n = max(int(round(_move_time(abs(end - at), seg.speed) / dt)), 2)
        s = np.arange(1, n + 1) / n
        shape = s**3 * (10.0 - 15.0 * s + 6.0 * s**2)
        rate = 30.0 * s**2 * (1.0 - s) ** 2
        return (at + (end - at) * shape).tolist(), ((end - at) * rate / (n * dt)).tolist()
    if seg.kind == "creep":
        distance = abs(seg.goal - at)
        n = max(int(round((distance / seg.speed + CREEP_RAMP) / dt)), 2)
        t = (np.arange(n) + 0.5) * dt
        w = np.minimum(np.clip(t / CREEP_RAMP, 0.0, 1.0), np.clip((n * dt - t) / CREEP_RAMP, 0.0, 1.0))
        vel = np.sign(seg.goal - at) * 0.5 * (1.0 - np.cos(np.pi * w))
        path = np.cumsum(vel) * dt
        scale = (seg.goal - at) / path[-1] if path[-1] != 0.0 else 0.0
        return (at + path * scale).tolist(), (vel * scale).tolist()
    raise RikError(f"segment kind '{seg.kind}' has no target profile")


# ------------------------------------------------------------------------------------------- simulation

@dataclass(frozen=True, eq=False)
class Run:
    """A simulated run on the :data:`TIMESTEP` grid: the state at t and the hand force from t to t + dt."""

    truth: ForeignTruth
    t: np.ndarray
    """s."""
    q: np.ndarray
    """m or rad."""
    v: np.ndarray
    """m/s or rad/s."""
    f: np.ndarray
    """Hand force, N or N·m (exactly 0 while released)."""
    released: np.ndarray
    """True where the hand has let go (or applies a set force)."""


def run(truth: ForeignTruth, segments: Sequence[Segment], *, start: float = 0.0, duration_s: float = 12.0,
        dt: float = TIMESTEP) -> Run:
    """Integrate ``truth`` driven by the hand through ``segments`` from rest at ``start`` (m or rad) for
    ``duration_s`` s (padded with a hold), semi-implicit Euler at ``dt`` s with an implicit bristle update. The
    hand is a PID on the target (see :func:`hand_gains`, :data:`HAND_INTEGRAL_S`), clipped to the joint's
    ``hand_max``; its integral restarts after every release."""
    if not isinstance(truth, ForeignTruth):
        raise RikError(f"truth must be a ForeignTruth, got {type(truth).__name__}")
    if not (math.isfinite(duration_s) and duration_s > 0 and math.isfinite(dt) and 0 < dt <= 1e-3):
        raise RikError(f"duration_s must be > 0 and dt in (0, 0.001] s, got {duration_s!r} and {dt!r}")
    steps = int(math.ceil(duration_s / dt - 1e-9)) + 1
    qs, vs_, fs = [0.0] * steps, [0.0] * steps, [0.0] * steps
    free = [False] * steps
    m, b = truth.mass, truth.damping
    fc0, fs0, vstr = truth.coulomb, truth.static, truth.stribeck_velocity
    stribeck = fs0 > fc0
    s0, s1 = truth.bristle_stiffness, truth.bristle_damping
    lower, upper = truth.range
    ks, cs = truth.stop_stiffness, truth.stop_damping
    law = effect_law(truth)
    extra = friction_levels(truth) if truth.kind == "load_friction" else None
    kp, kd = hand_gains(truth)
    ki = kp / HAND_INTEGRAL_S
    fmax = JOINTS[truth.joint].hand_max
    imax = HAND_INTEGRAL_SHARE * fmax
    integral = 0.0
    q, v, z = float(start), 0.0, 0.0
    target = q
    after_release = False
    queue = list(segments)
    k = 0
    while k < steps:
        seg = queue.pop(0) if queue else Segment("hold", duration=(steps - k) * dt)
        stop_below = seg.goal if seg.kind == "throw" else -math.inf
        pd = seg.kind not in ("release", "force")
        if pd:
            if after_release:
                target, after_release, integral = q, False, 0.0
            tq, tv = _profile(seg, target, dt)
            target = tq[-1]
            n = len(tq)
        else:
            n = max(int(round(seg.duration / dt)), 1)
            after_release = True
        n = min(n, steps - k)
        hand = seg.force if seg.kind == "force" else 0.0
        ramp = max(int(round(FORCE_RAMP / dt)), 1)
        for i in range(n):
            if q < stop_below:
                break
            if pd:
                error = tq[i] - q
                integral += ki * error * dt
                if integral > imax:
                    integral = imax
                elif integral < -imax:
                    integral = -imax
                f = kp * error + kd * (tv[i] - v) + integral
                if f > fmax:
                    f = fmax
                elif f < -fmax:
                    f = -fmax
            else:
                f = hand if i >= ramp else hand * 0.5 * (1.0 - math.cos(math.pi * i / ramp))
                free[k] = True
            qs[k], vs_[k], fs[k] = q, v, f
            # friction: LuGre with an implicit bristle update
            fc, fst = fc0, fs0
            if extra is not None:
                e = extra(q)
                fc, fst = fc + e, fst + e
            if stribeck:
                r = v / vstr
                g = fc + (fst - fc) / (1.0 + r * r)
            else:
                g = fst
            z_new = (z + v * dt) / (1.0 + s0 * abs(v) * dt / g)
            friction = s0 * z_new + s1 * (z_new - z) / dt
            z = z_new
            total = f - b * v - friction
            if law is not None:
                total += law(q, v)
            if q < lower:
                contact = ks * (lower - q) - cs * v
                if contact > 0.0:
                    total += contact
            elif q > upper:
                contact = ks * (q - upper) + cs * v
                if contact > 0.0:
                    total -= contact
            v += total / m * dt
            q += v * dt
            k += 1
    t = np.arange(steps) * dt
    return Run(truth, t, np.asarray(qs), np.asarray(vs_), np.asarray(fs), np.asarray(free))


# ------------------------------------------------------------------------------------------- measuring

def trial_units(joint: JointType) -> tuple[TrialUnits, TrialColumns]:
    """The SI units and CSV headers of a foreign trial of ``joint`` (rik's: :func:`rik.sysid.trials.si_columns`)."""
    return si_columns(joint)


def measure(sim: Run, rng: np.random.Generator, *, name: str, duration_s: float, rate_hz: float = 200.0,
            delay_s: float = 0.01) -> Trial:
    """Sample ``sim`` at ``rate_hz`` Hz for ``duration_s`` s: force (zero-order hold) + noise, position at
    ``delay_s`` s earlier (the position is recorded later than the force) + noise (0.2 mm or 0.2°, 0.3 N or
    0.03 N·m)."""
    c = JOINTS[sim.truth.joint]
    samples = int(math.floor(duration_s * rate_hz + 1e-9)) + 1
    t = np.arange(samples) / rate_hz
    dt = float(sim.t[1] - sim.t[0])
    offset = max(delay_s, 0.0)
    index = np.minimum(np.floor((t + offset) / dt + 1e-6).astype(np.int64), len(sim.f) - 1)
    f = sim.f[index] + rng.normal(0.0, c.force_noise, samples)
    q = np.interp(t + offset - delay_s, sim.t, sim.q) + rng.normal(0.0, c.position_noise, samples)
    units, columns = trial_units(sim.truth.joint)
    meta = TrialMeta(name=name, source=SOURCE, joint=sim.truth.joint, units=units, columns=columns,
                     samples=samples, duration=float(t[-1]))
    return Trial(meta, t, q, f)


def simulate_foreign(truth: ForeignTruth, n_trials: int = 3, seed: int = 0, duration_s: float = 12.0, *,
                     rate_hz: float = 200.0, delay_s: float = 0.01) -> list[Trial]:
    """``n_trials`` measured trials ``trial_1`` … of ``truth`` (the first starting at rest at closed, the others
    mid-range), each with its own excitation; deterministic for ``seed``. ``duration_s`` s at ``rate_hz`` Hz,
    position recorded ``delay_s`` s after the force."""
    if not isinstance(n_trials, int) or isinstance(n_trials, bool) or n_trials < 1:
        raise RikError(f"n_trials must be an integer ≥ 1, got {n_trials!r}")
    if not isinstance(seed, int) or isinstance(seed, bool) or seed < 0:
        raise RikError(f"seed must be an integer ≥ 0, got {seed!r}")
    if not (math.isfinite(duration_s) and duration_s >= 1.0):
        raise RikError(f"duration_s must be at least 1 s, got {duration_s!r}")
    trials = []
    for i, child in enumerate(np.random.SeedSequence(seed).spawn(n_trials)):
        plan_rng, noise_rng = (np.random.default_rng(s) for s in child.spawn(2))
        start, segments = excitation(truth.joint, truth.range[1], plan_rng, duration_s=duration_s,
                                     start=0.0 if i == 0 else None)
        sim = run(truth, segments, start=start, duration_s=duration_s + abs(delay_s) + 2 * TIMESTEP)
        trials.append(measure(sim, noise_rng, name=f"trial_{i + 1}", duration_s=duration_s, rate_hz=rate_hz,
                              delay_s=delay_s))
    return trials


def write_foreign(trials: Sequence[Trial], directory: str | Path, truth: ForeignTruth) -> list[Path]:
    """Write each trial to ``directory/<name>.csv`` (the rik generator's headers) and the truth to
    ``directory/truth.json``, the folder whole (:func:`rik.sysid.trials.write_simulated`: an existing folder is
    replaced only if it holds simulated trials); returns the CSV paths."""
    return write_simulated(trials, directory, truth.joint, truth.to_json())
