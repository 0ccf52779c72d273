"""Robots: what opens the fronts. A robot is a catalog entry (``robots:``) with its model's source and licence, its
mount, its joints' limits, its gripper with the sources of its figures, its wrist camera and its LeRobot layout.

Two kinds:

- ``floating``: rik's Robotiq Hand-E on a force-limited six-axis base (:mod:`rik.sim.robots.gripper`), the paper's
  set-up; its gripper's figures live in this entry, which :data:`rik.sim.robots.gripper.HAND_E` reads;
- ``arm``: a robot arm read from the MJCF files of an installed Python package (never downloaded at run time),
  attached to the scene through ``mujoco.MjSpec`` and driven through differential inverse kinematics
  (:mod:`rik.sim.robots.ik`), so that it takes the same target pose as the Hand-E.

Units are SI: m, rad, N, N·m, rad/s; joint stiffness N·m/rad, damping N·m·s/rad, armature kg·m².
"""

from __future__ import annotations

import math
import re
from enum import StrEnum
from pathlib import PurePosixPath
from typing import Annotated, Literal

from pydantic import Field, field_validator, model_validator

from rik.schemas.common import FieldError, Frozen, Length, Quat, Real, SimpleId, Vec3

Positive = Annotated[float, Field(gt=0, allow_inf_nan=False)]
NonNeg = Annotated[float, Field(ge=0, allow_inf_nan=False)]
Text = Annotated[str, Field(min_length=1)]


class RobotKind(StrEnum):
    floating = "floating"  #: a gripper on six servoed axes (rik's Hand-E)
    arm = "arm"  #: an arm model from a package, driven by inverse kinematics


class Sourced(Frozen):
    """A physical figure and where it comes from."""

    value: Positive
    source: Text
    """A datasheet, a manual, a measurement (say how) or an assumption (say why)."""


PACKAGE_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
"""A top-level import name: rik finds its folder without importing anything (a dotted name would import its
parent package to look inside it, running that package's code)."""


class ModelSource(Frozen):
    """Where a robot's MJCF comes from."""

    package: str | None = None
    """Import name of the installed distribution that ships the files (``gym_hil``); None: rik builds the model."""
    files: tuple[Text, ...] = ()
    """MJCF files inside the package, relative to it. One file is a whole model; several are ``mujocoinclude``
    fragments joined in order (the first holding assets and defaults, the rest bodies). No absolute path and no
    ``..``; where they resolve (symbolic links followed) is checked when the robot is used
    (:func:`rik.registry.robots.usable_robot`)."""
    root_body: str | None = None
    """The body of the model that is attached to the scene (the arm's base)."""
    licence: Text
    """SPDX expression of the model's licence."""
    origin: Text
    """Where the model was made and how it reached the package."""

    @field_validator("package")
    @classmethod
    def _top_level_name(cls, value: str | None) -> str | None:
        if value is not None and not PACKAGE_NAME.fullmatch(value):
            raise ValueError(f"{value!r} is not a top-level import name (letters, digits and '_', no '.'): rik finds "
                             "the package's folder without importing any of it")
        return value

    @model_validator(mode="after")
    def _package_needs_files(self) -> ModelSource:
        if self.package is not None and (not self.files or self.root_body is None):
            raise ValueError("a model from a package names its files and its root_body")
        for i, file in enumerate(self.files):
            path = PurePosixPath(file)
            if path.is_absolute() or ".." in path.parts or "\\" in file or "\x00" in file:
                raise FieldError(("files", i), f"{file!r} leads outside the package: model files are paths inside "
                                 "it, relative to its folder, without '..'")
        return self


class RobotJoint(Frozen):
    """One actuated joint of an arm, with the servo rik gives it (a position servo whose force is capped)."""

    name: Text
    """Joint name in the model (before rik's ``robot/`` prefix)."""
    range: tuple[Real, Real]
    """(lower, upper) position, rad."""
    torque: Positive
    """Largest torque the joint's motor applies, N·m (gravity compensation included where the robot has it)."""
    speed: Positive
    """Largest joint speed, rad/s: the IK's velocity limit."""
    stiffness: Positive
    """Servo stiffness, N·m/rad."""
    damping: NonNeg
    """Servo damping, N·m·s/rad."""
    friction: NonNeg | None = None
    """Dry friction of the joint, N·m; None keeps the model's."""
    armature: NonNeg | None = None
    """Reflected rotor inertia, kg·m²; None keeps the model's."""
    joint_damping: NonNeg | None = None
    """Viscous damping of the joint itself (beside the servo's ``damping``), N·m·s/rad; None keeps the model's."""

    @field_validator("range")
    @classmethod
    def _ordered(cls, value: tuple[float, float]) -> tuple[float, float]:
        if not value[0] < value[1]:
            raise ValueError(f"must be (lower, upper) with lower < upper, got ({value[0]}, {value[1]})")
        return value


