"""The per-step application of a joint's effects in MuJoCo (the laws: :mod:`rik.joints.laws`).

:func:`rik.joints.kinds.is_native` says which effects :mod:`rik.joints.mjcf` writes into the MJCF (joint
attributes and passive actuators); the others are applied each physics step by :class:`RuntimeEffects`, through
the channel the table gives each kind (:attr:`rik.joints.kinds.EffectKind.runtime`):

- ``frictionloss`` (friction-type effects): ``model.dof_frictionloss`` is set to the base friction plus their
  extra: the friction stays one of MuJoCo's constraints, so it holds a joint at rest without chatter;
- ``damping`` (``soft_close``): ``model.dof_damping`` is set to the base damping plus its damping while it acts,
  so MuJoCo's implicit integrators treat it as damping (stable for stiff dampers);
- ``qfrc_applied`` (everything else): the force is added to ``data.qfrc_applied``.

Every value is a function of the state before the step (``q``, ``v``), and :meth:`RuntimeEffects.undo` puts the
model arrays and ``qfrc_applied`` back after ``mj_step``, so recorded states never hold the effects' forces and
replays from them are exact.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import TYPE_CHECKING, cast

from rik.errors import RikError
from rik.joints.kinds import KINDS, Channel, as_effect
from rik.joints.laws import DAMPING_LAWS, extra, force
from rik.joints.mjcf import DIRECTION_FRICTION_SPEED
from rik.schemas.joints import JointEffect

if TYPE_CHECKING:
    import mujoco
    import numpy as np
    from numpy.typing import NDArray

__all__ = ["CHANNELS", "RuntimeEffects", "front_effects"]

CHANNELS: tuple[Channel, ...] = ("frictionloss", "damping", "qfrc_applied")
"""The channels :class:`RuntimeEffects` applies effects through (every kind's ``runtime`` is one of them)."""


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
        by = {c: tuple(e for e in self.effects if KINDS[e.kind].runtime == c) for c in CHANNELS}
        self._friction = by["frictionloss"]
        self._dampers = by["damping"]
        self._forces = by["qfrc_applied"]
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
            total += float(force(e, q, v, self.joint_type, 0.0))
        return total

    def frictionloss(self, q: float, v: float) -> float:
        """The joint's friction at (q, v) with the friction-type effects: N or N·m."""
        total = self.base_frictionloss
        for e in self._friction:
            total += float(extra(e, q, v, self._speed))
        return total

    def damping(self, q: float, v: float) -> float:
        """The joint's viscous damping at (q, v) with the dampers (soft-close) that act there: N·s/m or N·m·s/rad."""
        added = 0.0
        for e in self._dampers:
            added += float(DAMPING_LAWS[e.kind](e, q, v))
        return self.base_damping + added

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
