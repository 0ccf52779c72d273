"""Hostile values on the command line and in what rik reads: options out of their range (typer printed a box of five
lines), ``inf`` and ``nan`` where a finite number is meant (``rik serve --max-seconds inf`` stopped the station at the
first connection), a leader arm whose servos do not answer or whose calibration file is cut short (tracebacks), and
measured forces so large that the fit overflowed into NaN gains written to ``summary.json``. Each is one line,
``rik: error: ...``, naming the option, port or file (and column), exit 2, nothing written."""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pytest
from shared import BOW, builtin_catalog
from test_hostile_input import tree
from test_leader_teleop import EncoderLeader, write_calibration

from rik.errors import RikError

CAT = builtin_catalog()


def _float_options() -> list[tuple[tuple[str, ...], str, int, bool]]:
    """Every float option of the CLI, found in the click commands typer builds (so that a new one is tested too):
    (command path, option, values it takes, whether the command has required parameters)."""
    from typer._click import types
    from typer.main import get_command

    from rik.cli.app import app

    found = []

    def walk(command, path: tuple[str, ...]) -> None:
        for name, sub in getattr(command, "commands", {}).items():
            walk(sub, (*path, name))
        for param in command.params:
            kinds = param.type.types if isinstance(param.type, types.Tuple) else [param.type]
            if any(isinstance(k, types.FloatParamType) for k in kinds):
                found.append((path, param.opts[0], param.nargs, any(p.required for p in command.params)))

    walk(get_command(app), ())
    return found


FLOAT_OPTIONS = _float_options()


# ---- 1. options out of their range: one line, not typer's box ------------------------------------------------
@pytest.mark.parametrize(("args", "line"), [
    (("demo", "--res", "0"), "--res: 0 is not in the range 25<=x<=1024 (see rik demo --help)"),
    (("demo", "--episodes", "101"), "--episodes: 101 is not in the range 1<=x<=100 (see rik demo --help)"),
    (("eval", "-n", "0", "policy"), "--episodes-per-cell/-n: 0 is not in the range x>=1 (see rik eval --help)"),
    (("sysid", "simulate", "--trials", "1"), "--trials/-n: 1 is not in the range x>=2 (see rik sysid simulate --help)"),
    (("sysid", "fit", "--window", "-1", "d.csv"), "--window: -1.0 is not in the range x>=0.0 (see rik sysid fit --help)"),
    (("record", "-s", "grasp_vertical", "--action-noise", "0.5", BOW),
     "--action-noise: 0.5 is not in the range 0.0<=x<=0.05 (see rik record --help)"),
    (("variants", "show", BOW, "v.png", "--width", "10"),
     "--width: 10 is not in the range 64<=x<=4096 (see rik variants show --help)"),
    (("visual-gap", "--n", "2"), "--n: 2 is not in the range x>=4 (see rik visual-gap --help)"),
], ids=["demo-res", "demo-episodes", "eval-n", "sysid-simulate-trials", "sysid-fit-window", "record-action-noise",
        "variants-show-width", "visual-gap-n"])
def test_an_option_out_of_its_range_is_one_line(rik, tmp_path: Path, monkeypatch, args: tuple[str, ...],
                                                line: str) -> None:
    monkeypatch.chdir(tmp_path)
    r = rik(*args)
    assert r.code == 2 and r.err == f"rik: error: {line}\n", r.err
    assert tree(tmp_path) == []


def test_other_usage_errors_are_one_line_and_help_is_unchanged(rik, tmp_path: Path, monkeypatch) -> None:
    """An unknown command or option, a value that is no number, a missing argument: one line, exit 2. Help,
    ``--version``, ``rik`` alone and a command's own exit code (``typer.Exit(1)``) are as before."""
    monkeypatch.chdir(tmp_path)
    for args, line in [(("nosuch",), "No such command 'nosuch' (see rik --help)"),
                       (("demo", "--bogus"), "No such option: --bogus (see rik demo --help)"),
                       (("demo", "--res", "big"), "--res: 'big' is not a valid int range (see rik demo --help)"),
                       (("sysid", "fit"), "Missing argument 'data' (see rik sysid fit --help)")]:
        r = rik(*args)
        assert r.code == 2 and r.err == f"rik: error: {line}\n", r.err
    for args, code in [(("--help",), 0), (("demo", "--help"), 0), ((), 2), (("sysid",), 2)]:
        r = rik(*args)
        assert r.code == code and "Usage: rik" in r.out and r.err == "", (args, r)
    r = rik("--version")
    assert r.code == 0 and r.out.startswith("rik ") and r.err == ""
    r = rik("catalog", "robots-doc", "--check", "--out", str(tmp_path / "missing.md"))
    assert r.code == 1 and r.err == f"{tmp_path / 'missing.md'} is missing; restore it and run `rik catalog robots-doc`\n"
    assert tree(tmp_path) == []


