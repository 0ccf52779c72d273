"""The quantities of measured data and their units: the roles and column names, the unit tables (unit name →
factor to SI, per joint type), the ``name [unit]`` header and the messages that say which units are valid."""

from __future__ import annotations

import math
import re
from collections.abc import Iterable

from rik.errors import RikError
from rik.schemas.joints import JointType

ROLES = ("time", "position", "force", "velocity")
COLUMN_NAMES = {"time": ("time", "t"), "position": ("position", "q"), "force": ("force", "torque", "f"),
                "velocity": ("velocity", "qd")}
"""Accepted column names of each quantity (case-insensitive)."""
TRIAL_COLUMN = "trial"

TIME_UNITS = {"s": 1.0, "ms": 1e-3}
POSITION_UNITS = {JointType.slide: {"m": 1.0, "mm": 1e-3, "cm": 1e-2},
                  JointType.hinge: {"rad": 1.0, "deg": math.pi / 180}}
FORCE_UNITS = {JointType.slide: {"N": 1.0, "kN": 1e3},
               JointType.hinge: {"N·m": 1.0, "Nm": 1.0, "N*m": 1.0, "N·mm": 1e-3, "Nmm": 1e-3, "N*mm": 1e-3}}
VELOCITY_UNITS = {j: {f"{u}/s": s for u, s in units.items()} for j, units in POSITION_UNITS.items()}
"""Unit name → factor to SI, per joint type."""

_KIND = {("position", JointType.slide): "a length unit", ("position", JointType.hinge): "an angle unit",
         ("force", JointType.slide): "a force unit", ("force", JointType.hinge): "a torque unit",
         ("velocity", JointType.slide): "a linear velocity unit",
         ("velocity", JointType.hinge): "an angular velocity unit"}
_HEADER = re.compile(r"^\s*(?P<name>[^\[\]]*?)\s*(?:\[(?P<unit>[^\[\]]*)\])?\s*$")


def choices(units: Iterable[str]) -> str:
    """The names as a phrase for messages: "s", "s or ms", "m, mm or cm"."""
    names = list(units)
    return names[0] if len(names) == 1 else ", ".join(names[:-1]) + f" or {names[-1]}"


def unit_table(role: str) -> dict[JointType, dict[str, float]]:
    """The unit table (joint type → unit name → factor to SI) of ``position``, ``force`` or ``velocity``."""
    return {"position": POSITION_UNITS, "force": FORCE_UNITS, "velocity": VELOCITY_UNITS}[role]


def accepted_units(role: str, joint: JointType) -> str:
    """What the units of ``role`` may be, as a phrase: "a slide's position is in m, mm or cm"."""
    if role == "time":
        return f"time is in {choices(TIME_UNITS)}"
    word = "torque" if role == "force" and joint is JointType.hinge else role
    return f"a {joint.value}'s {word} is in {choices(unit_table(role)[joint])}"


def unit_option(role: str) -> str:
    """The ``rik sysid fit`` option that declares the unit of quantity ``role`` (``--position-unit``): what
    messages tell the user to add (the :class:`~rik.sysid.trials.ColumnMap` field is ``position_unit``)."""
    return f"--{role}-unit"


def unit_scale(role: str, unit: str | None, joint: JointType, header: str) -> float:
    """Factor from ``unit`` to SI for quantity ``role`` of a ``joint``; raises ValueError with the problem (the
    caller adds file and column) for a missing, unknown or mismatched unit."""
    if not unit:
        example = next(iter(TIME_UNITS if role == "time" else unit_table(role)[joint]))
        name = header.strip() or role
        raise ValueError(f"no unit; write the header as '{name} [unit]' (e.g. '{name} [{example}]') or pass "
                         f"{unit_option(role)}: {accepted_units(role, joint)}")
    if role == "time":
        if unit in TIME_UNITS:
            return TIME_UNITS[unit]
        raise ValueError(f"unknown unit '{unit}'; {accepted_units(role, joint)}")
    table = unit_table(role)
    if unit in table[joint]:
        return table[joint][unit]
    for other in JointType:
        if other is not joint and unit in table[other]:
            raise ValueError(f"'{unit}' is {_KIND[role, other]} but the joint is a {joint.value}; "
                             f"{accepted_units(role, joint)}")
    raise ValueError(f"unknown unit '{unit}'; {accepted_units(role, joint)}")


def joint_type(joint: str | JointType) -> JointType:
    """``slide`` or ``hinge`` as a :class:`JointType`; anything else is a :class:`RikError`."""
    try:
        return JointType(joint)
    except ValueError:
        raise RikError(f"unknown joint type '{joint}'; use 'slide' or 'hinge'") from None


def parse_header(header: str) -> tuple[str, str | None]:
    """(lower-case name, unit or None) of a header such as ``Position [mm]``."""
    match = _HEADER.match(header)
    if match is None:
        return header.strip().lower(), None
    unit = match["unit"]
    return match["name"].lower(), (unit.strip() if unit is not None else None)
