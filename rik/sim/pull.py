"""A quasi-static pull through a front's handle in rik's simulator: the force a force gauge hooked onto the handle
reads against the front's position, as real doors and drawers are measured (docs/sysid.md, "Real doors").

The gauge is a **hook**: a stiff spring-damper between the handle's grasp site and an anchor that moves along the
handle's own path at constant joint speed. The anchor is where the grasp site would be if the front were at the
target position ``q*(t) = q0 + speed·t`` (``q0``: the front at rest before the pull). The path ``p(q)`` is taken
once from the front at rest (the grasp site turned about the hinge axis, or moved along the slide: the axis is
fixed, since the base unit does not move; a handle that moves with more than its front's one joint is refused).
The hook's force

    F = k·(p(q*) - p(q)) + c·(speed - q')·dp/dq

(``k``: :data:`HOOK_STIFFNESS` N/m; ``c`` critical for the front's mass at the handle; ``q'`` the joint's
velocity) is computed from the state before each physics step and applied at the grasp site through
``mujoco.mj_applyFT`` (into ``qfrc_applied``), so the front feels exactly the force that is recorded; its
component along the handle's direction of motion (``dp/dq``) is the profile's force, and on a hinge ``|dp/dq|``
is the lever arm. An explicit spring rather than a mocap body and a weld: the force
read is the force applied (no solver output to interpret), and the front stays free in its joint (a weld or
``connect`` would be one more soft constraint in the same solve as the joint's friction). The spring is checked
stable at the model's timestep (:data:`MAX_HOOK_OMEGA_DT`).

No gripper is needed: the hook is the force gauge, attached at the grasp site (a real gauge hooks the handle; a
gripper's pinch would add its own compliance and slip). What the front feels is what it feels in rik's scenes:
the variant's ``model.xml`` is loaded as it is (contacts between the front and its cabinet included) with the
solver settings of :func:`rik.sim.build.build_scene` (elliptic cones, impratio, Newton), and the joint effects
MuJoCo lacks are applied around every physics step by the variant's
:class:`rik.joints.runtime.RuntimeEffects` (:func:`rik.joints.runtime.front_effects`, as scenes do). Every
front of the variant is simulated; only the one pulled is hooked. Deterministic: the same arguments give the
same profile, bit for bit.

A pull measures what a real quasi-static pull does: the force that moves the front at ``speed``, i.e. its
position-dependent forces plus its Coulomb friction plus its damping at that speed (``damping·speed``, a
constant over the pull) plus whatever inertia the small oscillations of the hook carry. Positions are the
joint's own (m or rad, 0 closed as built); a front held shut by a catch or a self-closing spring rests slightly
past 0, in its stop, before the pull.

Units: SI. Positions m (slide) or rad (hinge), forces at the handle N, joint forces N or N·m, times s.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from rik.errors import RikError
from rik.joints.runtime import front_effects
from rik.outputs import RECORDED, write_text
from rik.sim.build import add_environment, front_of, load_variant_spec, variant_info

if TYPE_CHECKING:
    import mujoco

__all__ = ["DEFAULT_SPACING", "DEFAULT_SPEED", "DEFAULT_STROKE", "HOOK_STIFFNESS", "PullProfile", "front_joint",
           "pull_profile", "write_profiles"]

DEFAULT_SPEED = {"slide": 5e-3, "hinge": math.radians(5.0)}
"""Joint speed of a pull, m/s or rad/s: 5 mm/s, 5 °/s (slow enough that damping adds little: a door of rik's
``normal`` preset, 0.8 N·m·s/rad, gets 0.07 N·m on its 6 N·m of friction)."""
DEFAULT_STROKE = {"slide": 0.1, "hinge": math.radians(36.0)}
"""How far a pull opens the front, m or rad (joint position it ends at): 10 cm, or 36° as the real door
profiles (36 bins of about one degree)."""
DEFAULT_SPACING = {"slide": 1e-3, "hinge": math.radians(1.0)}
"""Position step between the samples of a profile, m or rad: 1 mm, or 1° as the real door profiles' bins."""
HOOK_STIFFNESS = 5e4
"""N/m: the hook's spring (a load cell on a steel hook, held firmly). Stiffer than the falling part of any
profile it should follow (a catch's pull falls at ``2·force/decay``: 12 kN/m for 6 N over 1 mm), so the front
does not snap ahead of the anchor; soft enough to be integrated explicitly at 2 ms (:data:`MAX_HOOK_OMEGA_DT`).
The front lags the anchor by ``force / stiffness`` (0.3 mm at 15 N)."""
HOOK_DAMPING_RATIO = 1.0
"""The hook's damping as a fraction of critical for the front's mass at the handle: no ringing after a breakaway."""
MAX_HOOK_OMEGA_DT = 0.6
"""Largest ``sqrt(k / m)·dt`` (the hook's natural frequency times the timestep, ``m`` the front's mass at the
handle) accepted: explicit integration of a spring is stable below 2, and accurate well below 1."""
SETTLE_S = 0.2
"""s the front rests, unhooked, before the pull (a catch or a self-closing spring pulls it into its stop)."""


