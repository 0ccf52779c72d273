"""Measured trials in: CSV or Parquet files, or a LeRobot dataset, read into SI numpy arrays and checked.

Files (:func:`load_trials`; LeRobot datasets: :func:`load_lerobot_trials`)
--------------------------------------------------------------------------
``.csv`` (comma-separated, UTF-8, first line the header) or ``.parquet``/``.pq``. One row per sample; a file may
hold several trials told apart by a ``trial`` column (its rows need not be contiguous; trials keep the order of
their first row), and several files may be read at once. A column header is a name, then the unit in square
brackets: ``time [ms]``, ``position [mm]``, ``force [N]``. Names are case-insensitive, units are not:

=========  =======================  ======================================  ===========================
quantity   column names             slide units                             hinge units
=========  =======================  ======================================  ===========================
time       ``time``, ``t``          ``s``, ``ms``                           ``s``, ``ms``
position   ``position``, ``q``      ``m``, ``mm``, ``cm``                   ``rad``, ``deg``
force      ``force``, ``torque``,   ``N``, ``kN``                           ``N·m``, ``Nm``, ``N*m``,
           ``f``                                                            ``N·mm``, ``Nmm``, ``N*mm``
velocity   ``velocity``, ``qd``     ``m/s``, ``mm/s``, ``cm/s`` (optional)  ``rad/s``, ``deg/s`` (optional)
trial      ``trial``                none (optional; any values)             none
=========  =======================  ======================================  ===========================

Position is the joint coordinate (0 closed, positive opening, as in :class:`rik.schemas.joints.JointSpec`); force
is the applied force (slide) or torque (hinge) along it. Other columns are ignored. A trial without a ``trial``
column is named after its file's stem.

Other headers (a logger's ``timestamp_ms``, ``enc_pos``, ``ft_fx``; plain ``t,q,f``) are read through a
:class:`ColumnMap` (the ``rik sysid fit`` options ``--time``, ``--position``, ``--force``, ``--velocity``,
``--trial`` and ``--time-unit``, ``--position-unit``, ``--force-unit``, ``--velocity-unit``): it names the column
of a quantity (its header then may say anything) and declares the unit of a column whose header has none, from
the table above. A unit is needed for every column read; a header's own valid unit must agree with a declared one.
A named column not in a file is refused with the file's columns listed (and the closest, if one is close).

Messages name rows as the 0-based index among the file's data rows (what pandas or pyarrow show); CSV rows add
their line number in the file (the header is line 1).

Checks
------
Every value finite (no NaN, inf, empty cell); time strictly increasing within a trial; at least ``min_samples``
samples (default :data:`MIN_SAMPLES`); the position spanning at least ``min_motion`` (default
:data:`MIN_MOTION`: 1 mm or 0.5°); the force spanning at least ``min_force_range`` (default
:data:`MIN_FORCE_RANGE`: 0.01 N or 0.001 N·m). A failure raises :class:`TrialError`: one line naming the file,
trial and column at fault and what would be valid.
"""

from __future__ import annotations

import csv
import difflib
import json
import math
import re
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal, cast

import numpy as np

from rik.errors import RikError
from rik.schemas.joints import JointType
from rik.schemas.trajectory import TrialColumns, TrialMeta, TrialUnits

if TYPE_CHECKING:
    import pyarrow as pa

    from rik.paths import MadeFolder

MIN_SAMPLES = 50
"""Fewest samples a trial may have: below this no derivative or fit is meaningful."""
MIN_MOTION = {JointType.slide: 1e-3, JointType.hinge: math.radians(0.5)}
"""Smallest position range (max − min) of a trial, m (slide: 1 mm) or rad (hinge: 0.5°)."""
MIN_FORCE_RANGE = {JointType.slide: 0.01, JointType.hinge: 0.001}
"""Smallest force range (max − min) of a trial, N (slide) or N·m (hinge): below it the force is constant."""
MAX_SAMPLE_INTERVAL = 1.0
"""Largest median interval between a trial's samples, s: data sampled slower than 1 Hz cannot show a joint's
dynamics (the smoothing window is 0.1 s), and such intervals are what milliseconds (of a logger at 500 Hz or
slower), µs or ns read as s look like."""
MAX_FILE_BYTES = 256 * 2**20
"""Largest CSV file read, bytes (256 MiB, about 4 million rows of three numbers; parsing takes a few times that
in memory)."""
MAX_ROWS = 5_000_000
"""Most data rows read from one file (CSV or Parquet): about 83 minutes at 1 kHz."""
NOT_UTF8 = "not a UTF-8 text file; expected CSV with a header line"
EMPTY_FILE = "empty file; the first line must be a header such as 'time [s],position [m],force [N]'"

ROLES = ("time", "position", "force", "velocity")
COLUMN_NAMES = {"time": ("time", "t"), "position": ("position", "q"), "force": ("force", "torque", "f"),
                "velocity": ("velocity", "qd")}
"""Accepted column names of each quantity (case-insensitive)."""
TRIAL_COLUMN = "trial"
SUFFIXES = {".csv": "csv", ".parquet": "parquet", ".pq": "parquet"}

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


class TrialError(RikError):
    """Measured data is unreadable or unusable. The message names the file, the trial and the column at
    fault (those known) and what would be valid."""

    def __init__(self, file: str | Path, trial: str | None, column: str | None, problem: str):
        self.file, self.trial, self.column, self.problem = str(file), trial, column, problem
        parts = [str(file)]
        if trial is not None:
            parts.append(f"trial '{trial}'")
        if column is not None:
            parts.append(f"column '{column}'")
        super().__init__(", ".join(parts) + f": {problem}")