class Joints(Frozen):
    """An arm's actuated joints, base to wrist, and the sources of their figures."""

    joints: tuple[RobotJoint, ...] = Field(min_length=1)
    gravity_compensation: bool
    """True when the robot's controller compensates gravity (a Franka does; a hobby servo does not). The
    compensation counts against each joint's torque."""
    source: Text


class Mount(Frozen):
    """Where an arm's base stands, relative to the handle it operates: so the same entry serves every variant."""

    offset: Vec3
    """The base's origin from the operated handle's grasp point with the front closed, m, in the scene's axes (the
    base unit's: +x left as one faces the front, +y out of the front, +z up)."""
    yaw: Real
    """Heading of the base about +z, rad: 0 points its +x along the scene's +x."""
    clearance: NonNeg = 0.0
    """With a sideways ``offset`` (x not 0): the base stands at least this far outside the furniture's side, m, so
    that the fronts, drawers and their boxes pass it by."""
    mirror: bool = False
    """With a sideways ``offset``: stand on the furniture's side nearer the handle (x and yaw mirrored there, and a
    parallel gripper held half a turn round about its approach: the same grasp, the wrist in the same range)."""
    home: tuple[Real, ...]
    """Joint positions (rad, one per joint) from which the start pose is solved."""
    start_distance: Length = 0.25
    """How far in front of the handle the gripper frame starts, m (the Hand-E's 0.25 unless the arm is too short
    to fold back that far)."""
    reason: Text
    """Why here: what was checked (reach over the opening, joint margins)."""


class GripperFrame(Frozen):
    """rik's gripper frame on the robot's model: origin between the pads' centres, fingers along +z, jaws
    closing along x (the Hand-E's ``gripper/tcp``)."""

    body: Text
    pos: Vec3
    """m, in the body's frame."""
    quat: Quat = (1.0, 0.0, 0.0, 0.0)
    """Rotation from the body's frame (w, x, y, z)."""


class GripperActuation(Frozen):
    """How a gripper command (0 open, 1 closed with full force) reaches an arm's gripper."""

    actuator: Text
    """The gripper's actuator: one of the model's (kept as it is), or the position servo rik adds on ``joint``."""
    joint: str | None = None
    """With ``stiffness``: rik adds a position servo on this joint, its force capped at the gripper's force."""
    stiffness: Positive | None = None
    """Of the servo rik adds, N·m/rad."""
    force_limit: Sourced | None = None
    """Force cap of the servo rik adds, in its joint's unit (N·m for a hinge)."""
    friction: NonNeg | None = None
    """Dry friction of the servo's joint (N·m for a hinge); None keeps the model's."""
    joint_damping: NonNeg | None = None
    """Viscous damping of the servo's joint (N·m·s/rad for a hinge); None keeps the model's."""
    ctrl_open: Real
    """Actuator control for an open gripper (command 0)."""
    ctrl_closed: Real
    """Actuator control for a closed gripper pressing with its full force (command 1)."""
    opening_joint: Text
    """The joint whose position tells how far the gripper is open."""
    joint_open: Real
    """Its position with the jaws fully open, rad."""
    joint_closed: Real
    """Its position with the jaws touching, rad."""

    @model_validator(mode="after")
    def _servo_whole(self) -> GripperActuation:
        if not (self.joint is None) == (self.stiffness is None) == (self.force_limit is None):
            raise ValueError("a servo rik adds needs joint, stiffness and force_limit")
        if self.ctrl_open == self.ctrl_closed or self.joint_open == self.joint_closed:
            raise ValueError("open and closed must differ (ctrl_open/ctrl_closed, joint_open/joint_closed)")
        return self