# ---- 2. inf and nan where a finite number is meant ----------------------------------------------------------
@pytest.mark.parametrize("value", ["inf", "nan"])
@pytest.mark.parametrize(("path", "option", "nargs", "required"), FLOAT_OPTIONS,
                         ids=[f"{'-'.join(p)}{o}" for p, o, _, _ in FLOAT_OPTIONS])
def test_a_float_option_that_is_not_finite_is_one_line(rik, tmp_path: Path, monkeypatch, path: tuple[str, ...],
                                                       option: str, nargs: int, required: bool, value: str) -> None:
    """Every float option of every command. A command without required parameters gets an extra argument, which
    is checked after the options: where ``inf`` passed (before the fix) it stops at once instead of serving."""
    assert len(FLOAT_OPTIONS) >= 16  # serve, teleop, record, catalog list, assets import, variants, sysid
    monkeypatch.chdir(tmp_path)
    r = rik(*path, option, *["1"] * (nargs - 1), value, *([] if required else ["extra-argument"]))
    assert r.code == 2 and r.err == (f"rik: error: {option}: {value} is not a finite number; give a finite one "
                                     f"(see rik {' '.join(path)} --help)\n"), r.err
    assert tree(tmp_path) == []


# ---- 3. the SO-101 leader arm ---------------------------------------------------------------------------------
def _teleop(rik, tmp_path: Path, port: str):
    return rik("teleop", BOW, "--robot", "so101", "--device", "so101-leader", "--port", port, "--calibration-dir",
               str(tmp_path / "cal"), "--variants", str(tmp_path / "variants"))


def test_a_port_where_no_servo_answers_is_one_line(rik, tmp_path: Path) -> None:
    """A pseudo-terminal stands in for an unpowered arm: a serial port that opens, and nothing on it answers
    LeRobot's pings (each waits its packet timeout). Before: LeRobot's motor check, a traceback."""
    write_calibration(tmp_path / "cal", "blue")
    master, slave = os.openpty()
    try:
        port = os.ttyname(slave)
        r = _teleop(rik, tmp_path, port)
    finally:
        os.close(master)
        os.close(slave)
    assert r.code == 2 and r.err == (f"rik: error: --port {port}: the leader arm does not answer (servos 1, 2, 3, 4, "
                                     "5, 6 do not answer); check the port (lerobot-find-port), the cable and the "
                                     "arm's power\n"), r.err
    assert tree(tmp_path) == ["cal", "cal/blue.json"]


def _cut_short(data: dict) -> bytes:
    return json.dumps(data).encode()[:150]


def _without_gripper(data: dict) -> bytes:
    return json.dumps({m: v for m, v in data.items() if m != "gripper"}).encode()


def _field(name: str, value: object):
    def edit(data: dict) -> bytes:
        data["wrist_flex"][name] = value
        return json.dumps(data).encode()
    return edit


@pytest.mark.parametrize(("damage", "problem"), [
    (_cut_short, "not a calibration file of LeRobot (not JSON, or cut short: Unterminated string starting at: "),
    (lambda data: b"\x00\x9f\x92\x96 binary", "not a calibration file of LeRobot (not UTF-8 text); make it again "),
    (lambda data: b"[1, 2]", "not a calibration file of LeRobot (a JSON object of the motors shoulder_pan, "),
    (_without_gripper, "the calibration lacks the motors gripper; the leader's motors are shoulder_pan, "),
    (_field("range_min", "low"), 'motor wrist_flex: range_min "low": give a whole number from 0 to 4095'),
    (_field("range_max", 910), "motor wrist_flex: range_min 910 is not below range_max 910; calibrate the arm "),
    (_field("homing_offset", 1e9), "motor wrist_flex: homing_offset 1000000000.0: give a whole number from -2047 "),
], ids=["cut-short", "not-json", "a-list", "a-motor-missing", "a-field-no-number", "an-empty-range",
        "an-offset-out-of-range"])
