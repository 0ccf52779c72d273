"""The simulation scene: a built variant, the gripper on its force-limited base, a floor, lights, a fixed front
camera aimed at the operated front's handle, and the wrist camera.

Solver settings (what keeps a pinch on hundreds of convex parts stable):

- **elliptic friction cones with impratio 10**: pyramidal cones and impratio 1 let a pinched handle creep
  through the pads under a steady pull; MuJoCo's documentation recommends elliptic cones and a large impratio
  for grasping, which make friction as stiff as the normal direction and remove that creep;
- **Newton solver**, 100 iterations, 50 line-search iterations, tolerance 1e-8: the contact count jumps from
  none to dozens when fingers close on a decomposed handle; Newton converges in a few iterations where CG and PGS
  leave residual penetration that reads as slip;
- **implicitfast integration at 2 ms** (the variant's own settings): the servos' damping and the joints'
  damping are integrated implicitly, so stiff servos stay stable at the step that the checks validated;
- **pads with stiffer contact** (solref 4 ms, solimp 0.95-0.99) and torsional friction (condim 4), so a knob
  held in a pinch does not spin about the contact normal.

The gripper's servos are addressed by name (their control addresses), since a variant's own passive actuators
(native joint effects) come first in the model. Joint effects MuJoCo lacks (the variant's ``runtime_effects``)
are applied around every physics step, on every front that has them (:class:`rik.joints.runtime.RuntimeEffects`);
they leave no trace in the state, so replays stay exact.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from rik.errors import RikError
from rik.joints.runtime import RuntimeEffects
from rik.sim.gripper import BASE_JOINTS, GRIPPER_PREFIX, HAND_E, GripperSpec

if TYPE_CHECKING:
    import mujoco

    from rik.schemas.robots import Robot
    from rik.sim.drive import Drive

CONTROL_FPS = 20
"""Control (and recording) rate, Hz."""
IMPRATIO = 10.0
FRONT_CAMERA_DISTANCE = 0.9
"""Distance from the operated handle to the front camera, m."""
FINGERS = ("left", "right")
GRIPPER_BASE_QUAT = [0.7071067811865476, 0.0, 0.0, 0.7071067811865476]
"""The gripper frame's rotation at zero pitch, yaw and roll (x, y, z, w: a quarter turn about world x), which
:func:`gripper_rotation` composes with the angles and :func:`rik.sim.drive.angles_of` takes back out."""


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
    """How the robot takes the target pose (:mod:`rik.sim.drive`); set by :func:`build_scene`."""
    robot: Robot | None = None
    """The catalog entry of an arm (None: the Hand-E of :attr:`gripper`)."""

    @property
    def robot_id(self) -> str:
        """The robot's catalog id (``hand-e`` for the floating gripper)."""
        return self._drive.robot_id

    @property
    def _drive(self) -> Drive:
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
        return self._drive.pose(self)

    def finger_opening(self) -> float:
        """Jaw opening, m (both fingers)."""
        return self._drive.finger_opening(self)

    def robot_joints(self) -> np.ndarray:
        """The robot's joint positions, then its gripper's (:attr:`rik.sim.drive.Drive.joint_names`; rad or m)."""
        return self._drive.joints(self)

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

    def contact_summary(self) -> dict[str, float]:
        """Contacts between the gripper and the operated front (its panel and handle): how many, and the total
        normal and tangential force they carry, N."""
        import mujoco

        count, normal, tangential = 0, 0.0, 0.0
        wrench = np.zeros(6)
        d, m = self.data, self.model
        for i in range(d.ncon):
            g1, g2 = int(d.contact.geom1[i]), int(d.contact.geom2[i])
            ours = (g1 in self.gripper_geoms) != (g2 in self.gripper_geoms)
            other = g2 if g1 in self.gripper_geoms else g1
            if not ours or int(m.geom_bodyid[other]) not in self.front_bodies:
                continue
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
        self._drive.place(self, np.asarray(pose, np.float64), grip)

    def step(self, action: np.ndarray) -> None:
        """One control step: the robot aims at the target pose ``action[:6]`` (the Hand-E's base servos directly,
        an arm through one IK step); the jaws move towards the grip command ``action[6]`` at the gripper's finger
        speed."""
        action = np.asarray(action, dtype=np.float64)
        self._drive.command(self, action)
        self._run(float(action[6]))

    def step_joints(self, targets: np.ndarray, grip: float) -> None:
        """One control step of an arm driven joint by joint (a policy trained on an arm's export): its servos aim
        at ``targets`` (rad, held within reach of the joints as the IK's targets are), the jaws at ``grip``."""
        from rik.errors import RikError
        from rik.sim.drive import ArmDrive

        if not isinstance(self.drive, ArmDrive):
            raise RikError(f"robot {self.robot_id} takes a target pose, not joint targets")
        self.drive.set_targets(self, np.asarray(targets, np.float64))
        self._run(float(grip))

    def _run(self, grip: float) -> None:
        """The physics steps of one control step, the jaw servo slewing towards the grip command."""
        import mujoco

        m, d, jaw, effects = self.model, self.data, self.jaw_ctrl, self.effects
        goal, dmax = self._drive.jaw(self, grip)
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