@dataclass(frozen=True, eq=False)
class Trial:
    """One measured trial in SI units of its joint type; arrays are read-only and of equal length."""

    meta: TrialMeta
    t: np.ndarray
    """Time, s, strictly increasing (not necessarily uniform; not shifted to start at 0)."""
    q: np.ndarray
    """Joint position, m (slide) or rad (hinge); 0 closed, positive opening."""
    f: np.ndarray
    """Applied force, N (slide), or torque, N·m (hinge), along the joint."""
    qd: np.ndarray | None = None
    """Measured velocity, m/s or rad/s, if the data had one."""

    def __post_init__(self) -> None:
        for name in ("t", "q", "f", "qd"):
            value = getattr(self, name)
            if value is None:
                continue
            array = np.array(value, dtype=np.float64)
            if array.shape != (self.meta.samples,):
                raise ValueError(f"Trial.{name} has shape {array.shape}, expected ({self.meta.samples},)")
            array.flags.writeable = False
            object.__setattr__(self, name, array)

    @property
    def name(self) -> str:
        return self.meta.name

    @property
    def source(self) -> str:
        return self.meta.source

    @property
    def joint(self) -> JointType:
        return self.meta.joint

    @property
    def samples(self) -> int:
        return self.meta.samples


@dataclass(frozen=True)
class ColumnMap:
    """Which column holds which quantity, and in which unit: how to read data whose headers do not follow the
    ``name [unit]`` convention (a logger's ``timestamp_ms``, ``enc_pos``, ``ft_fx``), and a LeRobot dataset's
    features. The default (all None) reads headers with units as described in the module docstring.

    ``time``, ``position``, ``force``, ``velocity`` name a column (files: a header, matched exactly, else
    case-insensitively on its name without the ``[unit]``; LeRobot: a feature reference such as
    ``observation.state[2]``); a quantity left None is found by its usual names (:data:`COLUMN_NAMES`). A named
    column's header may carry any text. ``trial`` names the column that tells trials apart in a file (default: a
    ``trial`` column, if any; a LeRobot dataset's trials are its episodes).

    ``time_unit``, ``position_unit``, ``force_unit``, ``velocity_unit`` declare the unit of that quantity's
    column, named or found, from the unit tables of the module docstring (``force_unit`` is a torque unit for a
    hinge). A header without a unit needs one; a header whose brackets hold a valid unit must agree with it.
    Messages name the ``rik sysid fit`` options (``--position``, ``--position-unit``), which map one to one onto
    these fields."""

    time: str | None = None
    position: str | None = None
    force: str | None = None
    velocity: str | None = None
    trial: str | None = None
    time_unit: str | None = None
    """``s`` or ``ms``."""
    position_unit: str | None = None
    """m, mm, cm (slide) or rad, deg (hinge)."""
    force_unit: str | None = None
    """N, kN (slide) or N·m, N·mm and their spellings (hinge)."""
    velocity_unit: str | None = None
    """The position unit per second: ``mm/s``, ``deg/s``."""

    def __post_init__(self) -> None:
        named: dict[str, str] = {}
        for role in (*ROLES, "trial"):
            column = getattr(self, role)
            if column is None:
                continue
            if column in named:
                raise RikError(f"--{named[column]} and --{role} both name column '{column}'; each quantity "
                               "needs its own column")
            named[column] = role

    def column(self, role: str) -> str | None:
        """The column named for quantity ``role`` (``time``, ``position``, ``force``, ``velocity``), or None."""
        return cast("str | None", getattr(self, role))

    def unit(self, role: str) -> str | None:
        """The unit declared for quantity ``role``, or None."""
        return cast("str | None", getattr(self, f"{role}_unit"))


# ---------------------------------------------------------------------------------------------------- units

def _choices(units: Iterable[str]) -> str:
    names = list(units)
    return names[0] if len(names) == 1 else ", ".join(names[:-1]) + f" or {names[-1]}"


def _table(role: str) -> dict[JointType, dict[str, float]]:
    return {"position": POSITION_UNITS, "force": FORCE_UNITS, "velocity": VELOCITY_UNITS}[role]


def _accepted(role: str, joint: JointType) -> str:
    """What the units of ``role`` may be, as a phrase: "a slide's position is in m, mm or cm"."""
    if role == "time":
        return f"time is in {_choices(TIME_UNITS)}"
    word = "torque" if role == "force" and joint is JointType.hinge else role
    return f"a {joint.value}'s {word} is in {_choices(_table(role)[joint])}"


def unit_option(role: str) -> str:
    """The ``rik sysid fit`` option that declares the unit of quantity ``role`` (``--position-unit``): what
    messages tell the user to add (the :class:`ColumnMap` field is ``position_unit``)."""
    return f"--{role}-unit"


def unit_scale(role: str, unit: str | None, joint: JointType, header: str) -> float:
    """Factor from ``unit`` to SI for quantity ``role`` of a ``joint``; raises ValueError with the problem (the
    caller adds file and column) for a missing, unknown or mismatched unit."""
    if not unit:
        example = next(iter(TIME_UNITS if role == "time" else _table(role)[joint]))
        name = header.strip() or role
        raise ValueError(f"no unit; write the header as '{name} [unit]' (e.g. '{name} [{example}]') or pass "
                         f"{unit_option(role)}: {_accepted(role, joint)}")
    if role == "time":
        if unit in TIME_UNITS:
            return TIME_UNITS[unit]
        raise ValueError(f"unknown unit '{unit}'; {_accepted(role, joint)}")
    table = _table(role)
    if unit in table[joint]:
        return table[joint][unit]
    for other in JointType:
        if other is not joint and unit in table[other]:
            raise ValueError(f"'{unit}' is {_KIND[role, other]} but the joint is a {joint.value}; "
                             f"{_accepted(role, joint)}")
    raise ValueError(f"unknown unit '{unit}'; {_accepted(role, joint)}")


