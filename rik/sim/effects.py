"""The library's joint effects as force laws, and their per-step application in MuJoCo.

One implementation of every law of :data:`rik.schemas.joints.JointEffect` (the schema's docstrings define
them): :func:`effect_force` gives the generalised force an effect puts on its joint at position ``q`` (0 closed,
positive opening; m or rad) and velocity ``v`` (m/s or rad/s), positive pushing open (N or N·m). Friction-type
effects (``stiction``, ``direction_friction``, ``load_friction``) are friction magnitudes on top of the
joint's Coulomb friction: :func:`extra_friction` gives that magnitude (≥ 0), and :func:`effect_force` gives
``-extra * sign(v)``.

:func:`is_native` says which effects :mod:`rik.combinator.joints` writes into the MJCF (joint attributes and
passive actuators); the others are applied each physics step by :class:`RuntimeEffects`:

- friction-type effects set ``model.dof_frictionloss`` to the base friction plus their extra: the friction
  stays one of MuJoCo's constraints, so it holds a joint at rest without chatter;
- ``soft_close`` sets ``model.dof_damping`` to the base damping plus its damping while it acts, so MuJoCo's
  implicit integrators treat it as damping (stable for stiff dampers);
- everything else adds its force to ``data.qfrc_applied``.

Every value is a function of the state before the step (``q``, ``v``), and :meth:`RuntimeEffects.undo` puts the
model arrays and ``qfrc_applied`` back after ``mj_step``, so recorded states never hold the effects' forces and
replays from them are exact.
"""

from __future__ import annotations

import functools
from collections.abc import Iterable, Mapping
from typing import TYPE_CHECKING, cast

import numpy as np

from rik.combinator.joints import DIRECTION_FRICTION_SPEED, native_kind
from rik.errors import RikError
from rik.schemas.joints import JointEffect, JointType, SoftClose

if TYPE_CHECKING:
    import mujoco
    from numpy.typing import ArrayLike, NDArray
    from pydantic import TypeAdapter

    Values = float | np.floating | NDArray[np.floating]
    """A joint position, velocity or force: one value, or an array of them (the laws broadcast)."""

__all__ = ["DIRECTION_FRICTION_SPEED", "FRICTION_KINDS", "RuntimeEffects", "as_effect", "effect_force",
           "extra_friction", "front_effects", "is_native"]

FRICTION_KINDS = frozenset({"stiction", "direction_friction", "load_friction"})
"""Effects that are friction magnitudes (:func:`extra_friction`)."""


@functools.cache
def _adapter() -> TypeAdapter[JointEffect]:
    from pydantic import TypeAdapter

    return TypeAdapter(JointEffect)


def as_effect(effect: JointEffect | Mapping[str, object]) -> JointEffect:
    """An effect model from a model or its ``model_dump()`` dict (as variants record runtime effects)."""
    if isinstance(effect, Mapping):
        try:
            return _adapter().validate_python(dict(effect))
        except ValueError as exc:  # pydantic's ValidationError: many lines; keep the first problem
            first = exc.errors()[0] if hasattr(exc, "errors") else {"loc": (), "msg": str(exc)}
            where = ".".join(str(p) for p in first.get("loc", ()))
            raise RikError(f"joint effect {dict(effect)!r}: field '{where}': {first['msg']}") from None
    return effect


def _type(joint_type: JointType | str) -> str:
    value = getattr(joint_type, "value", joint_type)
    if value not in ("slide", "hinge"):
        raise RikError(f"joint type '{value}' is not one of slide, hinge")
    return value


def is_native(effect: JointEffect | Mapping[str, object], joint_type: JointType | str) -> bool:
    """True when MuJoCo expresses ``effect`` on a joint of ``joint_type`` in the MJCF itself (rik writes it there);
    False when :class:`RuntimeEffects` applies it each step."""
    return native_kind(as_effect(effect).kind, _type(joint_type))


def _extra(effect: JointEffect, q: Values, v: Values, regularisation: float) -> Values:
    """The friction laws, on floats or arrays alike (only ufuncs and arithmetic: fast on floats)."""
    if effect.kind == "stiction":
        return effect.breakaway * np.exp(-((v / effect.stribeck_velocity) ** 2))
    if effect.kind == "direction_friction":
        along = v if effect.direction == "opening" else -v
        if regularisation > 0:
            return effect.extra * np.minimum(np.maximum(along / regularisation, 0.0), 1.0)
        return effect.extra * (along > 0)
    if effect.kind == "load_friction":
        return effect.per_extension * np.maximum(q, 0.0)
    raise RikError(f"joint effect '{effect.kind}' is not a friction effect "
                   f"(those are {', '.join(sorted(FRICTION_KINDS))})")