@dataclass(frozen=True, eq=False)
class PullProfile:
    """One pull: samples of the front's position and the force at its handle (equal lengths, SI)."""

    variant: str
    front: str
    joint: str
    """``slide`` or ``hinge``."""
    speed: float
    """Joint speed of the anchor, m/s or rad/s."""
    start: float
    """Joint position of the front at rest before the pull, m or rad."""
    t: np.ndarray
    """Time since the pull began, s."""
    target: np.ndarray
    """The anchor's joint position (where the front would be with an infinitely stiff hook), m or rad."""
    q: np.ndarray
    """The front's joint position, m or rad (0 closed)."""
    force: np.ndarray
    """The hook's force along the handle's direction of motion, N (positive opening)."""
    lever: np.ndarray | None
    """Hinges: the grasp site's distance from the hinge axis, m (None for slides)."""

    @property
    def joint_force(self) -> np.ndarray:
        """The generalised force the hook puts on the joint: N (slide) or N·m (hinge: force × lever arm)."""
        return self.force if self.lever is None else self.force * self.lever

    def __len__(self) -> int:
        return len(self.q)


def _load(source: str | Path | mujoco.MjSpec) -> tuple[mujoco.MjSpec, Path]:
    import mujoco

    if isinstance(source, mujoco.MjSpec):
        return source.copy(), Path(source.modelname or "spec")
    return load_variant_spec(source)


def _positive(name: str, value: float, unit: str) -> float:
    if not (math.isfinite(value) and value > 0):
        raise RikError(f"pull: {name} must be a positive number of {unit}, got {value}")
    return float(value)


def front_joint(source: str | Path | mujoco.MjSpec, front: str | None = None) -> str:
    """``slide`` or ``hinge``: the joint of ``front`` (default: the first) of a built variant (``source`` as for
    :func:`pull_profile`)."""
    import mujoco

    spec, file = _load(source)
    record = front_of(variant_info(spec, file), front, file)
    model = spec.compile()
    joint = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, record["joint"])
    if joint < 0:
        raise RikError(f"{file}: front '{record['id']}': its joint is not in the model")
    return "slide" if int(model.jnt_type[joint]) == mujoco.mjtJoint.mjJNT_SLIDE else "hinge"


