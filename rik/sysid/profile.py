"""Quasi-static force profiles in: force against position, no time axis (a force gauge, a slow robot pull).

A profile file is a CSV (comma-separated, UTF-8, header line) or Parquet table with one row per measured point:

- a **position** column (``--position``; default a column named ``position`` or ``q``): the joint coordinate, 0
  where the front starts to open, positive opening. Units: a slide's in m, mm or cm; a hinge's in rad, deg, or
  ``bin`` -- angle bins of about one degree each (as in door-opening studies that resample an opening at regular
  angle steps), read as 1 bin = 1°;
- a **force** column (``--force``; default ``force``, ``torque`` or ``f``): the force that moves the front at that
  position. A slide's in N or kN; a hinge's either a torque (N·m, Nm, N*m, N·mm, ...) or a force **at the
  handle** (N, kN) when no lever arm is known: rik then reports forces at the handle, in N, against the angle;
- optional **trial** (``--trial``; default a column named ``trial``): one opening per value; without it the whole
  file (or group) is one trial;
- optional **group** (``--group``): one mechanism (door, drawer) per value; each group is fitted on its own.

Units are the ``--position-unit``/``--force-unit`` given, or else the one in square brackets in the header
(``force [N]``); the unit tables are :mod:`rik.sysid.trials`'s. Names match a header whole or without its
bracketed unit, case-insensitively.

Empty or NaN cells in the position, force, trial or group column are an error naming the file, row and column,
unless ``drop_nan`` is set: then those rows are left out and counted (:attr:`ProfileData.dropped`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from rik.errors import RikError
from rik.schemas.joints import JointType
from rik.sysid.trials import (
    COLUMN_NAMES,
    EMPTY_FILE,
    FORCE_UNITS,
    NOT_UTF8,
    POSITION_UNITS,
    TRIAL_COLUMN,
    RawTable,
    TrialError,
    check_size,
    joint_type,
    match_header,
    parse_header,
    read_table,
)
from rik.sysid.trials.load import check_magnitude, magnitude_problem

BIN_UNIT = "bin"
"""Position unit of angle bins; one bin is read as one degree (hinges only)."""
PROFILE_POSITION_UNITS = {JointType.slide: dict(POSITION_UNITS[JointType.slide]),
                          JointType.hinge: {**POSITION_UNITS[JointType.hinge], BIN_UNIT: math.pi / 180}}
"""Position unit → factor to SI (m or rad), per joint type."""
HANDLE_FORCE_UNITS = FORCE_UNITS[JointType.slide]
"""Units of a force (N, kN): on a hinge, a force at the handle (no lever arm), kept in N."""
MIN_POINTS = 5
"""Fewest points a trial (one opening) may have."""
MIN_SPAN = {JointType.slide: 1e-3, JointType.hinge: math.radians(2.0)}
"""Smallest position range of a trial: m (1 mm) or rad (2°)."""


@dataclass(frozen=True, eq=False)
class Profile:
    """One opening: positions and forces in SI (m or rad; N, N·m, or N at the handle), equal lengths."""

    name: str
    q: np.ndarray
    f: np.ndarray


@dataclass(frozen=True, eq=False)
class ProfileGroup:
    """The openings of one mechanism."""

    name: str
    """The group's value, or the file's stem without a group column."""
    profiles: tuple[Profile, ...]


@dataclass(frozen=True, eq=False)
class ProfileData:
    """Everything read from profile files."""

    joint: JointType
    groups: tuple[ProfileGroup, ...]
    force_unit: str
    """The SI unit of the forces: ``N``, ``N·m``, or ``N at the handle`` (a hinge without a lever arm)."""
    columns: dict[str, str]
    """Role (position, force, trial, group) → header used."""
    units: dict[str, str]
    """Role → unit as declared (position, force)."""
    dropped: int = 0
    """Rows left out for an empty or NaN cell (with ``drop_nan``)."""
    dropped_rows: tuple[str, ...] = field(default=())
    """``file row N (line L)`` of the first few rows left out."""

    @property
    def handle_force(self) -> bool:
        """Whether forces are at the handle of a hinge (no lever arm known)."""
        return self.force_unit == "N at the handle"

    @property
    def bins(self) -> bool:
        """Whether positions were angle bins (read as 1 bin = 1°)."""
        return self.units.get("position") == BIN_UNIT


def _columns_text(raw: RawTable) -> str:
    return ", ".join(f"'{h}'" for h in raw.headers)


def find_column(raw: RawTable, wanted: str | None, role: str, defaults: Sequence[str] = (),
                required: bool = True) -> str | None:
    """The header of ``role``: the one named ``wanted`` (as :mod:`rik.sysid.trials` matches a named column), else
    the first whose name is one of ``defaults``. A named column that is not there, or a required one with no
    default match, raises :class:`TrialError` listing the file's columns."""
    if wanted is not None:
        return match_header(raw, wanted, role)
    for header in raw.headers:
        if parse_header(header)[0] in defaults:
            return header
    if required:
        names = " or ".join(f"'{n}'" for n in defaults)
        raise TrialError(raw.file, None, None, f"no {role} column (looked for {names}); name it with "
                                               f"--{role} COLUMN; the columns are: {_columns_text(raw)}")
    return None


