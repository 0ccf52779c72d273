"""A measured-data file's table before any check (:class:`RawTable`): CSV and Parquet reading, with the limits on
what rik reads from one file."""

from __future__ import annotations

import csv
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rik.sysid.trials.errors import TrialError

MAX_FILE_BYTES = 256 * 2**20
"""Largest CSV file read, bytes (256 MiB, about 4 million rows of three numbers; parsing takes a few times that
in memory)."""
MAX_ROWS = 5_000_000
"""Most data rows read from one file (CSV or Parquet): about 83 minutes at 1 kHz."""
NOT_UTF8 = "not a UTF-8 text file; expected CSV with a header line"
EMPTY_FILE = "empty file; the first line must be a header such as 'time [s],position [m],force [N]'"
SUFFIXES = {".csv": "csv", ".parquet": "parquet", ".pq": "parquet"}


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


def first_line(exc: BaseException) -> str:
    """The first line of an exception's message (its class name if it has none), for a one-line message."""
    text = str(exc).strip().splitlines()
    return text[0] if text else type(exc).__name__


def too_many_rows(rows: int) -> str:
    """The problem of a file with more than :data:`MAX_ROWS` data rows."""
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
                raise TrialError(file, None, None, too_many_rows(len(cells)))
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
            raise TrialError(file, None, None, too_many_rows(rows))
        table = pq.read_table(path)
    except (pa.ArrowException, OSError) as exc:
        raise TrialError(file, None, None, f"not a readable Parquet file ({first_line(exc)})") from None

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
        raise TrialError(path, None, None, "not a regular file (a folder, a pipe or a device)" if path.exists()
                         else "no such file")
    return _read_csv(path) if kind == "csv" else _read_parquet(path)
