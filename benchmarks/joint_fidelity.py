"""Joint fidelity: a front pushed below its friction stays put, and everything above breakaway is as it was.

MuJoCo's joint ``frictionloss`` is a soft constraint. With MuJoCo's default impedance (``solimpfriction`` 0.9 to
0.95, ``solreffriction`` 20 ms) a front pushed below its friction creeps; rik's joint classes now set
:data:`rik.joints.mjcf.FRICTION_SOLIMP` and :data:`rik.joints.mjcf.FRICTION_SOLREF` (issue 31). Side by side in one
run, for each preset and joint kind (the first front of one variant each, see :data:`KINDS`):

- **after**: the variant's ``model.xml`` as built;
- **before**: the same ``MjSpec`` with every joint's friction impedance set back to MuJoCo's defaults
  (:func:`mujoco_default_friction`).

Measures (generalised forces on the joint through ``qfrc_applied``; N on a slide, N·m on a hinge; the load is
given as a fraction of the preset's ``frictionloss``, in the opening direction):

1. **creep**: a constant push at 25, 50 and 90 % of the friction from rest, held ``--seconds``: mean speed (mm/s,
   deg/s). Drawers and doors start closed. Flaps start at mid-range, where gravity acts on them: there the push
   is chosen so that the NET static load (push plus gravity, ``-qfrc_bias`` at rest with its sign) is that
   fraction (the lift-up flap's push is larger than the fraction, the drop-down flap's smaller or negative: it
   holds the flap back; the push stays constant while gravity changes with the angle: a flap that creeps
   degrees drifts off that load). A run that comes within 1 mm or 1 deg of the open stop ends there. Target
   (after): at most 0.01 mm/s (slides), 0.001 deg/s (hinges, flaps included), at every load shown.
2. **breakaway**: from rest, the net load rising at 2 % of the friction per second from 80 % of it: the load at
   which the joint has moved 0.5 mm or 0.1 deg, as a fraction of the friction. Target (after): within 5 % of 1.
   A model that creeps reaches the threshold below 100 %: the number is then where creep crossed the threshold,
   not a breakaway (marked "crept").
3. **force profile**: the joint opened at 5 mm/s or 5 deg/s, and at a tenth of that (from closed, for flaps too),
   by a stiff PD servo on the joint (a ``position`` actuator whose target ramps at that speed; stiffness from the
   joint's own inertia for a 10 Hz, critically damped servo, see :func:`with_servo`), for ``--seconds``: the
   median, over the motion after its first 0.2 s, of the servo's force minus the gravity load (``qfrc_bias``:
   zero on drawers and doors), against ``frictionloss + damping * v``. Target (after): within 5 %.
4. **motion above breakaway**: distance moved from rest in 0.5 s under a constant net load of 110 % and 150 % of
   the friction, after relative to before. Target: within 2 %. A flap started at mid-range can reach its open
   stop within the 0.5 s (marked "at the stop": the distance is then the stop's).
5. **gripper holding the handle** (the high preset of the drawer and of the door, where asked for): the scene of
   :func:`rik.sim.build.build_scene` (the floating Hand-E on its servoed base); a scripted strategy
   (``grasp_natural``, seed 0) approaches, closes and is stopped once it has closed (its phase turns to
   ``pull``, before it moves the gripper). Then the base's ``y`` servo is switched off (gain and bias 0: the
   gripper floats along the opening direction) and a constant generalised force on that axis pushes the gripper,
   and through the pads' contacts the front, at 90 % of the friction (the force divided by the lever the front
   offers at the pads' point), held ``--seconds`` with the jaws closed and the other axes servoed: creep speed
   of the front's joint, and the scene's real-time factor (``SimScene.step``: the median control step, the two
   scenes stepped in turn).
6. **real-time factor**: simulated seconds per wall second of the 90 % creep run (``mj_step`` in a Python loop,
   one process): ``--repeats`` runs timed in chunks of 0.5 s of simulated time, before and after in turn, the
   median chunk; the ratio also on the thread's CPU time. Target: after at most 10 % below before, judged on the
   CPU-time ratio (on this busy 2-core machine the wall-time ratio of one variant moved between 0.8 and 2.7 from
   run to run, the CPU-time ratio by 0.02).

Every measure but the real-time factor is deterministic (MuJoCo on one thread, fixed seed).

Run: ``uv run python benchmarks/joint_fidelity.py [--presets smooth,normal,high] [--kinds slide,hinge,lift-up,
drop-down] [--seconds 10] [--repeats 3] [--variants DIR] [--out FILE]``.
"""