def _unit(raw: RawTable, header: str, given: str | None, role: str, table: dict[str, float],
          other: dict[str, float], joint: JointType) -> tuple[str, float]:
    unit = given if given is not None else parse_header(header)[1]
    choices = ", ".join(table)
    if not unit:
        raise TrialError(raw.file, None, header, f"no unit; pass --{role}-unit or write the header as "
                                                 f"'{header.strip()} [unit]': a {joint.value}'s {role} is in "
                                                 f"{choices}")
    if unit in table:
        return unit, table[unit]
    if unit in other:
        wrong = "hinge" if joint is JointType.slide else "slide"
        raise TrialError(raw.file, None, header, f"'{unit}' is a {wrong}'s {role} unit but the joint is a "
                                                 f"{joint.value} (pass --joint {wrong}?); a {joint.value}'s "
                                                 f"{role} is in {choices}")
    raise TrialError(raw.file, None, header, f"unknown {role} unit '{unit}'; a {joint.value}'s {role} is in "
                                             f"{choices}")


def _force_table(joint: JointType) -> dict[str, float]:
    if joint is JointType.slide:
        return dict(HANDLE_FORCE_UNITS)
    return {**FORCE_UNITS[JointType.hinge], **HANDLE_FORCE_UNITS}


def has_time_column(paths: Sequence[str | Path], time: str | None = None) -> bool:
    """Whether the first of ``paths`` (CSV or Parquet) has a time column (``time`` named, or one named ``time``
    or ``t``): data without one can only be a quasi-static profile."""
    path = Path(paths[0])
    if path.suffix.lower() == ".csv" and path.is_file():
        import csv

        check_size(path)
        try:
            with path.open(encoding="utf-8-sig", newline="") as handle:
                header = next((row for row in csv.reader(handle) if any(c.strip() for c in row)), None)
        except UnicodeDecodeError:
            raise TrialError(path, None, None, NOT_UTF8) from None
        except csv.Error as exc:
            raise TrialError(path, None, None, f"malformed CSV header ({exc})") from None
        if header is None:
            raise TrialError(path, None, None, EMPTY_FILE)
        headers = [c.strip() for c in header]
    else:
        headers = read_table(path).headers
    names = [h.strip().lower() for h in headers] + [parse_header(h)[0] for h in headers]
    if time is not None:
        return time in headers or time.strip().lower() in names
    return any(n in COLUMN_NAMES["time"] for n in names)


def _bad_rows(values: np.ndarray, empty: np.ndarray) -> np.ndarray:
    return ~np.isfinite(values) | empty


