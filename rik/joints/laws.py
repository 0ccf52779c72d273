"""The library's joint effects as force laws (numpy; SI units of the joint).

One implementation of every law of :data:`rik.schemas.joints.JointEffect` (the schema's docstrings define
them): :func:`effect_force` gives the generalised force an effect puts on its joint at position ``q`` (0 closed,
positive opening; m or rad) and velocity ``v`` (m/s or rad/s), positive pushing open (N or N·m). Friction-type
effects (:data:`rik.joints.kinds.FRICTION_KINDS`) are friction magnitudes on top of the joint's Coulomb friction:
:func:`extra_friction` gives that magnitude (≥ 0), and :func:`effect_force` gives ``-extra * sign(v)``.

:data:`FRICTION_LAWS` and :data:`FORCE_LAWS` hold one law per kind of :data:`rik.joints.kinds.KINDS` (the friction
kinds in the first, the others in the second); :data:`DAMPING_LAWS` gives the kinds that the simulator applies as
damping (:attr:`rik.joints.kinds.EffectKind.runtime`) their damping, from which their force law is made.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any

import numpy as np

from rik.errors import RikError
from rik.joints.kinds import FRICTION_KINDS, as_effect, joint_type_name
from rik.schemas.joints import JointEffect, JointType

if TYPE_CHECKING:
    from numpy.typing import ArrayLike, NDArray

    Values = float | np.floating | NDArray[np.floating]
    """A joint position, velocity or force: one value, or an array of them (the laws broadcast)."""

__all__ = ["DAMPING_LAWS", "FORCE_LAWS", "FRICTION_LAWS", "effect_force", "extra_friction"]

# The laws take floats or arrays alike (only ufuncs and arithmetic: fast on floats). ``Any``: each gets its kind.


def _stiction(e: Any, q: Values, v: Values, regularisation: float) -> Values:
    return e.breakaway * np.exp(-((v / e.stribeck_velocity) ** 2))


def _direction_friction(e: Any, q: Values, v: Values, regularisation: float) -> Values:
    along = v if e.direction == "opening" else -v
    if regularisation > 0:
        return e.extra * np.minimum(np.maximum(along / regularisation, 0.0), 1.0)
    return e.extra * (along > 0)


def _load_friction(e: Any, q: Values, v: Values, regularisation: float) -> Values:
    return e.per_extension * np.maximum(q, 0.0)


FRICTION_LAWS: dict[str, Callable[[Any, Values, Values, float], Values]] = {
    "stiction": _stiction, "direction_friction": _direction_friction, "load_friction": _load_friction}
"""kind → (effect, q, v, regularisation) → the extra friction magnitude (≥ 0), for the friction kinds."""


def _soft_close_damping(e: Any, q: Values, v: Values) -> Values:
    return e.damping * ((q < e.zone) & ((v < 0) | (not e.closing_only)))


DAMPING_LAWS: dict[str, Callable[[Any, Values, Values], Values]] = {"soft_close": _soft_close_damping}
"""kind → (effect, q, v) → the viscous damping it adds there (N·s/m or N·m·s/rad), for the kinds that are
damping acting only in part of the state space (their force law is ``-damping * v``)."""


def _soft_close(e: Any, q: Values, v: Values, joint_type: str) -> Values:
    return -_soft_close_damping(e, q, v) * v


def _self_close(e: Any, q: Values, v: Values, joint_type: str) -> Values:
    return -e.stiffness * np.minimum(np.maximum(e.zone - q, 0.0), e.zone)


def _magnetic_catch(e: Any, q: Values, v: Values, joint_type: str) -> Values:
    return -e.force / (1.0 + np.maximum(q, 0.0) / e.decay) ** 2


def _tilt(e: Any, q: Values, v: Values, joint_type: str) -> Values:
    if joint_type == "slide":
        return e.force + 0.0 * q
    return e.force * np.cos(q) + e.sine * np.sin(q)


def _quadratic_damping(e: Any, q: Values, v: Values, joint_type: str) -> Values:
    return -e.coefficient * v * np.abs(v)


FORCE_LAWS: dict[str, Callable[[Any, Values, Values, str], Values]] = {
    "soft_close": _soft_close, "self_close": _self_close, "magnetic_catch": _magnetic_catch, "tilt": _tilt,
    "quadratic_damping": _quadratic_damping}
"""kind → (effect, q, v, joint type) → the force (positive opening), for the kinds that are not friction."""


def extra(effect: JointEffect, q: Values, v: Values, regularisation: float) -> Values:
    """The friction law of a friction-type ``effect`` on floats or arrays alike (see :func:`extra_friction`)."""
    law = FRICTION_LAWS.get(effect.kind)
    if law is None:
        raise RikError(f"joint effect '{effect.kind}' is not a friction effect "
                       f"(those are {', '.join(sorted(FRICTION_KINDS))})")
    return law(effect, q, v, regularisation)


def force(effect: JointEffect, q: Values, v: Values, joint_type: str, regularisation: float) -> Values:
    """The force law of ``effect`` on floats or arrays alike (see :func:`effect_force`); ``joint_type`` is
    ``slide`` or ``hinge``."""
    if effect.kind in FRICTION_KINDS:
        return -extra(effect, q, v, regularisation) * np.sign(v)
    return FORCE_LAWS[effect.kind](effect, q, v, joint_type)


def _arrays(q: ArrayLike, v: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    q, v = np.broadcast_arrays(np.asarray(q, np.float64), np.asarray(v, np.float64))
    return q, v


def extra_friction(effect: JointEffect | Mapping[str, object], q: ArrayLike, v: ArrayLike,
                   regularisation: float = 0.0) -> NDArray[np.float64]:
    """Friction magnitude (N or N·m, ≥ 0) a friction-type effect adds to the joint's Coulomb friction at position
    ``q`` (m or rad) and velocity ``v`` (m/s or rad/s); arrays broadcast.

    ``regularisation`` (m/s or rad/s; 0: the ideal law) ramps direction-dependent friction linearly from 0 at
    rest to its full value at that speed in its direction, as rik's simulation does
    (:data:`rik.joints.mjcf.DIRECTION_FRICTION_SPEED`)."""
    qa, va = _arrays(q, v)
    return np.asarray(extra(as_effect(effect), qa, va, regularisation), np.float64)


def effect_force(effect: JointEffect | Mapping[str, object], q: ArrayLike, v: ArrayLike, joint_type: JointType | str,
                 regularisation: float = 0.0) -> NDArray[np.float64]:
    """Generalised force (N or N·m; positive pushes open) of ``effect`` on a joint of ``joint_type`` at position
    ``q`` (m or rad, 0 closed) and velocity ``v`` (m/s or rad/s); arrays broadcast.

    Friction-type effects give ``-extra_friction * sign(v)`` (0 at rest, where friction is a reaction);
    ``regularisation`` is passed to :func:`extra_friction`. Where the schema leaves a law open, rik's choice:
    ``self_close`` pulls ``stiffness * zone`` past closed (q < 0), as its native actuator does; ``magnetic_catch``
    pulls ``force`` past closed; ``soft_close`` acts over ``q < zone``, past closed included."""
    qa, va = _arrays(q, v)
    return np.asarray(force(as_effect(effect), qa, va, joint_type_name(joint_type), regularisation), np.float64)
