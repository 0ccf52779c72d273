"""The simulation scene: a built variant with the robot that opens its front (:func:`rik.sim.build.build_scene`
assembles it), the names and addresses that operators, recorders and the environment use, and what a scene asks of
its robot (:class:`Drive`).

The gripper's servos are addressed by name (their control addresses), since a variant's own passive actuators
(native joint effects) come first in the model. Joint effects MuJoCo lacks (the variant's ``runtime_effects``)
are applied around every physics step, on every front that has them (:class:`rik.joints.runtime.RuntimeEffects`);
they leave no trace in the state, so replays stay exact.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

from rik.joints.runtime import RuntimeEffects
from rik.sim.pose import base_for_tcp
from rik.sim.robots.gripper import GripperSpec

if TYPE_CHECKING:
    import mujoco

    from rik.schemas.robots import Robot
    from rik.sim.robots.arm import Placement
    from rik.sim.robots.results import CheckResult, ReachPoint

CONTROL_FPS = 20
"""Control (and recording) rate, Hz."""
FINGERS = ("left", "right")


class Drive(Protocol):
    """What a scene asks of its robot."""

    robot_id: str
    joint_names: tuple[str, ...]
    """Names of :meth:`joints` (the robot's joints, then the gripper)."""
    arm_ctrl: np.ndarray
    """Indices in ``data.ctrl`` of the robot's own servos (not the jaw's), in :meth:`joint_positions`' order."""

    def pose(self, scene: SimScene) -> np.ndarray: ...

    def place(self, scene: SimScene, pose: np.ndarray, grip: float) -> None: ...

    def command(self, scene: SimScene, action: np.ndarray) -> None: ...

    def jaw(self, scene: SimScene, command: float) -> tuple[float, float]: ...

    def finger_opening(self, scene: SimScene) -> float: ...

    def joints(self, scene: SimScene) -> np.ndarray: ...

    def targets(self, scene: SimScene, action: np.ndarray) -> np.ndarray: ...

    def pose_is_free(self, scene: SimScene, pose: np.ndarray, opening: float,
                     ignore_bodies: frozenset[int] = frozenset()) -> bool: ...

    @property
    def mount(self) -> Placement | None:
        """Where the robot's base stands in the world (None: a base that moves freely in the world frame)."""

    def set_targets(self, scene: SimScene, q: np.ndarray) -> None:
        """Servo targets of the robot's own joints (rad), a policy's joint action; a robot that takes only a target
        pose refuses (one line)."""

    def joint_positions(self, scene: SimScene) -> np.ndarray:
        """Positions of the robot's own joints in its catalog order (rad; the Hand-E's base: m, then rad)."""

    def closure(self, scene: SimScene) -> float:
        """How closed the jaws are: 0 fully open, 1 touching."""

    def geoms(self, scene: SimScene) -> frozenset[int]:
        """The robot's colliding geoms (gripper included)."""

    def reach(self, scene: SimScene, openings: tuple[float, ...], force: float) -> list[ReachPoint]:
        """The natural pinch of the operated handle at each opening (fraction of the front's range) and what holding
        ``force`` N there asks of the robot (see :mod:`rik.sim.robots.checks`); the scene is left as it was."""

    def hold_reach(self, scene: SimScene, offset: np.ndarray, angles: np.ndarray,
                   position_first: bool = False) -> float:
        """The largest opening (fraction of the front's range, from its opening now) up to which the robot keeps its
        gripper frame at the handle's grasp point plus ``offset`` (m, world) with the gripper's ``angles`` (rad) as
        the front opens; -1 when not even the first; the scene is left as it was. ``position_first``: an arm of
        fewer than six joints may give up orientation (within the reach tolerance) for position
        (:meth:`rik.sim.robots.ik.ArmIK.step`), the planner's fallback for grasps it misses otherwise."""

    def reach_checks(self, scene: SimScene, force: float) -> list[CheckResult]:
        """The ``reach`` and ``torque_headroom`` checks of this robot holding the front's resistance ``force`` N."""


@dataclass(frozen=True)
class HandleContact:
    """The gripper's contacts with the operated front (:meth:`SimScene.handle_contact`)."""

    front: int
    """Contacts with the front (panel and handle)."""
    handle_bodies: int
    """How many of the gripper's bodies touch the handle (2 or more: both jaws)."""
    handle_force: float
    """Normal force of the gripper's contacts with the handle, N."""


@dataclass(frozen=True)
class FrontInfo:
    """The front a scene operates: its joint, range and handle."""

    id: str
    kind: str
    motion: str
    joint: int
    qpos_adr: int
    dof_adr: int
    range: tuple[float, float]
    body: int
    handle_body: int
    grasp_site: int


@dataclass
class SimScene:
    """A compiled scene and the names and addresses that operators, recorders and the environment use."""

    model: mujoco.MjModel
    data: mujoco.MjData
    info: dict[str, Any]
    """The variant's ``rik.variant`` record (id, base unit, handle, preset, fronts)."""
    front: FrontInfo
    gripper: GripperSpec
    directory: Path
    control_fps: int = CONTROL_FPS
    base_qpos: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    finger_qpos: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    gripper_geoms: frozenset[int] = frozenset()
    front_bodies: frozenset[int] = frozenset()
    tcp_site: int = -1
    arm_ctrl: np.ndarray = field(default_factory=lambda: np.arange(6))
    """Control addresses of the robot's servos: the Hand-E's base axes (x, y, z, pitch, yaw, roll), or an arm's
    joints."""
    jaw_ctrl: int = 6
    """Control address of the jaw servo."""
    effects: tuple[RuntimeEffects, ...] = ()
    """Runtime joint effects of the variant's fronts, applied around each physics step."""
    drive: Drive | None = None
    """How the robot takes the target pose (:mod:`rik.sim.robots.drive`); set by :func:`build_scene`."""
    robot: Robot | None = None
    """The catalog entry of an arm (None: the Hand-E of :attr:`gripper`)."""
    spec: mujoco.MjSpec | None = None
    """The spec :attr:`model` was compiled from (set by :func:`rik.sim.build.build_scene`): a view of the scene
    (the teleop station's decimated view model) is compiled from a copy of it; the physics never reads it."""

    @property
    def robot_id(self) -> str:
        """The robot's catalog id (``hand-e`` for the floating gripper)."""
        return self.robot_drive.robot_id

    @property
    def robot_drive(self) -> Drive:
        """The robot's :class:`Drive` (set by :func:`rik.sim.build.build_scene`)."""
        assert self.drive is not None, "build the scene with build_scene"
        return self.drive

    @property
    def substeps(self) -> int:
        """Physics steps per control step."""
        return max(1, round(1.0 / (self.control_fps * self.model.opt.timestep)))

    # ---- state ------------------------------------------------------------------------------------------------
    def front_q(self) -> tuple[float, float]:
        """The operated front's joint position (m or rad) and velocity (m/s or rad/s)."""
        return float(self.data.qpos[self.front.qpos_adr]), float(self.data.qvel[self.front.dof_adr])

    def opening(self) -> float:
        """How far the operated front is open, as a fraction of its range (0 closed, 1 fully open)."""
        lo, hi = self.front.range
        return (self.front_q()[0] - lo) / (hi - lo)

    def pose(self) -> np.ndarray:
        """The gripper base's pose: x, y, z (m, world) and pitch, yaw, roll (rad). An arm's is the pose its gripper
        frame gives (the flange's position and the frame's angles)."""
        return self.robot_drive.pose(self)

    def finger_opening(self) -> float:
        """Jaw opening, m (both fingers)."""
        return self.robot_drive.finger_opening(self)

    def robot_joints(self) -> np.ndarray:
        """The robot's joint positions, then its gripper's (:attr:`Drive.joint_names`; rad, m)."""
        return self.robot_drive.joints(self)

    def tcp_quat(self) -> np.ndarray:
        """World orientation of the gripper frame, unit quaternion (w, x, y, z)."""
        return _mat2quat(self.data.site_xmat[self.tcp_site])

    def tcp(self) -> np.ndarray:
        """World position of the point between the pads, m."""
        return self.data.site_xpos[self.tcp_site].copy()

    def gripper_rotation(self) -> np.ndarray:
        """World rotation matrix of the gripper frame (fingers along its z, jaws along its x)."""
        return self.data.site_xmat[self.tcp_site].reshape(3, 3).copy()

    def grasp_point(self) -> np.ndarray:
        """World position of the operated handle's grasp site (its bounding-box centre), m."""
        return self.data.site_xpos[self.front.grasp_site].copy()

    def handle_frame(self) -> tuple[np.ndarray, np.ndarray]:
        """World position and rotation of the operated handle's body."""
        b = self.front.handle_body
        return self.data.xpos[b].copy(), self.data.xmat[b].reshape(3, 3).copy()

    def pull_direction(self) -> np.ndarray:
        """Unit vector along which the grasp point moves when the front opens (world)."""
        import mujoco

        jacp = np.zeros((3, self.model.nv))
        mujoco.mj_jacSite(self.model, self.data, jacp, None, self.front.grasp_site)
        v = jacp[:, self.front.dof_adr]
        n = np.linalg.norm(v)
        return v / n if n > 0 else np.array([0.0, 1.0, 0.0])

    def front_contacts(self) -> Iterator[tuple[int, int, int]]:
        """The contacts between the gripper and the operated front (its panel and handle): (contact index, the
        gripper's geom, the front's geom) for each."""
        d, m = self.data, self.model
        for i in range(d.ncon):
            g1, g2 = int(d.contact.geom1[i]), int(d.contact.geom2[i])
            if (g1 in self.gripper_geoms) == (g2 in self.gripper_geoms):
                continue
            ours, other = (g1, g2) if g1 in self.gripper_geoms else (g2, g1)
            if int(m.geom_bodyid[other]) in self.front_bodies:
                yield i, ours, other

    def handle_contact(self) -> HandleContact:
        """The gripper's contacts with the operated front and its handle (:class:`HandleContact`)."""
        import mujoco

        m, d = self.model, self.data
        front, force, bodies = 0, 0.0, set()
        wrench = np.zeros(6)
        for i, ours, other in self.front_contacts():
            front += 1
            if int(m.geom_bodyid[other]) == self.front.handle_body:
                mujoco.mj_contactForce(m, d, i, wrench)
                force += abs(float(wrench[0]))
                bodies.add(int(m.geom_bodyid[ours]))
        return HandleContact(front, len(bodies), force)

    def contact_summary(self) -> dict[str, float]:
        """Contacts between the gripper and the operated front (its panel and handle): how many, and the total
        normal and tangential force they carry, N."""
        import mujoco

        count, normal, tangential = 0, 0.0, 0.0
        wrench = np.zeros(6)
        d, m = self.data, self.model
        for i, _, _ in self.front_contacts():
            mujoco.mj_contactForce(m, d, i, wrench)
            count += 1
            normal += abs(float(wrench[0]))
            tangential += float(np.hypot(wrench[1], wrench[2]))
        return {"contacts": float(count), "normal_force": normal, "tangential_force": tangential}

    # ---- control ----------------------------------------------------------------------------------------------
    def reset(self) -> None:
        """Back to the state of a freshly built scene: MuJoCo's initial state, every position computed from it
        (before that, the handle's site reads (0, 0, 0)), then the gripper at rest at :func:`start_pose`, in
        front of the operated handle."""
        import mujoco

        mujoco.mj_resetData(self.model, self.data)
        mujoco.mj_forward(self.model, self.data)
        self.set_pose(start_pose(self))

    def set_pose(self, pose: np.ndarray, grip: float = 0.0) -> None:
        """Put the gripper at ``pose`` at rest (fingers at the grip command's opening; an arm solved there from its
        home posture, its gripper open) and run kinematics."""
        self.robot_drive.place(self, np.asarray(pose, np.float64), grip)

    def step(self, action: np.ndarray) -> None:
        """One control step: the robot aims at the target pose ``action[:6]`` (the Hand-E's base servos directly,
        an arm through one IK step); the jaws move towards the grip command ``action[6]`` at the gripper's finger
        speed."""
        action = np.asarray(action, dtype=np.float64)
        self.robot_drive.command(self, action)
        self._run(float(action[6]))

    def step_joints(self, targets: np.ndarray, grip: float) -> None:
        """One control step of an arm driven joint by joint (a policy trained on an arm's export): its servos aim
        at ``targets`` (rad, held within reach of the joints as the IK's targets are), the jaws at ``grip``."""
        self.robot_drive.set_targets(self, np.asarray(targets, np.float64))
        self._run(float(grip))

    def _run(self, grip: float) -> None:
        """The physics steps of one control step, the jaw servo slewing towards the grip command."""
        import mujoco

        m, d, jaw, effects = self.model, self.data, self.jaw_ctrl, self.effects
        goal, dmax = self.robot_drive.jaw(self, grip)
        for _ in range(self.substeps):
            c = float(d.ctrl[jaw])
            d.ctrl[jaw] = c + min(max(goal - c, -dmax), dmax)
            for e in effects:
                e.apply(d)
            mujoco.mj_step(m, d)
            for e in effects:
                e.undo(d)

    def state(self) -> np.ndarray:
        """The full integration state (``mj_getState`` with ``mjSTATE_INTEGRATION``): time, positions,
        velocities, controls, warm start: everything a replay or a re-simulation needs."""
        import mujoco

        spec = mujoco.mjtState.mjSTATE_INTEGRATION
        out = np.empty(mujoco.mj_stateSize(self.model, spec))
        mujoco.mj_getState(self.model, self.data, out, spec)
        return out

    def restore(self, state: np.ndarray) -> None:
        """Set the integration state and recompute everything derived from it."""
        import mujoco

        mujoco.mj_setState(self.model, self.data, np.asarray(state, np.float64), mujoco.mjtState.mjSTATE_INTEGRATION)
        mujoco.mj_forward(self.model, self.data)


def _mat2quat(mat: np.ndarray) -> np.ndarray:
    """A rotation matrix (9 numbers, row-major) as a unit quaternion (w, x, y, z) with w >= 0."""
    import mujoco

    q = np.empty(4)
    mujoco.mju_mat2Quat(q, np.asarray(mat, np.float64).reshape(9))
    return -q if q[0] < 0 else q


START_DISTANCE = 0.25
"""How far in front of the operated handle the Hand-E starts, m (an arm's mount says its own)."""


def start_pose(scene: SimScene, distance: float | None = None) -> np.ndarray:
    """The gripper's rest pose: fingers towards the operated handle, ``distance`` in front of it (default: the
    robot's, :data:`START_DISTANCE` for the Hand-E)."""
    if distance is None:
        mount = scene.robot.mount if scene.robot is not None else None
        distance = mount.start_distance if mount is not None else START_DISTANCE
    target = scene.grasp_point() + np.array([0.0, distance, 0.0])
    return base_for_tcp(scene.gripper, target, np.zeros(3))
