"""What the operator is told about the grasp and the motion, from the simulation rather than from the commands: whether
the jaws hold the handle (contacts), whether it slipped out, whether the target is blocked; and motion along the
front's own path (a door's arc, a drawer's slide). Lengths in m, angles in rad."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from rik.sim.scene import HandleContact, SimScene

HOLD_FORCE = 2.0
"""Normal force the jaws must press the handle with, together, to hold it, N."""
BLOCKED_LEAD = 0.010
"""The target leads the gripper by more than this while a motion key is held: the gripper is blocked, m. Moving
freely at full speed the target leads by 3.8 mm (Hand-E) and 4.8 mm (Panda) at most (measured on the demo drawer)."""
MIN_ARC_RADIUS = 0.05
"""Radius below which an arc step is taken as at this radius (a handle next to the hinge), m."""
GRASP_STATES = ("free", "touching", "holding", "slipped")
"""What :class:`GraspWatch` reports: no contact with the front; a contact but no grip of the handle; both jaws press the
handle with the grip closing; the jaws held the handle and it left them while the grip was not fully opened (pulled
out, or the grip loosened)."""


class GraspWatch:
    """The grasp state after each control step (:data:`GRASP_STATES`): ``slipped`` from the step the handle leaves
    jaws that held it while the grip command is above 0 (still closing, or loosened part way), until the grip opens
    fully or takes the handle again."""

    def __init__(self) -> None:
        self.state = "free"
        self._held = False

    def update(self, contact: HandleContact, grip: float) -> str:
        """The state after a step with ``contact`` and the grip command ``grip`` (0 open .. 1 closed)."""
        closing = grip > 0.0
        holding = closing and contact.handle_bodies >= 2 and contact.handle_force >= HOLD_FORCE
        if holding:
            self._held = True
            self.state = "holding"
        elif closing and self._held:
            self.state = "slipped"
        else:
            self._held = False
            self.state = "touching" if contact.front else "free"
        return self.state


def front_path_step(scene: SimScene, pose: np.ndarray, distance: float) -> np.ndarray:
    """``pose`` (x, y, z m; pitch, yaw, roll rad of the gripper) carried ``distance`` along the operated front's path:
    positive opens. A drawer's slide moves it along the slide's axis; a hinge (door, flap) turns it about the hinge's
    axis by ``distance`` over the pose's distance from the axis, its orientation with it, so that a grip on the handle
    keeps its angle to the front."""
    from scipy.spatial.transform import Rotation

    from rik.sim.pose import angles_of, gripper_rotation, nearest_angles

    d, joint = scene.data, scene.front.joint
    axis = d.xaxis[joint] / np.linalg.norm(d.xaxis[joint])
    out = np.array(pose, np.float64)
    if scene.front.motion == "slide":
        out[:3] += distance * axis
        return out
    anchor = d.xanchor[joint]
    arm = out[:3] - anchor
    radius = float(np.linalg.norm(arm - (arm @ axis) * axis))
    turn = Rotation.from_rotvec(axis * (distance / max(radius, MIN_ARC_RADIUS))).as_matrix()
    out[:3] = anchor + turn @ arm
    out[3:] = nearest_angles(angles_of(turn @ gripper_rotation(out[3:])), out[3:])
    return out


def grasp_text(status: dict[str, Any]) -> str:
    """The grasp the contacts give, from :meth:`rik.teleop.session.TeleopSession.status`: ``holding``, or
    ``slipped: ...`` with what to do, and ``; blocked`` when the target leads the gripper."""
    text = str(status["grasp"])
    if status["grasp"] == "slipped":
        text += ": the handle left the jaws; open (Space) and grasp again"
    if status["blocked"]:
        text += "; blocked"
    return text


def front_text(status: dict[str, Any]) -> str:
    """The front's angle (``door at 34 deg``) or travel (``drawer out 120 mm``)."""
    front = status["front_position"]
    if "angle_deg" in front:
        return f"{front['kind']} at {front['angle_deg']:.0f} deg"
    return f"{front['kind']} out {front['travel_mm']:.0f} mm"


def motion_text(status: dict[str, Any]) -> str:
    """How W / S move the target now (``along the front's path`` or ``frame-fixed``) and the setting."""
    motion = status["motion"]
    if motion["mode"] == "frame":
        return "frame-fixed (M: along the front's path while holding)"
    return "along the front's path" if motion["on_path"] or status["grasp"] == "holding" else \
        "frame-fixed until the handle is held (M: always frame-fixed)"


def grasp_hint(scene: SimScene) -> str:
    """How to grasp the operated handle, from its own (visual) geometry in the scene as built, closed: its size, which
    roll puts the jaws across its narrow side (the roll the scripted pinch takes, :func:`rik.sim.grasp.pinch_fits`),
    how far it stands off the front, and how the front then opens."""
    from rik.sim.grasp import pinch_fits
    from rik.sim.probe import front_face_y, handle_extent

    lo, hi = handle_extent(scene, "visual")
    centre = 0.5 * (lo + hi)
    face = min(front_face_y(scene, float(centre[0]), float(centre[2]), float(hi[1]) + 0.05, "visual"), float(lo[1]))
    width, height, standoff = (hi[0] - lo[0]) * 1000, (hi[2] - lo[2]) * 1000, (hi[1] - face) * 1000
    if pinch_fits(scene, "visual"):
        roll = "roll 90 deg first (hold Q or E) so that the jaws close above and below it"
    else:
        roll = "keep the roll at 0 deg: the jaws close left and right of it"
    opens = ("hold S to pull the drawer out" if scene.front.motion == "slide" else
             "hold S: the gripper follows the front's arc (motion along the path, M switches it off)")
    return (f"the handle is {width:.0f} mm wide, {height:.0f} mm tall and stands {standoff:.0f} mm off the front: "
            f"{roll}, close (Space) on its outer part, and once the grip reads 'holding', {opens}.")
