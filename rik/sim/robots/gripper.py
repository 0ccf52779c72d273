"""The parallel-jaw gripper rik simulates, on a force-limited 6-DoF base that follows a target pose.

**The gripper is a Robotiq Hand-E** (a true parallel-jaw gripper, common on UR and Franka arms in teleoperation
data sets). Its figures (stroke, grip force, pad friction, finger speed, finger and pad sizes) and their sources live
once, in the built-in catalog's ``robots.yaml`` (entry ``hand-e``; ``rik catalog show hand-e``), which
:data:`HAND_E` reads. The fingers are synchronised (the manual: "finger movement is always synchronized"); the pad
friction there is the only one Robotiq publishes, measured on lubricated steel, so dry lacquer or metal is
grippier and the figure is conservative (``rik bench --sweep`` varies it). Palm size and mass (about 1 kg) are
approximate, from the Hand-E's outline drawings and specifications.

**The arm** is not modelled link by link: the gripper's base is a chain of three slides and three hinges driven by
position servos whose force is capped, so the gripper cannot push or pull harder than an arm could. The caps
(150 N per axis, 15 N·m per rotation) are an assumption of the order of a collaborative arm's default safety
force limit, not a datasheet figure. The base carries armature (reflected arm inertia) and gravity compensation,
as a real arm's controller compensates the hand's weight.

The base chain is x, y, z slides, then hinges about x (pitch), z (yaw) and y (roll), so that the poses the
strategies need (fingers towards the front, down or up, rolled about the approach) stay away from the chain's
singularity (yaw = ±90°). Gripper frame: fingers point along +z, the jaws close along x, y completes the frame.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from rik.registry.robots import builtin_robot
from rik.schemas.robots import friction_capacity

if TYPE_CHECKING:
    import mujoco

    from rik.schemas.robots import Robot

GRIPPER_PREFIX = "gripper/"
BASE_JOINTS = ("x", "y", "z", "pitch", "yaw", "roll")
"""The base chain's joints (``gripper/<name>``): three slides (m) then three hinges (rad)."""


@dataclass(frozen=True)
class GripperSpec:
    """A parallel-jaw gripper and the arm that carries it. SI units; sources in the module docstring."""

    name: str
    stroke: float
    """Jaw opening at full open, m (both fingers together)."""
    grip_force: float
    """Force each jaw presses with when closed on an object, N."""
    finger_speed: float
    """Closing speed of each finger, m/s."""
    pad_friction: float
    """Static friction coefficient of the fingertip pads."""
    finger_length: float
    """m."""
    finger_width: float
    """m."""
    finger_thickness: float
    """Along the closing direction, pad included, m."""
    pad_length: float
    """m."""
    mass: float = 1.0
    """kg."""
    arm_force: float = 150.0
    """Force cap of each translational axis of the arm, N (assumption)."""
    arm_torque: float = 15.0
    """Torque cap of each rotational axis of the arm, N·m (assumption)."""
    arm_stiffness: float = 3000.0
    """Servo stiffness of the translational axes, N/m."""
    arm_rot_stiffness: float = 150.0
    """Servo stiffness of the rotational axes, N·m/rad."""
    arm_armature: float = 2.0
    """Reflected inertia of the arm on each translational axis, kg."""
    arm_rot_armature: float = 0.01
    """Reflected inertia on each rotational axis, kg·m²."""
    palm: tuple[float, float, float] = (0.090, 0.050, 0.060)
    """Palm (housing) size along x, y, z, m."""
    fixed_jaw: float | None = None
    """A swinging gripper: where its fixed jaw's pad face lies along the gripper frame's x, m (None: parallel jaws
    that close on the frame's centre)."""
    tcp_distance: float | None = None
    """An arm's gripper: from its flange to the gripper frame along the fingers, m (None: the Hand-E's, from its
    palm and fingers)."""

    def with_(self, **changes: Any) -> GripperSpec:
        return replace(self, **changes)

    @property
    def finger_travel(self) -> float:
        """Travel of one finger, m."""
        return self.stroke / 2

    @property
    def tcp_offset(self) -> float:
        """Distance from the base origin (palm's back face; an arm's flange) to the middle of the pads along +z, m."""
        if self.tcp_distance is not None:
            return self.tcp_distance
        return self.palm[2] + self.finger_length - self.pad_length / 2

    def friction_capacity(self) -> float:
        """The largest pull a pinch can transmit by friction alone: two pads, each pressed with the grip force, N."""
        return friction_capacity(self.pad_friction, self.grip_force)


