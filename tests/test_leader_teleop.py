"""A real LeRobot leader arm drives the simulated SO-101 (``rik teleop VARIANT --robot so101 --device so101-leader
--port ...``), without the arm: LeRobot's own ``SOLeader`` and ``FeetechMotorsBus`` read raw encoder positions (the
integers an STS3215 reports) through their real sign decoding and calibration; only the serial port is replaced (a
stand-in that is open, and the bus's low-level ``_sync_read`` answering with the positions). rik's side is the real
one: the window's controls, the teleop session, the episode, its replay and the LeRobot export. Bad input is one
line each."""

from __future__ import annotations

import json
import math
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest
from shared import BOW, builtin_catalog

CAT = builtin_catalog()
REPO = "local/rik-leader"
CALIBRATION = {"shoulder_pan": (748, 3410), "shoulder_lift": (837, 3341), "elbow_flex": (793, 2995),
               "wrist_flex": (910, 3277), "wrist_roll": (0, 4095), "gripper": (2030, 3470)}
"""A leader's calibrated ranges (encoder steps): the body joints' are one real SO-101's (ros-physical-ai/demos#50),
wrist_roll's the whole turn LeRobot's calibration gives it, the gripper's chosen for the test."""
ENCODER_STEP_DEG = 360 / 4095
"""One STS3215 encoder step in LeRobot's degrees."""


def write_calibration(folder: Path, leader_id: str) -> Path:
    """LeRobot's calibration file of a leader arm, ``folder/<id>.json``."""
    folder.mkdir(parents=True, exist_ok=True)
    file = folder / f"{leader_id}.json"
    file.write_text(json.dumps({m: {"id": i + 1, "drive_mode": 0, "homing_offset": 0, "range_min": lo,
                                    "range_max": hi} for i, (m, (lo, hi)) in enumerate(CALIBRATION.items())}))
    return file


class EncoderLeader:
    """LeRobot's real ``SOLeader`` whose Feetech bus reads ``raw`` (motor id -> encoder steps) instead of a serial
    port: everything from ``sync_read`` up (sign decoding, normalisation with the calibration file) is LeRobot's."""

    def __init__(self, calibration: Path, leader_id: str) -> None:
        from lerobot.teleoperators.so_leader import SOLeader, SOLeaderTeleopConfig

        self.teleop = SOLeader(SOLeaderTeleopConfig(port="/dev/null", id=leader_id, calibration_dir=calibration))
        self.raw: dict[int, int] = {}
        bus = self.teleop.bus
        bus.port_handler = SimpleNamespace(is_open=True)  # the only stand-in: an open serial port

        def sync_read(addr: int, length: int, ids: list[int], **_: Any) -> tuple[dict[int, int], int]:
            return {i: self.raw[i] for i in ids}, 0

        bus._sync_read = sync_read

    def pose(self, action: dict[str, float]) -> None:
        """Put the leader's servos where LeRobot would read ``action`` (degrees, gripper 0..100): its own inverse
        normalisation gives the encoder steps."""
        bus = self.teleop.bus
        ids = {bus.motors[k.removesuffix(".pos")].id: v for k, v in action.items()}
        self.raw = {i: int(v) for i, v in bus._unnormalize(ids).items()}


@pytest.fixture(scope="module")
def variants(bow_variants: Path) -> Path:
    return bow_variants