from __future__ import annotations

import argparse
import math
import platform
import shutil
import subprocess
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np


@dataclass(frozen=True)
class Kind:
    base: str
    handle: str
    start: str
    """``closed`` (the range's lower end) or ``mid`` (its middle; flaps, where gravity acts)."""


KINDS = {
    "slide": Kind("drawer/chest-80", "two_point/bow-128", "closed"),
    "hinge": Kind("door/base-60-left", "knob/mushroom-30", "closed"),
    "lift-up": Kind("flap/lift-up-60", "knob/mushroom-30", "mid"),
    "drop-down": Kind("flap/drop-down-60", "knob/mushroom-30", "mid"),
}
"""Joint kinds measured: a slide (drawer), a hinge (door) and the two flaps (hinges about a horizontal axis)."""
PRESETS = ("smooth", "normal", "high")
MODELS = ("before", "after")
CREEP_LOADS = (0.25, 0.5, 0.9)
CREEP_TARGET = {"slide": 0.01, "hinge": 0.001}
"""Largest creep speed after the fix: mm/s (slide), deg/s (hinge)."""
THRESHOLD = {"slide": 0.5e-3, "hinge": math.radians(0.1)}
"""Motion that counts as breakaway: m, rad."""
STOP_MARGIN = {"slide": 1e-3, "hinge": math.radians(1.0)}
"""A creep run that comes this close to the open end of the range ends there (m, rad): a flap started at mid-range
that creeps at degrees per second can reach its stop within the hold."""
RAMP_START, RAMP_RATE, RAMP_END = 0.8, 0.02, 1.5
"""Breakaway ramp: net load from 80 % of the friction, rising 2 % of it per second, given up at 150 %."""
BREAKAWAY_TOLERANCE = 0.05
PROFILE_SPEEDS = {"slide": (5e-3, 0.5e-3), "hinge": (math.radians(5.0), math.radians(0.5))}
"""Opening speeds of the force profile: m/s, rad/s (the asked 5 mm/s or 5 deg/s, and a tenth of it, below the speed
at which MuJoCo's default friction impedance saturates)."""
PROFILE_SKIP = 0.2
"""Start of the profile left out (the servo's acceleration), s."""
SERVO_HZ = 10.0
"""Natural frequency of the profile's PD servo, Hz (critically damped)."""
PROFILE_TOLERANCE = 0.05
MOTION_LOADS = (1.1, 1.5)
MOTION_SECONDS = 0.5
MOTION_TOLERANCE = 0.02
RTF_TOLERANCE = 0.10
RTF_CHUNK = 0.5
"""Simulated seconds per timed chunk of the real-time factor."""
GRIPPER_LOAD = 0.9
GRIPPER_STRATEGY = "grasp_natural"
GRIPPER_KINDS = ("slide", "hinge")
UNITS = {"slide": ("mm", 1e3), "hinge": ("deg", 180.0 / math.pi)}
SERVO = "joint_fidelity/servo"


def mujoco_default_friction(spec: Any) -> None:
    """MuJoCo's defaults, rik before issue 31: every joint's friction impedance set back to ``solimpfriction``
    ``0.9 0.95 0.001 0.5 2`` and ``solreffriction`` ``0.02 1`` (``spec`` is a ``mujoco.MjSpec``, changed in
    place)."""
    for joint in spec.joints:
        joint.solimp_friction = [0.9, 0.95, 0.001, 0.5, 2.0]
        joint.solref_friction = [0.02, 1.0]


def load_spec(directory: Path, which: str) -> Any:
    """The ``MjSpec`` of a built variant's ``model.xml``: as built (``after``) or with MuJoCo's default friction
    impedance (``before``)."""
    import mujoco

    spec = mujoco.MjSpec.from_file(str(directory / "model.xml"))
    if which == "before":
        mujoco_default_friction(spec)
    return spec