def pull_profile(source: str | Path | mujoco.MjSpec, front: str | None = None, *, speed: float | None = None,
                 stroke: float | None = None, spacing: float | None = None, hook_stiffness: float = HOOK_STIFFNESS,
                 hook_damping_ratio: float = HOOK_DAMPING_RATIO, settle_s: float = SETTLE_S) -> PullProfile:
    """Pull ``front`` (default: the variant's first) of a built variant open through its handle, quasi-statically
    (module docstring), and return the force at the handle against the front's position.

    ``source`` is a variant folder, its ``model.xml``, or that file loaded as a ``mujoco.MjSpec`` (copied, not
    changed: a way to pull a variant whose joints were edited). The anchor moves at ``speed`` (m/s or rad/s;
    :data:`DEFAULT_SPEED`) from the front's rest position until the front reaches ``stroke`` (the joint position,
    m or rad; :data:`DEFAULT_STROKE`; it must lie inside the joint's range). Samples are taken where the front
    first reaches each multiple of ``spacing`` (m or rad, :data:`DEFAULT_SPACING`) above 0, up to ``stroke``;
    ``spacing=0`` keeps every physics step from the start of the pull: the rise to breakaway included, where the
    hook's damper adds ``c·speed`` at the handle while the front is still at rest (22 N on a 40 cm door at
    5 °/s), so the raw breakaway comes early; it has died out (within a few ms after breakaway) well before the
    first sample of a spaced profile.
    ``hook_stiffness`` is N/m, ``settle_s`` s.

    Raises :class:`RikError` (one line) for a file that is not a built variant, an unknown front, a stroke
    outside the joint's range, a hook too stiff for the timestep, or a front that does not reach the stroke."""
    import mujoco

    spec, file = _load(source)
    info = variant_info(spec, file)
    record = front_of(info, front, file)
    add_environment(spec)  # the solver settings of rik's scenes (and their floor)
    model = spec.compile()
    data = mujoco.MjData(model)
    joint = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, record["joint"])
    site = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, record["grasp_site"])
    if joint < 0 or site < 0:
        raise RikError(f"{file}: front '{record['id']}': its joint or grasp site is not in the model")
    handle = int(model.site_bodyid[site])
    slide = int(model.jnt_type[joint]) == mujoco.mjtJoint.mjJNT_SLIDE
    kind = "slide" if slide else "hinge"
    qadr, dof = int(model.jnt_qposadr[joint]), int(model.jnt_dofadr[joint])
    lo, hi = (float(x) for x in model.jnt_range[joint])
    speed = _positive("speed", DEFAULT_SPEED[kind] if speed is None else speed, "m/s" if slide else "rad/s")
    stroke = _positive("stroke", DEFAULT_STROKE[kind] if stroke is None else stroke, "m" if slide else "rad")
    spacing = DEFAULT_SPACING[kind] if spacing is None else float(spacing)
    if not (math.isfinite(spacing) and 0 <= spacing < stroke):
        raise RikError(f"pull: spacing must lie in 0 .. the stroke ({stroke:.4g}), got {spacing}")
    if stroke >= hi:
        unit = "m" if slide else "rad"
        raise RikError(f"pull: a stroke of {stroke:.4g} {unit} does not fit front '{record['id']}', whose joint "
                       f"opens to {hi:.4g} {unit}; pull less far")
    hook_stiffness = _positive("hook_stiffness", hook_stiffness, "N/m")
    if not (math.isfinite(hook_damping_ratio) and hook_damping_ratio >= 0):
        raise RikError(f"pull: hook_damping_ratio must be 0 or more, got {hook_damping_ratio}")
    effects = front_effects(model, info["fronts"])
    dt = float(model.opt.timestep)

    chain, body = 0, handle
    while body > 0:
        chain += int(model.body_dofnum[body])
        body = int(model.body_parentid[body])
    if chain != 1:  # the path below is the one joint's: the front hangs from a fixed base unit
        raise RikError(f"{file}: front '{record['id']}': its handle moves with {chain} degrees of freedom, not its "
                       "joint's one")

    def step() -> None:
        for e in effects:
            e.apply(data)
        mujoco.mj_step(model, data)
        for e in effects:
            e.undo(data)

    mujoco.mj_resetData(model, data)
    mujoco.mj_forward(model, data)
    for _ in range(round(max(settle_s, 0.0) / dt)):
        step()
    mujoco.mj_forward(model, data)
    q0 = float(data.qpos[qadr])
    if q0 >= stroke:
        raise RikError(f"pull: front '{record['id']}' rests at {q0:.4g}, past the stroke {stroke:.4g}")

    # The handle's path: the grasp site at rest, moved along the slide's axis or turned about the hinge's (the
    # axis is fixed in the world: the base unit does not move), p(q) = a + h + r·cos(q - q0) + w·sin(q - q0)
    # (Rodrigues), its tangent dp/dq (the site's Jacobian column) and the lever arm |w|.
    axis = data.xaxis[joint].copy()
    p0 = data.site_xpos[site].copy()
    pivot = data.xanchor[joint].copy()
    r0 = p0 - pivot
    along_axis = axis * float(axis @ r0)
    radial, w = r0 - along_axis, np.cross(axis, r0)
    reach = 1.0 if slide else float(np.linalg.norm(w))
    if reach < 1e-6:
        raise RikError(f"{file}: front '{record['id']}': its grasp site lies on the hinge axis; nothing to pull")

    def path(q: float) -> tuple[np.ndarray, np.ndarray]:
        if slide:
            return p0 + (q - q0) * axis, axis
        c, s = math.cos(q - q0), math.sin(q - q0)
        return pivot + along_axis + radial * c + w * s, w * c - radial * s

    # the front's mass (or inertia) at the handle, for the hook's damping and its stability
    full = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, full)
    mass = float(full[dof, dof]) / reach ** 2
    omega = math.sqrt(hook_stiffness / mass)
    if omega * dt > MAX_HOOK_OMEGA_DT:
        raise RikError(f"pull: a hook of {hook_stiffness:.4g} N/m on front '{record['id']}' ({mass:.3g} kg at the "
                       f"handle) is too stiff for the {dt * 1e3:.3g} ms timestep; use at most "
                       f"{mass * (MAX_HOOK_OMEGA_DT / dt) ** 2:.4g} N/m")
    damping = 2.0 * hook_damping_ratio * math.sqrt(hook_stiffness * mass)

    qpos, qvel, qfrc = data.qpos, data.qvel, data.qfrc_applied
    zero3 = np.zeros(3)
    limit_s = 2.0 * (stroke - q0) / speed + 2.0
    steps_max = math.ceil(limit_s / dt)
    t_, target_, q_, f_ = [], [], [], []
    next_k = 1
    for n in range(steps_max + 1):
        t = n * dt
        target = q0 + speed * t
        q, v = float(qpos[qadr]), float(qvel[dof])
        p, tangent = path(q)
        force = hook_stiffness * (path(target)[0] - p) + (damping * (speed - v)) * tangent
        if spacing == 0.0 or q >= next_k * spacing:
            t_.append(t)
            target_.append(target)
            q_.append(q)
            f_.append(float(force @ tangent) / reach)
            if spacing > 0:
                next_k = math.floor(q / spacing + 1e-9) + 1
        if q >= stroke:
            break
        qfrc[:] = 0.0
        mujoco.mj_applyFT(model, data, force, zero3, p, handle, qfrc)  # J^T F: the joint's Jacobian is constant
        step()
    else:
        raise RikError(f"pull: front '{record['id']}' did not reach {stroke:.4g} within {limit_s:.3g} s of pulling "
                       f"(it got to {float(qpos[qadr]):.4g}); is it blocked?")
    return PullProfile(info["id"], record["id"], kind, speed, q0, np.array(t_), np.array(target_), np.array(q_),
                       np.array(f_), None if slide else np.full(len(q_), reach))