def read_profiles(paths: str | Path | Sequence[str | Path], joint: str | JointType, *, position: str | None = None,
                  position_unit: str | None = None, force: str | None = None, force_unit: str | None = None,
                  trial: str | None = None, group: str | None = None, drop_nan: bool = False) -> ProfileData:
    """Read force profiles (module docstring) into SI units. Raises :class:`TrialError` (a :class:`RikError`)
    naming the file, row and column of the first problem."""
    kind = joint_type(joint)
    files = [paths] if isinstance(paths, (str, Path)) else list(paths)
    if not files:
        raise RikError("no profile files given; pass one or more .csv or .parquet files")
    groups: dict[str, dict[str, tuple[list[np.ndarray], list[np.ndarray]]]] = {}
    dropped, dropped_rows = 0, []
    columns: dict[str, str] = {}
    units: dict[str, str] = {}
    force_si = ""
    for path in files:
        raw = read_table(Path(path))
        if raw.rows == 0:
            raise TrialError(raw.file, None, None, "no data rows below the header")
        pos_h = find_column(raw, position, "position", COLUMN_NAMES["position"])
        force_h = find_column(raw, force, "force", COLUMN_NAMES["force"])
        trial_h = find_column(raw, trial, "trial", (TRIAL_COLUMN,), required=False)
        group_h = find_column(raw, group, "group", (), required=False)
        assert pos_h is not None and force_h is not None
        pos_unit, pos_scale = _unit(raw, pos_h, position_unit, "position", PROFILE_POSITION_UNITS[kind],
                                    PROFILE_POSITION_UNITS[_other(kind)], kind)
        f_unit, f_scale = _unit(raw, force_h, force_unit, "force", _force_table(kind), _force_table(_other(kind)),
                                kind)
        si = "N" if kind is JointType.slide else ("N at the handle" if f_unit in HANDLE_FORCE_UNITS else "N·m")
        if force_si and si != force_si:
            raise TrialError(raw.file, None, force_h, f"forces in {si} but an earlier file's are in {force_si}; "
                                                      "give every file the same kind of force")
        force_si = si
        columns = {"position": pos_h, "force": force_h, **({"trial": trial_h} if trial_h else {}),
                   **({"group": group_h} if group_h else {})}
        units = {"position": pos_unit, "force": f_unit}
        pos, frc = raw.numbers(pos_h), raw.numbers(force_h)
        bad = np.zeros(raw.rows, dtype=bool)
        first: tuple[int, str, str] | None = None
        for header, column in ((pos_h, pos), (force_h, frc)):
            rows = _bad_rows(column.values, column.empty)
            if rows.any():
                i = int(np.flatnonzero(rows)[0])
                what = "empty" if column.empty[i] else ("NaN" if np.isnan(column.values[i]) else "infinite")
                if first is None or i < first[0]:
                    first = (i, header, what)
            bad |= rows
        labels = {}
        for role, label_h in (("trial", trial_h), ("group", group_h)):
            if label_h is None:
                continue
            values = np.asarray(raw.labels(label_h), dtype=object)
            rows = np.array([v == "" or v.lower() == "nan" for v in values], dtype=bool)
            if rows.any():
                i = int(np.flatnonzero(rows)[0])
                if first is None or i < first[0]:
                    first = (i, label_h, "empty")
            bad |= rows
            labels[role] = values
        if first is not None:
            if not drop_nan:
                i, header, what = first
                raise TrialError(raw.file, None, header, f"{raw.where(i)} is {what}; every value must be a finite "
                                                         f"number (or pass --drop-nan to leave such rows out, "
                                                         f"counted)")
            dropped += int(bad.sum())
            dropped_rows += [f"{raw.file} {raw.where(int(i))}" for i in np.flatnonzero(bad)]
        keep = ~bad
        stem = Path(raw.file).stem
        group_of = labels["group"] if "group" in labels else np.full(raw.rows, stem, dtype=object)
        trial_of = labels["trial"] if "trial" in labels else group_of
        _check_magnitudes(raw, keep, ((pos_h, "position", pos.values, pos_unit, pos_scale),
                                      (force_h, "force", frc.values, f_unit, f_scale)))
        q = pos.values * pos_scale
        f = frc.values * f_scale
        for i in np.flatnonzero(keep):
            g = groups.setdefault(str(group_of[i]), {})
            qs, fs = g.setdefault(str(trial_of[i]), ([], []))
            qs.append(q[i])
            fs.append(f[i])
    result = []
    for gname, trials in groups.items():
        profiles = []
        for tname, (qs, fs) in trials.items():
            qa, fa = np.asarray(qs, dtype=np.float64), np.asarray(fs, dtype=np.float64)
            _check(files, gname, tname, qa, kind, columns["position"], units["position"])
            profiles.append(Profile(tname, qa, fa))
        result.append(ProfileGroup(gname, tuple(profiles)))
    if not result:
        raise TrialError(files[0], None, None, "no rows left after leaving out those with empty or NaN cells")
    return ProfileData(kind, tuple(result), force_si, columns, units, dropped, tuple(dropped_rows[:5]))


def _check_magnitudes(raw: RawTable, keep: np.ndarray,
                      columns: Sequence[tuple[str, str, np.ndarray, str, float]]) -> None:
    """Refuse the first kept value beyond :data:`MAX_MAGNITUDE` (SI) of each of ``columns`` (header, quantity,
    values as read, their unit, its scale to SI): the fit of such values overflows."""
    for header, role, values, unit, scale in columns:
        i = check_magnitude(np.where(keep, values, 0.0), role, scale)
        if i is not None:
            problem = magnitude_problem(float(values[i]), unit, role, scale)
            raise TrialError(raw.file, None, header, f"{raw.where(i)} {problem}")


def _other(joint: JointType) -> JointType:
    return JointType.hinge if joint is JointType.slide else JointType.slide


def _check(files: Sequence[str | Path], group: str, trial: str, q: np.ndarray, joint: JointType, header: str,
           unit: str) -> None:
    where = f"{files[0]}" if len(files) == 1 else ", ".join(str(f) for f in files)
    within = f" (group '{group}')" if group != trial else ""
    if len(q) < MIN_POINTS:
        raise TrialError(where, trial, header, f"only {len(q)} points{within}; an opening needs at least "
                                               f"{MIN_POINTS}")
    scale = PROFILE_POSITION_UNITS[joint][unit]
    span = float(q.max() - q.min())
    if span < MIN_SPAN[joint]:
        raise TrialError(where, trial, header, f"the position spans {span / scale:.4g} {unit}{within}; an opening "
                                               f"must span at least {MIN_SPAN[joint] / scale:.4g} {unit}")
