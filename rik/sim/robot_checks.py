"""Checks of a robot on a variant (``rik robot-check``): can it start, reach the handle over the front's travel,
hold the pull the preset asks for, and grip it?

- ``start_clear``: at the start pose nothing of the robot penetrates the furniture or the floor;
- ``reach``: the natural pinch of the handle (:func:`rik.sim.operators.pinch_plan`) at openings 0, 10, ..., 100 %,
  solved by the arm's IK from the previous opening's posture, as the arm would follow the pull; the reachable
  opening is the largest one up to which every grasp is met within :data:`REACH_TOLERANCE`;
- ``torque_headroom``: at each reachable opening, the joint torques that hold the preset's resistance at the
  handle (``J^T F``, F = friction + damping x pull speed along the pull) plus gravity (a compensating controller
  spends torque on it too), against each joint's torque; the Hand-E's base against its force cap;
- ``grip``: what two pads pressed with the grip force hold by friction (2 mu F) against that resistance.

Every check is measured, not assumed: each returns the numbers it decided on.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from rik.errors import RikError

if TYPE_CHECKING:
    from rik.sim.scene import SimScene

OPENINGS = tuple(np.round(np.linspace(0.0, 1.0, 11), 2))
"""Openings (fractions of the front's range) at which reach and torque are checked."""
REACH_TOLERANCE = (0.005, 0.25)
"""A grasp is reached within 5 mm and 0.25 rad (an arm of five joints meets a full pose only approximately)."""


@dataclass(frozen=True)
class CheckResult:
    name: str
    passed: bool
    reason: str
    values: dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class ReachPoint:
    opening: float
    position_error: float
    """m"""
    orientation_error: float
    """rad"""
    joints: tuple[float, ...]
    torque_use: float
    """Largest share of a joint's torque the held pull and gravity need (1: all of it)."""
    limiting_joint: str


def _resistance(scene: SimScene) -> float:
    """The force the front resists a pull at its handle with, N: friction plus damping at the strategies' pull
    speed, felt at the grasp point (a hinge's torque divided by the lever arm)."""
    import mujoco

    from rik.sim.operators import PULL_SPEED

    m, d, f = scene.model, scene.data, scene.front
    jacp = np.zeros((3, m.nv))
    mujoco.mj_jacSite(m, d, jacp, None, f.grasp_site)
    lever = max(float(np.linalg.norm(jacp[:, f.dof_adr])), 1e-6)
    return float(m.dof_frictionloss[f.dof_adr]) / lever + float(m.dof_damping[f.dof_adr]) * PULL_SPEED / lever ** 2


def _set_opening(scene: SimScene, fraction: float) -> None:
    import mujoco

    lo, hi = scene.front.range
    scene.data.qpos[scene.front.qpos_adr] = lo + fraction * (hi - lo)
    mujoco.mj_kinematics(scene.model, scene.data)
    mujoco.mj_comPos(scene.model, scene.data)


def _grasp(scene: SimScene) -> tuple[np.ndarray, np.ndarray]:
    """(gripper frame position, angles) of the natural pinch of the handle where the front is now."""
    from rik.sim.operators import pinch_fits, pinch_plan

    plan = pinch_plan(scene, vertical=pinch_fits(scene))
    return plan.tcp, plan.angles


def _torque_use(scene: SimScene, q: np.ndarray, force: float) -> tuple[float, str]:
    """Largest share of a joint's torque an arm at ``q`` needs to pull with ``force`` N along the pull at its
    gripper frame and hold itself up; and that joint's name."""
    import mujoco

    from rik.sim.drive import ArmDrive

    drive = scene.drive
    assert isinstance(drive, ArmDrive) and drive.robot.joints is not None
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


def reach_profile(scene: SimScene, openings: tuple[float, ...] = OPENINGS) -> list[ReachPoint]:
    """The natural pinch at each opening, solved as the arm would follow the pull (see the module docstring); the
    scene is left as it was."""
    from rik.sim.drive import ArmDrive
    from rik.sim.scene import base_for_tcp

    drive = scene.drive
    if not isinstance(drive, ArmDrive):
        return [ReachPoint(o, 0.0, 0.0, (), 0.0, "") for o in openings]
    saved = scene.state()
    force = _resistance(scene)
    points = []
    q = drive.ik.home
    try:
        for opening in openings:
            _set_opening(scene, opening)
            tcp, angles = _grasp(scene)
            position, rotation = drive._frame_target(scene, base_for_tcp(scene.gripper, tcp, angles))
            q, dp, da = drive.ik.solve(position, rotation, q)
            use, joint = _torque_use(scene, q, force)
            points.append(ReachPoint(float(opening), dp, da, tuple(float(v) for v in q), use, joint))
    finally:
        scene.restore(saved)  # positions, velocities and everything derived from them (mj_forward)
    return points


def reached(point: ReachPoint) -> bool:
    return point.position_error <= REACH_TOLERANCE[0] and point.orientation_error <= REACH_TOLERANCE[1]


def reachable_opening(points: list[ReachPoint]) -> float:
    """The largest opening up to which every grasp of the profile is reached (-1: not even the closed one)."""
    best = -1.0
    for p in points:
        if not reached(p):
            break
        best = p.opening
    return best


def _handle_words(scene: SimScene) -> str:
    return f"handle {scene.info['handle']} of variant {scene.info['id']} (front {scene.front.id})"


def require_reach(scene: SimScene) -> None:
    """Refuse an arm that cannot reach the operated handle with the front closed (one line naming the handle and
    how far it is short)."""
    from rik.sim.drive import ArmDrive

    if not isinstance(scene.drive, ArmDrive):
        return
    point = reach_profile(scene, (0.0,))[0]
    if not reached(point):
        raise RikError(f"robot {scene.robot_id} cannot reach {_handle_words(scene)}: "
                       f"{point.position_error * 1000:.0f} mm short of its grasp point with the front closed "
                       f"(and {np.degrees(point.orientation_error):.0f} deg off its orientation); its mount is in "
                       "the catalog (rik catalog show " + scene.robot_id + ")")


def start_clear(scene: SimScene) -> CheckResult:
    """Nothing of the robot penetrates anything at the start pose."""
    import mujoco

    from rik.sim.drive import ArmDrive

    m, d = scene.model, scene.data
    scene.reset()
    mujoco.mj_forward(m, d)
    drive = scene.drive
    ours = drive.robot_geoms if isinstance(drive, ArmDrive) else scene.gripper_geoms
    hits = set()
    for i in range(d.ncon):
        g1, g2 = int(d.contact.geom1[i]), int(d.contact.geom2[i])
        if (g1 in ours) != (g2 in ours) and d.contact.dist[i] < -1e-4:
            other = g2 if g1 in ours else g1
            hits.add(m.body(int(m.geom_bodyid[other])).name or "world")
    if hits:
        return CheckResult("start_clear", False, f"at the start pose the robot is inside {', '.join(sorted(hits))}",
                           {"bodies": sorted(hits)})
    return CheckResult("start_clear", True, "the robot starts clear of the furniture and the floor")


def run_checks(scene: SimScene) -> list[CheckResult]:
    """Every check of the robot on the scene's variant and front."""
    from rik.sim.drive import ArmDrive

    results = [start_clear(scene)]
    force = _resistance(scene)
    g = scene.gripper
    if isinstance(scene.drive, ArmDrive):
        points = reach_profile(scene)
        best = reachable_opening(points)
        words = _handle_words(scene)
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
    else:
        share = force / g.arm_force
        results.append(CheckResult("reach", True, "the floating base reaches every opening", {"reachable_opening": 1}))
        results.append(CheckResult("torque_headroom", share <= 1.0, f"holding {force:.1f} N needs {share:.0%} of the "
                                   f"base's {g.arm_force:.0f} N", {"resistance_N": round(force, 2),
                                                                    "largest_share": round(share, 3)}))
    capacity = g.friction_capacity()
    results.append(CheckResult("grip", capacity >= force, f"two pads at {g.grip_force:.0f} N with friction "
                               f"{g.pad_friction:.2f} hold {capacity:.1f} N by friction; the front resists with "
                               f"{force:.1f} N", {"capacity_N": round(capacity, 2), "resistance_N": round(force, 2)}))
    return results
