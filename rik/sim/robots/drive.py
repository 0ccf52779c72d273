"""How a scene's robot takes rik's action: the target pose of the gripper (x, y, z m; pitch, yaw, roll rad, as the
Hand-E's base) and a gripper command (0 open, 1 closed with the full grip force).

- :class:`FloatingDrive`: the Hand-E on six servoed axes: the pose is the axes' targets, as it always was;
- :class:`ArmDrive`: an arm: the pose of its gripper frame is turned into joint targets by one IK step per control
  step (:mod:`rik.sim.robots.ik`). The IK starts from the joints' previous targets (the servos' controls), so a blocked
  arm's targets run ahead of its joints and its servos push, but never further ahead than full torque needs (or
  one control step at full speed): it cannot wind up. Everything the IK reads is in MuJoCo's integration state
  (positions and controls), so a recorded episode re-simulates exactly.

Every operator (the scripted strategies, the teleop front-ends, the gym env's pose actions) works with either.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from rik.errors import RikError
from rik.sim.pose import angles_of, base_for_tcp, gripper_rotation
from rik.sim.robots.arm import ROBOT_PREFIX, Placement
from rik.sim.robots.gripper import jaw_target
from rik.sim.robots.reach import (
    OPENINGS,
    REACH_TOLERANCE,
    handle_words,
    natural_grasp,
    reachable_opening,
    reached,
    set_opening,
)
from rik.sim.robots.results import CheckResult, ReachPoint

PROBE_ITERATIONS = 40
"""IK steps a planner's collision probe of an arm takes towards the probed pose (the floor is then checked by
collision, not by the IK's limit)."""
HALF_TURN = np.diag([-1.0, -1.0, 1.0])
"""Half a turn about the gripper frame's z (the approach): how a mirrored arm holds its parallel jaws."""
TRACKING_GAIN = 0.5
"""An arm's servos sag under gravity and lag under load: each control step the IK aims past the target by this
fraction of the gap between the gripper frame where the servos aim and where it is (0: plain open-loop IK)."""

if TYPE_CHECKING:
    import mujoco

    from rik.schemas.robots import Robot
    from rik.sim.robots.ik import ArmIK
    from rik.sim.scene import SimScene


def _touches(scene: SimScene, geoms: frozenset[int], ignore_bodies: frozenset[int] = frozenset()) -> bool:
    """Whether any of ``geoms`` penetrates anything but geoms of ``ignore_bodies``, with the scene's current
    positions (collision only)."""
    import mujoco

    m, d = scene.model, scene.data
    mujoco.mj_collision(m, d)
    for i in range(d.ncon):
        g1, g2 = int(d.contact.geom1[i]), int(d.contact.geom2[i])
        if (g1 in geoms or g2 in geoms) and d.contact.dist[i] < 0 \
                and int(m.geom_bodyid[g1]) not in ignore_bodies and int(m.geom_bodyid[g2]) not in ignore_bodies:
            return True
    return False