def gripper_spec(robot: Robot) -> GripperSpec:
    """The :class:`GripperSpec` of a catalog robot (what the strategies plan with and episodes record); the arm and
    palm figures of the floating base (not in the catalog) keep their defaults."""
    g = robot.gripper
    spec = GripperSpec(name=g.name, stroke=g.stroke, grip_force=g.grip_force.value,
                       pad_friction=g.pad_friction.value, finger_speed=g.finger_speed.value,
                       finger_length=g.finger_length, finger_width=g.finger_width,
                       finger_thickness=g.finger_thickness, pad_length=g.pad_length)
    if robot.as_arm is not None:
        spec = spec.with_(tcp_distance=g.tcp_offset, fixed_jaw=g.fixed_jaw)
    return spec


HAND_E = gripper_spec(builtin_robot("hand-e"))
"""The Robotiq Hand-E, its figures (and their sources) read from the built-in catalog's ``robots.yaml``."""


BASE_QUAT = (0.7071067811865476, 0.7071067811865476, 0.0, 0.0)
"""The base body's fixed rotation: at zero joint angles the fingers point along world -y (into a front, which
faces +y) and the jaws close along world x."""
_AXES = {"x": [1, 0, 0], "y": [0, 0, -1], "z": [0, 1, 0], "pitch": [1, 0, 0], "yaw": [0, 1, 0], "roll": [0, 0, 1]}
"""Joint axes in the base frame: the slides move along world x, y, z; pitch turns about world x (positive: fingers
down), yaw about the (pitched) vertical, roll about the approach axis."""


