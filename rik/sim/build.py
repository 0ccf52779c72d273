"""Assembling a scene: a built variant, the robot (the Hand-E on its force-limited base, or an arm) with its drive, a
floor, lights, a fixed front camera aimed at the operated front's handle, and the wrist camera.

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
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from rik.errors import RikError
from rik.joints.runtime import front_effects
from rik.sim.robots.arm import ROBOT_PREFIX, TCP_SITE, attach_arm, footprint, placement
from rik.sim.robots.drive import FloatingDrive, arm_drive
from rik.sim.robots.gripper import BASE_JOINTS, GRIPPER_PREFIX, HAND_E, GripperSpec, add_gripper, gripper_spec
from rik.sim.robots.ik import ArmIK
from rik.sim.scene import CONTROL_FPS, FINGERS, FrontInfo, SimScene

if TYPE_CHECKING:
    import mujoco

    from rik.schemas.robots import Robot

IMPRATIO = 10.0
FRONT_CAMERA_DISTANCE = 0.9
"""Distance from the operated handle to the front camera, m."""


def load_variant_spec(path: str | Path) -> tuple[mujoco.MjSpec, Path]:
    """A built variant's ``model.xml`` (``path``: the variant folder or the file) loaded as an MjSpec, and the file;
    a missing file or one MuJoCo cannot parse is a one-line :class:`RikError`."""
    import mujoco

    path = Path(path)
    file = path / "model.xml" if path.is_dir() else path
    if not file.is_file():
        raise RikError(f"{file}: no such variant file; build the variant with rik variants build")
    try:
        return mujoco.MjSpec.from_file(str(file)), file
    except Exception as exc:  # MuJoCo's parse errors are ValueErrors with the file's problem
        raise RikError(f"{file}: MuJoCo cannot load it: {str(exc).splitlines()[0]}") from None


def variant_info(spec: mujoco.MjSpec, file: Path) -> dict[str, Any]:
    """The variant's own description (its ``rik.variant`` text element: id, preset, fronts); ``file`` names the
    model in the error when there is none."""
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


def add_environment(spec: mujoco.MjSpec) -> None:
    """The physics rules and surroundings every rik scene adds to a variant: the solver settings above, offscreen
    buffer, lights and floor."""
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

    arm = robot is not None and robot.as_arm is not None
    spec, file = load_variant_spec(Path(variant_dir) / "model.xml")
    info = variant_info(spec, file)
    record = front_of(info, front, file)
    add_environment(spec)
    if not arm:
        add_gripper(spec, gripper)
    # Aim the front camera at the operated handle (and place an arm by it): compile once to find it.
    model = spec.compile()
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    target = data.site_xpos[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, record["grasp_site"])].copy()
    view = np.array([0.35, 0.85, 0.40])
    if arm:
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
        assert robot is not None and robot.gripper.body is not None
        ik = ArmIK(robot, where)
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
    scene.spec = spec
    scene.reset()
    return scene


def _descends(model: mujoco.MjModel, body: int, ancestor: int) -> bool:
    """Whether ``body`` is ``ancestor`` or lies below it in the kinematic tree."""
    while body > 0:
        if body == ancestor:
            return True
        body = int(model.body_parentid[body])
    return body == ancestor


def _ctrl_adr(model: mujoco.MjModel, actuator: str) -> int:
    """The address in ``data.ctrl`` of the (single) control of the actuator named ``actuator``."""
    import mujoco

    i = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_ACTUATOR, actuator)
    if i < 0:  # pragma: no cover - add_gripper always adds it
        raise RikError(f"the scene has no actuator '{actuator}'")
    return int(model.actuator_ctrladr[i])
