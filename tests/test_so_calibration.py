"""The SO arms' LeRobot numbers are what lerobot's own SO follower reports after its own calibration: a follower
whose servos are the simulated arm's joints (tests/so_follower.py) is calibrated by lerobot's ``SOFollower.calibrate``
(homed at the middle of each joint's range, its range of motion recorded over the catalog's ranges, the jaw's
from closed to open), then lerobot's ``_normalize`` reads the joints rik's layout reads, and lerobot's
``_unnormalize`` turns rik's actions into the servos' goals. Within a step of the encoder (4096 a turn)."""

from __future__ import annotations

import math
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from shared import BOW, builtin_catalog
from so_follower import SimulatedBus, so_follower_motors

from rik.schemas.robots import Robot
from rik.sim.build import build_scene
from rik.sim.robots.layout import robot_layout

CAT = builtin_catalog()
ARMS = ("so100", "so101")


@pytest.fixture(scope="module")
def variants(bow_variants: Path) -> Path:
    return bow_variants


def _motor_joints(robot: Robot) -> dict[str, tuple[str, tuple[float, float]]]:
    """LeRobot motor -> (the arm's joint it turns, the range an operator moves it through when calibrating, rad):
    a body joint's catalog range, the jaw from closed to open."""
    act = robot.gripper.actuation
    assert robot.joints is not None and act is not None
    ranges = {j.name: j.range for j in robot.joints.joints}
    out = {}
    for e in robot.lerobot.joints:
        motor = e.name.removesuffix(".pos")
        out[motor] = (e.joint, ranges[e.joint]) if e.joint else (act.opening_joint, (act.joint_closed, act.joint_open))
    return out


def calibrated_follower(robot: Robot, monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> tuple[SimulatedBus, dict]:
    """An SO follower on the simulated arm, calibrated by lerobot's own ``SOFollower.calibrate``: the operator
    (``input``) holds the arm at the middle of every joint's range when asked, then moves each joint through its
    range. Returns the bus and the pose the servos read (motor -> rad; set it to read another)."""
    from lerobot.robots.so_follower import SOFollower

    motors = so_follower_motors()
    joints = _motor_joints(robot)
    assert list(joints) == list(motors), "rik's layout lists lerobot's motors in lerobot's order"
    pose = {m: (lo + hi) / 2 for m, (_, (lo, hi)) in joints.items()}
    origin = {m: 900 + 131 * motors[m].id for m in motors}  # any horn mounting: the calibration takes it out
    bus = SimulatedBus(motors, lambda: pose, {m: r for m, (_, r) in joints.items()}, origin)
    follower = SimpleNamespace(bus=bus, calibration={}, id="sim", calibration_fpath=tmp_path / "sim.json",
                               _save_calibration=lambda: None)
    monkeypatch.setattr("builtins.input", lambda *args: "")
    SOFollower.calibrate(follower)
    assert set(bus.calibration) == set(motors) and bus.calibration["wrist_roll"].range_max == 4095
    return bus, pose


@pytest.mark.parametrize("robot_id", ARMS)
def test_state_is_what_lerobots_calibrated_follower_reads(robot_id: str, variants: Path, tmp_path: Path,
                                                          monkeypatch: pytest.MonkeyPatch) -> None:
    import mujoco

    robot = CAT.robot(robot_id)
    layout = robot_layout(robot)
    bus, _ = calibrated_follower(robot, monkeypatch, tmp_path)
    joints = _motor_joints(robot)
    scene = build_scene(variants / BOW, None, robot=robot)
    m, d = scene.model, scene.data
    rng = np.random.default_rng(3)
    step = {name: 360 / 4096 if mo.norm_mode.value == "degrees" else
            100 / abs(bus.present(name, joints[name][1][1]) - bus.present(name, joints[name][1][0]))
            for name, mo in bus.motors.items()}
    tolerance = np.array([2 * step[name] for name in bus.motors])
    for trial in range(8):
        q = {name: rng.uniform(lo, hi) for name, (_, (lo, hi)) in joints.items()}
        if trial == 0:  # the ends of the ranges, and the jaw closed
            q = {name: r[k % 2] for k, (name, (_, r)) in enumerate(joints.items())}
        for name, (joint, _) in joints.items():
            d.qpos[m.jnt_qposadr[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, f"robot/{joint}")]] = q[name]
        mujoco.mj_forward(m, d)
        ours = layout.state(scene)
        raw = {bus.motors[name].id: bus.present(name, q[name]) for name in bus.motors}
        theirs = bus._normalize(raw)
        lerobot = np.array([theirs[bus.motors[name].id] for name in bus.motors])
        assert layout.state_names == tuple(f"{name}.pos" for name in bus.motors)
        assert np.all(np.abs(ours - lerobot) <= tolerance), (robot_id, q, ours, lerobot)


@pytest.mark.parametrize("robot_id", ARMS)
def test_actions_are_the_goals_lerobot_writes(robot_id: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The body joints' actions, written to a calibrated follower by lerobot's ``_unnormalize``, are the encoder
    positions of rik's joint targets. The SO-101's gripper action is its jaw servo's goal on the same scale; the
    SO-100's closes past the closed end (rik's ctrl_closed), which a real follower's 0..100 cannot ask."""
    robot = CAT.robot(robot_id)
    act = robot.gripper.actuation
    assert act is not None
    layout = robot_layout(robot)
    bus, _ = calibrated_follower(robot, monkeypatch, tmp_path)
    joints = _motor_joints(robot)
    rng = np.random.default_rng(5)
    names = list(bus.motors)
    for _ in range(8):
        targets = np.array([rng.uniform(*joints[name][1]) for name in names[:-1]])
        grip = float(rng.uniform(0.0, 1.0))
        action = layout.action(np.array([0, 0, 0, 0, 0, 0, grip]), targets)
        goals = bus._unnormalize({bus.motors[name].id: float(v) for name, v in zip(names, action, strict=True)})
        for name, q in zip(names[:-1], targets, strict=True):
            assert abs(goals[bus.motors[name].id] - bus.present(name, q)) <= 2, (robot_id, name, q)
        jaw_goal = act.ctrl_open + grip * (act.ctrl_closed - act.ctrl_open)
        gripper = bus.motors["gripper"].id
        if robot_id == "so101":
            assert abs(goals[gripper] - bus.present("gripper", jaw_goal)) <= 2, (grip, jaw_goal)
        else:
            assert act.ctrl_closed < act.joint_closed and goals[gripper] >= bus.present("gripper", act.joint_closed)
    # and back: the environment takes lerobot's numbers as the same targets
    back, command = layout.joint_targets(action)
    np.testing.assert_allclose(back, targets, atol=1e-9)
    assert command == pytest.approx(grip)


def test_so100_zeros_are_its_ranges_middles() -> None:
    """The SO-100's model does not put 0 at mid-range (Menagerie's SO-ARM100): its export counts from the middle
    of each catalog range; the SO-101's model already does, so its zeros are 0."""
    so100, so101 = robot_layout(CAT.robot("so100")), robot_layout(CAT.robot("so101"))
    assert [round(math.degrees(z), 3) for z in so100.zeros] == [0.0, -84.27, 90.0, -5.73, 0.0, 0.0]
    assert so101.zeros == (0.0,) * 6
