"""Where to grasp a handle, from the scene's ground truth: a friction pinch of the handle's outer part, or a hook of a
finger behind material of the front (:func:`rik.sim.probe.find_hooks`). The scripted strategies plan with these,
and the robot checks size a robot's reach with the natural pinch. Lengths in m, angles in rad."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

from rik.sim.outcome import SUCCESS_OPENING
from rik.sim.pose import angles_of, base_for_tcp, gripper_rotation
from rik.sim.probe import APPROACH, CLEARANCE, find_hooks, front_face_y, handle_extent, pose_is_free, ray

if TYPE_CHECKING:
    from rik.sim.scene import SimScene

PULL_SPEED = 0.12
"""Speed of the pull, m/s."""
SWING_MARGIN = 0.008
"""A swinging gripper's fixed jaw comes this far clear of the handle (beyond :data:`CLEARANCE`), m: a hobby arm's servos
sag a few millimetres under its own weight."""
FIXED_GAP = 0.004
"""A swinging gripper's fixed pad is placed this far from the handle's far side, m (the scripted strategies correct
the arm's sag before they come in: :data:`rik.episodes.operators.SAG_GAIN`)."""
SWING_TILTS = (75.0, 60.0, 45.0, 30.0, 15.0, 0.0)
"""Angles of a swinging gripper's fingers from the front's normal, steepest first, deg: the steeper, the more of
the pull presses the handle into the fixed jaw (sin of the angle) instead of resting on friction; 0 is the
pinch straight into the front, the fixed jaw beside the handle."""
SWING_BACK_OFF = 0.003
"""Step by which a swinging gripper's grasp is drawn back along its fingers when their tips would touch the front
(up to half the pad's length), m."""
SWING_SIDES = {"below": np.array([0.0, 0.0, -1.0]), "above": np.array([0.0, 0.0, 1.0]),
               "left": np.array([-1.0, 0.0, 0.0]), "right": np.array([1.0, 0.0, 0.0])}
"""The sides a swinging gripper may come from (world), for the jaws closing in the vertical plane (below, above)
or in the horizontal one (left, right)."""

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
    position_first: bool = False
    """Reached only by the arm's position-first reach check (:func:`swing_plans`): the scripted operator tries it after
    every other plan."""


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


def hook_plans(scene: SimScene, limit: int = 6, geometry: str = "collision", prefer: str | None = None
               ) -> list[GraspPlan]:
    """Form-closure grasps: a finger behind material of the front (see :func:`rik.sim.probe.find_hooks`), with
    the jaws open across the handle and the whole gripper clear of the furniture there and on the way in; with
    ``prefer`` (``above`` or ``below``) the hooks from that side first, in their own order, then the others."""
    g = scene.gripper
    plans: list[GraspPlan] = []
    hooks = find_hooks(scene, g.finger_thickness, g.finger_width, g.stroke, g.pad_length, geometry=geometry)
    if prefer is not None:
        hooks.sort(key=lambda h: h.side != prefer)  # stable: each side keeps find_hooks' ranking
    for h in hooks:
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


def swing_frame(pull: np.ndarray, side: np.ndarray, tilt: float) -> np.ndarray:
    """World rotation of a swinging gripper's frame (columns: closing axis x, y, fingers z) whose fingers point into
    the front, tilted by ``tilt`` (rad) towards the handle from ``side`` (a unit vector across the pull), with the
    fixed jaw (on the frame's +x) on the far side of the handle: x has a component against the pull."""
    p = pull / np.linalg.norm(pull)
    u = side - (side @ p) * p
    u = u / np.linalg.norm(u)
    fingers = -math.cos(tilt) * p - math.sin(tilt) * u
    closing = -math.sin(tilt) * p + math.cos(tilt) * u
    return np.column_stack([closing, np.cross(fingers, closing), fingers])


def swing_plans(scene: SimScene, sides: tuple[str, ...] = ("below", "above"), limit: int = 1,
                geometry: str = "collision") -> list[GraspPlan]:
    """Grasps for a fixed and a swinging jaw (the SO arms): the fixed jaw's pad placed :data:`FIXED_GAP` from the
    handle's far side (the side away from the pull, so that the pull presses the handle into the fixed jaw), the
    swinging jaw open; closing it holds the handle against the fixed one. The fingers come in from one of
    ``sides`` (:data:`SWING_SIDES`), tilted by :data:`SWING_TILTS` from the front's normal; a plan is kept when the
    arm reaches it with the front closed (:func:`plan_reach`) and it, its way in and the pre-grasp pose touch
    nothing (:func:`rik.sim.probe.pose_is_free`,
    the robot's own geometry). The handle's cross-section is its bounding box from its far side (a ray from the
    front's surface at the grasp point) to its outer face. Up to ``limit`` plans, those the arm can follow furthest
    along the pull first (:func:`plan_reach`; every reach from a success's opening on counts alike), then the
    steeper, then in the order of ``sides``. Where fewer than ``limit`` are kept, the plans dropped as out of reach
    that the arm's position-first IK steps reach (:meth:`rik.sim.robots.ik.ArmIK.step`: a five-joint arm gives up
    orientation within the reach tolerance) follow, ranked alike among themselves and marked
    :attr:`GraspPlan.position_first`: after every plan of the usual reach, whose set, order and reach they leave as
    they were (ranked among them, a steeper plan that reaches further this way came first and slipped over the
    pull, docs/benchmark.md). None for a gripper with parallel jaws."""
    g = scene.gripper
    if g.fixed_jaw is None:
        return []
    lo, hi = handle_extent(scene, geometry)
    centre = scene.grasp_point()
    face = min(front_face_y(scene, centre[0], centre[2], hi[1] + 0.05, geometry), lo[1])
    dist, _ = ray(scene, np.array([centre[0], face + 0.0005, centre[2]]), np.array([0.0, 1.0, 0.0]),
                  geometry=geometry)
    if not face + 0.0005 + dist < hi[1]:
        return []
    back = face + 0.0005 + dist
    pull = scene.pull_direction()
    plans: list[GraspPlan] = []
    for tilt_deg in SWING_TILTS:
        for side in sides:
            u = SWING_SIDES[side]
            axis = int(np.argmax(np.abs(u)))
            rot = swing_frame(pull, u, math.radians(tilt_deg))
            closing, fingers = rot[:, 0], rot[:, 2]
            # the cross-section's corners in the plane of the pull and the side: where the fixed pad's face goes
            corners = []
            for y in (back, hi[1]):
                for a in (lo[axis], hi[axis]):
                    c = centre.copy()
                    c[1], c[axis] = y, a
                    corners.append(c)
            mid = 0.5 * (corners[0] + corners[-1])
            reach_far = max(float(closing @ c) for c in corners)
            placed = mid + closing * (reach_far - float(closing @ mid) + FIXED_GAP - g.fixed_jaw)
            angles = angles_of(rot)
            # where the fingertips would touch the front, hold the handle nearer the tips of the pads
            for back_off in np.arange(0.0, 0.5 * g.pad_length + 1e-9, SWING_BACK_OFF):
                tcp = placed - fingers * back_off
                if all(pose_is_free(scene, base_for_tcp(g, tcp - fingers * k * APPROACH, angles), g.finger_travel,
                                    geometry) for k in (0.0, 0.5, 1.0)):
                    break
            else:
                continue
            plans.append(GraspPlan(f"swing_{side}", tcp, angles, -fingers, f"tilt {tilt_deg:.0f} deg",
                                   f"swing_{side}_{tilt_deg:.0f}"))
    reach = [plan_reach(scene, p) for p in plans]
    kept = [_with_detail(plans[i], f"reaches {reach[i]:.0%}") for i in _ranked(reach)][:limit]
    missed = [i for i in range(len(plans)) if reach[i] < 0.0]
    if len(kept) == limit or not missed:
        return kept
    # the fallback: only for the plans dropped, and ranked after every plan kept, so it cannot reorder them
    first = [plan_reach(scene, plans[i], position_first=True) for i in missed]
    return kept + [replace(_with_detail(plans[missed[j]], f"reaches {first[j]:.0%} position first"),
                           position_first=True) for j in _ranked(first)][:limit - len(kept)]


def _ranked(reach: list[float]) -> list[int]:
    """Indices of the plans whose ``reach`` (fraction of the front's range) is at least the closed front, furthest
    first: past a success's opening a further reach gains nothing, and among equals the earlier (a steeper tilt,
    which holds by more than friction; the sort is stable) first."""
    return sorted((i for i in range(len(reach)) if reach[i] >= 0.0),
                  key=lambda i: -min(round(reach[i], 2), SUCCESS_OPENING))


def _with_detail(plan: GraspPlan, words: str) -> GraspPlan:
    return replace(plan, detail=f"{plan.detail}, {words}".strip(", "))


def plan_reach(scene: SimScene, plan: GraspPlan, position_first: bool = False) -> float:
    """The largest opening up to which the scene's robot can hold ``plan``'s grasp as the front opens (the pads kept
    where they are on the handle, the gripper's angles kept): the drive's :meth:`hold_reach` (``position_first``:
    with the arm's position-first IK steps); -1: not even the closed one."""
    return scene.robot_drive.hold_reach(scene, plan.tcp - scene.grasp_point(), plan.angles, position_first)