@dataclass
class Front:
    """A compiled variant (its first front's joint) and the start state of the measures."""

    model: Any
    data: Any
    joint: str
    type: str
    """``slide`` or ``hinge``."""
    dof: int
    qadr: int
    frictionloss: float
    damping: float
    q0: float

    def reset(self) -> float:
        """Rest at the start position; returns the gravity load there as ``qfrc_bias`` (opposite to gravity's
        generalised force: a push of ``f + bias`` makes a net load of ``f``)."""
        import mujoco

        m, d = self.model, self.data
        mujoco.mj_resetData(m, d)
        d.qpos[self.qadr] = self.q0
        mujoco.mj_forward(m, d)
        return float(d.qfrc_bias[self.dof])

    def q(self) -> float:
        return float(self.data.qpos[self.qadr])


def compile_front(spec: Any, kind: Kind) -> Front:
    import mujoco

    model = spec.compile()
    joint = 0  # every variant's first joint is its first front's
    lo, hi = model.jnt_range[joint]
    jtype = "slide" if model.jnt_type[joint] == mujoco.mjtJoint.mjJNT_SLIDE else "hinge"
    dof = int(model.jnt_dofadr[joint])
    return Front(model, mujoco.MjData(model), model.joint(joint).name, jtype, dof, int(model.jnt_qposadr[joint]),
                 float(model.dof_frictionloss[dof]), float(np.ravel(model.dof_damping[dof])[0]),
                 float(lo) if kind.start == "closed" else float(lo + hi) / 2)


def steps(front: Front, seconds: float) -> int:
    return int(round(seconds / front.model.opt.timestep))


# ---- the measures --------------------------------------------------------------------------------------------
def creep(front: Front, load: float, seconds: float) -> tuple[float, float | None]:
    """Mean speed (SI) under a constant net load (fraction of the friction) from rest over ``seconds``, or until the
    joint comes within :data:`STOP_MARGIN` of the open end of its range (then also that time, s; else None)."""
    import mujoco

    m, d = front.model, front.data
    bias = front.reset()
    d.qfrc_applied[front.dof] = load * front.frictionloss + bias
    stop = float(m.jnt_range[0][1]) - STOP_MARGIN[front.type]
    n = steps(front, seconds)
    for k in range(n):
        mujoco.mj_step(m, d)
        if front.q() >= stop:
            return (front.q() - front.q0) / ((k + 1) * m.opt.timestep), (k + 1) * m.opt.timestep
    return (front.q() - front.q0) / (n * m.opt.timestep), None


def breakaway(front: Front) -> float | None:
    """The net load (fraction of the friction) at which the joint has moved :data:`THRESHOLD` under the ramp; None
    if it has not by :data:`RAMP_END`."""
    import mujoco

    m, d = front.model, front.data
    bias = front.reset()
    dt, threshold = m.opt.timestep, THRESHOLD[front.type]
    for k in range(steps(front, (RAMP_END - RAMP_START) / RAMP_RATE)):
        load = RAMP_START + RAMP_RATE * k * dt
        d.qfrc_applied[front.dof] = load * front.frictionloss + bias
        mujoco.mj_step(m, d)
        if abs(front.q() - front.q0) >= threshold:
            return load
    return None


def motion(front: Front, load: float) -> tuple[float, bool]:
    """Distance moved (SI) from rest in :data:`MOTION_SECONDS` under a constant net load (fraction of friction), and
    whether the joint reached its open stop (within :data:`STOP_MARGIN`) on the way: then the distance is the
    stop's, not the load's."""
    import mujoco

    m, d = front.model, front.data
    bias = front.reset()
    d.qfrc_applied[front.dof] = load * front.frictionloss + bias
    stop, reached = float(m.jnt_range[0][1]) - STOP_MARGIN[front.type], False
    for _ in range(steps(front, MOTION_SECONDS)):
        mujoco.mj_step(m, d)
        reached = reached or front.q() >= stop
    return front.q() - front.q0, reached