def friction_capacity(pad_friction: float, grip_force: float) -> float:
    """The largest pull a pinch transmits to a handle by friction alone, N: two pads, each pressed with
    ``grip_force`` (N), times ``pad_friction``: ``2 μ F``. The catalog's gripper and the simulator's both use it."""
    return 2.0 * pad_friction * grip_force


class Gripper(Frozen):
    """A robot's gripper: its figures with their sources, and its geometry as the scripted strategies plan with
    it."""

    name: Text
    kind: Literal["parallel", "swing"]
    """``parallel``: two jaws closing together; ``swing``: a fixed jaw and one that swings against it."""
    stroke: Length
    """Jaw opening at full open, m."""
    grip_force: Sourced
    """Force each jaw presses with on a held object, N."""
    pad_friction: Sourced
    """Static friction coefficient of the pads."""
    finger_speed: Sourced
    """Speed of each finger, m/s."""
    pads: tuple[Text, ...] = ()
    """Geoms of the model whose friction is set to ``pad_friction`` (empty: rik's own Hand-E)."""
    body: str | None = None
    """The gripper's root body in an arm's model: its subtree's geoms are the gripper's."""
    frame: GripperFrame | None = None
    """rik's gripper frame on an arm's model (the Hand-E's is built by rik)."""
    tcp_offset: Length
    """From the flange (or the Hand-E's palm back) to the gripper frame along the fingers, m: the target pose is
    the pose of that point's frame."""
    finger_length: Length
    finger_width: Length
    finger_thickness: Length
    pad_length: Length
    """Finger and pad dimensions, m, as the grasp planner sees them."""
    fixed_jaw: Real | None = None
    """A swinging gripper: where its fixed jaw's pad face lies along the frame's x (the closing axis), m. The grasp
    planner puts that face just beside the handle, and the swinging jaw closes the handle against it."""
    actuation: GripperActuation | None = None
    """How an arm's gripper is driven (the Hand-E's is built by rik)."""

    @property
    def pull_capacity(self) -> float:
        """The largest pull the gripper transmits to a handle by friction alone, N: two pads (both jaws of a
        parallel gripper; the fixed and the swinging jaw of a swinging one), each pressed with ``grip_force``,
        times ``pad_friction``: :func:`friction_capacity`."""
        return friction_capacity(self.pad_friction.value, self.grip_force.value)


class WristCamera(Frozen):
    """The camera that rides on the gripper (``wrist`` in images and datasets)."""

    body: Text
    pos: Vec3
    """m, in the body's frame."""
    xyaxes: tuple[Real, Real, Real, Real, Real, Real]
    """The image's right and up directions in the body's frame."""
    fovy: Annotated[float, Field(gt=0, lt=180)]
    """Vertical field of view, degrees."""
    source: Text
    """Where the real robot carries it."""


class LayoutEntry(Frozen):
    """One number of a robot's LeRobot state and action."""

    name: Text
    """Feature name, e.g. ``shoulder_pan.pos``."""
    joint: str | None = None
    """The robot joint it reads (None: the gripper)."""
    unit: Literal["rad", "deg", "fraction", "percent"]
    """A joint in rad or deg; the gripper as its closure: a fraction (0 open, 1 closed) or percent of opening
    (100 open at ``joint_open``, 0 closed at ``joint_closed``, linear in the jaw joint's angle: LeRobot's
    ``RANGE_0_100`` over a calibrated range from closed to open)."""
    zero: Literal["model", "mid_range"] = "model"
    """A joint's 0: the model's, or the middle of the joint's ``range`` (where LeRobot's calibration puts a real
    arm's 0: its SO follower reads ``(raw - (range_min + range_max) / 2) * 360 / 4095`` degrees over the range of
    motion recorded when calibrating)."""


