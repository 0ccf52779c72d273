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
Every value finite (no NaN, inf, empty cell) and, in SI, within :data:`MAX_MAGNITUDE` (1 km or rad, 1 km/s,
1 MN or MN·m: beyond it the fit would overflow); time strictly increasing within a trial; at least ``min_samples``
samples (default :data:`MIN_SAMPLES`); the position spanning at least ``min_motion`` (default
:data:`MIN_MOTION`: 1 mm or 0.5°); the force spanning at least ``min_force_range`` (default
:data:`MIN_FORCE_RANGE`: 0.01 N or 0.001 N·m). A failure raises :class:`TrialError`: one line naming the file,
trial and column at fault and what would be valid.

Modules
-------
One module per job (everything public is re-exported here, so ``from rik.sysid.trials import X`` works):

- :mod:`~rik.sysid.trials.units`: the quantities, their column names and unit tables, the ``name [unit]`` header;
- :mod:`~rik.sysid.trials.errors`: :class:`TrialError`;
- :mod:`~rik.sysid.trials.tables`: a file's raw table (CSV, Parquet) and the limits on its size;
- :mod:`~rik.sysid.trials.load`: :class:`Trial`, :class:`ColumnMap`, column matching, the checks and
  :func:`load_trials`;
- :mod:`~rik.sysid.trials.lerobot`: :func:`load_lerobot_trials`;
- :mod:`~rik.sysid.trials.write`: :func:`si_columns`, :func:`write_csv_trials` and the folder of simulated trials
  (:func:`write_simulated`).
"""

from __future__ import annotations

from rik.sysid.trials.errors import TrialError
from rik.sysid.trials.lerobot import load_lerobot_trials
from rik.sysid.trials.load import (
    MAX_MAGNITUDE,
    MAX_SAMPLE_INTERVAL,
    MIN_FORCE_RANGE,
    MIN_MOTION,
    MIN_SAMPLES,
    ColumnMap,
    Trial,
    load_trials,
    match_header,
)
from rik.sysid.trials.tables import (
    EMPTY_FILE,
    MAX_FILE_BYTES,
    MAX_ROWS,
    NOT_UTF8,
    SUFFIXES,
    RawTable,
    check_size,
    read_table,
)
from rik.sysid.trials.units import (
    COLUMN_NAMES,
    FORCE_UNITS,
    POSITION_UNITS,
    ROLES,
    TIME_UNITS,
    TRIAL_COLUMN,
    VELOCITY_UNITS,
    joint_type,
    parse_header,
    unit_option,
    unit_scale,
)
from rik.sysid.trials.write import (
    TRUTH_FILE,
    is_simulated,
    si_columns,
    simulated_folder,
    write_csv_trials,
    write_simulated,
)

__all__ = [
    "COLUMN_NAMES", "ColumnMap", "EMPTY_FILE", "FORCE_UNITS", "MAX_FILE_BYTES", "MAX_MAGNITUDE", "MAX_ROWS",
    "MAX_SAMPLE_INTERVAL", "MIN_FORCE_RANGE", "MIN_MOTION", "MIN_SAMPLES", "NOT_UTF8", "POSITION_UNITS", "ROLES",
    "RawTable", "SUFFIXES", "TIME_UNITS", "TRIAL_COLUMN", "TRUTH_FILE", "Trial", "TrialError", "VELOCITY_UNITS",
    "check_size",
    "is_simulated", "joint_type", "load_lerobot_trials", "load_trials", "match_header", "parse_header",
    "read_table", "si_columns", "simulated_folder", "unit_option", "unit_scale", "write_csv_trials",
    "write_simulated",
]
