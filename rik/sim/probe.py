"""Ground-truth geometry for scripted strategies, read from the compiled scene by ray casting.

The strategies get the handle's true pose and shape, as the paper's baselines do. Rays are cast against the
furniture (never the gripper), in one of two :data:`GEOMETRY` sources: its ``collision`` geoms, so that what a
strategy plans is what the fingers will touch; or its ``visual`` geoms, the catalog's own meshes, which are the
same whichever collision model a variant was built with (convex hull, CoACD), so that a plan made on them is the
same plan in simulators of different fidelity.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rik.sim.scene import SimScene

COLLISION_GROUPS = np.array([0, 0, 0, 1, 0, 0], np.uint8)
"""Only group 3 (rik's collision geoms) is hit."""
VISUAL_GROUPS = np.array([0, 0, 1, 0, 0, 0], np.uint8)
"""Only group 2 (rik's visual geoms, the catalog's meshes) is hit."""
GEOMETRY = {"collision": (COLLISION_GROUPS, 3), "visual": (VISUAL_GROUPS, 2)}
"""Geometry source -> (the geom groups rays hit, the geom group read for bounds)."""
CLEARANCE = 0.002
"""Gap left between a finger and the surface it is placed against, m."""
APPROACH = 0.04
"""How far above (below) the handle a hooking finger starts its way in, m."""
BACK_FACE_COS = 0.7
"""A surface counts as a hook's bite when its normal is within 45° of pointing straight against the pull."""
OVERREACH = 0.004
"""How far past the handle's far side a hooking finger may go, m."""


def ray(scene: SimScene, origin: np.ndarray, direction: np.ndarray, exclude_body: int = -1,
        normal: np.ndarray | None = None, geometry: str = "collision") -> tuple[float, int]:
    """Distance to the first geom of the ``geometry`` source hit from ``origin`` along unit ``direction`` (inf if
    none), and the geom's id (-1 if none); geoms of ``exclude_body`` are passed through. ``normal``, when given,
    receives the surface normal at the hit."""
    import mujoco

    geom = np.array([-1], np.int32)
    d = mujoco.mj_ray(scene.model, scene.data, np.asarray(origin, np.float64), np.asarray(direction, np.float64),
                      GEOMETRY[geometry][0], 1, exclude_body, geom, normal)
    return (float(d) if d >= 0 else float("inf")), int(geom[0])


def handle_extent(scene: SimScene, geometry: str = "collision") -> tuple[np.ndarray, np.ndarray]:
    """World-axis bounding box (min, max corners) of the operated handle's geoms of the ``geometry`` source, m."""
    m, d = scene.model, scene.data
    group = GEOMETRY[geometry][1]
    lo, hi = np.full(3, np.inf), np.full(3, -np.inf)
    for g in range(m.ngeom):
        if int(m.geom_bodyid[g]) != scene.front.handle_body or m.geom_group[g] != group:
            continue
        centre, half = m.geom_aabb[g][:3], m.geom_aabb[g][3:]
        rot = d.geom_xmat[g].reshape(3, 3)
        for corner in np.array(np.meshgrid([-1, 1], [-1, 1], [-1, 1])).T.reshape(-1, 3):
            p = d.geom_xpos[g] + rot @ (centre + corner * half)
            lo, hi = np.minimum(lo, p), np.maximum(hi, p)
    return lo, hi


def front_face_y(scene: SimScene, x: float, z: float, y_from: float, geometry: str = "collision") -> float:
    """World y of the front's surface behind the handle: the first surface met going from ``y_from`` towards -y
    at (x, z), passing through the handle."""
    dist, _ = ray(scene, np.array([x, y_from, z]), np.array([0.0, -1.0, 0.0]), scene.front.handle_body,
                  geometry=geometry)
    return y_from - dist


@dataclass(frozen=True)
class Hook:
    """Where a finger can be put behind material of the front, to pull it by normal force instead of friction."""

    side: str
    """``above`` (the finger comes down) or ``below`` (it comes up)."""
    tilt: float
    """Angle of the finger from the horizontal, rad (pi/2: vertical)."""
    pad: np.ndarray
    """World position of the hooking finger's pad face at the middle of the pad, m."""
    finger: np.ndarray
    """Unit vector along the finger, base to tip (world)."""
    normal: np.ndarray
    """Unit normal of the hooking pad, towards the material it pulls (world)."""
    engagement: float
    """Length of the pad (m) that has material of the front in front of it: the hook's bite."""


def _hook_frame(side: str, tilt: float) -> tuple[np.ndarray, np.ndarray]:
    sign = 1.0 if side == "above" else -1.0
    finger = np.array([0.0, -math.cos(tilt), -sign * math.sin(tilt)])
    normal = np.array([0.0, math.sin(tilt), -sign * math.cos(tilt)])
    return finger, normal


HOOK_TILTS = (math.pi / 2, math.pi / 3, math.pi / 4)
"""Finger angles tried for a hook: vertical, then leaning in so the palm stays clear of the front."""


def find_hooks(scene: SimScene, finger_thickness: float, finger_width: float, stroke: float, pad_length: float,
               step: float = 0.0015, geometry: str = "collision") -> list[Hook]:
    """Places where a finger can come down from above (or up from below), straight or leaning towards the front,
    behind some part of the front, with material in front of its pad within the jaws' span: the pocket behind
    a bar, the neck behind a knob's head, the groove behind a lip, the cup of a hood. Best (largest bite)
    first. Only the finger's path is checked here; :func:`pose_is_free` checks the whole gripper."""
    lo, hi = handle_extent(scene, geometry)
    centre = scene.grasp_point()
    pull = scene.pull_direction()
    x = float(centre[0])
    xs = (x - finger_width / 2 + 0.001, x, x + finger_width / 2 - 0.001)
    corners = np.array(np.meshgrid(*zip(lo, hi, strict=True))).T.reshape(-1, 3)
    hooks = []
    for side in ("above", "below"):
        for tilt in HOOK_TILTS:
            finger, normal = _hook_frame(side, tilt)
            for s in np.arange(-0.035, 0.025, step):
                face = centre + s * normal  # a point of the hooking pad's face
                # how far the finger's tip may go: just past the handle's far side along the finger
                far = float(np.max((corners - face) @ finger)) + OVERREACH
                back = APPROACH + 0.03
                travel = far + back
                for xx in xs:
                    for u in (0.0005, finger_thickness / 2, finger_thickness - 0.0005):
                        origin = face - normal * u + finger * (-back)
                        origin[0] = xx
                        travel = min(travel, ray(scene, origin, finger, geometry=geometry)[0] - CLEARANCE)
                tip = face + finger * (travel - back)
                # material of the front in front of the pad, within the jaws' span, along the pad from the tip,
                # whose surface there faces back against the pull (a back face the pad can push outwards)
                bite = 0.0
                hit_normal = np.zeros(3)
                for h in np.arange(0.001, pad_length, step):
                    dist, geom = ray(scene, tip - finger * h + normal * 0.0005, normal, normal=hit_normal,
                                     geometry=geometry)
                    if (dist < stroke and int(scene.model.geom_bodyid[geom]) in scene.front_bodies
                            and hit_normal @ pull <= -BACK_FACE_COS):
                        bite += step
                if bite >= 0.003:
                    hooks.append(Hook(side, tilt, tip - finger * (pad_length / 2), finger, normal, float(bite)))
    # prefer the deepest bite, then a steeper finger (the pad's normal closer to the pull)
    hooks.sort(key=lambda h: (-round(h.engagement / 0.003), -h.tilt))
    return hooks


def pose_is_free(scene: SimScene, pose: np.ndarray, opening: float, geometry: str = "collision") -> bool:
    """Whether the gripper at base ``pose`` with each finger ``opening`` from the centre touches nothing (the
    furniture, the floor); an arm is solved to the pose and all of it must be free. The scene's state is left as
    it was. With ``visual`` geometry the handle's collision geoms do not count (they differ between collision
    models; the finger's path past the handle was checked on the visual mesh)."""
    ignore = frozenset({scene.front.handle_body}) if geometry == "visual" else frozenset()
    return scene.robot_drive.pose_is_free(scene, np.asarray(pose, np.float64), opening, ignore)
