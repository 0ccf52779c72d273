"""The truth's force laws (the shapes of :mod:`rik.sysid.synthetic.generate`'s table), each written once for floats
(the step loop) and arrays."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, overload

import numpy as np

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
from rik.sysid.synthetic.generate.constants import (
    CUBIC_FRACTION,
    CUBIC_VREF,
    DIRECTION_FEPS,
    DIRECTION_VEPS,
    EDGE_FRACTION,
    LOAD_EXPONENT,
    SOFT_CLOSE_EXPONENT,
    SOFT_CLOSE_VREF,
    STRIBECK_EXPONENT,
)
from rik.sysid.synthetic.generate.truth import Effect, GroundTruth


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