@dataclass
class FloatingDrive:
    """The Hand-E's base: three slides and three hinges whose servo targets are the pose itself."""

    base_qpos: np.ndarray
    finger_qpos: np.ndarray
    arm_ctrl: np.ndarray
    jaw_ctrl: int
    robot_id: str = "hand-e"
    joint_names: tuple[str, ...] = ("x", "y", "z", "pitch", "yaw", "roll", "jaw_opening")

    def pose(self, scene: SimScene) -> np.ndarray:
        return scene.data.qpos[self.base_qpos].copy()

    def place(self, scene: SimScene, pose: np.ndarray, grip: float) -> None:
        import mujoco

        g = scene.gripper
        scene.data.qpos[self.base_qpos] = pose
        scene.data.qvel[:] = 0.0
        opening = min(max(jaw_target(g, grip), 0.0), g.stroke)
        scene.data.qpos[self.finger_qpos] = opening / 2
        scene.data.ctrl[self.arm_ctrl] = pose
        scene.data.ctrl[self.jaw_ctrl] = opening
        mujoco.mj_forward(scene.model, scene.data)

    def command(self, scene: SimScene, action: np.ndarray) -> None:
        scene.data.ctrl[self.arm_ctrl] = action[:6]

    def jaw(self, scene: SimScene, command: float) -> tuple[float, float]:
        return jaw_target(scene.gripper, command), 2.0 * scene.gripper.finger_speed * scene.model.opt.timestep

    def finger_opening(self, scene: SimScene) -> float:
        return float(scene.data.qpos[self.finger_qpos].sum())

    def joints(self, scene: SimScene) -> np.ndarray:
        return np.concatenate([scene.data.qpos[self.base_qpos], [self.finger_opening(scene)]])

    def targets(self, scene: SimScene, action: np.ndarray) -> np.ndarray:
        return np.concatenate([scene.data.ctrl[self.arm_ctrl], [jaw_target(scene.gripper, float(action[6]))]])

    def pose_is_free(self, scene: SimScene, pose: np.ndarray, opening: float,
                     ignore_bodies: frozenset[int] = frozenset()) -> bool:
        import mujoco

        m, d = scene.model, scene.data
        saved = d.qpos.copy()
        d.qpos[self.base_qpos] = pose
        d.qpos[self.finger_qpos] = opening
        mujoco.mj_kinematics(m, d)
        free = not _touches(scene, scene.gripper_geoms, ignore_bodies)
        d.qpos[:] = saved
        mujoco.mj_forward(m, d)
        return free


    @property
    def mount(self) -> Placement | None:
        return None

    def set_targets(self, scene: SimScene, q: np.ndarray) -> None:
        raise RikError(f"robot {self.robot_id} takes a target pose, not joint targets")

    def joint_positions(self, scene: SimScene) -> np.ndarray:
        return scene.data.qpos[self.base_qpos].copy()

    def closure(self, scene: SimScene) -> float:
        return 1.0 - self.finger_opening(scene) / scene.gripper.stroke

    def geoms(self, scene: SimScene) -> frozenset[int]:
        return scene.gripper_geoms

    def reach(self, scene: SimScene, openings: tuple[float, ...], force: float) -> list[ReachPoint]:
        """The base's servos reach every pose in the scene: every grasp is met exactly."""
        return [ReachPoint(o, 0.0, 0.0, (), 0.0, "") for o in openings]

    def hold_reach(self, scene: SimScene, offset: np.ndarray, angles: np.ndarray,
                   position_first: bool = False) -> float:
        """The base's servos hold any grasp over the whole opening: 1."""
        return 1.0

    def reach_checks(self, scene: SimScene, force: float) -> list[CheckResult]:
        g = scene.gripper
        share = force / g.arm_force
        return [CheckResult("reach", True, "the floating base reaches every opening", {"reachable_opening": 1}),
                CheckResult("torque_headroom", share <= 1.0, f"holding {force:.1f} N needs {share:.0%} of the "
                            f"base's {g.arm_force:.0f} N", {"resistance_N": round(force, 2),
                                                             "largest_share": round(share, 3)})]