@pytest.mark.slow
def test_a_leader_drives_the_so101_and_its_episode_replays_and_exports_as_the_leader(variants: Path, tmp_path: Path,
                                                                                  rik) -> None:
    """The leader moves every joint (15..30 deg) and closes its gripper over 3 s, then holds 1 s; the simulated
    SO-101 follows: its servo targets are the leader's positions exactly, and its joints, as LeRobot's follower
    would report them, are within the droop a position servo of stiffness kp has under the arm's weight
    (gravity torque / kp: 1.7 deg at the elbow here), its friction loss (frictionloss / kp) and one encoder step.
    The saved episode replays bit for bit, and its LeRobot export's action is the leader's readings."""
    from rik.episodes.episode import read_episode
    from rik.episodes.replay import verify_episode
    from rik.sim.build import build_scene
    from rik.sim.robots.layout import robot_layout
    from rik.teleop.desktop import Controls
    from rik.teleop.leader import leader_arm
    from rik.teleop.session import TeleopSession

    robot = CAT.robot("so101")
    write_calibration(tmp_path / "calibration", "blue")
    leader = EncoderLeader(tmp_path / "calibration", "blue")  # LeRobot reads the file when the leader is made
    arm = leader_arm("so101-leader", leader.teleop, robot)
    scene = build_scene(variants / BOW, robot=robot.as_arm)
    session = TeleopSession(scene, tmp_path / "episodes", operator="so101-leader")
    controls = Controls(session, arm, lambda line: None)
    layout = robot_layout(robot)
    names = layout.action_names
    start = layout.state(scene)  # the simulated arm's start pose as LeRobot's numbers
    swing = np.array([15.0, -20.0, 25.0, 20.0, 30.0, 0.0])
    readings = []
    for k in range(80):  # 3 s of motion at 20 Hz, then 1 s still
        f = math.sin(math.pi / 2 * min(k / 60, 1.0))
        target = start + swing * f
        target[5] = 60.0 - 40.0 * f  # the gripper from 60 % open to 20 %
        leader.pose(dict(zip(names, target, strict=True)))
        controls.apply(frozenset())  # what the window does each frame: read the leader
        if session.tick():
            readings.append(leader.teleop.get_action())
    # recording starts with the first reading more than 1 deg from the first one (wrist_roll 1.6 deg at k = 2)
    assert session.recorder.steps == len(readings) == 78
    assert session.status()["state"] == "recording"

    read = np.array([readings[-1][n] for n in names])
    assert np.abs(read[:5] - (start + swing)[:5]).max() <= ENCODER_STEP_DEG  # what the encoders gave, to a step
    drive, m, d = scene.robot_drive, scene.model, scene.data
    commanded = layout.joint_action(d.ctrl[drive.arm_ctrl], 0.0)[:5]
    np.testing.assert_allclose(commanded, read[:5], atol=1e-9)  # the servos aim at the leader exactly
    follower = layout.state(scene)  # the follower's reading, LeRobot's degrees and gripper percent
    kp = m.actuator_gainprm[drive.arm_ctrl, 0]
    droop = np.degrees((np.abs(d.qfrc_bias[drive.dofs]) + m.dof_frictionloss[drive.dofs]) / kp) + ENCODER_STEP_DEG
    error = np.abs(follower[:5] - read[:5])
    assert np.all(error <= droop), f"follower off by {error.round(3)} deg, droop allows {droop.round(3)}"
    assert error.max() > 0.1  # the elbow does droop: the check compares two different things
    assert abs(follower[5] - read[5]) <= 1.0  # the jaw, closing freely, stops within 1 % of its range
    assert np.abs(follower[:5] - start[:5]).min() >= 14.0  # every joint followed the leader's swing

    saved = session.save()
    assert saved is not None and saved.meta.operator == "so101-leader" and saved.meta.action_kind == "joints"
    assert saved.meta.id.endswith("__so101-leader.so101__s0000")
    assert verify_episode(CAT, saved.path, variants).exact
    meta, table = read_episode(saved.path)
    steps = meta.steps  # the idle end is trimmed to 0.5 s after the leader's last move
    assert 60 <= steps < 78

    ds = tmp_path / "ds"
    r = rik("export-lerobot", str(tmp_path / "episodes"), "--streams", "none", "--repo-id", REPO, "--out", str(ds),
            "--variants", str(variants))
    assert r.code == 0, r.err
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    dataset = LeRobotDataset(REPO, root=ds)
    assert dataset.meta.robot_type == "so_follower" and dataset.meta.features["action"]["names"] == list(names)
    action = np.stack([np.asarray(a, np.float64) for a in dataset.hf_dataset["action"]])
    expected = np.array([[a[n] for n in names] for a in [*readings[:steps], readings[steps - 1]]])
    assert action.shape == expected.shape == (steps + 1, 6)
    np.testing.assert_allclose(action, expected, atol=1e-4)  # the leader's readings, as float32
    state = np.stack([np.asarray(a, np.float64) for a in dataset.hf_dataset["observation.state"]])
    assert np.abs(state[-1, :5] - expected[-1, :5]).max() < 3.0  # the follower where the leader was, as it reads
    card = (ds / "README.md").read_text()
    assert "In 1 episode(s) a leader arm drove the joints" in card  # not "rik's differential IK" alone