def _force(effect: JointEffect, q: Values, v: Values, joint_type: str, regularisation: float) -> Values:
    """The force laws, on floats or arrays alike (see :func:`effect_force`)."""
    if effect.kind in FRICTION_KINDS:
        return -_extra(effect, q, v, regularisation) * np.sign(v)
    if effect.kind == "soft_close":
        return -effect.damping * v * ((q < effect.zone) & ((v < 0) | (not effect.closing_only)))
    if effect.kind == "self_close":
        return -effect.stiffness * np.minimum(np.maximum(effect.zone - q, 0.0), effect.zone)
    if effect.kind == "magnetic_catch":
        return -effect.force / (1.0 + np.maximum(q, 0.0) / effect.decay) ** 2
    if effect.kind == "tilt":
        if joint_type == "slide":
            return effect.force + 0.0 * q
        return effect.force * np.cos(q) + effect.sine * np.sin(q)
    if effect.kind == "quadratic_damping":
        return -effect.coefficient * v * np.abs(v)
    # the schema's union is closed: no other kind gets here
    raise RikError(f"joint effect kind '{effect.kind}' has no force law")  # pragma: no cover


def _arrays(q: ArrayLike, v: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    q, v = np.broadcast_arrays(np.asarray(q, np.float64), np.asarray(v, np.float64))
    return q, v


def extra_friction(effect: JointEffect | Mapping[str, object], q: ArrayLike, v: ArrayLike,
                   regularisation: float = 0.0) -> NDArray[np.float64]:
    """Friction magnitude (N or N·m, ≥ 0) a friction-type effect adds to the joint's Coulomb friction at position
    ``q`` (m or rad) and velocity ``v`` (m/s or rad/s); arrays broadcast.

    ``regularisation`` (m/s or rad/s; 0: the ideal law) ramps direction-dependent friction linearly from 0 at
    rest to its full value at that speed in its direction, as rik's simulation does
    (:data:`rik.combinator.joints.DIRECTION_FRICTION_SPEED`)."""
    qa, va = _arrays(q, v)
    return np.asarray(_extra(as_effect(effect), qa, va, regularisation), np.float64)


def effect_force(effect: JointEffect | Mapping[str, object], q: ArrayLike, v: ArrayLike, joint_type: JointType | str,
                 regularisation: float = 0.0) -> NDArray[np.float64]:
    """Generalised force (N or N·m; positive pushes open) of ``effect`` on a joint of ``joint_type`` at position
    ``q`` (m or rad, 0 closed) and velocity ``v`` (m/s or rad/s); arrays broadcast.

    Friction-type effects give ``-extra_friction * sign(v)`` (0 at rest, where friction is a reaction);
    ``regularisation`` is passed to :func:`extra_friction`. Where the schema leaves a law open, rik's choice:
    ``self_close`` pulls ``stiffness * zone`` past closed (q < 0), as its native actuator does; ``magnetic_catch``
    pulls ``force`` past closed; ``soft_close`` acts over ``q < zone``, past closed included."""
    qa, va = _arrays(q, v)
    return np.asarray(_force(as_effect(effect), qa, va, _type(joint_type), regularisation), np.float64)


class RuntimeEffects:
    """Applies a joint's non-native effects in a MuJoCo simulation, one physics step at a time.

    Call :meth:`apply` right before each ``mj_step`` and :meth:`undo` right after it (or use :meth:`step`): apply
    sets ``model.dof_frictionloss`` and ``model.dof_damping`` of the joint from the state (friction-type effects,
    soft-close) and adds the other effects' forces to ``data.qfrc_applied``; undo restores both model arrays and
    the ``qfrc_applied`` entry to what they were, so other users of ``qfrc_applied`` keep theirs and the state
    after a step holds none of the effects' forces. An :meth:`apply` while another is pending undoes that first.

    ``base_frictionloss`` and ``base_damping`` (N or N·m; N·s/m or N·m·s/rad) default to the model's values at
    construction.
    """

    def __init__(self, model: mujoco.MjModel, dof_adr: int, qpos_adr: int,
                 effects: Iterable[JointEffect | Mapping[str, object]],
                 base_frictionloss: float | None = None, base_damping: float | None = None):
        import mujoco

        self.model = model
        self.dof = int(dof_adr)
        self.qpos = int(qpos_adr)
        self.effects = tuple(as_effect(e) for e in effects)
        joint = int(model.dof_jntid[self.dof])
        self.joint_type = "slide" if int(model.jnt_type[joint]) == mujoco.mjtJoint.mjJNT_SLIDE else "hinge"
        self.base_frictionloss = float(model.dof_frictionloss[self.dof] if base_frictionloss is None
                                       else base_frictionloss)
        self.base_damping = float(model.dof_damping[self.dof] if base_damping is None else base_damping)
        self._friction = tuple(e for e in self.effects if e.kind in FRICTION_KINDS)
        self._dampers = tuple(e for e in self.effects if isinstance(e, SoftClose))
        self._forces = tuple(e for e in self.effects if e.kind not in FRICTION_KINDS and e.kind != "soft_close")
        self._speed = DIRECTION_FRICTION_SPEED[self.joint_type]
        self._pending: tuple[mujoco.MjData, float, float] | None = None
        self._frictionloss: NDArray[np.float64] = model.dof_frictionloss
        self._damping: NDArray[np.float64] = model.dof_damping
        self._data: mujoco.MjData | None = None
        self._arrays: tuple[NDArray[np.float64], ...] = ()

    def __bool__(self) -> bool:
        return bool(self.effects)

    def force(self, q: float, v: float) -> float:
        """Force the effects applied through ``qfrc_applied`` put on the joint at (q, v): N or N·m."""
        total = 0.0
        for e in self._forces:
            total += float(_force(e, q, v, self.joint_type, 0.0))
        return total

    def frictionloss(self, q: float, v: float) -> float:
        """The joint's friction at (q, v) with the friction-type effects: N or N·m."""
        total = self.base_frictionloss
        for e in self._friction:
            total += float(_extra(e, q, v, self._speed))
        return total

    def damping(self, q: float, v: float) -> float:
        """The joint's viscous damping at (q, v) with the soft-close dampers that act there: N·s/m or N·m·s/rad."""
        extra = 0.0
        for e in self._dampers:
            if q < e.zone and (v < 0 or not e.closing_only):
                extra += e.damping
        return self.base_damping + extra

    def _views(self, data: mujoco.MjData) -> tuple[NDArray[np.float64], ...]:
        if data is not self._data:  # attribute access builds a new array wrapper each time: keep them
            self._data, self._arrays = data, (data.qpos, data.qvel, data.qfrc_applied)
        return self._arrays

    def apply(self, data: mujoco.MjData) -> None:
        """Set the joint's friction and damping and add the effects' forces for the coming ``mj_step``."""
        if self._pending is not None:
            self.undo(data)
        if not self.effects:
            return
        qpos, qvel, qfrc = self._views(data)
        q, v = float(qpos[self.qpos]), float(qvel[self.dof])
        if self._friction:
            self._frictionloss[self.dof] = self.frictionloss(q, v)
        if self._dampers:
            self._damping[self.dof] = self.damping(q, v)
        if self._forces:
            before = float(qfrc[self.dof])
            written = before + self.force(q, v)
            qfrc[self.dof] = written
            self._pending = (data, before, written)

    def undo(self, data: mujoco.MjData) -> None:
        """Put back the model's friction and damping and the ``qfrc_applied`` entry as they were before
        :meth:`apply` (if something else changed that entry since, only the effects' force is taken off)."""
        if self._friction:
            self._frictionloss[self.dof] = self.base_frictionloss
        if self._dampers:
            self._damping[self.dof] = self.base_damping
        if self._pending is not None:
            target, before, written = self._pending
            self._pending = None
            qfrc = self._views(target)[2]
            current = float(qfrc[self.dof])
            qfrc[self.dof] = before if current == written else current - (written - before)

    def step(self, data: mujoco.MjData, steps: int = 1) -> None:
        """``steps`` physics steps with the effects applied."""
        import mujoco

        for _ in range(steps):
            self.apply(data)
            mujoco.mj_step(self.model, data)
            self.undo(data)


def front_effects(model: mujoco.MjModel, fronts: Iterable[Mapping[str, object]]) -> tuple[RuntimeEffects, ...]:
    """The appliers of a compiled variant's (or scene's) runtime effects, from the ``rik.variant`` record's
    fronts (their ``joint`` and ``runtime_effects``); fronts without runtime effects get none."""
    import mujoco

    appliers = []
    for front in fronts:
        effects = cast("list[dict[str, object]]", front.get("runtime_effects") or [])  # JSON: effect dumps
        if not effects:
            continue
        joint = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, front["joint"])
        if joint < 0:
            raise RikError(f"variant front '{front.get('id')}': its joint '{front['joint']}' is not in the model")
        appliers.append(RuntimeEffects(model, int(model.jnt_dofadr[joint]), int(model.jnt_qposadr[joint]), effects))
    return tuple(appliers)