def with_servo(directory: Path, which: str, kind: Kind) -> tuple[Front, int]:
    """The variant with a PD servo on its first front's joint (a ``position`` actuator): stiffness ``M w^2`` and
    damping ``2 M w`` for the joint's inertia ``M`` (armature included) and ``w = 2 pi`` :data:`SERVO_HZ`: its lag
    under the full friction is 0.8 mm on the high-preset drawer. Returns the front (starting closed) and the
    servo's actuator id."""
    import mujoco

    plain = compile_front(load_spec(directory, which), kind)
    plain.reset()
    inertia = np.zeros((plain.model.nv, plain.model.nv))
    mujoco.mj_fullM(plain.model, plain.data, inertia)
    mass = float(inertia[plain.dof, plain.dof])
    w = 2.0 * math.pi * SERVO_HZ
    spec = load_spec(directory, which)
    act = spec.add_actuator(name=SERVO, target=plain.joint, trntype=mujoco.mjtTrn.mjTRN_JOINT)
    act.set_to_position(kp=mass * w * w, kv=2.0 * mass * w)
    front = compile_front(spec, Kind(kind.base, kind.handle, "closed"))
    return front, int(mujoco.mj_name2id(front.model, mujoco.mjtObj.mjOBJ_ACTUATOR, SERVO))


def profile(front: Front, actuator: int, seconds: float, speed: float) -> tuple[float, float]:
    """The median of the servo's force minus the gravity load while it opens the joint at ``speed`` (after its
    first :data:`PROFILE_SKIP` s), and ``frictionloss + damping * speed``."""
    import mujoco

    m, d = front.model, front.data
    front.reset()
    lo, hi = m.jnt_range[0]
    seconds = min(seconds, 0.9 * float(hi - lo) / speed)
    dt, forces = m.opt.timestep, []
    for k in range(steps(front, seconds)):
        d.ctrl[actuator] = front.q0 + speed * k * dt
        mujoco.mj_step(m, d)  # actuator_force and qfrc_bias: of the state the step started from
        if k * dt >= PROFILE_SKIP:
            forces.append(float(d.actuator_force[actuator]) - float(d.qfrc_bias[front.dof]))
    return float(np.median(forces)), front.frictionloss + front.damping * speed


def real_time_factors(fronts: dict[str, Front], seconds: float,
                      repeats: int) -> tuple[dict[str, float], dict[str, float]]:
    """Simulated seconds per wall second of each model's 90 % creep run: ``repeats`` runs of ``seconds``, timed in
    chunks of :data:`RTF_CHUNK` s of simulated time that alternate between the models (so both share whatever else
    loads the machine); the median chunk. Also the same per second of the thread's CPU time (``time.thread_time``:
    time the process waits for a core on a busy machine is not counted)."""
    import mujoco

    wall: dict[str, list[float]] = {w: [] for w in fronts}
    cpu: dict[str, list[float]] = {w: [] for w in fronts}
    for _ in range(repeats):
        for f in fronts.values():
            f.data.qfrc_applied[f.dof] = 0.9 * f.frictionloss + f.reset()
        for c in range(max(1, int(round(seconds / RTF_CHUNK)))):
            for w in (list(fronts) if c % 2 == 0 else list(reversed(fronts))):
                m, d = fronts[w].model, fronts[w].data
                n = steps(fronts[w], RTF_CHUNK)
                start, start_cpu = time.perf_counter(), time.thread_time()
                for _ in range(n):
                    mujoco.mj_step(m, d)
                wall[w].append(time.perf_counter() - start)
                cpu[w].append(time.thread_time() - start_cpu)
    return ({w: RTF_CHUNK / float(np.median(t)) for w, t in wall.items()},
            {w: RTF_CHUNK / float(np.median(t)) for w, t in cpu.items()})


def before_copy(directory: Path, where: Path) -> Path:
    """A copy of the variant folder ``directory`` under ``where`` whose ``model.xml`` has MuJoCo's default
    friction impedance (:func:`mujoco_default_friction`)."""
    out = where / directory.name
    shutil.copytree(directory, out)
    (out / "model.xml").write_text(load_spec(directory, "before").to_xml())
    return out


@dataclass
class Grip:
    """A scene whose gripper holds the operated handle and pushes it (:func:`grasp_and_push`)."""

    scene: Any
    action: np.ndarray
    """The operator's last action (the closed grasp), repeated while holding."""
    q0: float
    grasped: bool
    plan: str
    force: float
    """On the gripper's y axis, N."""
    lever: float
    """The front's generalised force per N on the gripper's y axis (1 on a drawer, m on a door)."""


