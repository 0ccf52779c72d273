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
from rik.paths import read_json

if TYPE_CHECKING:
    from rik.schemas.robots import Robot
    from rik.sim.robots.layout import RobotLayout

LEADERS = {"so101-leader": ("so101", "so101_leader"), "so100-leader": ("so100", "so100_leader")}
"""Leader device -> (the catalog robot it drives, LeRobot's teleoperator type for ``lerobot-calibrate``)."""


class LeaderError(RikError):
    """A leader arm cannot drive this robot, has no calibration, or cannot be reached."""


MAX_CALIBRATION_BYTES = 2**20
"""Largest calibration file read (LeRobot's are about 1 kB)."""
CALIBRATION_FIELDS = {"id": (0, 253), "drive_mode": (0, 1), "homing_offset": (-2047, 2047), "range_min": (0, 4095),
                      "range_max": (0, 4095)}
"""Each motor's fields in LeRobot's calibration file and the values an STS3215 holds (ids 0..253, a homing offset of
11 bits and a sign, positions of 12 bits)."""
BUS_ERRORS = (ConnectionError, OSError, RuntimeError)
"""What LeRobot's Feetech bus raises when the port cannot be opened or the servos do not answer (a RuntimeError
when the servos it pings are missing)."""


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
    found = sorted(f.stem for f in folder.glob("*.json") if f.is_file()) if folder.is_dir() else []
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


def read_calibration(file: Path, motors: list[str]) -> dict[str, dict[str, int]]:
    """LeRobot's calibration of a leader arm, ``{motor: {"id", "drive_mode", "homing_offset", "range_min",
    "range_max"}}`` for each of ``motors``, checked before LeRobot reads it (it would end in a traceback): one
    line naming the file (and the motor and field) when it is unreadable, not JSON (cut short), or of another shape."""

    try:
        data = read_json(file, MAX_CALIBRATION_BYTES)
    except OSError as exc:
        raise LeaderError(f"{file}: cannot read the leader's calibration ({exc.strerror or exc})") from None
    except ValueError as exc:  # too large, not UTF-8, not JSON (cut short), nested too deeply
        raise LeaderError(f"{file}: not a calibration file of LeRobot ({_json_problem(exc)}); make it again with "
                          "lerobot-calibrate") from None
    if not isinstance(data, dict):
        raise LeaderError(f"{file}: not a calibration file of LeRobot (a JSON object of the motors {', '.join(motors)} "
                          "is expected); make it again with lerobot-calibrate")
    missing = [m for m in motors if m not in data]
    extra = [str(m) for m in data if m not in motors]
    if missing or extra:
        what = (f"lacks the motors {', '.join(missing)}" if missing else
                f"has motors this leader does not ({', '.join(extra)})")
        raise LeaderError(f"{file}: the calibration {what}; the leader's motors are {', '.join(motors)}")
    return {m: _motor_calibration(file, m, data[m]) for m in motors}


def _json_problem(exc: ValueError) -> str:
    """Why a JSON file could not be read, in words: a cut-short file is not JSON."""
    import json

    if isinstance(exc, json.JSONDecodeError):
        return f"not JSON, or cut short: {exc}"
    if isinstance(exc, UnicodeDecodeError):
        return "not UTF-8 text"
    return str(exc)


def _motor_calibration(file: Path, motor: str, entry: object) -> dict[str, int]:
    """One motor's calibration entry, its fields whole numbers within what the servo holds; one line otherwise."""
    if not isinstance(entry, dict) or set(entry) != set(CALIBRATION_FIELDS):
        raise LeaderError(f"{file}: motor {motor}: give an object of the fields {', '.join(CALIBRATION_FIELDS)}")
    for field, (lo, hi) in CALIBRATION_FIELDS.items():
        value = entry[field]
        if isinstance(value, bool) or not isinstance(value, int) or not lo <= value <= hi:
            raise LeaderError(f"{file}: motor {motor}: {field} {_json_repr(value)}: give a whole number from {lo} to "
                              f"{hi}")
    if entry["range_min"] >= entry["range_max"]:
        raise LeaderError(f"{file}: motor {motor}: range_min {entry['range_min']} is not below range_max "
                          f"{entry['range_max']}; calibrate the arm again with lerobot-calibrate")
    return entry


def _json_repr(value: object, limit: int = 40) -> str:
    """``value`` as JSON, cut to ``limit`` characters (for a message)."""
    import json

    text = json.dumps(value)
    return text if len(text) <= limit else text[:limit] + "..."


def _no_answer(port: str, exc: BaseException) -> LeaderError:
    """The one line for a leader on ``port`` that cannot be opened or whose servos do not answer (``exc``, LeRobot's
    error, whose text is several lines: the servos it missed are named)."""
    import re

    text = str(exc.__cause__ or exc).strip()
    missing = re.findall(r"^\s*- (\d+) \(expected model", text, flags=re.MULTILINE)
    reason = (f"servos {', '.join(missing)} do not answer" if missing and "incorrect model" not in text
              else " ".join(text.splitlines()[0].split()) if text else type(exc).__name__)
    return LeaderError(f"--port {port}: the leader arm does not answer ({reason.rstrip(':')}); check the port "
                       "(lerobot-find-port), the cable and the arm's power")


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
        try:
            action = self.teleop.get_action()
        except BUS_ERRORS as exc:  # unplugged, or its power lost, while it drives the arm
            raise _no_answer(getattr(getattr(self.teleop, "config", None), "port", "?"), exc) from None
        return self.joint_targets(action)

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
    from rik.sim.robots.layout import robot_layout

    read_calibration(file, [n.removesuffix(".pos") for n in robot_layout(robot).action_names])
    from lerobot.teleoperators.so_leader import SOLeader, SOLeaderTeleopConfig

    teleop = SOLeader(SOLeaderTeleopConfig(port=port, id=leader_id, calibration_dir=file.parent))
    try:
        teleop.connect(calibrate=False)  # LeRobot pings each servo, each within its packet timeout
    except BUS_ERRORS as exc:
        _close_port(teleop)
        raise _no_answer(port, exc) from None
    try:
        if not teleop.is_calibrated:
            teleop.bus.write_calibration(teleop.calibration)
        return leader_arm(device, teleop, robot)
    except BUS_ERRORS as exc:
        _disconnect(teleop)
        raise _no_answer(port, exc) from None
    except BaseException:
        _disconnect(teleop)
        raise


def _disconnect(teleop: Any) -> None:
    """Disconnect a leader that failed half way, quietly (the first error is the one to report), its port closed
    even when its servos do not answer LeRobot's torque-off."""
    try:
        teleop.disconnect()
    except BUS_ERRORS:
        pass
    finally:
        _close_port(teleop)


def _close_port(teleop: Any) -> None:
    """Close the serial port of a leader that LeRobot opened but could not connect (its servos did not answer)."""
    handler = getattr(getattr(teleop, "bus", None), "port_handler", None)
    if handler is not None and getattr(handler, "is_open", False):
        handler.closePort()
