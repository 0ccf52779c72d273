"""Tabular views of catalog entries: the columns that ``rik catalog list`` and CATALOG.md show per kind.

Values are formatted for people (lengths in mm); JSON and CSV output use the raw SI entries instead.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

Row = dict[str, Any]

#: CLI names of the kinds and the catalog section each shows.
KINDS = {"handles": "handles", "designs": "designs", "bases": "base_units", "presets": "presets",
         "finishes": "finishes", "robots": "robots"}


def srgb_hex(rgb: list[float]) -> str:
    """An sRGB colour (three numbers in 0..1) as ``#rrggbb``."""
    return "#" + "".join(f"{round(c * 255):02x}" for c in rgb)


def mm(value: float | None) -> str:
    """A length in metres shown in millimetres ('' when absent)."""
    return "" if value is None else f"{value * 1000:.4g}"


def _clearance(row: Row) -> str:
    c = row["geometry"].get("clearance")
    return "" if c is None else f"{mm(c['depth'])} x {mm(c['width'])}"


def _fronts(row: Row) -> str:
    kinds = [f["kind"] for f in row["fronts"]]
    return ", ".join(f"{kinds.count(k)} {k}{'s' if kinds.count(k) > 1 else ''}" for k in dict.fromkeys(kinds))


def _resistance(row: Row, joint: str) -> str:
    r = row[joint]
    return f"{r['damping']:g} / {r['frictionloss']:g}"


def preset_source(row: Row) -> str:
    """Where a preset comes from, in a few words: ``paper``, or ``measured: door X of FILE, RMS a N fitted / b N
    held out`` (forces at the handle), or ``–`` when the entry does not say."""
    src = row.get("source")
    if not src:
        return "–"
    if src["kind"] != "measured" or not src.get("data"):
        return str(src["kind"])
    where = f"{src['data']} {src['mechanism']}" if src.get("mechanism") else str(src["data"])
    errors = [f"{src[k]:.3g} N {what}" for k, what in (("fit_rms_n", "fitted"), ("heldout_rms_n", "held out"))
              if src.get(k) is not None]
    return f"measured: {where}" + (f"; RMS {', '.join(errors)}" if errors else "")


def _effects(row: Row, joint: str) -> str:
    r = row[joint]
    kinds = [e["kind"] for e in r.get("effects") or ()] + (["spring"] if r.get("spring") else [])
    return ", ".join(kinds) or "–"


def _generator(row: Row) -> str:
    gen = dict(row["generator"])
    name = gen.pop("name")
    first = next(iter(gen.values()), None)
    return f"{name} ({first})" if isinstance(first, str) else name


def _robot_joints(row: Row) -> str:
    return str(len(row["joints"]["joints"])) if row.get("joints") else ""


def _robot_torque(row: Row) -> str:
    return f"{max(j['torque'] for j in row['joints']['joints']):g}" if row.get("joints") else ""