def add_gripper(spec: mujoco.MjSpec, gripper: GripperSpec = HAND_E) -> None:
    """Add the gripper, its base chain, servos and wrist camera to ``spec`` (a ``mujoco.MjSpec``).

    The base sits at the world origin, so the slide joints' values are the world position of the base (the back
    face of the palm) and the hinge values its pitch, yaw and roll: together, the target pose."""
    import mujoco

    p = GRIPPER_PREFIX
    geom_box = mujoco.mjtGeom.mjGEOM_BOX
    base = spec.worldbody.add_body(name=f"{p}base", quat=list(BASE_QUAT), gravcomp=1.0)
    slide, hinge = mujoco.mjtJoint.mjJNT_SLIDE, mujoco.mjtJoint.mjJNT_HINGE
    for name in BASE_JOINTS:
        rotary = name in ("pitch", "yaw", "roll")
        base.add_joint(name=f"{p}{name}", type=hinge if rotary else slide, axis=_AXES[name],
                       armature=gripper.arm_rot_armature if rotary else gripper.arm_armature,
                       range=[-3.2, 3.2] if rotary else [-3.0, 3.0])
        act = spec.add_actuator(name=f"{p}{name}", target=f"{p}{name}", trntype=mujoco.mjtTrn.mjTRN_JOINT)
        act.set_to_position(kp=gripper.arm_rot_stiffness if rotary else gripper.arm_stiffness, dampratio=1.0)
        limit = gripper.arm_torque if rotary else gripper.arm_force
        act.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
        act.forcerange = [-limit, limit]
    px, py, pz = gripper.palm
    _box_inertial(base, gripper.mass * 0.8, (px, py, pz), (0.0, 0.0, pz / 2))
    base.add_geom(name=f"{p}palm", type=geom_box, size=[px / 2, py / 2, pz / 2], pos=[0, 0, pz / 2],
                  mass=gripper.mass * 0.8, rgba=[0.15, 0.15, 0.17, 1])
    base.add_site(name=f"{p}tcp", pos=[0, 0, gripper.tcp_offset], size=[0.004, 0.004, 0.004], group=4)
    # The wrist camera sits at the palm's front edge and looks past the fingertips (3 cm beyond the TCP), image up away
    # from the palm, so the fingers and what they grasp show in the lower half of the image.
    eye = np.array([0.0, -py / 2 - 0.015, pz + 0.005])
    look = np.array([0.0, 0.0, gripper.tcp_offset + 0.03]) - eye
    back = -look / np.linalg.norm(look)
    right = np.array([1.0, 0.0, 0.0])
    base.add_camera(name="wrist", pos=eye.tolist(), xyaxes=[*right, *np.cross(back, right)], fovy=70)
    for side, sign in (("left", -1.0), ("right", 1.0)):
        finger = base.add_body(name=f"{p}{side}", pos=[0, 0, pz], gravcomp=1.0)
        # The joint measures how far the finger's inner face is from the centre line: 0 closed, travel open.
        finger.add_joint(name=f"{p}{side}", type=slide, axis=[sign, 0, 0], range=[0.0, gripper.finger_travel],
                         armature=0.5, damping=20.0)
        t, w, length = gripper.finger_thickness, gripper.finger_width, gripper.finger_length
        _box_inertial(finger, gripper.mass * 0.1, (t, w, length), (sign * t / 2, 0.0, length / 2))
        finger.add_geom(name=f"{p}{side}/finger", type=geom_box, size=[t / 2, w / 2, length / 2],
                        pos=[sign * t / 2, 0, length / 2], mass=gripper.mass * 0.1, rgba=[0.3, 0.3, 0.32, 1],
                        friction=[gripper.pad_friction, 0.005, 0.0001], priority=1)
        finger.add_geom(name=f"{p}{side}/pad", type=geom_box, size=[0.0015, w / 2, gripper.pad_length / 2],
                        pos=[sign * 0.001, 0, length - gripper.pad_length / 2], mass=0.0, rgba=[0.1, 0.1, 0.1, 1],
                        friction=[gripper.pad_friction, 0.005, 0.0001], priority=2, condim=4,
                        solref=[0.004, 1.0], solimp=[0.95, 0.99, 0.001, 0.5, 2.0])
    # The Hand-E's fingers move together (one motor, synchronised): the right finger's opening equals the left's,
    # and one servo drives the jaw opening (a tendon: the sum of both). A closed command aims a full stroke past
    # closed, so on an object the servo saturates at the grip force, as the gripper's force setting caps its
    # motor current. Each jaw then presses with the servo's force.
    spec.add_equality(type=mujoco.mjtEq.mjEQ_JOINT, name1=f"{p}right", name2=f"{p}left",
                      solref=[0.004, 1.0])
    jaw = spec.add_tendon(name=f"{p}jaw")
    jaw.wrap_joint(f"{p}left", 1.0)
    jaw.wrap_joint(f"{p}right", 1.0)
    act = spec.add_actuator(name=f"{p}jaw", target=f"{p}jaw", trntype=mujoco.mjtTrn.mjTRN_TENDON)
    act.set_to_position(kp=20.0 * gripper.grip_force / gripper.stroke, dampratio=1.0)
    act.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
    act.forcerange = [-gripper.grip_force, gripper.grip_force]
    spec.add_exclude(bodyname1=f"{p}base", bodyname2=f"{p}left")
    spec.add_exclude(bodyname1=f"{p}base", bodyname2=f"{p}right")
    spec.add_exclude(bodyname1=f"{p}left", bodyname2=f"{p}right")


def _box_inertial(body: mujoco.MjsBody, mass: float, size: tuple[float, float, float],
                  com: tuple[float, float, float]) -> None:
    """Explicit inertia of a solid box (variants compile with ``inertiafromgeom="false"``)."""
    x, y, z = size
    body.explicitinertial = True
    body.mass = mass
    body.ipos = list(com)
    body.inertia = [mass * (y * y + z * z) / 12, mass * (x * x + z * z) / 12, mass * (x * x + y * y) / 12]


def jaw_target(gripper: GripperSpec, command: float) -> float:
    """Jaw-opening target (m, both fingers) for a gripper command in [0, 1]: 0 fully open, 0.5 closed with no
    force, 1 closed and pressing with the full grip force."""
    return gripper.stroke * (1.0 - 2.0 * min(max(command, 0.0), 1.0))
