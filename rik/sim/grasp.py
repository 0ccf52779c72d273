"""Where to grasp a handle, from the scene's ground truth: a friction pinch of the handle's outer part, or a hook of a
finger behind material of the front (:func:`rik.sim.probe.find_hooks`). The scripted strategies plan with these,
and the robot checks size a robot's reach with the natural pinch. Lengths in m, angles in rad."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from rik.sim.pose import base_for_tcp, gripper_rotation
from rik.sim.probe import APPROACH, CLEARANCE, find_hooks, front_face_y, handle_extent, pose_is_free

if TYPE_CHECKING:
    from rik.sim.scene import SimScene

PULL_SPEED = 0.12
"""Speed of the pull, m/s."""
SWING_MARGIN = 0.008
"""A swinging gripper's fixed jaw comes this far clear of the handle (beyond :data:`CLEARANCE`), m: a hobby arm's servos
sag a few millimetres under its own weight."""

@dataclass(frozen=True)
class GraspPlan:
    """Where to put the pads (``tcp``, world), how to turn the gripper, and where to come from."""

    mode: str
    tcp: np.ndarray
    angles: np.ndarray
    approach: np.ndarray
    """Unit vector from the grasp towards the pre-grasp pose."""
    detail: str = ""
    key: str = ""
    """Plans with the same key are one way of grasping; a re-grasp tries another."""


def pinch_plan(scene: SimScene, vertical: bool, geometry: str = "collision") -> GraspPlan:
    """Friction grasp: fingers towards the front, jaws horizontal or vertical, pads on the handle's outer part
    (measured on the ``geometry`` source's geoms, :data:`rik.sim.probe.GEOMETRY`)."""
    g = scene.gripper
    lo, hi = handle_extent(scene, geometry)
    centre = scene.grasp_point()
    face = min(front_face_y(scene, centre[0], centre[2], hi[1] + 0.05, geometry), lo[1])
    pad_y = max(hi[1] - g.pad_length / 2, face + CLEARANCE + 0.001 + g.pad_length / 2)
    tcp = np.array([centre[0], pad_y, centre[2]])
    angles = np.array([0.0, 0.0, math.pi / 2 if vertical else 0.0])
    mode = "pinch_vertical" if vertical else "pinch_horizontal"
    if g.fixed_jaw is not None:  # a swinging jaw closes the handle against the fixed one: put that one beside it
        closing = gripper_rotation(angles)[:, 0]
        half = 0.5 * float(np.abs(closing) @ (hi - lo))
        tcp = tcp + closing * (half + CLEARANCE + SWING_MARGIN - g.fixed_jaw)
    return GraspPlan(mode, tcp, angles, np.array([0.0, 1.0, 0.0]), key=mode)


def hook_plans(scene: SimScene, limit: int = 6, geometry: str = "collision") -> list[GraspPlan]:
    """Form-closure grasps: a finger behind material of the front (see :func:`rik.sim.probe.find_hooks`), with
    the jaws open across the handle and the whole gripper clear of the furniture there and on the way in."""
    g = scene.gripper
    plans: list[GraspPlan] = []
    for h in find_hooks(scene, g.finger_thickness, g.finger_width, g.stroke, g.pad_length, geometry=geometry):
        sign = 1.0 if h.side == "above" else -1.0
        tcp = h.pad + h.normal * g.finger_travel
        angles = np.array([sign * h.tilt, 0.0, math.pi / 2])
        if not all(pose_is_free(scene, base_for_tcp(g, tcp - h.finger * k * APPROACH, angles), g.finger_travel,
                                geometry) for k in (0.0, 0.5, 1.0)):
            continue
        plan = GraspPlan(f"hook_{h.side}", tcp, angles, -h.finger,
                         f"tilt {math.degrees(h.tilt):.0f} deg, bite {h.engagement * 1000:.0f} mm",
                         f"hook_{h.side}_{math.degrees(h.tilt):.0f}")
        if all(np.linalg.norm(plan.tcp - p.tcp) > 0.006 or p.mode != plan.mode for p in plans):
            plans.append(plan)
        if len(plans) >= limit:
            break
    return plans


def pinch_fits(scene: SimScene, geometry: str = "collision") -> bool:
    """Whether the handle is narrower vertically than horizontally (so a vertical pinch is the natural one)."""
    lo, hi = handle_extent(scene, geometry)
    return (hi[2] - lo[2]) <= (hi[0] - lo[0])