@pytest.mark.parametrize(("args", "line"), [
    (("--robot", "so101", "--device", "so101-leader", "--port", "/dev/ttyNO-SUCH-LEADER"),
     "--port /dev/ttyNO-SUCH-LEADER: no such device; plug the leader arm in and find its port with lerobot-find-port"),
    (("--robot", "so100", "--device", "so101-leader", "--port", "/dev/null"),
     "--device so101-leader: this leader arm drives the simulated so101 only (--robot so101); robot so100's leader "
     "is --device so100-leader"),
    (("--device", "so101-leader", "--port", "/dev/null"),
     "--device so101-leader: this leader arm drives the simulated so101 only (--robot so101); robot hand-e has no "
     "leader arm"),
    (("--robot", "so101", "--device", "so100-leader", "--port", "/dev/null"),
     "--device so100-leader: this leader arm drives the simulated so100 only (--robot so100); robot so101's leader "
     "is --device so101-leader"),
    (("--robot", "so101", "--port", "/dev/ttyACM0"),
     "--port is for a leader arm (--device so101-leader or so100-leader), not --device keyboard"),
    (("--robot", "so101", "--device", "so101-leader"),
     "--device so101-leader: give the leader arm's serial port, --port /dev/ttyACM0 (lerobot-find-port finds it)"),
])
def test_bad_leader_input_is_one_line(rik, tmp_path: Path, args: tuple[str, ...], line: str) -> None:
    """Refused before any scene, window or serial port (the variant is not even built)."""
    r = rik("teleop", BOW, *args, "--variants", str(tmp_path / "variants"))
    assert r.code == 2 and r.err == f"rik: error: {line}\n" and "Traceback" not in r.err + r.out


def test_a_leader_without_calibration_says_how_to_make_one(rik, tmp_path: Path) -> None:
    """No calibration file in the folder (or none for the given id): one line naming the folder (or file) and the
    lerobot-calibrate command that makes one; LeRobot's interactive calibration is never started."""
    folder = tmp_path / "cal"
    folder.mkdir()
    base = ("teleop", BOW, "--robot", "so101", "--device", "so101-leader", "--port", "/dev/null",
            "--calibration-dir", str(folder))
    r = rik(*base)
    assert r.code == 2 and r.err == (
        f"rik: error: {folder}: no leader arm calibration (LeRobot's <id>.json); make one with: lerobot-calibrate "
        f"--teleop.type=so101_leader --teleop.port=/dev/null --teleop.id=my_leader --teleop.calibration_dir={folder}\n")
    write_calibration(folder, "blue")
    write_calibration(folder, "green")
    r = rik(*base, "--leader-id", "red")
    assert r.code == 2 and r.err == (
        f"rik: error: {folder / 'red.json'}: no calibration for leader 'red' (this folder has blue, green); make one "
        f"with: lerobot-calibrate --teleop.type=so101_leader --teleop.port=/dev/null --teleop.id=red "
        f"--teleop.calibration_dir={folder}\n")
    r = rik(*base)
    assert r.code == 2 and r.err == (f"rik: error: {folder}: calibrations of several leader arms (blue, green); say "
                                     "which with --leader-id\n")


def test_a_port_that_is_no_leader_is_one_line(rik, tmp_path: Path) -> None:
    """A port that exists but is no serial device (/dev/null): LeRobot's bus cannot open it; one line, exit 2."""
    write_calibration(tmp_path / "cal", "blue")
    r = rik("teleop", BOW, "--robot", "so101", "--device", "so101-leader", "--port", "/dev/null", "--calibration-dir",
            str(tmp_path / "cal"))
    assert r.code == 2 and r.err.startswith("rik: error: --port /dev/null: the leader arm does not answer (")
    assert r.err.endswith("check the port (lerobot-find-port), the cable and the arm's power\n")
    assert r.err.count("\n") == 1 and "Traceback" not in r.err