def _variant_info(spec: mujoco.MjSpec, file: Path) -> dict[str, Any]:
    text = spec.text("rik.variant") if hasattr(spec, "text") else None
    data = getattr(text, "data", None)
    if not data:
        raise RikError(f"{file}: not a rik variant (no rik.variant text element); build it with rik variants build")
    return json.loads(data)


def _look_at(eye: np.ndarray, target: np.ndarray) -> list[float]:
    """``xyaxes`` of a camera at ``eye`` looking at ``target`` with world z up."""
    back = eye - target
    back /= np.linalg.norm(back)
    x = np.cross([0.0, 0.0, 1.0], back)
    x /= np.linalg.norm(x)
    y = np.cross(back, x)
    return [*x.tolist(), *y.tolist()]


def _add_environment(spec: mujoco.MjSpec) -> None:
    import mujoco

    spec.option.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
    spec.option.impratio = IMPRATIO
    spec.option.solver = mujoco.mjtSolver.mjSOL_NEWTON
    spec.option.iterations = 100
    spec.option.ls_iterations = 50
    spec.option.tolerance = 1e-8
    spec.visual.global_.offwidth = 1280
    spec.visual.global_.offheight = 960
    # Shadow maps of 2048 px (MuJoCo's default is 4096): on a CPU rasteriser (Mesa llvmpipe) the 4096 map made
    # every offscreen frame cost 0.14 s whatever its size; 2048 halves that and looks the same at camera sizes.
    spec.visual.quality.shadowsize = 2048
    spec.visual.headlight.ambient = [0.3, 0.3, 0.3]
    spec.visual.headlight.diffuse = [0.5, 0.5, 0.5]
    spec.worldbody.add_geom(name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[0, 0, 0.05],
                            rgba=[0.55, 0.5, 0.45, 1], group=1)
    directional = mujoco.mjtLightType.mjLIGHT_DIRECTIONAL
    spec.worldbody.add_light(name="key", pos=[0.8, 2.0, 2.8], dir=[-0.25, -0.6, -0.75], type=directional,
                             diffuse=[0.7, 0.7, 0.7])
    spec.worldbody.add_light(name="fill", pos=[-1.5, 1.5, 2.0], dir=[0.5, -0.5, -0.6], type=directional,
                             diffuse=[0.3, 0.3, 0.3])


def front_of(info: dict[str, Any], front: str | None, file: Path) -> dict[str, Any]:
    """The variant's front record called ``front`` (default: its first front)."""
    fronts = info["fronts"]
    if front is None:
        return fronts[0]
    for f in fronts:
        if f["id"] == front:
            return f
    known = ", ".join(f["id"] for f in fronts)
    raise RikError(f"{file}: variant {info['id']} has no front '{front}' (fronts: {known})")


