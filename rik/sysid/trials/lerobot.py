"""Measured trials from a LeRobot v3.0 dataset, one per episode (:func:`load_lerobot_trials`), read with pyarrow."""

from __future__ import annotations

import difflib
import math
import re
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal, cast

import numpy as np

from rik.paths import read_json
from rik.schemas.joints import JointType
from rik.sysid.trials.errors import TrialError
from rik.sysid.trials.load import MIN_SAMPLES, ColumnMap, Source, Trial, build_trial, rows_where, thresholds
from rik.sysid.trials.tables import MAX_ROWS, first_line, too_many_rows
from rik.sysid.trials.units import accepted_units, joint_type, unit_option, unit_scale

if TYPE_CHECKING:
    import pyarrow as pa


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

    try:
        info = read_json(info_file)
    except ValueError as exc:  # not JSON, not UTF-8, too large or nested too deeply
        raise TrialError(info_file, None, None, f"not valid JSON ({first_line(exc)})") from None
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
            raise TrialError(file, None, None, too_many_rows(parquet.metadata.num_rows))
        wanted = [c for c in dict.fromkeys(["episode_index", "timestamp", "frame_index",
                                            *(r.key for r in refs.values())]) if c in names]
        table = pq.read_table(path, columns=wanted)  # only these: a dataset's frames may hold images
    except (pa.ArrowException, OSError) as exc:
        raise TrialError(file, None, None, f"not a readable Parquet file ({first_line(exc)})") from None
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
    LeRobot records no units, so each named quantity needs its unit declared (the units of the file table of
    :mod:`rik.sysid.trials`). Time is the ``timestamp`` column, s (else ``frame_index / fps``), unless ``time`` names
    another feature; ``time_unit`` alone declares the ``timestamp`` column's unit. Trials are named
    ``episode_<index>``, in index order (``trial`` is refused: the episodes are the trials); ``episodes`` keeps
    only those indices. Checks and thresholds are those of :func:`load_trials`."""
    kind = joint_type(joint)
    limits = thresholds(kind, min_samples, min_motion, min_force_range)
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
                                               f"{accepted_units(role, kind)}")
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
        src = Source(file, f"episode_{ep}", kind, names, units, scales,
                     {role: values[role][0][rows] for role in values},
                     {role: values[role][1][rows] for role in values},
                     rows_where(lambda row: f"row {row}", rows))
        trials.append(build_trial(src, limits))
    return trials
