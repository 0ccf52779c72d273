"""The operator's view of the front: a camera that keeps the gripper, the handle and the front in frame while the
front opens (a door swings out of the fixed front camera's picture from about half open). Only what the operator
sees: episodes store states, and every stream rendered from them uses the scene's own fixed cameras."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    import mujoco

    from rik.sim.scene import SimScene

FOLLOWED = "front"
"""The scene camera whose direction and framing the follow view keeps."""


class FollowView:
    """A MuJoCo free camera looking the way the scene's :data:`FOLLOWED` camera looks, from the distance at which it
    frames the closed front (measured to the middle of its handle and its body, whatever the robot), at the mean of
    the pads' centre, the handle's grasp point and the front's body: as the front opens, the camera moves with what
    is being operated."""

    def __init__(self, scene: SimScene) -> None:
        import mujoco

        m = scene.model
        self.scene = scene
        start = mujoco.MjData(m)  # the model's initial state: the front closed (the robot wherever its zeros put it)
        mujoco.mj_forward(m, start)
        closed_front = (start.site_xpos[scene.front.grasp_site] + start.xpos[scene.front.body]) / 2.0
        cid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_CAMERA, FOLLOWED)
        forward = -start.cam_xmat[cid].reshape(3, 3)[:, 2]
        along = float(np.dot(closed_front - start.cam_xpos[cid], forward))
        # a free camera's field of view is the model's global one: keep the fixed camera's framing
        fixed, free = math.radians(float(m.cam_fovy[cid])), math.radians(float(m.vis.global_.fovy))
        scale = math.tan(fixed / 2) / math.tan(free / 2)
        self.camera = mujoco.MjvCamera()
        self.camera.type = mujoco.mjtCamera.mjCAMERA_FREE
        self.azimuth = math.degrees(math.atan2(forward[1], forward[0]))
        self.elevation = math.degrees(math.asin(float(np.clip(forward[2], -1.0, 1.0))))
        self.camera.azimuth, self.camera.elevation = self.azimuth, self.elevation
        self.camera.distance = max(along, 0.1) * scale

    def target(self, data: mujoco.MjData) -> np.ndarray:
        """The point the view looks at in ``data``: the mean of the pads' centre, the grasp point and the front's body
        origin, m (world)."""
        s = self.scene
        return (data.site_xpos[s.tcp_site] + data.site_xpos[s.front.grasp_site] + data.xpos[s.front.body]) / 3.0

    def at(self, data: mujoco.MjData, turn: tuple[float, float] = (0.0, 0.0)) -> mujoco.MjvCamera:
        """The camera for the state in ``data`` (after ``mj_forward``), orbited by ``turn`` (azimuth, elevation
        degrees, as the operator dragged it; the elevation stays within +-85 degrees)."""
        self.camera.lookat[:] = self.target(data)
        self.camera.azimuth = self.azimuth + turn[0]
        self.camera.elevation = float(np.clip(self.elevation + turn[1], -85.0, 85.0))
        return self.camera


JAWS_RGBA = (0.95, 0.45, 0.05, 1.0)
"""The gripper's colour in the operator's view (orange), RGBA."""
JAWS_ALT_RGBA = (0.85, 0.15, 0.80, 1.0)
"""The gripper's colour when the arm's own paint is close to :data:`JAWS_RGBA` (the SO-100 is orange): magenta."""
NEAR_COLOUR = 0.25
"""Colours closer than this in every RGB channel (0..1) read as the same colour."""
HANDLE_RGBA = (0.10, 0.45, 0.95, 1.0)
"""The operated handle's colour in the operator's view (blue): a white handle on a white front stands out, RGBA."""


def paint_for_contrast(view: mujoco.MjvScene, scene: SimScene) -> None:
    """Colour the gripper :data:`JAWS_RGBA` (:data:`JAWS_ALT_RGBA` on an arm painted close to it) and the operated
    handle :data:`HANDLE_RGBA` in a view made by ``update_scene`` (textures dropped): depth is easier to read when
    jaws, handle, front and arm differ. The operator's view only: the scene's materials, and every recorded stream,
    stay as they are."""
    import mujoco

    bodies = scene.model.geom_bodyid
    hand = gripper_bodies(scene)
    robot = frozenset(int(bodies[g]) for g in scene.robot_drive.geoms(scene))
    drawn = [view.geoms[i] for i in range(view.ngeom) if view.geoms[i].objtype == mujoco.mjtObj.mjOBJ_GEOM]
    arm = [g.rgba[:3] for g in drawn if int(bodies[g.objid]) in robot - hand]
    jaws = JAWS_ALT_RGBA if any(max(abs(c - j) for c, j in zip(rgb, JAWS_RGBA[:3], strict=True)) < NEAR_COLOUR
                                for rgb in arm) else JAWS_RGBA
    for g in drawn:
        if int(bodies[g.objid]) in hand:
            rgba = jaws
        elif int(bodies[g.objid]) == scene.front.handle_body:
            rgba = HANDLE_RGBA
        else:
            continue
        g.rgba[:] = rgba
        g.matid = -1


def gripper_bodies(scene: SimScene) -> frozenset[int]:
    """The bodies of the gripper's geoms: an arm's gripper geoms are its collision shapes, and the meshes drawn for
    its hand and fingers hang on the same bodies."""
    return frozenset(int(scene.model.geom_bodyid[g]) for g in scene.gripper_geoms)
