"""The figures of docs/robots.md, generated from the catalog's robots (``rik catalog robots-doc``).

The page is written by people except one part, between :data:`BEGIN` and :data:`END`: per robot, its joints
(range, torque, speed, servo gains), its gripper (stroke, grip force, pad friction, finger speed), its mount, its
wrist camera and its LeRobot layout, each figure with the source the catalog records for it. Only that part is
replaced; a test keeps it equal to the catalog.
"""

from __future__ import annotations

import math
from typing import Any

from rik.errors import RikError
from rik.registry.index import CatalogIndex
from rik.registry.views import COLUMNS, mm

BEGIN = "<!-- BEGIN rik catalog robots-doc: generated from rik/registry/data/robots.yaml; do not edit by hand -->"
END = "<!-- END rik catalog robots-doc -->"
NO_SOURCE = "not recorded in the catalog"


def _num(value: float) -> str:
    return f"{value:g}"


def _sentence(text: str) -> str:
    """``text`` stripped, ending with a full stop."""
    text = " ".join(text.split())
    return text if text.endswith((".", "!", "?")) else text + "."


def _md_table(headers: list[str], rows: list[list[str]]) -> list[str]:
    def esc(cell: str) -> str:
        return cell.replace("|", "\\|").replace("\n", " ")

    return ["| " + " | ".join(headers) + " |", "|" + "---|" * len(headers),
            *["| " + " | ".join(esc(c) for c in row) + " |" for row in rows]]


def summary_table(index: CatalogIndex) -> list[str]:
    """The robots as ``rik catalog list --kind robots`` shows them, as a Markdown table (also in CATALOG.md)."""
    columns = COLUMNS["robots"]
    return _md_table([h for h, _ in columns], [[cell(r) for _, cell in columns] for r in index.entries("robots")])


def _joints(robot: dict[str, Any]) -> list[str]:
    joints = robot.get("joints")
    if not joints:
        return ["No arm joints in the catalog (a floating base). " + _sentence(robot["description"]), ""]
    rows = []
    for j in joints["joints"]:
        lo, hi = j["range"]
        rows.append([f"`{j['name']}`", f"{_num(lo)} to {_num(hi)}",
                     f"{math.degrees(lo):.0f} to {math.degrees(hi):.0f}", _num(j["torque"]), _num(j["speed"]),
                     _num(j["stiffness"]), _num(j["damping"]),
                     "the model's" if j["friction"] is None else _num(j["friction"]),
                     "the model's" if j["armature"] is None else _num(j["armature"])])
    compensation = ("yes (the controller compensates gravity, within each joint's torque)"
                    if joints["gravity_compensation"] else "no (gravity loads the servos)")
    return [*_md_table(["joint", "range rad", "range °", "torque N·m", "speed rad/s", "stiffness N·m/rad",
                        "damping N·m·s/rad", "friction N·m", "armature kg·m²"], rows), "",
            f"Gravity compensation: {compensation}. Sources: {_sentence(joints['source'])}", ""]


def _gripper(robot: dict[str, Any]) -> list[str]:
    g = robot["gripper"]
    rows = [["stroke", f"{mm(g['stroke'])} mm", NO_SOURCE],
            ["grip force (each jaw)", f"{_num(g['grip_force']['value'])} N", g["grip_force"]["source"]],
            ["pad friction (static)", _num(g["pad_friction"]["value"]), g["pad_friction"]["source"]],
            ["finger speed", f"{_num(g['finger_speed']['value'])} m/s", g["finger_speed"]["source"]]]
    act = g.get("actuation") or {}
    if act.get("force_limit"):
        rows.append(["jaw servo force cap", f"{_num(act['force_limit']['value'])} N·m",
                     act["force_limit"]["source"]])
    dims = (f"tcp offset {mm(g['tcp_offset'])} mm; fingers {mm(g['finger_length'])} long, "
            f"{mm(g['finger_width'])} wide, {mm(g['finger_thickness'])} thick; pads {mm(g['pad_length'])} long (mm, "
            "as the grasp planner sees them)")
    return [f"Gripper: {g['name']} ({g['kind']}).", "", *_md_table(["figure", "value", "source"], rows), "",
            f"Geometry: {dims}.", ""]


def _mount(robot: dict[str, Any]) -> list[str]:
    m = robot.get("mount")
    if not m:
        return []
    where = f"offset {', '.join(_num(v) for v in m['offset'])} m from the grasp point, yaw {_num(m['yaw'])} rad"
    if m["offset"][0] != 0:
        where += (f", at least {_num(m['clearance'])} m outside the furniture's side"
                  + (", on the side nearer the handle" if m["mirror"] else ""))
    home = ", ".join(_num(q) for q in m["home"])
    return [f"Mount: {where}; home posture ({home}) rad. Why: {_sentence(m['reason'])}", ""]


def _camera_and_layout(robot: dict[str, Any]) -> list[str]:
    out = []
    cam = robot.get("wrist_camera")
    if cam:
        out += [f"Wrist camera: on `{cam['body']}`, vertical field of view {_num(cam['fovy'])}°: {cam['source']}.",
                ""]
    lay = robot["lerobot"]
    if lay["layout"] == "joints":
        names = ", ".join(f"`{e['name']}` ({e['unit']}{', 0 mid-range' if e.get('zero') == 'mid_range' else ''})"
                          for e in lay["joints"])
        what = f"`observation.state` and `action`: {names}" + (
            "; `observation.ee_pose`: `ee.x` .. `ee.wz`" if lay["ee_pose"] else "")
    else:
        what = "rik's pose layout (docs/lerobot.md)"
    out += [f"LeRobot: `robot_type` `{lay['robot_type']}`; {what}. Source: {_sentence(lay['source'])}", ""]
    return out


def render_robot_figures(index: CatalogIndex) -> str:
    """The generated part of docs/robots.md (without its markers)."""
    out = ["Generated by `rik catalog robots-doc` from the catalog; `rik catalog show ROBOT` shows every field. "
           "Units: m (mm where a header says so), rad, N, N·m, rad/s, m/s.", "", *summary_table(index), ""]
    for robot in index.entries("robots"):
        model = robot["model"]
        source = f"`{model['package']}` ({', '.join(model['files'])})" if model["package"] else "rik"
        out += [f"### {robot['id']}: {robot['name']}", "",
                f"Model from {source}, licence {model['licence']}: {_sentence(model['origin'])}", ""]
        out += _joints(robot) + _gripper(robot) + _mount(robot) + _camera_and_layout(robot)
    return "\n".join(out).rstrip("\n") + "\n"


def splice(text: str, generated: str, shown: str) -> str:
    """``text`` (the page, shown in messages as ``shown``) with the part between its markers replaced by
    ``generated``; a page without both markers, in order, once each, is a :class:`RikError`."""
    begin, end = text.count(BEGIN), text.count(END)
    if begin != 1 or end != 1 or text.index(BEGIN) > text.index(END):
        raise RikError(f"{shown}: the generated figures go between the lines {BEGIN!r} and {END!r}, each once and in "
                       f"that order (found {begin} and {end})")
    head, rest = text.split(BEGIN)
    tail = rest.split(END)[1]
    return f"{head}{BEGIN}\n{generated}{END}{tail}"