def test_a_damaged_leader_calibration_is_one_line(rik, tmp_path: Path, damage, problem: str) -> None:
    """Checked before the port is opened (/dev/null would fail later). Before: a JSONDecodeError or draccus
    traceback, or LeRobot writing a bad calibration to the servos."""
    file = write_calibration(tmp_path / "cal", "blue")
    file.write_bytes(damage(json.loads(file.read_text())))
    r = _teleop(rik, tmp_path, "/dev/null")
    assert r.code == 2 and r.err.startswith(f"rik: error: {file}: {problem}") and r.err.count("\n") == 1, r.err
    assert tree(tmp_path) == ["cal", "cal/blue.json"]


def test_a_leader_that_stops_answering_is_one_line(tmp_path: Path) -> None:
    """A leader unplugged (or its power lost) while it drives the arm: LeRobot's bus raises what it raises when no
    status packet comes back; the read is one line naming the port."""
    from rik.teleop.leader import LeaderError, leader_arm

    write_calibration(tmp_path, "blue")
    leader = EncoderLeader(tmp_path, "blue")

    def unplugged(*args: object, **kwargs: object) -> None:
        raise ConnectionError("Failed to sync read 'Present_Position' on ids=[1, 2, 3, 4, 5, 6] after 1 tries. "
                              "[TxRxResult] There is no status packet!")

    leader.teleop.bus._sync_read = unplugged
    arm = leader_arm("so101-leader", leader.teleop, CAT.robot("so101"))
    with pytest.raises(LeaderError) as exc:
        arm.read()
    assert str(exc.value) == ("--port /dev/null: the leader arm does not answer (Failed to sync read "
                              "'Present_Position' on ids=[1, 2, 3, 4, 5, 6] after 1 tries. [TxRxResult] There is no "
                              "status packet!); check the port (lerobot-find-port), the cable and the arm's power")


# ---- 4. measured values too large to fit ------------------------------------------------------------------------
@pytest.fixture(scope="module")
def drawer():
    """Two simulated trials of a drawer with a self-closing spring."""
    from rik.sysid.synthetic.generate import random_truth, simulate_trials

    return simulate_trials(random_truth("self_close", "slide", np.random.default_rng(3)), n_trials=2, seed=3)


@pytest.mark.parametrize(("header", "columns", "where", "unit"), [
    ("time [s],position [m],force [N]", lambda t, q, f: (t, q, f * 1e300), "trial 'data', column 'force [N]'", "N"),
    ("time [s],position [mm],force [N]", lambda t, q, f: (t, q * 1e303, f), "trial 'data', column 'position [mm]'",
     "mm"),
    ("position [mm],force [N]", lambda t, q, f: (q * 1e3, f * 1e300), "column 'force [N]'", "N"),  # quasi-static
], ids=["forces", "positions", "profile-forces"])
def test_measured_values_too_large_to_fit_are_one_line(rik, drawer, tmp_path: Path, header: str, columns,
                                                       where: str, unit: str) -> None:
    """Before: forces x 1e300 were fitted into inf errors and NaN gains, written to summary.json."""
    rows = np.column_stack(columns(drawer[0].t, drawer[0].q, drawer[0].f))
    data = tmp_path / "data.csv"
    data.write_text(header + "\n" + "".join(",".join(repr(float(v)) for v in row) + "\n" for row in rows))
    r = rik("sysid", "fit", str(data), "--report", str(tmp_path / "report"))
    assert r.code == 2 and r.err.startswith(f"rik: error: {data}, {where}: row 0 (line 2) is ") and \
        r.err.endswith(f", beyond ±1e+06 {unit}, far more than any furniture joint: too large to fit; is the unit "
                       "right?\n") and r.err.count("\n") == 1, r.err
    assert tree(tmp_path) == ["data.csv"]


def test_a_fit_that_overflows_is_refused_not_written_as_nan(drawer) -> None:
    """The last guard, behind the bounds on what is read: trials made in code (not read from a file) whose forces
    overflow the fit give one line naming their source and force column, never a Discovery holding NaN."""
    from rik.sysid.discover import discover
    from rik.sysid.trials import Trial

    huge = [Trial(t.meta, t.t, t.q, t.f * 1e300) for t in drawer]
    with np.errstate(all="ignore"), pytest.raises(RikError) as exc:
        discover(huge, resimulate=False)
    assert str(exc.value) == ("simulated, column 'force [N]': the fit of baseline is not a finite number (an overflow): "
                              "the values are too large or too degenerate to fit; check the units")