#: Columns per kind: (header, cell function).
COLUMNS: dict[str, list[tuple[str, Callable[[Row], str]]]] = {
    "handles": [
        ("id", lambda r: r["id"]),
        ("type", lambda r: r["type"]),
        ("length mm", lambda r: mm(r["geometry"]["length"])),
        ("width mm", lambda r: mm(r["geometry"]["width"])),
        ("projection mm", lambda r: mm(r["geometry"]["projection"])),
        ("grip Ø mm", lambda r: mm(r["geometry"]["grip_diameter"])),
        ("holes c-c mm", lambda r: mm(r["geometry"].get("hole_spacing"))),
        ("clearance mm (depth x width)", _clearance),
        ("mount", lambda r: r["mount"]["kind"] + (f" ({r['mount']['edge']})" if r["mount"].get("edge") else "")),
        ("finish", lambda r: r["finish"]),
        ("mass g", lambda r: f"{r['mass'] * 1000:.0f}"),
        ("split", lambda r: r["split"]),
    ],
    "designs": [
        ("id", lambda r: r["id"]),
        ("type", lambda r: r["type"]),
        ("subtype", lambda r: r["subtype"]),
        ("name", lambda r: r["name"]),
        ("generator", _generator),
        ("handles", lambda r: str(r["handle_count"])),
        ("split", lambda r: r["split"]),
    ],
    "base_units": [
        ("id", lambda r: r["id"]),
        ("name", lambda r: r["name"]),
        ("fronts", _fronts),
        ("joints", lambda r: ", ".join(r["joint_types"])),
        ("carcass mm (w x h x d)", lambda r: " x ".join(mm(r["carcass"][k]) for k in ("width", "height", "depth"))),
        ("install", lambda r: r["install"] + (f" at {mm(r['install_height'])} mm" if r["install_height"] else "")),
    ],
    "presets": [
        ("id", lambda r: r["id"]),
        ("name", lambda r: r["name"]),
        ("slide damping N·s/m / friction N", lambda r: _resistance(r, "slide")),
        ("hinge damping N·m·s/rad / friction N·m", lambda r: _resistance(r, "hinge")),
        ("hinge effects", lambda r: _effects(r, "hinge")),
        ("provenance (slide, hinge)", lambda r: f"{r['slide']['provenance']}, {r['hinge']['provenance']}"),
        ("source", preset_source),
    ],
    "finishes": [
        ("id", lambda r: r["id"]),
        ("name", lambda r: r["name"]),
        ("kind", lambda r: r["kind"]),
        ("colour (sRGB)", lambda r: srgb_hex(r["base_color"])),
        ("metallic", lambda r: f"{r['metallic']:g}"),
        ("roughness", lambda r: f"{r['roughness']:g}"),
        ("pattern", lambda r: r["pattern"]),
    ],
    "robots": [
        ("id", lambda r: r["id"]),
        ("name", lambda r: r["name"]),
        ("kind", lambda r: r["kind"]),
        ("joints", _robot_joints),
        ("max torque N·m", _robot_torque),
        ("stroke mm", lambda r: mm(r["gripper"]["stroke"])),
        ("grip force N", lambda r: f"{r['gripper']['grip_force']['value']:g}"),
        ("pad friction", lambda r: f"{r['gripper']['pad_friction']['value']:g}"),
        ("model from", lambda r: r["model"]["package"] or "rik"),
        ("LeRobot robot_type", lambda r: r["lerobot"]["robot_type"]),
        ("licence", lambda r: r["model"]["licence"]),
    ],
}

#: What the table of a kind shows its figures in (``rik catalog list``'s last line); lengths in mm by default.
UNITS = {"robots": "stroke in mm, forces in N, torques in N·m",
         "presets": "variants are built with measured presets only when named (--preset ID); RMS: the error of the "
                    "force at the handle, N"}


def table(section: str, rows: list[Row]) -> tuple[list[str], list[list[str]]]:
    """Headers and formatted cells of ``rows`` of a section."""
    columns = COLUMNS[section]
    return [h for h, _ in columns], [[cell(r) for _, cell in columns] for r in rows]


def flatten(row: Row, prefix: str = "") -> dict[str, object]:
    """Nested dicts as dotted keys (``geometry.length``); lists of scalars joined by spaces; others as JSON."""
    import json

    flat: dict[str, Any] = {}
    for key, value in row.items():
        name = f"{prefix}{key}"
        if isinstance(value, dict):
            flat.update(flatten(value, f"{name}."))
        elif isinstance(value, list) and all(isinstance(v, (int, float, str)) for v in value):
            flat[name] = " ".join(str(v) for v in value)
        elif isinstance(value, list):
            flat[name] = json.dumps(value, separators=(",", ":"))
        else:
            flat[name] = "" if value is None else value
    return flat


def format_columns(headers: list[str], rows: list[list[str]], gap: int = 2) -> str:
    """Rows as plain aligned text columns (as ``kubectl get`` prints): a header, a rule, one line per row.

    Columns whose cells are all numbers (or empty) are right-aligned. No colours or box characters, so the
    output greps, pipes and diffs cleanly.
    """

    def numeric(cell: str) -> bool:
        try:
            float(cell)
        except ValueError:
            return cell == ""
        return True

    widths = [max([len(h), *(len(r[i]) for r in rows)]) for i, h in enumerate(headers)]
    right = [bool(rows) and all(numeric(r[i]) for r in rows) for i in range(len(headers))]

    def line(cells: list[str]) -> str:
        parts = [c.rjust(w) if r else c.ljust(w) for c, w, r in zip(cells, widths, right, strict=True)]
        return (" " * gap).join(parts).rstrip()

    return "\n".join([line(headers), line(["-" * w for w in widths]), *(line(r) for r in rows)])