def build_scene(variant_dir: Path, front: str | None = None, gripper: GripperSpec = HAND_E,
                control_fps: int = CONTROL_FPS, robot: Robot | None = None) -> SimScene:
    """Compile the scene of the variant built in ``variant_dir`` (its ``model.xml``), operating ``front``, with
    the Hand-E ``gripper`` or, when ``robot`` is an arm (a catalog entry), that arm at its mount."""
    import mujoco

    from rik.joints.runtime import front_effects
    from rik.sim.drive import FloatingDrive

    arm = robot is not None and robot.as_arm is not None
    file = Path(variant_dir) / "model.xml"
    if not file.is_file():
        raise RikError(f"{file}: no such variant file; build the variant with rik variants build")
    try:
        spec = mujoco.MjSpec.from_file(str(file))
    except Exception as exc:  # MuJoCo's parse errors are ValueErrors with the file's problem
        raise RikError(f"{file}: MuJoCo cannot load it: {str(exc).splitlines()[0]}") from None
    info = _variant_info(spec, file)
    record = front_of(info, front, file)
    _add_environment(spec)
    if not arm:
        from rik.sim.gripper import add_gripper

        add_gripper(spec, gripper)
    # Aim the front camera at the operated handle (and place an arm by it): compile once to find it.
    model = spec.compile()
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    target = data.site_xpos[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, record["grasp_site"])].copy()
    view = np.array([0.35, 0.85, 0.40])
    if arm:
        from rik.sim.arm import attach_arm, footprint, placement

        assert robot is not None
        where = placement(robot, target, footprint(model, data))
        attach_arm(spec, robot, where)
        if where.pos[0] - target[0] > 0.05:  # an arm standing on the camera's side would hide the handle
            view[0] = -view[0]
    eye = target + FRONT_CAMERA_DISTANCE * view / math.hypot(*view)
    spec.worldbody.add_camera(name="front", pos=eye.tolist(), xyaxes=_look_at(eye, target), fovy=50)
    model = spec.compile()
    data = mujoco.MjData(model)

    def name2id(kind: mujoco.mjtObj, name: str) -> int:
        return mujoco.mj_name2id(model, kind, name)

    joint = name2id(mujoco.mjtObj.mjOBJ_JOINT, record["joint"])
    body = int(model.jnt_bodyid[joint])
    handle_body = name2id(mujoco.mjtObj.mjOBJ_BODY, record["handle_body"])
    lo, hi = model.jnt_range[joint]
    front_info = FrontInfo(record["id"], record["kind"], record["motion"], joint, int(model.jnt_qposadr[joint]),
                           int(model.jnt_dofadr[joint]), (float(lo), float(hi)), body,
                           handle_body, name2id(mujoco.mjtObj.mjOBJ_SITE, record["grasp_site"]))
    front_bodies = frozenset({body, handle_body})
    effects = front_effects(model, info["fronts"])
    if arm:
        from rik.sim.arm import ROBOT_PREFIX, TCP_SITE
        from rik.sim.drive import arm_drive, gripper_spec
        from rik.sim.ik import ArmIK

        assert robot is not None and robot.gripper.body is not None
        ik = ArmIK(robot, where, orientation_cost=1.0 if len(robot.joint_names) >= 6 else 0.2)
        drive = arm_drive(model, robot, ik, where, control_fps)
        hand = ROBOT_PREFIX + robot.gripper.body
        hand_bodies = {b for b in range(model.nbody) if _descends(model, b, name2id(mujoco.mjtObj.mjOBJ_BODY, hand))}
        gripper_geoms = frozenset(g for g in drive.robot_geoms if int(model.geom_bodyid[g]) in hand_bodies)
        scene = SimScene(model, data, info, front_info, gripper_spec(robot), Path(variant_dir), control_fps,
                         np.zeros(0, int), np.zeros(0, int), gripper_geoms, front_bodies,
                         name2id(mujoco.mjtObj.mjOBJ_SITE, ROBOT_PREFIX + TCP_SITE), drive.arm_ctrl, drive.jaw_ctrl,
                         effects, drive, robot)
    else:
        base_qpos = np.array([model.jnt_qposadr[name2id(mujoco.mjtObj.mjOBJ_JOINT, GRIPPER_PREFIX + j)]
                              for j in BASE_JOINTS])
        finger_qpos = np.array([model.jnt_qposadr[name2id(mujoco.mjtObj.mjOBJ_JOINT, GRIPPER_PREFIX + f)]
                                for f in FINGERS])
        gripper_bodies = {name2id(mujoco.mjtObj.mjOBJ_BODY, GRIPPER_PREFIX + b) for b in ("base", *FINGERS)}
        gripper_geoms = frozenset(g for g in range(model.ngeom) if int(model.geom_bodyid[g]) in gripper_bodies)
        arm_ctrl = np.array([_ctrl_adr(model, GRIPPER_PREFIX + j) for j in BASE_JOINTS])
        jaw_ctrl = _ctrl_adr(model, GRIPPER_PREFIX + "jaw")
        scene = SimScene(model, data, info, front_info, gripper, Path(variant_dir), control_fps, base_qpos,
                         finger_qpos, gripper_geoms, front_bodies,
                         name2id(mujoco.mjtObj.mjOBJ_SITE, GRIPPER_PREFIX + "tcp"), arm_ctrl, jaw_ctrl, effects,
                         FloatingDrive(base_qpos, finger_qpos, arm_ctrl, jaw_ctrl))
    scene.reset()
    return scene