def grasp_and_push(directory: Path) -> Grip:
    """Grasp the variant's first front's handle with the Hand-E (:data:`GRIPPER_STRATEGY`, seed 0, stopped once
    closed: its phase turns to ``pull`` on the control step after the jaws have had their closing time), then
    switch the base's y servo off and push the gripper along y at :data:`GRIPPER_LOAD` of the front's friction."""
    import mujoco

    from rik.episodes.operators import make_operator
    from rik.sim.build import build_scene
    from rik.sim.robots.gripper import GRIPPER_PREFIX

    scene = build_scene(directory)
    m, d = scene.model, scene.data
    operator = make_operator(GRIPPER_STRATEGY)
    operator.reset(scene, np.random.default_rng(0))
    action = np.concatenate([scene.pose(), [0.0]])
    for _ in range(int(10 * scene.control_fps)):
        if operator._phase == "pull" or operator.done:  # closed on the handle; the next act would start the pull
            break
        action = operator.act(scene)
        scene.step(action)
    y_joint = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, GRIPPER_PREFIX + "y")
    y_servo = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_ACTUATOR, GRIPPER_PREFIX + "y")
    m.actuator_gainprm[y_servo, 0] = 0.0
    m.actuator_biasprm[y_servo, :3] = 0.0
    jac = np.zeros((3, m.nv))
    mujoco.mj_jac(m, d, jac, None, scene.tcp(), scene.front.body)
    lever = float(d.xaxis[y_joint] @ jac[:, scene.front.dof_adr])
    force = GRIPPER_LOAD * float(m.dof_frictionloss[scene.front.dof_adr]) / lever
    d.qfrc_applied[int(m.jnt_dofadr[y_joint])] = force
    return Grip(scene, action, scene.front_q()[0], operator._phase == "pull",
                operator.log[-1] if operator.log else "", force, lever)


def hold(grips: dict[str, Grip], seconds: float) -> dict[str, tuple[float, float]]:
    """Step every scene ``seconds`` with its gripper holding and pushing, control step by control step in turn:
    each front's creep speed (SI) and each scene's real-time factor (``SimScene.step``, median control step)."""
    times: dict[str, list[float]] = {w: [] for w in grips}
    for k in range(int(round(seconds * next(iter(grips.values())).scene.control_fps))):
        for w in (list(grips) if k % 2 == 0 else list(reversed(grips))):
            start = time.perf_counter()
            grips[w].scene.step(grips[w].action)
            times[w].append(time.perf_counter() - start)
    out = {}
    for w, g in grips.items():
        step = g.scene.substeps * g.scene.model.opt.timestep
        out[w] = ((g.scene.front_q()[0] - g.q0) / (len(times[w]) * step), step / float(np.median(times[w])))
    return out


# ---- tables ---------------------------------------------------------------------------------------------------
def verdict(ok: bool) -> str:
    return "PASS" if ok else "**FAIL**"


def fmt(x: float) -> str:
    """Three significant digits."""
    return f"{x:.3g}" if abs(x) < 1000 else f"{x:.0f}"


def table(header: list[str], rows: list[list[str]]) -> list[str]:
    align = ["---" if i < 2 else "---:" for i in range(len(header))]
    return ["| " + " | ".join(header) + " |", "|" + "|".join(align) + "|", *("| " + " | ".join(r) + " |" for r in rows)]


def environment() -> str:
    import mujoco

    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                            cwd=Path(__file__).parent, check=False).stdout.strip()
    return f"Python {platform.python_version()}, mujoco {mujoco.__version__}, commit {commit or 'unknown'}"


@dataclass
class Report:
    creep: list[list[str]]
    breakaway: list[list[str]]
    profile: list[list[str]]
    motion: list[list[str]]
    rtf: list[list[str]]
    gripper: list[list[str]]


