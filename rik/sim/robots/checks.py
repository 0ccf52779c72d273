"""Checks of a robot on a variant (``rik robot-check``): can it start, reach the handle over the front's travel,
hold the pull the preset asks for, and grip it?

- ``start_clear``: at the start pose nothing of the robot penetrates the furniture or the floor;
- ``reach``: the natural pinch of the handle (:func:`rik.sim.grasp.pinch_plan`) at openings 0, 10, ..., 100 %,
  solved by the arm's IK from the previous opening's posture, as the arm would follow the pull; the reachable
  opening is the largest one up to which every grasp is met within :data:`REACH_TOLERANCE`;
- ``torque_headroom``: at each reachable opening, the joint torques that hold the preset's resistance at the
  handle (``J^T F``, F = friction + damping x pull speed along the pull) plus gravity (a compensating controller
  spends torque on it too), against each joint's torque; the Hand-E's base against its force cap;
- ``grip``: what two pads pressed with the grip force hold by friction (2 mu F) against that resistance.

Every check is measured, not assumed: each returns the numbers it decided on.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from rik.errors import RikError
from rik.sim.robots.reach import OPENINGS, handle_words, reached, resistance
from rik.sim.robots.results import CheckResult, ReachPoint

if TYPE_CHECKING:
    from rik.sim.scene import SimScene


def reach_profile(scene: SimScene, openings: tuple[float, ...] = OPENINGS) -> list[ReachPoint]:
    """The natural pinch at each opening, as the scene's robot would follow the pull (see the module docstring);
    the scene is left as it was."""
    return scene.robot_drive.reach(scene, openings, resistance(scene))


def require_reach(scene: SimScene) -> None:
    """Refuse an arm that cannot reach the operated handle with the front closed (one line naming the handle and
    how far it is short); a robot that reaches everywhere (the floating Hand-E) always passes."""
    point = reach_profile(scene, (0.0,))[0]
    if not reached(point):
        raise RikError(f"robot {scene.robot_id} cannot reach {handle_words(scene)}: "
                       f"{point.position_error * 1000:.0f} mm short of its grasp point with the front closed "
                       f"(and {np.degrees(point.orientation_error):.0f} deg off its orientation); its mount is in "
                       "the catalog (rik catalog show " + scene.robot_id + ")")


def start_clear(scene: SimScene) -> CheckResult:
    """Nothing of the robot penetrates anything at the start pose."""
    import mujoco

    m, d = scene.model, scene.data
    scene.reset()
    mujoco.mj_forward(m, d)
    ours = scene.robot_drive.geoms(scene)
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
    results = [start_clear(scene)]
    force = resistance(scene)
    g = scene.gripper
    results += scene.robot_drive.reach_checks(scene, force)
    capacity = g.friction_capacity()
    results.append(CheckResult("grip", capacity >= force, f"two pads at {g.grip_force:.0f} N with friction "
                               f"{g.pad_friction:.2f} hold {capacity:.1f} N by friction; the front resists with "
                               f"{force:.1f} N", {"capacity_N": round(capacity, 2), "resistance_N": round(force, 2)}))
    return results