def write_profiles(path: str | Path, pulls: Sequence[PullProfile], *, at_handle: bool = False) -> Path:
    """Write pulls of one front as a force profile file that ``rik sysid fit --quasi-static`` reads
    (:mod:`rik.sysid.profile`): a CSV with columns ``trial``, ``position [m]`` or ``position [rad]``, and
    ``force [N]`` (slides; hinges with ``at_handle``: the force at the handle) or ``torque [N·m]`` (hinges: the
    joint torque, force × lever arm, so that fitted parameters compare with a preset's). One trial per pull,
    numbered from 0. Returns ``path``. A file already at ``path`` is replaced only when it is rik's own earlier
    profile there (:data:`rik.outputs.RECORDED`): the same format as a measured profile, so nothing else tells."""

    if not pulls:
        raise RikError("write_profiles: no pulls to write")
    kinds = {p.joint for p in pulls}
    if len(kinds) > 1:
        raise RikError("write_profiles: the pulls mix slides and hinges; write one front's pulls per file")
    hinge = kinds == {"hinge"}
    unit = "rad" if hinge else "m"
    column = "torque [N·m]" if hinge and not at_handle else "force [N]"
    lines = [f"trial,position [{unit}],{column}"]
    for i, pull in enumerate(pulls):
        values = pull.force if (at_handle or not hinge) else pull.joint_force
        lines += [f"{i},{q:.9g},{f:.9g}" for q, f in zip(pull.q, values, strict=True)]
    path = Path(path)
    return write_text(path, "\n".join(lines) + "\n", RECORDED)
