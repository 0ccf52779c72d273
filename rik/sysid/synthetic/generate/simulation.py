"""Simulation of a truth driven by the impedance hand (MuJoCo, on a fine grid)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from rik.schemas.joints import JointType
from rik.sysid.synthetic.generate.common import _positive
from rik.sysid.synthetic.generate.constants import (
    CREEP_STIFFNESS,
    HAND_DEADBAND,
    HAND_MAX,
    HAND_OMEGA,
    HAND_ZETA,
    SOLIMP_FRICTION,
    SOLREF_LIMIT,
)
from rik.sysid.synthetic.generate.excitation import ExcitationPlan, Segment, _profile
from rik.sysid.synthetic.generate.laws import _scalar_laws, effect_laws
from rik.sysid.synthetic.generate.truth import GroundTruth


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
