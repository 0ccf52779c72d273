"""A robot's LeRobot layout: what ``observation.state`` and ``action`` hold for it, shared by the export, the gym
environment and ``rik eval`` so that a policy trained on an export runs in the environment unchanged.

- the Hand-E (``layout: pose``): the robot's state of :data:`rik.sim.observation.ROBOT_STATE_NAMES` and the
  recorded action (target pose and gripper command, :data:`POSE_ACTION_NAMES`), its position either in the world
  (``action_frame="world"``, the default), from the handle's grasp point (``"handle"``,
  :data:`HANDLE_ACTION_NAMES`: the target minus the grasp point of the same step's
  ``observation.environment_state``, world axes) or from the gripper base's own position (``"gripper"``,
  :data:`GRIPPER_ACTION_NAMES`: the target minus the same step's position in ``observation.state``, world axes; its
  ``observation.environment_state`` then also holds the grasp point from the gripper), which leave a policy
  millimetres to learn near the handle where the world frame leaves it a fraction of the whole workspace;
- an arm (``layout: joints``): its joint positions in ``observation.state`` and the joint targets its servos were
  given in ``action``, named and scaled as the catalog's ``lerobot.joints`` say (rad or deg, from the model's 0 or
  from the middle of the joint's range as LeRobot's calibration counts; the gripper as a closure fraction, 0 open
  and 1 closed, or as percent of its opening, 100 open and 0 closed), plus, where the
  entry asks for it, ``observation.ee_pose``: the gripper frame in the arm's base frame, as LeRobot's
  end-effector names (``ee.x``, ``ee.y``, ``ee.z`` m; ``ee.wx``, ``ee.wy``, ``ee.wz``: a rotation vector, rad).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from rik.errors import RikError
from rik.sim.observation import ROBOT_STATE_NAMES, robot_state

if TYPE_CHECKING:
    from rik.schemas.robots import Robot
    from rik.sim.scene import SimScene

POSE_ACTION_NAMES = ("target_x", "target_y", "target_z", "target_pitch", "target_yaw", "target_roll", "gripper")
"""The Hand-E's action: target pose of the gripper base (m, rad) and gripper command (0 open, 1 closed)."""
HANDLE_ACTION_NAMES = ("target_dx", "target_dy", "target_dz", "target_pitch", "target_yaw", "target_roll", "gripper")
"""The Hand-E's action in the handle frame: the target position minus the handle's grasp point (m, world axes; the
grasp point of the same step's ``observation.environment_state``), then as :data:`POSE_ACTION_NAMES`."""
GRIPPER_ACTION_NAMES = ("target_from_gripper_x", "target_from_gripper_y", "target_from_gripper_z", "target_pitch",
                        "target_yaw", "target_roll", "gripper")
"""The Hand-E's action in the gripper frame: the target position minus the gripper base's position of the same step
(m, world axes; ``observation.state``'s ``x``, ``y``, ``z``), then as :data:`POSE_ACTION_NAMES`."""
FRAME_ACTION_NAMES = {"world": POSE_ACTION_NAMES, "handle": HANDLE_ACTION_NAMES, "gripper": GRIPPER_ACTION_NAMES}
"""A pose action's frame -> its names."""
ACTION_FRAMES = tuple(FRAME_ACTION_NAMES)
"""Where a pose action's position is measured from: the world's origin, the handle's grasp point or the gripper
base."""
EE_NAMES = ("ee.x", "ee.y", "ee.z", "ee.wx", "ee.wy", "ee.wz")
HAND_E_ROBOT_TYPE = "rik_hand_e"


