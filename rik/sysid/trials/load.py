"""Measured trials from CSV and Parquet files: :class:`Trial`, :class:`ColumnMap`, the matching of columns to
quantities, the checks of every trial (the format and the checks: :mod:`rik.sysid.trials`) and :func:`load_trials`."""

from __future__ import annotations

import difflib
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Literal, cast

import numpy as np

from rik.errors import RikError
from rik.schemas.joints import JointType
from rik.schemas.trajectory import TrialColumns, TrialMeta, TrialUnits
from rik.sysid.trials.errors import TrialError
from rik.sysid.trials.tables import RawTable, read_table
from rik.sysid.trials.units import (
    COLUMN_NAMES,
    ROLES,
    TIME_UNITS,
    TRIAL_COLUMN,
    accepted_units,
    choices,
    joint_type,
    parse_header,
    unit_option,
    unit_scale,
    unit_table,
)

MIN_SAMPLES = 50
"""Fewest samples a trial may have: below this no derivative or fit is meaningful."""
MIN_MOTION = {JointType.slide: 1e-3, JointType.hinge: math.radians(0.5)}
"""Smallest position range (max − min) of a trial, m (slide: 1 mm) or rad (hinge: 0.5°)."""
MIN_FORCE_RANGE = {JointType.slide: 0.01, JointType.hinge: 0.001}
"""Smallest force range (max − min) of a trial, N (slide) or N·m (hinge): below it the force is constant."""
MAX_MAGNITUDE = {"position": 1e3, "velocity": 1e3, "force": 1e6}
"""Largest magnitude of a measured value, SI (m or rad, m/s or rad/s, N or N·m): far beyond any furniture joint
(a kilometre, a meganewton), and small enough that the fit's squares and sums of millions of samples stay finite
(forces of 1e300 N overflowed into NaN gains). A value beyond it is a wrong unit or a damaged file."""
MAX_SAMPLE_INTERVAL = 1.0
"""Largest median interval between a trial's samples, s: data sampled slower than 1 Hz cannot show a joint's
dynamics (the smoothing window is 0.1 s), and such intervals are what milliseconds (of a logger at 500 Hz or
slower), µs or ns read as s look like."""


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
    features. The default (all None) reads headers with units as described in :mod:`rik.sysid.trials`.

    ``time``, ``position``, ``force``, ``velocity`` name a column (files: a header, matched exactly, else
    case-insensitively on its name without the ``[unit]``; LeRobot: a feature reference such as
    ``observation.state[2]``); a quantity left None is found by its usual names (:data:`COLUMN_NAMES`). A named
    column's header may carry any text. ``trial`` names the column that tells trials apart in a file (default: a
    ``trial`` column, if any; a LeRobot dataset's trials are its episodes).

    ``time_unit``, ``position_unit``, ``force_unit``, ``velocity_unit`` declare the unit of that quantity's
    column, named or found, from the unit tables of :mod:`rik.sysid.trials` (``force_unit`` is a torque unit
    for a hinge). A header without a unit needs one; a header whose brackets hold a valid unit must agree with it.
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


# ------------------------------------------------------------------------------------------ column matching

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
                                                     f"{accepted_units(role, joint)}")
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
            unit = next(iter(TIME_UNITS if role == "time" else unit_table(role)[joint]))
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


def thresholds(joint: JointType, min_samples: int, min_motion: float | None,
               min_force_range: float | None) -> _Thresholds:
    """The thresholds of a trial's checks: the given ones, else the defaults of the joint type."""
    return _Thresholds(min_samples, MIN_MOTION[joint] if min_motion is None else min_motion,
                       MIN_FORCE_RANGE[joint] if min_force_range is None else min_force_range)


def _num(x: float) -> str:
    return f"{x:.6g}"


@dataclass
class Source:
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


def _check_finite(src: Source) -> None:
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


def check_magnitude(values: np.ndarray, role: str, scale: float) -> int | None:
    """The index of the first of ``values`` (of quantity ``role``, ``scale`` to SI) beyond :data:`MAX_MAGNITUDE`,
    else None (compared in the values' own unit: their SI values may overflow)."""
    bad = np.flatnonzero(np.abs(values) > MAX_MAGNITUDE[role] / scale)
    return int(bad[0]) if bad.size else None


def magnitude_problem(value: float, unit: str, role: str, scale: float) -> str:
    """What is wrong with ``value`` (in ``unit``, ``scale`` to SI) beyond :data:`MAX_MAGNITUDE` of ``role``."""
    return (f"is {_num(value)} {unit}, beyond ±{_num(MAX_MAGNITUDE[role] / scale)} {unit}, far more than any furniture "
            "joint: too large to fit; is the unit right?")


def _check_magnitude(src: Source) -> None:
    for role in ("position", "velocity", "force"):
        if role not in src.values:
            continue
        i = check_magnitude(src.values[role], role, src.scales[role])
        if i is not None:
            value = float(src.values[role][i])
            raise src.error(role, f"{src.where(i)} {magnitude_problem(value, src.units[role], role, src.scales[role])}")


def _check_time(src: Source) -> None:
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


def _check_time_unit(src: Source) -> None:
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
        advice = f"if it is in {likely}, convert it to s or ms (rik reads time in {choices(TIME_UNITS)})"
    else:
        advice = "give the time in s or ms"
    raise src.error("time", f"samples are {_num(interval)} s apart (median of the time read in {unit}), slower "
                            f"than 1 Hz: is the time in another unit? {advice}")


def _check_range(src: Source, role: str, minimum_si: float) -> None:
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


def build_trial(src: Source, limits: _Thresholds) -> Trial:
    """Check a trial's data (in the order of :mod:`rik.sysid.trials`' checks) and convert it to SI."""
    _check_finite(src)
    _check_magnitude(src)
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

def rows_where(where: Callable[[int], str], rows: np.ndarray) -> Callable[[int], str]:
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
        src = Source(raw.file, name, joint, columns, units, scales,
                     {role: col.values[rows] for role, col in data.items()},
                     {role: col.empty[rows] for role, col in data.items()},
                     rows_where(raw.where, rows))
        trials.append(build_trial(src, limits))
    return trials


def load_trials(paths: str | Path | Sequence[str | Path], joint: Literal["slide", "hinge"] | JointType, *,
                columns: ColumnMap | None = None, min_samples: int = MIN_SAMPLES, min_motion: float | None = None,
                min_force_range: float | None = None) -> list[Trial]:
    """Every trial in the CSV or Parquet ``paths`` (see :mod:`rik.sysid.trials` for the format), in SI units.

    ``columns`` names columns and declares units the headers do not (:class:`ColumnMap`; the same for every file).
    ``min_motion`` (m or rad) and ``min_force_range`` (N or N·m) default to :data:`MIN_MOTION` and
    :data:`MIN_FORCE_RANGE` of the joint type. Raises :class:`TrialError` (a :class:`RikError`) naming the file,
    trial and column of the first problem."""
    kind = joint_type(joint)
    limits = thresholds(kind, min_samples, min_motion, min_force_range)
    files = [paths] if isinstance(paths, (str, Path)) else list(paths)
    if not files:
        raise RikError("no trial files given; pass one or more .csv or .parquet files")
    trials: list[Trial] = []
    for path in files:
        trials += _file_trials(read_table(Path(path)), kind, limits, columns or ColumnMap())
    return trials