def measure_variant(report: Report, kind_name: str, preset: str, directory: Path, args: argparse.Namespace,
                    tmp: Path) -> None:
    """Every measure of one variant, before and after, appended to the report's rows."""
    kind = KINDS[kind_name]
    fronts = {w: compile_front(load_spec(directory, w), kind) for w in MODELS}
    jtype = fronts["after"].type
    unit, scale = UNITS[jtype]
    force_unit = "N" if jtype == "slide" else "N·m"
    fl = fronts["after"].frictionloss
    label = [kind_name, preset]
    for load in CREEP_LOADS:
        shown = {}
        for w in MODELS:
            speed, stopped = creep(fronts[w], load, args.seconds)
            shown[w] = (f"{fmt(speed * scale)} {unit}/s" + (f" (stop after {stopped:.1f} s)" if stopped else ""),
                        speed * scale)
        target = CREEP_TARGET[jtype]
        report.creep.append([*label, f"{load:.0%}", shown["before"][0], shown["after"][0], f"≤ {target:g} {unit}/s",
                             verdict(abs(shown["after"][1]) <= target)])

    def crossed(x: float | None) -> str:
        if x is None:
            return f"none below {RAMP_END:.0%}"
        return f"{x:.3f}" + (" (crept)" if x < 1.0 - BREAKAWAY_TOLERANCE else "")

    found = {w: breakaway(fronts[w]) for w in MODELS}
    after = found["after"]
    report.breakaway.append([*label, f"{fl:g} {force_unit}", crossed(found["before"]), crossed(after),
                             f"1 ± {BREAKAWAY_TOLERANCE:g}",
                             verdict(after is not None and abs(after - 1.0) <= BREAKAWAY_TOLERANCE)])
    servoed = {w: with_servo(directory, w, kind) for w in MODELS}
    for speed in PROFILE_SPEEDS[jtype]:
        medians = {}
        for w in MODELS:
            medians[w], expected = profile(*servoed[w], args.seconds, speed)
        ratio = medians["after"] / expected
        report.profile.append([*label, f"{speed * scale:g} {unit}/s", f"{expected:.3f} {force_unit}",
                               f"{medians['before']:.3f} ({medians['before'] / expected:.3f})",
                               f"{medians['after']:.3f} ({ratio:.3f})", f"1 ± {PROFILE_TOLERANCE:g}",
                               verdict(abs(ratio - 1.0) <= PROFILE_TOLERANCE)])
    for load in MOTION_LOADS:
        runs = {w: motion(fronts[w], load) for w in MODELS}
        moved = {w: runs[w][0] * scale for w in MODELS}
        cells = {w: f"{moved[w]:.3f} {unit}" + (" (at the stop)" if runs[w][1] else "") for w in MODELS}
        ratio = moved["after"] / moved["before"]
        report.motion.append([*label, f"{load:.0%}", cells["before"], cells["after"],
                              f"{ratio:.4f}", f"1 ± {MOTION_TOLERANCE:g}",
                              verdict(abs(ratio - 1.0) <= MOTION_TOLERANCE)])
    rtf, rtf_cpu = real_time_factors(fronts, args.seconds, args.repeats)
    ratio = rtf_cpu["after"] / rtf_cpu["before"]
    report.rtf.append([*label, f"{rtf['before']:.0f}", f"{rtf['after']:.0f}", f"{rtf['after'] / rtf['before']:.2f}",
                       f"{ratio:.2f}", f"≥ {1 - RTF_TOLERANCE:.2f}", verdict(ratio >= 1.0 - RTF_TOLERANCE)])
    if preset == "high" and kind_name in GRIPPER_KINDS:
        grips = {"before": grasp_and_push(before_copy(directory, tmp / "before")), "after": grasp_and_push(directory)}
        held = hold(grips, args.seconds)
        target = CREEP_TARGET[jtype]
        creeps = {w: held[w][0] * scale for w in MODELS}
        a = grips["after"]
        contacts = a.scene.contact_summary()["contacts"]
        grasp = (f"{a.plan} ({'closed' if a.grasped else 'NOT grasped'}); {a.force:.1f} N on the gripper, lever "
                 f"{a.lever:.3f}{' m' if jtype == 'hinge' else ''}; {contacts:.0f} contacts")
        ok = all(g.grasped for g in grips.values()) and abs(creeps["after"]) <= target
        report.gripper.append([directory.name, grasp, f"{fmt(creeps['before'])} {unit}/s",
                               f"{fmt(creeps['after'])} {unit}/s", f"≤ {target:g} {unit}/s", verdict(ok),
                               f"{held['before'][1]:.0f}", f"{held['after'][1]:.0f}",
                               f"{held['after'][1] / held['before'][1]:.2f}"])