@dataclass(frozen=True)
class RobotLayout:
    """The state and action layout of one robot (see the module docstring)."""

    robot_id: str
    robot_type: str
    state_names: tuple[str, ...]
    action_names: tuple[str, ...]
    ee_pose: bool
    joints: tuple[tuple[str | None, str], ...] = ()
    """An arm's (joint name or None for the gripper, unit) per state and action number."""
    zeros: tuple[float, ...] = ()
    """An arm's joint position (rad) that reads 0, per state and action number (0.0 for the gripper)."""
    robot: Robot | None = None
    action_frame: str = "world"
    """A pose action's frame (:data:`ACTION_FRAMES`); an arm's joint action is always ``world``."""

    @property
    def is_pose(self) -> bool:
        return self.robot is None

    # ---- observation.state ----------------------------------------------------------------------------------
    def state(self, scene: SimScene) -> np.ndarray:
        """``observation.state`` of a scene, float64."""
        if self.robot is None:
            return robot_state(scene)
        drive = scene.robot_drive
        return self._in_units(drive.joint_positions(scene), drive.closure(scene))

    # ---- action ---------------------------------------------------------------------------------------------
    def frame_origin(self, scene: SimScene) -> np.ndarray:
        """Where this layout's pose action measures its position from in ``scene`` now (m, world): the origin, the
        handle's grasp point or the gripper base's position."""
        if self.action_frame == "handle":
            return scene.grasp_point()
        if self.action_frame == "gripper":
            return np.asarray(scene.pose()[:3], np.float64)
        return np.zeros(3)

    def action(self, pose_action: np.ndarray, targets: np.ndarray, origin: np.ndarray | None = None
               ) -> np.ndarray:
        """``action`` of a recorded row: the pose action itself for the Hand-E, its position less ``origin`` (m,
        world: :meth:`frame_origin` of the same step) in the handle or the gripper frame; for an arm its servos'
        joint targets (``robot_targets``, rad) and the gripper command (``pose_action[6]``, 0 open .. 1 closed)."""
        if self.robot is None:
            out = np.array(pose_action, np.float64)
            if self.action_frame != "world":
                assert origin is not None, f"a {self.action_frame}-frame action needs the step's frame origin"
                out[:3] -= np.asarray(origin, np.float64)
            return out
        return self.joint_action(targets, float(pose_action[6]))

    def world_action(self, action: np.ndarray, origin: np.ndarray) -> np.ndarray:
        """The inverse of :meth:`action` for the Hand-E: the world-frame pose action (target pose m, rad; gripper)
        of an ``action`` in this layout's frame, given its frame's origin now (:meth:`frame_origin`, m, world)."""
        out = np.array(action, np.float64)
        if self.action_frame != "world":
            out[:3] += np.asarray(origin, np.float64)
        return out

    def joint_action(self, targets: np.ndarray, grip: float) -> np.ndarray:
        """An arm's ``action`` from its joint targets (rad, the robot's joint order; more numbers after them are
        ignored) and gripper command (0 open .. 1 closed): what :meth:`joint_targets` inverts."""
        return self._in_units(targets, grip)

    def _in_units(self, q: np.ndarray, grip: float) -> np.ndarray:
        """An arm's joint positions or targets ``q`` (rad, the robot's joint order) and its gripper's closure or
        command ``grip`` (0 open .. 1 closed, clamped) in this layout's names, zeros and units, float64."""
        assert self.robot is not None
        names = list(self.robot.joint_names)
        grip = min(max(grip, 0.0), 1.0)
        return np.array([_to_unit(float(q[names.index(j)]) - zero, unit) if j is not None
                         else _grip_to_unit(grip, unit) for (j, unit), zero in zip(self.joints, self.zeros,
                                                                                    strict=True)], np.float64)

    def joint_targets(self, action: np.ndarray) -> tuple[np.ndarray, float]:
        """The inverse of :meth:`action` for an arm: (joint targets rad in the robot's joint order, gripper command
        0..1)."""
        assert self.robot is not None
        names = list(self.robot.joint_names)
        targets = np.zeros(len(names))
        grip = 0.0
        for value, (joint, unit), zero in zip(np.asarray(action, np.float64), self.joints, self.zeros, strict=True):
            if joint is None:
                grip = _grip_from_unit(float(value), unit)
            else:
                targets[names.index(joint)] = _from_unit(float(value), unit) + zero
        return targets, min(max(grip, 0.0), 1.0)

    # ---- observation.ee_pose ----------------------------------------------------------------------------------
    def ee(self, scene: SimScene) -> np.ndarray:
        """The gripper frame in the arm's base frame: x, y, z (m) and a rotation vector (rad)."""
        from scipy.spatial.transform import Rotation

        mount = scene.robot_drive.mount
        assert mount is not None  # an ee pose layout is an arm's, which stands on a mount
        base = Rotation.from_euler("z", mount.yaw)
        position = base.inv().apply(scene.tcp() - mount.pos)
        rotation = base.inv() * Rotation.from_matrix(scene.gripper_rotation())
        return np.concatenate([position, rotation.as_rotvec()]).astype(np.float64)


def _to_unit(value: float, unit: str) -> float:
    return math.degrees(value) if unit == "deg" else value


def _from_unit(value: float, unit: str) -> float:
    return math.radians(value) if unit == "deg" else value


def _grip_to_unit(closure: float, unit: str) -> float:
    return 100.0 * (1.0 - closure) if unit == "percent" else closure


def _grip_from_unit(value: float, unit: str) -> float:
    return 1.0 - value / 100.0 if unit == "percent" else value


def robot_layout(robot: Robot | None, action_frame: str = "world") -> RobotLayout:
    """The layout of a catalog robot (None, or a floating one: the Hand-E's pose layout), its pose action in
    ``action_frame`` (:data:`ACTION_FRAMES`; only a pose layout has a handle or a gripper frame)."""
    if action_frame not in ACTION_FRAMES:
        raise RikError(f"action frame '{action_frame}': use one of {', '.join(ACTION_FRAMES)}")
    if robot is None or robot.lerobot.layout == "pose":
        robot_type = HAND_E_ROBOT_TYPE if robot is None else robot.lerobot.robot_type
        return RobotLayout("hand-e" if robot is None else robot.id, robot_type, ROBOT_STATE_NAMES,
                           FRAME_ACTION_NAMES[action_frame],
                           False, action_frame=action_frame)
    if action_frame != "world":
        raise RikError(f"action frame '{action_frame}': robot {robot.id} acts with joint targets, which have no "
                       f"{action_frame} frame (it is the Hand-E's pose action's)")
    names = tuple(j.name for j in robot.lerobot.joints)
    return RobotLayout(robot.id, robot.lerobot.robot_type, names, names, robot.lerobot.ee_pose,
                       tuple((j.joint, j.unit) for j in robot.lerobot.joints),
                       tuple(joint_zero(robot, j.joint) if j.joint is not None and j.zero == "mid_range" else 0.0
                             for j in robot.lerobot.joints), robot)


def joint_zero(robot: Robot, joint: str) -> float:
    """The position (rad) of ``joint`` that LeRobot's calibration reads as 0: the middle of its range."""
    assert robot.joints is not None
    lo, hi = next(j.range for j in robot.joints.joints if j.name == joint)
    return (lo + hi) / 2