@dataclass
class ArmDrive:
    """An arm driven through its IK (see the module docstring)."""

    robot: Robot
    ik: ArmIK
    placement: Placement
    qpos: np.ndarray
    """Addresses of the arm joints in ``qpos``."""
    arm_ctrl: np.ndarray
    jaw_ctrl: int
    opening_qpos: int
    robot_geoms: frozenset[int]
    dofs: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    """Addresses of the arm joints in ``qvel`` (and the Jacobians' columns)."""
    lead: np.ndarray = field(default_factory=lambda: np.zeros(0))
    """Largest lead of a joint's target over its position, rad."""
    robot_id: str = ""
    joint_names: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        assert self.robot.joints is not None
        self.robot_id = self.robot.id
        self.joint_names = (*self.robot.joint_names, "gripper")
        self._lower = np.array([j.range[0] for j in self.robot.joints.joints])
        self._upper = np.array([j.range[1] for j in self.robot.joints.joints])

    # ---- the gripper frame ------------------------------------------------------------------------------------
    def _frame_target(self, scene: SimScene, pose: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        rot = gripper_rotation(np.asarray(pose[3:6], float))
        if self.placement.mirrored:
            rot = rot @ HALF_TURN
        return np.asarray(pose[:3], float) + rot[:, 2] * scene.gripper.tcp_offset, rot

    def pose(self, scene: SimScene) -> np.ndarray:
        rot = scene.gripper_rotation()
        if self.placement.mirrored:
            rot = rot @ HALF_TURN
        return np.concatenate([scene.tcp() - rot[:, 2] * scene.gripper.tcp_offset, angles_of(rot)])

    # ---- placing and commanding -------------------------------------------------------------------------------
    def _solve(self, scene: SimScene, pose: np.ndarray) -> np.ndarray:
        position, rotation = self._frame_target(scene, pose)
        q, _, _ = self.ik.solve(position, rotation)
        return q

    def place(self, scene: SimScene, pose: np.ndarray, grip: float) -> None:
        import mujoco

        q = self._solve(scene, pose)
        m, d = scene.model, scene.data
        d.qvel[:] = 0.0
        d.qpos[self.qpos] = q
        d.ctrl[self.arm_ctrl] = q
        goal, _ = self.jaw(scene, grip)
        d.ctrl[self.jaw_ctrl] = goal
        act = self.robot.gripper.actuation
        assert act is not None
        if act.joint is not None:  # a one-joint jaw starts where the command puts it (a linkage starts open)
            c = min(max(grip, 0.0), 1.0)
            d.qpos[self.opening_qpos] = act.joint_open + c * (act.joint_closed - act.joint_open)
        mujoco.mj_forward(m, d)

    def command(self, scene: SimScene, action: np.ndarray) -> None:
        d = scene.data
        position, rotation = self._frame_target(scene, action)
        q_cmd = d.ctrl[self.arm_ctrl].copy()
        if TRACKING_GAIN > 0:  # aim past the target by the gap between where the servos aim and where they are
            # both frames from joint positions alone (the IK's kinematics): mjData's derived positions are those
            # before the last integration while recording but fresh after a replay's restore
            p_cmd, r_cmd = self.ik.frame(q_cmd)
            p_now, r_now = self.ik.frame(d.qpos[self.qpos])
            position = position + TRACKING_GAIN * (p_cmd - p_now)
            rotation = _fraction(r_cmd @ r_now.T, TRACKING_GAIN) @ rotation
        self.set_targets(scene, self.ik.step(q_cmd, position, rotation, 1.0 / scene.control_fps))

    def set_targets(self, scene: SimScene, q: np.ndarray) -> None:
        """Servo targets ``q`` (rad), held within the joints' ranges and within :attr:`lead` of where the joints
        are."""
        d = scene.data
        now = d.qpos[self.qpos]
        q = np.clip(np.asarray(q, float), now - self.lead, now + self.lead)
        d.ctrl[self.arm_ctrl] = np.clip(q, self._lower, self._upper)

    def jaw(self, scene: SimScene, command: float) -> tuple[float, float]:
        act = self.robot.gripper.actuation
        assert act is not None
        c = min(max(command, 0.0), 1.0)
        span = act.ctrl_closed - act.ctrl_open
        rate = abs(span) * 2.0 * scene.gripper.finger_speed / scene.gripper.stroke
        return act.ctrl_open + c * span, rate * scene.model.opt.timestep

    def closure(self, scene: SimScene) -> float:
        """How closed the jaws are: 0 fully open, 1 touching (a fraction of the stroke; may pass 1 a little)."""
        act = self.robot.gripper.actuation
        assert act is not None
        q = float(scene.data.qpos[self.opening_qpos])
        return (q - act.joint_open) / (act.joint_closed - act.joint_open)

    def finger_opening(self, scene: SimScene) -> float:
        return float(scene.gripper.stroke * min(max(1.0 - self.closure(scene), 0.0), 1.0))

    def joints(self, scene: SimScene) -> np.ndarray:
        return np.concatenate([scene.data.qpos[self.qpos], [scene.data.qpos[self.opening_qpos]]])

    def targets(self, scene: SimScene, action: np.ndarray) -> np.ndarray:
        goal, _ = self.jaw(scene, float(action[6]))
        return np.concatenate([scene.data.ctrl[self.arm_ctrl], [goal]])

    def pose_is_free(self, scene: SimScene, pose: np.ndarray, opening: float,
                     ignore_bodies: frozenset[int] = frozenset()) -> bool:
        """Whether the arm, solved to ``pose`` from where its joints are, touches nothing but ``ignore_bodies``
        (gripper open)."""
        import mujoco

        m, d = scene.model, scene.data
        saved = d.qpos.copy()
        position, rotation = self._frame_target(scene, pose)
        q, dp, _ = self.ik.solve(position, rotation, d.qpos[self.qpos], iterations=PROBE_ITERATIONS, floor=False)
        d.qpos[self.qpos] = q
        mujoco.mj_kinematics(m, d)
        free = dp < 0.01 and not _touches(scene, self.robot_geoms, ignore_bodies)
        d.qpos[:] = saved
        mujoco.mj_forward(m, d)
        return free


    @property
    def mount(self) -> Placement | None:
        return self.placement

    def joint_positions(self, scene: SimScene) -> np.ndarray:
        return scene.data.qpos[self.qpos].copy()

    def geoms(self, scene: SimScene) -> frozenset[int]:
        return self.robot_geoms

    def reach(self, scene: SimScene, openings: tuple[float, ...], force: float) -> list[ReachPoint]:
        return _arm_reach_profile(scene, self, openings, force)

    def hold_reach(self, scene: SimScene, offset: np.ndarray, angles: np.ndarray,
                   position_first: bool = False) -> float:
        return _arm_hold_reach(scene, self, offset, angles, position_first)

    def reach_checks(self, scene: SimScene, force: float) -> list[CheckResult]:
        return _arm_reach_checks(scene, self, force)


def _torque_use(scene: SimScene, drive: ArmDrive, q: np.ndarray, force: float) -> tuple[float, str]:
    """Largest share of a joint's torque an arm at ``q`` needs to pull with ``force`` N along the pull at its
    gripper frame and hold itself up; and that joint's name."""
    import mujoco

    assert drive.robot.joints is not None
    m, d = scene.model, scene.data
    saved = (d.qpos.copy(), d.qvel.copy())
    d.qpos[drive.qpos] = q
    d.qvel[:] = 0.0
    mujoco.mj_forward(m, d)
    jacp = np.zeros((3, m.nv))
    mujoco.mj_jacSite(m, d, jacp, None, scene.tcp_site)
    dofs = drive.dofs
    pull = scene.pull_direction()
    # at rest qfrc_bias is gravity: the motors carry it, compensated or not
    tau = jacp[:, dofs].T @ (force * pull) + d.qfrc_bias[dofs]
    limits = np.array([j.torque for j in drive.robot.joints.joints])
    share = np.abs(tau) / limits
    worst = int(np.argmax(share))
    d.qpos[:], d.qvel[:] = saved
    mujoco.mj_forward(m, d)
    return float(share[worst]), drive.robot.joints.joints[worst].name


HOLD_STEPS = tuple(np.round(np.linspace(0.0, 1.0, 11), 2))
"""Openings at which :func:`_arm_hold_reach` solves the arm, fractions of the front's range."""


def _arm_hold_reach(scene: SimScene, drive: ArmDrive, offset: np.ndarray, angles: np.ndarray,
                    position_first: bool = False) -> float:
    """:meth:`Drive.hold_reach` of an arm: from the front's opening now on, each of :data:`HOLD_STEPS` solved by its
    IK from the previous one's posture (with position-first steps where ``position_first``:
    :meth:`rik.sim.robots.ik.ArmIK.step`), the gripper frame at the grasp point plus ``offset`` (m, world) with
    ``angles``, met within :data:`rik.sim.robots.reach.REACH_TOLERANCE`; the largest opening met, -1 for none. The
    scene is left as it was."""
    saved = scene.state()
    best, q = -1.0, None
    lo, hi = scene.front.range
    now = (float(scene.data.qpos[scene.front.qpos_adr]) - lo) / (hi - lo) if hi > lo else 0.0
    try:
        for opening in HOLD_STEPS:
            if opening < now - 1e-6:
                continue
            set_opening(scene, float(opening))
            pose = base_for_tcp(scene.gripper, scene.grasp_point() + offset, angles)
            position, rotation = drive._frame_target(scene, pose)
            q, dp, da = drive.ik.solve(position, rotation, q, position_first=position_first)
            if dp > REACH_TOLERANCE[0] or da > REACH_TOLERANCE[1]:
                break
            best = float(opening)
    finally:
        scene.restore(saved)
    return best


def _arm_reach_profile(scene: SimScene, drive: ArmDrive, openings: tuple[float, ...], force: float
                      ) -> list[ReachPoint]:
    """:func:`reach_profile` of an arm: each opening's pinch solved by its IK from the previous opening's posture,
    and the torque share that holding ``force`` N there needs."""
    saved = scene.state()
    points = []
    q = drive.ik.home
    try:
        for opening in openings:
            set_opening(scene, opening)
            tcp, angles = natural_grasp(scene)
            position, rotation = drive._frame_target(scene, base_for_tcp(scene.gripper, tcp, angles))
            q, dp, da = drive.ik.solve(position, rotation, q)
            use, joint = _torque_use(scene, drive, q, force)
            points.append(ReachPoint(float(opening), dp, da, tuple(float(v) for v in q), use, joint))
    finally:
        scene.restore(saved)  # positions, velocities and everything derived from them (mj_forward)
    return points


def _arm_reach_checks(scene: SimScene, drive: ArmDrive, force: float) -> list[CheckResult]:
    """An arm's ``reach`` (the largest opening every grasp up to is met) and ``torque_headroom`` (the largest share
    of a joint's torque that holding ``force`` N needs at a reached opening)."""
    results: list[CheckResult] = []
    points = _arm_reach_profile(scene, drive, OPENINGS, force)
    best = reachable_opening(points)
    words = handle_words(scene)
    if best < 0:
        p = points[0]
        results.append(CheckResult("reach", False, f"cannot reach {words}: {p.position_error * 1000:.0f} mm short "
                                   "with the front closed", {"reachable_opening": best}))
    else:
        first_miss = next((p for p in points if not reached(p)), None)
        reason = (f"reaches {words} over the whole opening" if first_miss is None else
                  f"reaches {words} up to {best:.0%} open; at {first_miss.opening:.0%} it is "
                  f"{first_miss.position_error * 1000:.0f} mm short")
        results.append(CheckResult("reach", first_miss is None, reason,
                                   {"reachable_opening": best,
                                    "errors_mm": [round(p.position_error * 1000, 1) for p in points]}))
    held = [p for p in points if reached(p)]
    if held:
        worst = max(held, key=lambda p: p.torque_use)
        results.append(CheckResult(
            "torque_headroom", worst.torque_use <= 1.0,
            f"holding {force:.1f} N at the handle needs at most {worst.torque_use:.0%} of joint "
            f"{worst.limiting_joint}'s torque (at {worst.opening:.0%} open)",
            {"resistance_N": round(force, 2), "largest_share": round(worst.torque_use, 3),
             "joint": worst.limiting_joint, "opening": worst.opening}))
    return results


def _fraction(rotation: np.ndarray, gain: float) -> np.ndarray:
    """``gain`` of a rotation matrix: the same axis, ``gain`` times the angle."""
    import mujoco

    q = np.empty(4)
    mujoco.mju_mat2Quat(q, np.ascontiguousarray(rotation, np.float64).reshape(9))
    if q[0] < 0:
        q = -q
    norm = float(np.linalg.norm(q[1:]))
    if norm < 1e-12:
        return np.eye(3)
    half = gain * float(np.arctan2(norm, q[0]))
    scaled = np.concatenate([[np.cos(half)], q[1:] / norm * np.sin(half)])
    out = np.empty(9)
    mujoco.mju_quat2Mat(out, scaled)
    return out.reshape(3, 3)


def arm_lead(robot: Robot, control_fps: int) -> np.ndarray:
    """Per joint, how far a servo target may lead its joint (rad): what full torque needs, or one control step
    at full speed, whichever is larger."""
    assert robot.joints is not None
    return np.array([max(j.torque / j.stiffness, j.speed / control_fps) for j in robot.joints.joints])


def arm_drive(model: mujoco.MjModel, robot: Robot, ik: ArmIK, where: Placement, control_fps: int) -> ArmDrive:
    """The drive of an arm attached to a compiled scene (:func:`rik.sim.robots.arm.attach_arm`)."""
    act = robot.gripper.actuation
    assert act is not None
    p = ROBOT_PREFIX
    qpos = np.array([model.joint(p + n).qposadr[0] for n in robot.joint_names])
    arm_ctrl = np.array([model.actuator_ctrladr[model.actuator(p + n).id] for n in robot.joint_names])
    jaw_ctrl = int(model.actuator_ctrladr[model.actuator(p + act.actuator).id])
    opening = int(model.joint(p + act.opening_joint).qposadr[0])
    geoms = frozenset(g for g in range(model.ngeom) if model.body(int(model.geom_bodyid[g])).name.startswith(p)
                      and (model.geom_contype[g] or model.geom_conaffinity[g]))
    dofs = np.array([model.joint(p + n).dofadr[0] for n in robot.joint_names])
    return ArmDrive(robot, ik, where, qpos, arm_ctrl, jaw_ctrl, opening, geoms, dofs, arm_lead(robot, control_fps))