def render(report: Report, args: argparse.Namespace, wall: float) -> str:
    lines = [f"Joint fidelity, `--seconds {args.seconds:g} --repeats {args.repeats}`, {environment()}", "",
             f"### 1. Creep under a constant push, held {args.seconds:g} s (mean speed; flaps from mid-range, net load "
             "with gravity)", ""]
    lines += table(["kind", "preset", "net load", "before", "after", "target (after)", "after"], report.creep)
    lines += ["", f"### 2. Breakaway: net load rising {RAMP_RATE:.0%} of the friction per second from "
              f"{RAMP_START:.0%}, at 0.5 mm or 0.1 deg moved (/ frictionloss)", ""]
    lines += table(["kind", "preset", "frictionloss", "before", "after", "target (after)", "after"], report.breakaway)
    lines += ["", "### 3. Quasi-static force profile: PD servo opening the joint (median of servo force minus gravity "
              "load; its ratio to frictionloss + damping·v)", ""]
    lines += table(["kind", "preset", "speed", "frictionloss + damping·v", "before", "after", "target (after)",
                    "after"], report.profile)
    lines += ["", f"### 4. Motion above breakaway: distance from rest in {MOTION_SECONDS:g} s", ""]
    lines += table(["kind", "preset", "net load", "before", "after", "after/before", "target", "after"],
                   report.motion)
    if report.gripper:
        lines += ["", f"### 5. Gripper holding the handle, pushed at {GRIPPER_LOAD:.0%} of the friction for "
                  f"{args.seconds:g} s (creep of the front; real-time factor of the scene)", ""]
        lines += table(["variant", "grasp (after)", "creep before", "creep after", "target (after)", "after",
                        "RTF before", "RTF after", "after/before"], report.gripper)
    lines += ["", f"### 6. Real-time factor of the 90 % creep run (median {RTF_CHUNK:g} s chunk, {args.repeats} "
              "runs interleaved)", ""]
    lines += table(["kind", "preset", "before", "after", "after/before", "after/before, CPU time",
                    "target (CPU time)", "after"], report.rtf)
    lines += ["", f"Benchmark wall time: {wall:.1f} s (variant builds included)."]
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--presets", default=",".join(PRESETS))
    parser.add_argument("--kinds", default=",".join(KINDS), help=f"of {', '.join(KINDS)}")
    parser.add_argument("--seconds", type=float, default=10.0, help="creep hold, profile and gripper hold, s")
    parser.add_argument("--repeats", type=int, default=3, help="timed runs per model for the real-time factor")
    parser.add_argument("--variants", type=Path, help="variants folder (default: a temporary one)")
    parser.add_argument("--out", type=Path, help="also write the tables to this markdown file")
    args = parser.parse_args()
    presets = [p for p in args.presets.split(",") if p]
    kinds = [k for k in args.kinds.split(",") if k]
    if unknown := [k for k in kinds if k not in KINDS]:
        parser.error(f"unknown kinds {unknown}: choose from {', '.join(KINDS)}")

    from rik.combinator.build import ensure_variant
    from rik.registry import load_catalog
    from rik.registry.ids import variant_id

    catalog = load_catalog()
    started = time.perf_counter()
    report = Report([], [], [], [], [], [])
    with tempfile.TemporaryDirectory() as tmp:
        variants = args.variants or Path(tmp) / "variants"
        variants.mkdir(parents=True, exist_ok=True)
        for kind_name in kinds:
            for preset in presets:
                directory = ensure_variant(catalog, variant_id(KINDS[kind_name].base, KINDS[kind_name].handle, preset),
                                        variants)
                measure_variant(report, kind_name, preset, directory, args, Path(tmp))
                print(f"measured {directory.name}", flush=True)
    text = render(report, args, time.perf_counter() - started)
    print(text)
    if args.out:
        args.out.write_text(text + "\n")


if __name__ == "__main__":
    main()
