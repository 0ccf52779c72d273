"""How a robot's reach is measured: the natural pinch of the operated handle at openings of the front, the
resistance the front pulls back with, and when a grasp counts as reached. Lengths in m, angles in rad, forces
in N."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from rik.sim.grasp import PULL_SPEED, pinch_fits, pinch_plan
from rik.sim.robots.results import ReachPoint

if TYPE_CHECKING:
    from rik.sim.scene import SimScene

OPENINGS = tuple(np.round(np.linspace(0.0, 1.0, 11), 2))
"""Openings (fractions of the front's range) at which reach and torque are checked."""
REACH_TOLERANCE = (0.005, 0.25)
"""A grasp is reached within 5 mm and 0.25 rad (an arm of five joints meets a full pose only approximately)."""


def resistance(scene: SimScene) -> float:
    """The force the front resists a pull at its handle with, N: friction plus damping at the strategies' pull
    speed, felt at the grasp point (a hinge's torque divided by the lever arm)."""
    import mujoco

    m, d, f = scene.model, scene.data, scene.front
    jacp = np.zeros((3, m.nv))
    mujoco.mj_jacSite(m, d, jacp, None, f.grasp_site)
    lever = max(float(np.linalg.norm(jacp[:, f.dof_adr])), 1e-6)
    return float(m.dof_frictionloss[f.dof_adr]) / lever + float(m.dof_damping[f.dof_adr]) * PULL_SPEED / lever ** 2


def set_opening(scene: SimScene, fraction: float) -> None:
    import mujoco

    lo, hi = scene.front.range
    scene.data.qpos[scene.front.qpos_adr] = lo + fraction * (hi - lo)
    mujoco.mj_kinematics(scene.model, scene.data)
    mujoco.mj_comPos(scene.model, scene.data)


def natural_grasp(scene: SimScene) -> tuple[np.ndarray, np.ndarray]:
    """(gripper frame position, angles) of the natural pinch of the handle where the front is now."""
    plan = pinch_plan(scene, vertical=pinch_fits(scene))
    return plan.tcp, plan.angles


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


def handle_words(scene: SimScene) -> str:
    return f"handle {scene.info['handle']} of variant {scene.info['id']} (front {scene.front.id})"
