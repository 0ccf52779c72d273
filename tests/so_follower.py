"""lerobot's SO follower without its hardware, for the tests of the SO arms' exports: its motor table read from
``SOFollower.__init__``'s own source, and a motor bus whose servos are a simulated arm's joints, on which lerobot's
own ``SOFollower.calibrate`` homes and records ranges and lerobot's own ``_normalize`` / ``_unnormalize`` read and
write positions. Nothing here opens a port or needs the Feetech SDK (lerobot's ``feetech`` extra): the bus's
methods that do the arithmetic are lerobot's, called on this bus."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any


def so_follower_motors() -> dict:
    """The motor table lerobot's ``SOFollower`` builds in ``__init__`` (its ``Motor(...)`` entries, with the body
    motors' norm mode its config's default chooses), read from the class's own source (constructing the class
    opens no port but needs the Feetech SDK)."""
    import ast
    import dataclasses
    import inspect
    import textwrap
    from types import SimpleNamespace

    from lerobot.motors import Motor, MotorNormMode
    from lerobot.robots.so_follower import SOFollower
    from lerobot.robots.so_follower.config_so_follower import SOFollowerConfig

    tree = ast.parse(textwrap.dedent(inspect.getsource(SOFollower.__init__)))
    config = SimpleNamespace(**{f.name: f.default for f in dataclasses.fields(SOFollowerConfig)
                                if f.default is not dataclasses.MISSING})
    names: dict = {"Motor": Motor, "MotorNormMode": MotorNormMode, "config": config}
    for node in ast.walk(tree):  # norm_mode_body = MotorNormMode.DEGREES if config.use_degrees else ...
        if isinstance(node, ast.Assign) and isinstance(node.targets[0], ast.Name):
            names[node.targets[0].id] = eval(compile(ast.Expression(node.value), "<SOFollower>", "eval"), names)
    motors = [k.value for node in ast.walk(tree) if isinstance(node, ast.Call) for k in node.keywords
              if k.arg == "motors"]
    assert len(motors) == 1, "SOFollower.__init__ no longer passes one motors={...} table to its bus"
    table = eval(compile(ast.Expression(motors[0]), "<SOFollower>", "eval"), names)
    assert table and all(isinstance(m, Motor) for m in table.values())
    return table


class SimulatedBus:
    """An SO follower's motor bus whose motors are a simulated arm's joints: motor ``name`` turns joint
    ``joints[name]`` (rad), and its encoder counts ``steps`` a turn in the joint's direction from ``origin[name]``
    (an arbitrary mounting of the horn). ``pose`` gives the joints' positions the servos read now. lerobot's own
    methods do the work: homing (``set_half_turn_homings``, the Feetech ``_get_half_turn_homings``), and the
    normalisation both ways."""

    def __init__(self, motors: dict, pose: Callable[[], dict[str, float]],
                 ranges: dict[str, tuple[float, float]], origin: dict[str, int]) -> None:
        from lerobot.motors.feetech import FeetechMotorsBus

        self.motors, self.pose, self.ranges, self.origin = motors, pose, ranges, origin
        self.calibration: dict[str, Any] = {}
        self.homing: dict[str, int] = {name: 0 for name in motors}
        self.apply_drive_mode = FeetechMotorsBus.apply_drive_mode
        self.model_resolution_table = FeetechMotorsBus.model_resolution_table
        self._id_to_name_dict = {m.id: name for name, m in motors.items()}
        self._id_to_model_dict = {m.id: m.model for m in motors.values()}

    def __getattr__(self, name: str) -> Any:
        """lerobot's bus methods (the Feetech bus's, then the generic serial bus's), bound to this bus."""
        from lerobot.motors.feetech import FeetechMotorsBus

        if name in ("set_half_turn_homings", "_get_half_turn_homings", "_normalize", "_unnormalize",
                    "_get_motors_list", "_get_motor_model", "_get_motor_id", "_id_to_name", "_id_to_model"):
            return getattr(FeetechMotorsBus, name).__get__(self)
        raise AttributeError(name)

    def steps(self, name: str) -> int:
        return self.model_resolution_table[self.motors[name].model]

    def actual(self, name: str, q: float) -> int:
        """The encoder's position with the joint at ``q`` rad (before homing)."""
        return self.origin[name] + round(q * self.steps(name) / (2 * math.pi))

    def present(self, name: str, q: float) -> int:
        """``Present_Position`` with the joint at ``q`` rad: the Feetech servo's ``Actual - Homing_Offset``."""
        return self.actual(name, q) - self.homing[name]

    # ---- what SOFollower.calibrate asks of its bus ---------------------------------------------------------------
    def disable_torque(self, *args: Any, **kwargs: Any) -> None:
        pass

    def write(self, register: str, motor: str, value: int, **kwargs: Any) -> None:
        if register == "Homing_Offset":
            self.homing[motor] = value

    def reset_calibration(self, motors: Any = None) -> None:
        for name in self._get_motors_list(motors):
            self.homing[name] = 0

    def sync_read(self, register: str, motors: Any = None, *, normalize: bool = True, **kwargs: Any) -> dict:
        assert register == "Present_Position" and not normalize
        pose = self.pose()
        return {name: self.present(name, pose[name]) for name in self._get_motors_list(motors)}

    def record_ranges_of_motion(self, motors: Any = None, **kwargs: Any) -> tuple[dict, dict]:
        """The operator moves each joint through its whole range: the extremes are the range's ends."""
        ends = {name: sorted((self.present(name, self.ranges[name][0]), self.present(name, self.ranges[name][1])))
                for name in self._get_motors_list(motors)}
        return {n: e[0] for n, e in ends.items()}, {n: e[1] for n, e in ends.items()}

    def write_calibration(self, calibration: dict) -> None:
        self.calibration = calibration
