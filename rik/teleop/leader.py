"""A real LeRobot leader arm as a teleoperation device: the SO-101's (or SO-100's) leader, read through LeRobot's own
``SOLeader`` teleoperator and its Feetech motor bus, drives the simulated arm of the same type joint by joint.

Each read is LeRobot's ``get_action()``: ``{"shoulder_pan.pos": deg, ..., "gripper.pos": 0..100}`` in LeRobot's
calibration (body joints in degrees from the middle of each joint's calibrated range, the gripper 0 closed .. 100
open), which is what the follower arm would be sent. The robot's LeRobot layout (:mod:`rik.sim.robots.layout`, the
same numbers rik exports) turns it into the simulated arm's joint targets (rad) and grip command (0 open .. 1 closed).

The leader's calibration is LeRobot's file ``<calibration dir>/<id>.json`` (by default
``$HF_LEROBOT_CALIBRATION/teleoperators/so_leader``, i.e. ``~/.cache/huggingface/lerobot/calibration/...``): rik
never starts LeRobot's interactive calibration; without a file it says how to make one with ``lerobot-calibrate``.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from rik.errors import RikError

if TYPE_CHECKING:
    from rik.schemas.robots import Robot
    from rik.sim.robots.layout import RobotLayout

LEADERS = {"so101-leader": ("so101", "so101_leader"), "so100-leader": ("so100", "so100_leader")}
"""Leader device -> (the catalog robot it drives, LeRobot's teleoperator type for ``lerobot-calibrate``)."""


class LeaderError(RikError):
    """A leader arm cannot drive this robot, has no calibration, or cannot be reached."""


def check_leader(device: str, robot: Robot | None) -> None:
    """A leader drives the simulated arm of its own type only (``so101-leader`` the ``so101``); one line otherwise."""
    want, _ = LEADERS[device]
    robot_id = "hand-e" if robot is None else robot.id
    if robot_id != want:
        other = [d for d, (r, _) in LEADERS.items() if r == robot_id]
        hint = f"robot {robot_id}'s leader is --device {other[0]}" if other else f"robot {robot_id} has no leader arm"
        raise LeaderError(f"--device {device}: this leader arm drives the simulated {want} only (--robot {want}); "
                          f"{hint}")


def calibration_dir(directory: Path | None) -> Path:
    """Where LeRobot keeps an SO leader's calibration files: ``directory`` or LeRobot's default."""
    if directory is not None:
        return Path(directory)
    from lerobot.utils.constants import HF_LEROBOT_CALIBRATION, TELEOPERATORS

    return Path(HF_LEROBOT_CALIBRATION) / TELEOPERATORS / "so_leader"


def calibration_file(device: str, leader_id: str | None, directory: Path | None, port: str) -> tuple[str, Path]:
    """(leader id, its calibration file): ``--leader-id`` or, without one, the only file in the calibration folder;
    a missing file is one line saying how ``lerobot-calibrate`` makes it."""
    folder = calibration_dir(directory)
    found = sorted(f.stem for f in folder.glob("*.json")) if folder.is_dir() else []
    _, teleop_type = LEADERS[device]
    make = (f"make one with: lerobot-calibrate --teleop.type={teleop_type} --teleop.port={port} "
            f"--teleop.id={leader_id or 'my_leader'}"
            + (f" --teleop.calibration_dir={folder}" if directory is not None else ""))
    if leader_id is None:
        if len(found) == 1:
            leader_id = found[0]
        elif found:
            raise LeaderError(f"{folder}: calibrations of several leader arms ({', '.join(found)}); say which with "
                              "--leader-id")
        else:
            raise LeaderError(f"{folder}: no leader arm calibration (LeRobot's <id>.json); {make}")
    file = folder / f"{leader_id}.json"
    if not file.is_file():
        raise LeaderError(f"{file}: no calibration for leader '{leader_id}'"
                          + (f" (this folder has {', '.join(found)})" if found else "") + f"; {make}")
    return leader_id, file


@dataclass
class LeaderArm:
    """A connected LeRobot teleoperator (anything with ``get_action()`` giving ``<joint>.pos`` numbers) and the
    layout of the simulated arm it drives."""

    name: str
    """The device's name (``so101-leader``), the episodes' operator."""
    teleop: Any
    layout: RobotLayout

    def read(self) -> tuple[np.ndarray, float]:
        """The leader's position now as the simulated arm's joint targets (rad, the robot's joint order) and grip
        command (0 open .. 1 closed)."""
        return self.joint_targets(self.teleop.get_action())

    def joint_targets(self, action: dict[str, float]) -> tuple[np.ndarray, float]:
        """A LeRobot action (``{"shoulder_pan.pos": deg, ..., "gripper.pos": 0..100}``) as joint targets and grip."""
        missing = [n for n in self.layout.action_names if n not in action]
        if missing:
            raise LeaderError(f"the leader arm's reading lacks {', '.join(missing)} (it gave "
                              f"{', '.join(action) or 'nothing'})")
        return self.layout.joint_targets(np.array([float(action[n]) for n in self.layout.action_names]))

    def close(self) -> None:
        """Disconnect the leader (its torque is off already: a leader is moved by hand)."""
        if getattr(self.teleop, "is_connected", False):
            self.teleop.disconnect()


def leader_arm(device: str, teleop: Any, robot: Robot | None) -> LeaderArm:
    """A LeRobot teleoperator (connected, or with its bus otherwise ready to read) as the ``device`` driving
    ``robot``; a leader of another robot type is refused (:func:`check_leader`)."""
    from rik.sim.robots.layout import robot_layout

    check_leader(device, robot)
    return LeaderArm(device, teleop, robot_layout(robot))


def open_leader(device: str, robot: Robot | None, port: str, *, leader_id: str | None = None,
                calibration: Path | None = None) -> LeaderArm:
    """Connect the real leader arm ``device`` on serial ``port`` through LeRobot's ``SOLeader`` with its
    calibration file (:func:`calibration_file`), to drive ``robot``. Each bad input is one line: a leader of another
    robot type, a missing calibration, a port that does not exist or does not answer. Motors whose stored
    calibration differs from the file get the file's (what ``lerobot-teleoperate`` does when ENTER is pressed)."""
    check_leader(device, robot)
    if port.startswith("/") and not Path(port).exists():
        raise LeaderError(f"--port {port}: no such device; plug the leader arm in and find its port with "
                          "lerobot-find-port")
    leader_id, file = calibration_file(device, leader_id, calibration, port)
    from lerobot.teleoperators.so_leader import SOLeader, SOLeaderTeleopConfig

    teleop = SOLeader(SOLeaderTeleopConfig(port=port, id=leader_id, calibration_dir=file.parent))
    try:
        teleop.connect(calibrate=False)
    except (ConnectionError, OSError) as exc:
        cause = exc.__cause__ or exc
        raise LeaderError(f"--port {port}: the leader arm does not answer ({str(cause).strip().splitlines()[0]}); "
                          "check the port (lerobot-find-port), the cable and the arm's power") from None
    try:
        if not teleop.is_calibrated:
            teleop.bus.write_calibration(teleop.calibration)
        return leader_arm(device, teleop, robot)
    except BaseException:
        teleop.disconnect()
        raise