def joint_type(joint: str | JointType) -> JointType:
    """``slide`` or ``hinge`` as a :class:`JointType`; anything else is a :class:`RikError`."""
    try:
        return JointType(joint)
    except ValueError:
        raise RikError(f"unknown joint type '{joint}'; use 'slide' or 'hinge'") from None


# ------------------------------------------------------------------------------------------- raw file tables

@dataclass
class _Column:
    """One column's values in the declared unit, with the cells that were empty (CSV) or null (Parquet)."""

    values: np.ndarray
    empty: np.ndarray


@dataclass
class RawTable:
    """A file's table before any check: headers, a reader of numeric columns, and row labels for messages."""

    file: str
    headers: list[str]
    numbers: Callable[[str], _Column]
    labels: Callable[[str], list[str]]
    lines: np.ndarray | None
    """CSV: the file line of each data row; Parquet: None."""
    rows: int

    def where(self, row: int) -> str:
        return f"row {row} (line {self.lines[row]})" if self.lines is not None else f"row {row}"


def _first_line(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return text[0] if text else type(exc).__name__


def _too_many_rows(rows: int) -> str:
    return f"more than {MAX_ROWS:,} data rows ({rows:,}); split the file (by trial) or downsample it"


def check_size(path: Path) -> None:
    """Refuse a CSV file larger than :data:`MAX_FILE_BYTES` before reading it."""
    size = path.stat().st_size
    if size > MAX_FILE_BYTES:
        raise TrialError(path, None, None, f"{size / 2**20:,.0f} MiB, more than rik reads from one CSV file "
                                           f"({MAX_FILE_BYTES // 2**20} MiB); split it (by trial) or downsample it")


def _read_csv(path: Path) -> RawTable:
    file = str(path)
    check_size(path)
    try:
        text = path.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError:
        raise TrialError(file, None, None, NOT_UTF8) from None
    reader = csv.reader(text.splitlines())
    header: list[str] | None = None
    cells: list[list[str]] = []
    lines: list[int] = []
    try:
        for row in reader:
            if not row or all(not c.strip() for c in row):
                continue
            if header is None:
                header = [c.strip() for c in row]
                continue
            if len(row) != len(header):
                raise TrialError(file, None, None, f"malformed CSV: line {reader.line_num} has {len(row)} fields "
                                                   f"but the header has {len(header)}")
            cells.append(row)
            lines.append(reader.line_num)
            if len(cells) > MAX_ROWS:
                raise TrialError(file, None, None, _too_many_rows(len(cells)))
    except csv.Error as exc:
        raise TrialError(file, None, None, f"malformed CSV at line {reader.line_num}: {exc}") from None
    if header is None:
        raise TrialError(file, None, None, EMPTY_FILE)
    index = {h: i for i, h in enumerate(header)}
    line_array = np.asarray(lines, dtype=np.int64)

    def strings(h: str) -> list[str]:
        return [row[index[h]].strip() for row in cells]

    def numbers(h: str) -> _Column:
        text_values = strings(h)
        empty = np.array([s == "" for s in text_values], dtype=bool)
        try:
            values = np.array(["nan" if e else s for s, e in zip(text_values, empty, strict=True)], dtype=np.float64)
        except ValueError:
            row = next(i for i, s in enumerate(text_values) if s and not _is_float(s))
            raise TrialError(file, None, h, f"malformed CSV: row {row} (line {lines[row]}) holds "
                                            f"'{text_values[row]}', not a number") from None
        return _Column(values.reshape(len(cells)), empty)

    return RawTable(file, header, numbers, strings, line_array, len(cells))


def _is_float(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _read_parquet(path: Path) -> RawTable:
    import pyarrow as pa
    import pyarrow.parquet as pq

    file = str(path)
    try:
        rows = pq.ParquetFile(path).metadata.num_rows
        if rows > MAX_ROWS:
            raise TrialError(file, None, None, _too_many_rows(rows))
        table = pq.read_table(path)
    except (pa.ArrowException, OSError) as exc:
        raise TrialError(file, None, None, f"not a readable Parquet file ({_first_line(exc)})") from None

    def numbers(h: str) -> _Column:
        column = table.column(h)
        kind = column.type
        if not (pa.types.is_integer(kind) or pa.types.is_floating(kind) or pa.types.is_decimal(kind)):
            raise TrialError(file, None, h, f"holds {kind} values, not numbers")
        empty = column.is_null().to_numpy(zero_copy_only=False).astype(bool)
        values = column.cast(pa.float64()).to_numpy(zero_copy_only=False).astype(np.float64)
        return _Column(values, empty)

    def labels(h: str) -> list[str]:
        return ["" if v is None else str(v) for v in table.column(h).to_pylist()]

    return RawTable(file, list(table.column_names), numbers, labels, None, table.num_rows)


def read_table(path: Path) -> RawTable:
    kind = SUFFIXES.get(path.suffix.lower())
    if kind is None:
        raise TrialError(path, None, None, f"unknown file type '{path.suffix}'; use .csv, .parquet or .pq")
    if not path.is_file():
        raise TrialError(path, None, None, "no such file")
    return _read_csv(path) if kind == "csv" else _read_parquet(path)


# ------------------------------------------------------------------------------------------ column matching

def parse_header(header: str) -> tuple[str, str | None]:
    """(lower-case name, unit or None) of a header such as ``Position [mm]``."""
    match = _HEADER.match(header)
    if match is None:
        return header.strip().lower(), None
    unit = match["unit"]
    return match["name"].lower(), (unit.strip() if unit is not None else None)


def match_header(raw: RawTable, wanted: str, role: str) -> str:
    """The header of ``raw`` named by the user for ``role``: equal to ``wanted``, else the one whose name
    (without ``[unit]``) or whole text equals it case-insensitively."""
    if wanted in raw.headers:
        return wanted
    key = wanted.strip().lower()
    hits = [h for h in raw.headers if h.strip().lower() == key or parse_header(h)[0] == key]
    if len(hits) == 1:
        return hits[0]
    if len(hits) > 1:
        listed = " and ".join(f"'{h}'" for h in hits)
        raise TrialError(raw.file, None, wanted, f"--{role} matches {listed}; name one exactly")
    close = difflib.get_close_matches(wanted, raw.headers, n=2, cutoff=0.6)
    hint = f"; did you mean {' or '.join(repr(c) for c in close)}?" if close else ""
    columns = ", ".join(f"'{h}'" for h in raw.headers)
    raise TrialError(raw.file, None, wanted, f"no such column (--{role}){hint} (columns: {columns})")


def _column_unit(raw: RawTable, role: str, header: str, joint: JointType, columns: ColumnMap) -> tuple[str, float]:
    """(unit, SI factor) of the column ``header`` holding ``role``: the declared unit option, else the header's."""
    name, declared = parse_header(header)
    option = columns.unit(role)
    if not option:
        if declared is None and columns.column(role) is not None:
            raise TrialError(raw.file, None, header, f"no unit in the header; pass {unit_option(role)}: "
                                                     f"{_accepted(role, joint)}")
        try:
            return declared or "", unit_scale(role, declared, joint, name)
        except ValueError as exc:
            raise TrialError(raw.file, None, header, str(exc)) from None
    try:
        scale = unit_scale(role, option, joint, name)
    except ValueError as exc:
        raise TrialError(raw.file, None, header, f"{unit_option(role)}: {exc}") from None
    if declared:
        try:
            if unit_scale(role, declared, joint, name) == scale:
                return option, scale
        except ValueError:
            return option, scale  # the brackets hold no unit of this quantity: the option declares it
        raise TrialError(raw.file, None, header, f"the header says '{declared}' but {unit_option(role)} says "
                                                 f"'{option}'; drop the option or make them agree")
    return option, scale


def _find_columns(raw: RawTable, joint: JointType, columns: ColumnMap
                  ) -> tuple[dict[str, str], dict[str, str], dict[str, float], str | None]:
    """Headers, declared units and SI factors of each quantity, and the trial column's header (or None): the
    columns ``columns`` names, the others found by their usual names."""
    found = {role: match_header(raw, columns.column(role) or "", role) for role in ROLES
             if columns.column(role) is not None}
    trial = None if columns.trial is None else match_header(raw, columns.trial, "trial")
    taken = set(found.values()) | {trial}
    for header in raw.headers:
        if header in taken:
            continue
        name, _ = parse_header(header)
        if name == TRIAL_COLUMN:
            if columns.trial is None:
                trial = header
            continue
        for role, aliases in COLUMN_NAMES.items():
            if name in aliases and columns.column(role) is None:
                if role in found:
                    raise TrialError(raw.file, None, header, f"a second {role} column (besides "
                                                             f"'{found[role]}'); keep one or name one with --{role}")
                found[role] = header
    for role in ("time", "position", "force"):
        if role not in found:
            names = " or ".join(n for n in COLUMN_NAMES[role] if not (role == "force" and n == _other_word(joint)))
            listed = ", ".join(f"'{h}'" for h in raw.headers)
            word = "torque" if role == "force" and joint is JointType.hinge else role
            unit = next(iter(TIME_UNITS if role == "time" else _table(role)[joint]))
            raise TrialError(raw.file, None, word, f"missing; the file needs a {word} column named {names} with "
                                                   f"its unit, e.g. '{word} [{unit}]', or name it with --{role} "
                                                   f"(columns: {listed})")
    if columns.velocity_unit is not None and "velocity" not in found:
        raise TrialError(raw.file, None, None, f"{unit_option('velocity')} is given but the file has no velocity "
                                               "column; name it with --velocity")
    units: dict[str, str] = {}
    scales: dict[str, float] = {}
    for role, header in found.items():
        units[role], scales[role] = _column_unit(raw, role, header, joint, columns)
    return found, units, scales, trial


def _other_word(joint: JointType) -> str:
    """The force column name that does not fit the joint (``torque`` for a slide, ``force`` for a hinge): still
    accepted, but not suggested."""
    return "torque" if joint is JointType.slide else "force"


# ---------------------------------------------------------------------------------------------- trial checks

@dataclass(frozen=True)
class _Thresholds:
    min_samples: int
    min_motion: float
    """m or rad"""
    min_force_range: float
    """N or N·m"""


def _thresholds(joint: JointType, min_samples: int, min_motion: float | None,
                min_force_range: float | None) -> _Thresholds:
    return _Thresholds(min_samples, MIN_MOTION[joint] if min_motion is None else min_motion,
                       MIN_FORCE_RANGE[joint] if min_force_range is None else min_force_range)


def _num(x: float) -> str:
    return f"{x:.6g}"


@dataclass
class _Source:
    """A trial's data as read (declared units) with everything a message needs."""

    file: str
    name: str
    joint: JointType
    columns: dict[str, str]
    units: dict[str, str]
    scales: dict[str, float]
    values: dict[str, np.ndarray]
    empty: dict[str, np.ndarray]
    where: Callable[[int], str]
    """Sample index in the trial → its row label in the file."""

    def error(self, role: str | None, problem: str) -> TrialError:
        return TrialError(self.file, self.name, self.columns[role] if role else None, problem)


def _check_finite(src: _Source) -> None:
    first: tuple[int, int, str] | None = None
    for order, role in enumerate(ROLES):
        if role not in src.values:
            continue
        bad = np.flatnonzero(~np.isfinite(src.values[role]) | src.empty[role])
        if bad.size and (first is None or (bad[0], order) < first[:2]):
            first = (int(bad[0]), order, role)
    if first is None:
        return
    i, _, role = first
    value = src.values[role][i]
    what = "empty" if src.empty[role][i] else ("NaN" if np.isnan(value) else ("inf" if value > 0 else "-inf"))
    raise src.error(role, f"{src.where(i)} is {what}; every value must be a finite number")


def _check_time(src: _Source) -> None:
    t = src.values["time"]
    steps = np.diff(t)
    bad = np.flatnonzero(steps <= 0)
    if not bad.size:
        return
    i = int(bad[0]) + 1
    unit = src.units["time"]
    if t[i] == t[i - 1]:
        problem = f"time repeats at {src.where(i)}: {_num(t[i])} {unit} twice"
    else:
        problem = f"time goes back at {src.where(i)}: {_num(t[i])} {unit} after {_num(t[i - 1])} {unit}"
    raise src.error("time", problem + "; time must increase strictly within a trial")


def _check_time_unit(src: _Source) -> None:
    """Refuse a time axis whose samples are :data:`MAX_SAMPLE_INTERVAL` or more apart (median): most likely time
    in another unit than the one read (ms as s, µs, ns); named with the unit that would give a usual rate."""
    t = src.values["time"]
    if len(t) < 2 or (interval := float(np.median(np.diff(t))) * src.scales["time"]) <= MAX_SAMPLE_INTERVAL:
        return
    unit = src.units["time"]
    likely = next((name for name, scale in (("ms", 1e-3), ("µs", 1e-6), ("ns", 1e-9))
                   if 1e-5 <= interval * scale <= 0.1), None)
    if likely == "ms" and unit != "ms":
        advice = "if it is in ms, write the header as 'time [ms]' or pass --time-unit ms"
    elif likely is not None:
        advice = f"if it is in {likely}, convert it to s or ms (rik reads time in {_choices(TIME_UNITS)})"
    else:
        advice = "give the time in s or ms"
    raise src.error("time", f"samples are {_num(interval)} s apart (median of the time read in {unit}), slower "
                            f"than 1 Hz: is the time in another unit? {advice}")


def _check_range(src: _Source, role: str, minimum_si: float) -> None:
    values = src.values[role]
    lo, hi = float(values.min()), float(values.max())
    unit = src.units[role]
    minimum = minimum_si / src.scales[role]
    if (hi - lo) * src.scales[role] >= minimum_si:
        return
    if role == "position":
        raise src.error(role, f"no motion: the position spans {_num(hi - lo)} {unit} (from {_num(lo)} to "
                              f"{_num(hi)} {unit}); a trial must move at least {_num(minimum)} {unit}")
    word = "torque" if src.joint is JointType.hinge else "force"
    raise src.error(role, f"constant {word}: it spans {_num(hi - lo)} {unit} (from {_num(lo)} to {_num(hi)} "
                          f"{unit}); a trial's {word} must vary by at least {_num(minimum)} {unit}")


def _build(src: _Source, limits: _Thresholds) -> Trial:
    """Check a trial's data (in the order of the module docstring) and convert it to SI."""
    _check_finite(src)
    _check_time(src)
    _check_time_unit(src)
    n = len(src.values["time"])
    if n < limits.min_samples:
        raise src.error(None, f"only {n} samples; a trial needs at least {limits.min_samples}")
    _check_range(src, "position", limits.min_motion)
    _check_range(src, "force", limits.min_force_range)
    si = {role: src.values[role] * src.scales[role] for role in src.values}
    meta = TrialMeta(
        name=src.name, source=src.file, joint=src.joint, samples=n, duration=float(si["time"][-1] - si["time"][0]),
        units=TrialUnits(**{role: src.units[role] for role in src.values}),
        columns=TrialColumns(**{role: src.columns[role] for role in src.values}))
    return Trial(meta, si["time"], si["position"], si["force"], si.get("velocity"))


# ------------------------------------------------------------------------------------------------ files in

def _rows_where(where: Callable[[int], str], rows: np.ndarray) -> Callable[[int], str]:
    """Sample index in a trial → its row's label, from the file's rows the trial takes and ``where`` (file row
    index → label)."""
    return lambda i: where(int(rows[i]))


def _file_trials(raw: RawTable, joint: JointType, limits: _Thresholds, column_map: ColumnMap) -> list[Trial]:
    columns, units, scales, trial_header = _find_columns(raw, joint, column_map)
    data = {role: raw.numbers(header) for role, header in columns.items()}
    if raw.rows == 0:
        raise TrialError(raw.file, None, None, "no data rows below the header")
    groups: list[tuple[str, np.ndarray]]
    if trial_header is None:
        groups = [(Path(raw.file).stem, np.arange(raw.rows))]
    else:
        names = np.asarray(raw.labels(trial_header), dtype=object)
        missing = np.flatnonzero(names == "")
        if missing.size:
            raise TrialError(raw.file, None, trial_header, f"{raw.where(int(missing[0]))} is empty; every row "
                                                           "needs a trial name")
        _, first = np.unique(names.astype(str), return_index=True)
        groups = [(str(names[i]), np.flatnonzero(names == names[i])) for i in sorted(first)]
    trials = []
    for name, rows in groups:
        src = _Source(raw.file, name, joint, columns, units, scales,
                      {role: col.values[rows] for role, col in data.items()},
                      {role: col.empty[rows] for role, col in data.items()},
                      _rows_where(raw.where, rows))
        trials.append(_build(src, limits))
    return trials


def load_trials(paths: str | Path | Sequence[str | Path], joint: Literal["slide", "hinge"] | JointType, *,
                columns: ColumnMap | None = None, min_samples: int = MIN_SAMPLES, min_motion: float | None = None,
                min_force_range: float | None = None) -> list[Trial]:
    """Every trial in the CSV or Parquet ``paths`` (see the module docstring for the format), in SI units.

    ``columns`` names columns and declares units the headers do not (:class:`ColumnMap`; the same for every file).
    ``min_motion`` (m or rad) and ``min_force_range`` (N or N·m) default to :data:`MIN_MOTION` and
    :data:`MIN_FORCE_RANGE` of the joint type. Raises :class:`TrialError` (a :class:`RikError`) naming the file,
    trial and column of the first problem."""
    kind = joint_type(joint)
    limits = _thresholds(kind, min_samples, min_motion, min_force_range)
    files = [paths] if isinstance(paths, (str, Path)) else list(paths)
    if not files:
        raise RikError("no trial files given; pass one or more .csv or .parquet files")
    trials: list[Trial] = []
    for path in files:
        trials += _file_trials(read_table(Path(path)), kind, limits, columns or ColumnMap())
    return trials


# --------------------------------------------------------------------------------------------- LeRobot in

@dataclass(frozen=True)
class _FeatureRef:
    """A number inside a LeRobot feature: the column ``key`` and the flat ``index`` within its value."""

    text: str
    key: str
    index: int
    size: int


_REF = re.compile(r"^\s*(?P<key>[^\[\]]+?)\s*(?:\[\s*(?P<sel>[^\[\]]+?)\s*\])?\s*$")


def _feature_names(feature: dict[str, Any], size: int) -> list[str]:
    names = feature.get("names")
    if isinstance(names, dict):
        names = next((v for v in names.values() if isinstance(v, list) and len(v) == size), None)
    if isinstance(names, list) and len(names) == size and all(isinstance(n, str) for n in names):
        return names
    return []


def _feature_ref(text: str, features: dict[str, Any], info_file: str) -> _FeatureRef:
    """Parse ``key``, ``key[3]`` or ``key[name]`` against the dataset's features."""
    match = _REF.match(text)
    key = match["key"] if match else text
    if key not in features:
        close = difflib.get_close_matches(key, list(features), n=2, cutoff=0.6)
        hint = f"; did you mean {' or '.join(repr(c) for c in close)}?" if close else ""
        raise TrialError(info_file, None, text, f"no feature '{key}' in the dataset{hint}")
    feature = features[key]
    shape = feature.get("shape") if isinstance(feature, dict) else None
    if not isinstance(feature, dict) or not (shape is None or isinstance(shape, list) and all(
            isinstance(n, int) and not isinstance(n, bool) and 0 < n <= MAX_ROWS for n in shape)):
        raise TrialError(info_file, None, text, f"feature '{key}' is malformed: it needs a 'shape', a list of "
                                                "positive whole numbers")
    size = int(np.prod(shape or [1]))
    sel = match["sel"] if match else None
    if sel is None:
        if size != 1:
            raise TrialError(info_file, None, text, f"'{key}' holds {size} values; name one as '{key}[index]' "
                                                    f"or '{key}[name]'")
        return _FeatureRef(text, key, 0, 1)
    names = _feature_names(feature, size)
    if sel.lstrip("-").isdigit():
        index = int(sel)
        if not 0 <= index < size:
            raise TrialError(info_file, None, text, f"index {index} is out of range; '{key}' holds {size} values "
                                                    f"(0 to {size - 1})")
        return _FeatureRef(text, key, index, size)
    if sel in names:
        return _FeatureRef(text, key, names.index(sel), size)
    listed = ", ".join(names) if names else "none; use an index"
    raise TrialError(info_file, None, text, f"'{key}' has no value named '{sel}' (names: {listed})")


def _read_info(root: Path) -> tuple[str, dict[str, Any]]:
    info_file = root / "meta" / "info.json"
    if not info_file.is_file():
        raise TrialError(root, None, None, "not a LeRobot dataset (no meta/info.json)")
    from rik.paths import read_json

    try:
        info = read_json(info_file)
    except ValueError as exc:  # not JSON, not UTF-8, too large or nested too deeply
        raise TrialError(info_file, None, None, f"not valid JSON ({_first_line(exc)})") from None
    if not isinstance(info, dict) or not isinstance(info.get("features"), dict) or not info.get("fps"):
        raise TrialError(info_file, None, None, "malformed LeRobot info: needs 'fps' and 'features'")
    fps = info["fps"]
    if isinstance(fps, bool) or not isinstance(fps, (int, float)) or not math.isfinite(fps) or fps <= 0:
        raise TrialError(info_file, None, None, f"field 'fps' must be a positive number of frames per second, "
                                                f"got {fps!r}")
    return str(info_file), info


def _is_number(kind: pa.DataType) -> bool:
    import pyarrow as pa

    return pa.types.is_integer(kind) or pa.types.is_floating(kind) or pa.types.is_decimal(kind)


def _ref_values(table: pa.Table, ref: _FeatureRef, file: str) -> tuple[np.ndarray, np.ndarray]:
    """(values, null mask) of one referenced number, per row of a data file's table."""
    import pyarrow as pa

    if ref.key not in table.column_names:
        raise TrialError(file, None, ref.text, f"no column '{ref.key}' in the data file")
    column = table.column(ref.key).combine_chunks()
    rows = len(column)
    listed = pa.types.is_list(column.type) or pa.types.is_fixed_size_list(column.type) \
        or pa.types.is_large_list(column.type)
    if not _is_number(column.type.value_type if listed else column.type):
        raise TrialError(file, None, ref.text, f"column '{ref.key}' holds {column.type} values, not numbers")
    if listed:
        null = column.is_null().to_numpy(zero_copy_only=False).astype(bool)
        flat = cast("pa.ListArray", column).flatten().cast(pa.float64()).to_numpy(zero_copy_only=False)
        if null.any() or flat.size != rows * ref.size:
            raise TrialError(file, None, ref.text, f"rows do not all hold {ref.size} values as info.json says")
        return flat.reshape(rows, ref.size)[:, ref.index].astype(np.float64), np.zeros(rows, dtype=bool)
    null = column.is_null().to_numpy(zero_copy_only=False).astype(bool)
    return column.cast(pa.float64()).to_numpy(zero_copy_only=False).astype(np.float64), null


def _lerobot_file(path: Path, refs: dict[str, _FeatureRef], fps: float) -> tuple[dict[str, Any], np.ndarray]:
    """The referenced columns of one data file (plus time, unless referenced) and its episode index per row."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    file = str(path)
    try:
        parquet = pq.ParquetFile(path)
        names = set(parquet.schema_arrow.names)
        if parquet.metadata.num_rows > MAX_ROWS:
            raise TrialError(file, None, None, _too_many_rows(parquet.metadata.num_rows))
        wanted = [c for c in dict.fromkeys(["episode_index", "timestamp", "frame_index",
                                            *(r.key for r in refs.values())]) if c in names]
        table = pq.read_table(path, columns=wanted)  # only these: a dataset's frames may hold images
    except (pa.ArrowException, OSError) as exc:
        raise TrialError(file, None, None, f"not a readable Parquet file ({_first_line(exc)})") from None
    if "episode_index" not in table.column_names:
        raise TrialError(file, None, "episode_index", "missing; a LeRobot data file has one per row")
    index = table.column("episode_index")
    if not pa.types.is_integer(index.type) or index.null_count:
        raise TrialError(file, None, "episode_index", f"must be whole numbers in every row, got {index.type}"
                                                      + (f" with {index.null_count} empty" if index.null_count else ""))
    episodes = index.to_numpy().astype(np.int64)
    columns = {role: _ref_values(table, ref, file) for role, ref in refs.items()}
    if "time" in refs:
        return columns, episodes
    if "timestamp" in table.column_names:
        columns["time"] = _ref_values(table, _FeatureRef("timestamp", "timestamp", 0, 1), file)
    elif "frame_index" in table.column_names:
        frames, null = _ref_values(table, _FeatureRef("frame_index", "frame_index", 0, 1), file)
        columns["time"] = (frames / fps, null)
    else:
        raise TrialError(file, None, "timestamp", "missing (and no frame_index); LeRobot data files have both")
    return columns, episodes


def load_lerobot_trials(root: str | Path, joint: Literal["slide", "hinge"] | JointType, columns: ColumnMap, *,
                        episodes: Iterable[int] | None = None, min_samples: int = MIN_SAMPLES,
                        min_motion: float | None = None, min_force_range: float | None = None) -> list[Trial]:
    """One trial per episode of the LeRobot v3.0 dataset in folder ``root`` (the folder holding ``meta/`` and
    ``data/``), read with pyarrow from ``data/**/*.parquet`` (lerobot itself is not imported).

    ``columns`` (:class:`ColumnMap`) must name ``position`` and ``force``, and may name ``velocity`` and
    ``time``: each a number in the dataset: a scalar feature (``key``), or one value of a vector feature by index
    (``observation.state[3]``) or by its name in the feature's ``names`` (``observation.state[front_qpos]``).
    LeRobot records no units, so each named quantity needs its unit declared (the units of the file table in the
    module docstring). Time is the ``timestamp`` column, s (else ``frame_index / fps``), unless ``time`` names
    another feature; ``time_unit`` alone declares the ``timestamp`` column's unit. Trials are named
    ``episode_<index>``, in index order (``trial`` is refused: the episodes are the trials); ``episodes`` keeps
    only those indices. Checks and thresholds are those of :func:`load_trials`."""
    kind = joint_type(joint)
    limits = _thresholds(kind, min_samples, min_motion, min_force_range)
    root = Path(root)
    if columns.position is None or columns.force is None:
        raise TrialError(root, None, None, "a LeRobot dataset needs --position and --force naming its features")
    if columns.trial is not None:
        raise TrialError(root, None, columns.trial, "a LeRobot dataset's trials are its episodes (episode_index); "
                                                    "--trial is for CSV and Parquet files")
    if columns.velocity_unit is not None and columns.velocity is None:
        raise TrialError(root, None, None, f"{unit_option('velocity')} is given but no --velocity feature")
    info_file, info = _read_info(root)
    time = columns.time if columns.time is not None else ("timestamp" if columns.time_unit else None)
    declared: dict[str, tuple[str, str | None]] = {
        role: (text, columns.unit(role)) for role, text in
        (("time", time), ("position", columns.position), ("force", columns.force), ("velocity", columns.velocity))
        if text is not None}
    refs = {role: _feature_ref(text, info["features"], info_file) for role, (text, _) in declared.items()}
    scales = {"time": 1.0}
    for role, (text, unit) in declared.items():
        if not unit:
            raise TrialError(root, None, text, f"no unit (LeRobot records none); pass {unit_option(role)}: "
                                               f"{_accepted(role, kind)}")
        try:
            scales[role] = unit_scale(role, unit, kind, role)
        except ValueError as exc:
            raise TrialError(root, None, text, f"{unit_option(role)}: {exc}") from None
    files = sorted((root / "data").glob("**/*.parquet"))
    if not files:
        raise TrialError(root, None, None, "no data/**/*.parquet files; not a LeRobot v3.0 dataset")
    wanted = None if episodes is None else {int(e) for e in episodes}
    found: dict[int, tuple[str, dict[str, Any], np.ndarray]] = {}
    for path in files:
        values, index = _lerobot_file(path, refs, float(info["fps"]))
        for ep in np.unique(index):
            if wanted is not None and int(ep) not in wanted:
                continue
            if int(ep) in found:
                raise TrialError(path, f"episode_{ep}", "episode_index", f"the episode is also in "
                                                                         f"{found[int(ep)][0]}; one file per episode")
            found[int(ep)] = (str(path), values, np.flatnonzero(index == ep))
    if wanted is not None and (missing := sorted(wanted - set(found))):
        raise TrialError(root, None, "episode_index", f"no episode {missing[0]} in the dataset")
    units = {"time": "s", **{role: unit or "" for role, (_, unit) in declared.items()}}  # each checked above
    names = {"time": "timestamp", **{role: ref.text for role, ref in refs.items()}}
    trials = []
    for ep in sorted(found):
        file, values, rows = found[ep]
        src = _Source(file, f"episode_{ep}", kind, names, units, scales,
                      {role: values[role][0][rows] for role in values},
                      {role: values[role][1][rows] for role in values},
                      _rows_where(lambda row: f"row {row}", rows))
        trials.append(_build(src, limits))
    return trials


# ----------------------------------------------------------------------------------------------------- writing

def si_columns(joint: JointType) -> tuple[TrialUnits, TrialColumns]:
    """The SI units and CSV headers of a trial of ``joint`` as rik writes it: ``time [s]``, ``position [m|rad]``,
    ``force [N]`` or ``torque [N·m]``."""
    position, force = ("m", "N") if joint is JointType.slide else ("rad", "N·m")
    word = "force" if joint is JointType.slide else "torque"
    return (TrialUnits(time="s", position=position, force=force),
            TrialColumns(time="time [s]", position=f"position [{position}]", force=f"{word} [{force}]"))


def _check_writable(trials: Sequence[Trial], joint: JointType) -> None:
    """Refuse an empty list, repeated names, a name that is no file name and a trial of another joint type."""
    if not trials:
        raise RikError("trials is empty; nothing to write")
    names = [t.name for t in trials]
    if len(set(names)) != len(names):
        raise RikError(f"trials have repeated names ({', '.join(sorted({n for n in names if names.count(n) > 1}))})")
    for trial in trials:
        if trial.joint is not joint:
            raise RikError(f"trials: '{trial.name}' is a {trial.joint.value} trial but the truth is a {joint.value}")
        if "/" in trial.name or "\\" in trial.name or trial.name.startswith("."):
            raise RikError(f"trials: name '{trial.name}' cannot be a file name")


def _csv_header(joint: JointType) -> str:
    """The header line rik writes into a trial CSV of ``joint``."""
    _, columns = si_columns(joint)
    return f"{columns.time},{columns.position},{columns.force}\n"


def write_csv_trials(trials: Sequence[Trial], directory: str | Path, joint: JointType) -> list[Path]:
    """Write each trial of ``joint`` to ``directory/<name>.csv`` (:func:`si_columns`' headers, values printed to
    round-trip exactly), each atomically; returns the paths (what :func:`load_trials` reads back). Refuses an empty
    list, repeated names, a name that is no file name and a trial of another joint type, each in one line."""
    from rik.paths import write_atomic

    _check_writable(trials, joint)
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    header = _csv_header(joint)
    paths = []
    for trial in trials:
        rows = zip(trial.t.tolist(), trial.q.tolist(), trial.f.tolist(), strict=True)
        path = directory / f"{trial.name}.csv"
        write_atomic(path, header + "".join(f"{a!r},{b!r},{c!r}\n" for a, b, c in rows))
        paths.append(path)
    return paths


TRUTH_FILE = "truth.json"
"""The ground truth beside simulated trials (the generators' ``TRUTH_FILE``)."""


def is_simulated(folder: Path) -> bool:
    """Whether ``folder`` holds trials a generator wrote (:func:`write_simulated`): a ``truth.json`` object naming
    the joint, and nothing else but CSV files that start with rik's header line."""
    from rik.paths import holds_only, json_object

    truth = json_object(folder / TRUTH_FILE)
    if truth is None or truth.get("joint") not in {j.value for j in JointType}:
        return False
    headers = {_csv_header(j) for j in JointType}

    def rik_file(name: str) -> bool:
        if name == TRUTH_FILE:
            return True
        try:
            with (folder / name).open(encoding="utf-8") as handle:
                return name.endswith(".csv") and handle.readline() in headers
        except (OSError, UnicodeDecodeError):
            return False

    return holds_only(folder, rik_file)


def simulated_folder() -> MadeFolder:
    """The folder ``rik sysid simulate --out`` writes: replaced whole, and only if :func:`is_simulated`."""
    from rik.paths import MadeFolder

    return MadeFolder("a folder of trials rik sysid simulate wrote", is_simulated, "choose another --out")


def write_simulated(trials: Sequence[Trial], directory: str | Path, joint: JointType,
                    truth: dict[str, Any]) -> list[Path]:
    """Write simulated ``trials`` (:func:`write_csv_trials`) and their ``truth`` (JSON) to ``directory`` as a whole:
    into a hidden sibling first, then renamed into place, replacing an earlier folder of simulated trials only (any
    other folder that is not empty is refused, before anything is written). Returns the CSV paths."""

    from rik.paths import staged_directory, write_atomic

    _check_writable(trials, joint)
    directory = Path(directory)
    with staged_directory(directory, simulated_folder()) as stage:
        written = write_csv_trials(trials, stage, joint)
        write_atomic(stage / TRUTH_FILE, json.dumps(truth, indent=2) + "\n")
    return [directory / p.name for p in written]
