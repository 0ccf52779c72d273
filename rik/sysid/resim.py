"""Re-simulating measured trials with a joint model: the check that a fitted model reproduces the motion.

:func:`joint_spec_model` builds a one-joint MuJoCo model whose joint takes its class from the same mapping that
variants use (:mod:`rik.joints.mjcf`: native effects in the MJCF, the others through a
:class:`~rik.joints.runtime.RuntimeEffects`), so what is simulated here is exactly what a variant's front gets.
:func:`resimulate` drives it with the measured force by multiple shooting: it restarts from the measured state
every ``window_s`` seconds, so a model's error shows as drift within a window, not as an accumulated phase error
over a whole trial.

Units are SI: m or rad, m/s or rad/s, N or N·m, s; kg (slide) or kg·m² (hinge).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from rik.errors import RikError

if TYPE_CHECKING:
    from collections.abc import Iterable

    import mujoco

    from rik.joints.runtime import RuntimeEffects
    from rik.schemas.joints import JointResistance, JointType

TIMESTEP = 0.002
"""s: the variants' timestep (:data:`rik.combinator.mjcf.TIMESTEP`)."""
JOINT = "joint"
"""Name of the joint (and of its body) in the model."""


def joint_spec_model(joint_type: JointType | str, inertia: float, resistance: JointResistance,
                     range: tuple[float, float], *, timestep: float = TIMESTEP) -> tuple[Any, RuntimeEffects]:
    """A 1-DOF MuJoCo model of a joint with ``resistance`` and the applier of its runtime effects.

    ``inertia`` is the moving body's mass (slide, kg) or moment of inertia about the joint axis (hinge, kg·m²),
    *without* the resistance's ``armature``, which the joint class adds as it does in variants. The joint moves
    along (about) x from 0 (closed), limited to ``range`` (m or rad, containing 0); gravity is off (a ``tilt``
    effect is the library's gravity along the joint); ``implicitfast`` at ``timestep`` s (default 2 ms)."""
    import mujoco

    from rik.joints.mjcf import add_effect_actuators, add_front_joint, add_joint_classes, joint_model
    from rik.joints.runtime import RuntimeEffects
    from rik.schemas.joints import JointSpec, JointType, ResistancePreset

    try:
        jtype = JointType(getattr(joint_type, "value", joint_type))
    except ValueError:
        raise RikError(f"joint type '{joint_type}' is not one of slide, hinge") from None
    if not (math.isfinite(inertia) and inertia > 0):
        raise RikError(f"joint model: field 'inertia': must be a positive number (kg or kg·m²), got {inertia}")
    if not (math.isfinite(timestep) and timestep > 0):
        raise RikError(f"joint model: field 'timestep': must be a positive number of seconds, got {timestep}")
    try:
        joint = JointSpec(type=jtype, axis=(1.0, 0.0, 0.0), anchor=(0.0, 0.0, 0.0), range=tuple(range))
    except ValueError as exc:
        problem = exc.errors()[0]["msg"] if hasattr(exc, "errors") else str(exc)
        raise RikError(f"joint model: field 'range': {problem}") from None
    preset = ResistancePreset(id="resim", name="resim", slide=resistance, hinge=resistance)
    spec = mujoco.MjSpec()
    spec.modelname = "rik-joint"
    spec.compiler.degree = False
    spec.option.timestep = timestep
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    spec.option.gravity = [0.0, 0.0, 0.0]
    classes = add_joint_classes(spec, preset, [jtype])
    body = spec.worldbody.add_body(name=JOINT)
    body.explicitinertial = True
    if jtype is JointType.slide:
        body.mass = float(inertia)
        body.inertia = [1e-3, 1e-3, 1e-3]
    else:
        body.mass = 1.0  # centred on the axis: no lever, whatever the mass
        body.inertia = [float(inertia)] * 3
    add_front_joint(body, JOINT, joint, classes[jtype.value])
    jmodel = joint_model(resistance, jtype)
    add_effect_actuators(spec, JOINT, jmodel)
    model = spec.compile()
    return model, RuntimeEffects(model, 0, 0, jmodel.runtime_effects)


def resimulate(model_and_applier: tuple[mujoco.MjModel, RuntimeEffects], t: np.ndarray, q: np.ndarray,
               qd: np.ndarray, force: np.ndarray, *, window_s: float = 0.5) -> np.ndarray:
    """The joint's simulated position at the sample times ``t`` (s, increasing) of a measured trial, by multiple
    shooting: every ``window_s`` s the joint restarts from the measured position ``q`` and velocity ``qd``, and
    it is driven by the measured generalised ``force`` (N or N·m, positive opening) as ``qfrc_applied``. The
    force is interpolated linearly to the middle of each timestep (its mean over the step); positions between
    steps are interpolated linearly."""
    import mujoco

    model, applier = model_and_applier
    t, q, qd, force = (np.asarray(a, np.float64).ravel() for a in (t, q, qd, force))
    n = len(t)
    if not (len(q) == len(qd) == len(force) == n):
        raise RikError(f"resimulate: t, q, qd and force must have the same length, got {n}, {len(q)}, {len(qd)}, "
                       f"{len(force)}")
    if n == 0:
        return np.zeros(0)
    if n > 1 and not np.all(np.diff(t) > 0):
        raise RikError("resimulate: the sample times t must increase")
    if not (math.isfinite(window_s) and window_s > 0):
        raise RikError(f"resimulate: window_s must be a positive number of seconds, got {window_s}")
    data = mujoco.MjData(model)
    dt = float(model.opt.timestep)
    out = np.empty(n)
    apply, undo, step = applier.apply, applier.undo, mujoco.mj_step
    effects = bool(applier)
    i0 = 0
    while i0 < n:
        i1 = max(i0 + 1, int(np.searchsorted(t, t[i0] + window_s, side="left")))
        steps = math.ceil((t[i1 - 1] - t[i0]) / dt - 1e-9)
        grid = t[i0] + dt * np.arange(steps + 1)
        drive = np.interp(grid[:-1] + dt / 2, t, force).tolist()
        mujoco.mj_resetData(model, data)
        data.qpos[0], data.qvel[0], data.time = q[i0], qd[i0], t[i0]
        qpos, qfrc = data.qpos, data.qfrc_applied
        sim = np.empty(steps + 1)
        sim[0] = q[i0]
        for k in range(steps):
            qfrc[0] = drive[k]
            if effects:
                apply(data)
                step(model, data)
                undo(data)
            else:
                step(model, data)
            sim[k + 1] = qpos[0]
        out[i0:i1] = np.interp(t[i0:i1], grid, sim)
        i0 = i1
    return out


def position_rmse(model_and_applier: tuple[mujoco.MjModel, RuntimeEffects],
                  trials: Iterable[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]], *,
                  window_s: float = 0.5) -> float:
    """Root-mean-square error (m or rad) between measured and re-simulated positions over ``trials``: an
    iterable of ``(t, q, qd, force)`` array tuples (SI units)."""
    total, count = 0.0, 0
    for t, q, qd, force in trials:
        sim = resimulate(model_and_applier, t, q, qd, force, window_s=window_s)
        err = sim - np.asarray(q, np.float64).ravel()
        total += float(np.dot(err, err))
        count += len(err)
    if count == 0:
        raise RikError("position_rmse: no samples in the trials")
    return math.sqrt(total / count)