def _descends(model: mujoco.MjModel, body: int, ancestor: int) -> bool:
    """Whether ``body`` is ``ancestor`` or lies below it in the kinematic tree."""
    while body > 0:
        if body == ancestor:
            return True
        body = int(model.body_parentid[body])
    return body == ancestor


def _mat2quat(mat: np.ndarray) -> np.ndarray:
    """A rotation matrix (9 numbers, row-major) as a unit quaternion (w, x, y, z) with w >= 0."""
    import mujoco

    q = np.empty(4)
    mujoco.mju_mat2Quat(q, np.asarray(mat, np.float64).reshape(9))
    return -q if q[0] < 0 else q


def _ctrl_adr(model: mujoco.MjModel, actuator: str) -> int:
    """The address in ``data.ctrl`` of the (single) control of the actuator named ``actuator``."""
    import mujoco

    i = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_ACTUATOR, actuator)
    if i < 0:  # pragma: no cover - add_gripper always adds it
        raise RikError(f"the scene has no actuator '{actuator}'")
    return int(model.actuator_ctrladr[i])


def base_for_tcp(gripper: GripperSpec, tcp: np.ndarray, angles: np.ndarray) -> np.ndarray:
    """The base pose (x, y, z, pitch, yaw, roll) that puts the pads' centre at ``tcp`` with ``angles``."""
    rot = gripper_rotation(angles)
    return np.concatenate([np.asarray(tcp) - rot[:, 2] * gripper.tcp_offset, angles])


def gripper_rotation(angles: np.ndarray) -> np.ndarray:
    """World rotation of the gripper frame for pitch, yaw, roll (the base chain's composition)."""
    from scipy.spatial.transform import Rotation

    base = Rotation.from_quat(GRIPPER_BASE_QUAT, scalar_first=False)
    pitch, yaw, roll = angles
    # joints are applied in the base frame, in chain order: about x, then the (pitched) y, then the approach z
    chain = Rotation.from_euler("XYZ", [pitch, yaw, roll])
    return (base * chain).as_matrix()


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