class LeRobotLayout(Frozen):
    """What ``rik export-lerobot`` writes for this robot, and what the gym env reads and takes with it."""

    robot_type: Text
    """``info.json``'s ``robot_type``."""
    layout: Literal["pose", "joints"]
    """``pose``: the gripper's pose and state (the Hand-E, :data:`rik.sim.observation.ROBOT_STATE_NAMES`);
    ``joints``: the arm's joint positions in ``observation.state`` and their targets in ``action``."""
    joints: tuple[LayoutEntry, ...] = ()
    """With ``joints``: the numbers of ``observation.state`` and ``action``, in order."""
    ee_pose: bool = False
    """Also write ``observation.ee_pose``: the gripper frame in the arm's base frame (``ee.x`` .. ``ee.wz``: m, and
    a rotation vector in rad, LeRobot's end-effector names)."""
    source: Text

    @model_validator(mode="after")
    def _joints_for_joint_layout(self) -> LeRobotLayout:
        if self.layout == "joints" and not self.joints:
            raise ValueError("a joints layout lists its joints")
        if self.layout == "pose" and (self.joints or self.ee_pose):
            raise ValueError("the pose layout takes no joints and no ee_pose")
        names = [j.name for j in self.joints]
        for i, name in enumerate(names):
            if name in names[:i]:
                raise FieldError(("joints", i, "name"), f"feature name '{name}' repeats (entry {names.index(name)})")
        for i, entry in enumerate(self.joints):
            if entry.joint is None and entry.zero != "model":
                raise FieldError(("joints", i, "zero"), f"'{entry.name}' is the gripper: its 0 is the closed jaw "
                                 "(zero: mid_range is for joints)")
        grippers = [i for i, j in enumerate(self.joints) if j.joint is None]
        if len(grippers) > 1:
            raise FieldError(("joints", grippers[1], "joint"), "only one entry may be the gripper (joint: null)")
        return self


class Robot(Frozen):
    """A robot that opens fronts (see the module docstring)."""

    id: SimpleId
    name: Text
    kind: RobotKind
    description: str = ""
    model: ModelSource
    joints: Joints | None = None
    """An arm's actuated joints (None for the floating Hand-E)."""
    mount: Mount | None = None
    gripper: Gripper
    wrist_camera: WristCamera | None = None
    """An arm's wrist camera (the Hand-E's is built by rik)."""
    lerobot: LeRobotLayout

    @model_validator(mode="after")
    def _arm_is_whole(self) -> Robot:
        if (self.gripper.kind == "swing") != (self.gripper.fixed_jaw is not None):
            raise ValueError("a swinging gripper (and only one) gives gripper.fixed_jaw")
        if self.kind is RobotKind.arm:
            missing = [f for f in ("joints", "mount", "wrist_camera") if getattr(self, f) is None]
            missing += [f"gripper.{f}" for f in ("body", "frame", "actuation") if getattr(self.gripper, f) is None]
            if self.model.package is None:
                missing.append("model.package")
            if missing:
                raise ValueError(f"an arm needs {', '.join(missing)}")
            assert self.joints is not None and self.mount is not None
            if len(self.mount.home) != len(self.joints.joints):
                raise FieldError(("mount", "home"), f"{len(self.mount.home)} positions for "
                                 f"{len(self.joints.joints)} joints (one per joint, rad)")
            for i, (j, q) in enumerate(zip(self.joints.joints, self.mount.home, strict=True)):
                if not j.range[0] <= q <= j.range[1]:
                    raise FieldError(("mount", "home", i), f"puts joint {j.name} at {q} rad, outside its range "
                                     f"({j.range[0]}, {j.range[1]})")
            known = [j.name for j in self.joints.joints]
            for i, entry in enumerate(self.lerobot.joints):
                if entry.joint is not None and entry.joint not in known:
                    raise FieldError(("lerobot", "joints", i, "joint"), f"layout entry '{entry.name}' reads joint "
                                     f"'{entry.joint}', which is not one of the robot's joints ({', '.join(known)})")
            if self.lerobot.layout != "joints":
                raise FieldError(("lerobot", "layout"), "an arm exports its joints (lerobot.layout: joints)")
        elif self.joints is not None or self.mount is not None:
            raise FieldError(("joints" if self.joints is not None else "mount",),
                             "a floating robot has no joints or mount")
        return self

    @property
    def as_arm(self) -> Robot | None:
        """This entry when it is an arm, None for the floating Hand-E: what ``build_scene``'s ``robot=`` and
        ``robot_layout`` take."""
        return self if self.kind is RobotKind.arm else None

    @property
    def joint_names(self) -> tuple[str, ...]:
        return tuple(j.name for j in self.joints.joints) if self.joints else ()


def yaw_quat(yaw: float) -> tuple[float, float, float, float]:
    """The unit quaternion (w, x, y, z) of a turn by ``yaw`` rad about +z."""
    return (math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2))
