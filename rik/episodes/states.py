"""An episode's ``states.parquet``: its columns, and the one reader of it, bounded before anything is decoded
(:func:`rik.episodes.episode.read_episode` reads the meta, then calls :func:`read_states`).

A ``states.parquet`` is data from elsewhere: a file of a few hundred kB can declare millions of rows, or pages
that decompress or expand to gigabytes, and still carry the sha256 its (re-sealed) ``meta.json`` records. So
:func:`read_states` decodes nothing until what the file declares fits what its meta can need:

1. the meta itself: at most :data:`MAX_EPISODE_SECONDS` of steps at its ``fps``, and at most
   :data:`MAX_DECODED_BYTES` for ``steps + 1`` rows of its columns (``state_size`` numbers of state, the action's
   and the robot's widths, the scalars);
2. the file: at most what those rows can take on disk (unread beyond it), then its sha256;
3. the Parquet footer (its length is in the file's last 8 bytes: at most :data:`MAX_FOOTER_BYTES`): the columns,
   the row count (``steps + 1``: the state before each step, then the final one) and their types;
4. every column's pages, walked header by header: the values they hold and the bytes they decompress to, at most
   :data:`SIZE_MARGIN` times what the meta's rows need (plus :data:`SIZE_SLACK_BYTES`), and at most
   :data:`MAX_DECODED_BYTES` in all;

and then decodes only the columns asked for. Each refusal is one line naming the file and the bound.
"""

from __future__ import annotations

import hashlib
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rik.errors import RikError

if TYPE_CHECKING:
    import pyarrow as pa
    import pyarrow.parquet as pq

    from rik.schemas.episodes import EpisodeMeta

META = "meta.json"
"""An episode's metadata file (:func:`rik.episodes.episode.read_meta`)."""
STATES = "states.parquet"
"""An episode's recorded rows: one per control step, then the final state."""
COLUMNS_2 = ("step", "time", "state", "action", "front_qpos", "front_qvel", "opening", "gripper_opening",
             "tcp", "contacts", "contact_normal_force", "contact_tangential_force")
"""The columns of episodes before format 3."""
COLUMNS = (*COLUMNS_2, "tcp_quat", "robot_joints", "robot_targets")
"""``tcp_quat``: the gripper frame's world orientation (w, x, y, z); ``robot_joints``: the robot's joint positions
and its gripper's (meta.json's ``robot_joints`` names them); ``robot_targets``: what the servos were commanded in
the row's step (the IK's joint targets for an arm, then the gripper's goal)."""
EXECUTED = "executed_action"
"""The column of an episode recorded with action noise (meta ``action_noise``): the action sent to the robot, where
``action`` holds the operator's own (the label a policy learns, DART-style); episodes without noise lack it."""
VECTORS = {"state": None, "action": 7, "tcp": 3, "tcp_quat": 4, "robot_joints": None, "robot_targets": None,
           EXECUTED: 7}
"""Vector columns and their widths (None: the meta's ``state_size``, or the robot's joint count)."""


def columns_of(meta: EpisodeMeta) -> tuple[str, ...]:
    """The columns of an episode's ``states.parquet``, in order, by its meta's format and noise."""
    if meta.format < 3:
        return COLUMNS_2
    return (*COLUMNS, EXECUTED) if meta.action_noise is not None else COLUMNS


class EpisodeError(RikError):
    """An episode on disk is missing, truncated or corrupt."""


MAX_EPISODE_SECONDS = 24 * 3600
"""Longest episode read, s of simulated time (``steps / fps``): a day. rik's strategies record 30 s; a teleoperated
episode at 20 Hz holds 1.7 million steps a day, about 1.7 GB of Hand-E rows (the decoded bound below is then the
tighter one)."""
MAX_DECODED_BYTES = 2**30
"""Most bytes an episode's columns may decode to (1 GiB), by its meta and by what its file declares; rik's
30 s episodes decode to about 0.6 MB, an hour at 20 Hz to about 70 MB."""
MAX_FOOTER_BYTES = 4 * 2**20
"""Largest Parquet footer read (4 MiB); rik writes about 4 kB."""
MAX_PAGES = 100_000
"""Most page headers walked in one file; rik writes a page per column and 20,000 rows (or 1 MiB)."""
SIZE_MARGIN = 2
"""How many times the bytes its rows need a column may declare (encodings, levels, a dictionary page)."""
SIZE_SLACK_BYTES = 2**20
"""Bytes a column may declare on top (page headers and statistics of a short episode), per column."""
MAX_THRIFT_DEPTH = 16
"""Deepest nesting of structs read in a page header (Parquet's are 3 deep)."""
NUMBER_BYTES = 8
"""Bytes of one number of a column (float64; the int32 columns take less)."""
ACTION_WIDTH = 7
"""Numbers of a pose action (:data:`rik.exporters.lerobot_frames.ACTION_NAMES`)."""


def read_states(directory: Path, meta: EpisodeMeta, columns: Sequence[str] | None = None) -> pa.Table:
    """The ``columns`` of the ``states.parquet`` in ``directory`` (all, in order, when None), bounded by its
    ``meta`` (the episode's meta.json, read and checked) before decoding (see the module) and checked: sha256,
    columns, rows, types, and the widths of the vectors decoded. Anything else: an :class:`EpisodeError` of one line
    naming the file."""
    file = Path(directory) / STATES
    layout = columns_of(meta)
    wanted = layout if columns is None else tuple(columns)
    if unknown := [c for c in wanted if c not in layout]:
        raise EpisodeError(f"{file}: no column {', '.join(repr(c) for c in unknown)} in an episode of format "
                           f"{meta.format} (its columns: {', '.join(layout)})")
    need = Need.of(meta)
    need.check_meta(Path(directory) / META)
    data = _read_bytes(file, meta, need)
    parquet = _open(file, data)
    _check_layout(file, parquet, meta, layout)
    _check_sizes(file, data, parquet.metadata, need)
    table = _decode(file, parquet, wanted)
    _check_widths(file, table, meta)
    return table


@dataclass(frozen=True)
class Need:
    """What an episode's columns can need, by its meta: ``rows`` (``steps + 1``) and each column's numbers per row."""

    rows: int
    widths: dict[str, int]
    steps: int
    fps: int

    @classmethod
    def of(cls, meta: EpisodeMeta) -> Need:
        joints = len(meta.robot_joints)
        vectors: dict[str, int] = {"state": meta.state_size, "robot_joints": joints, "robot_targets": joints,
                                   "action": joints if meta.action_kind == "joints" else ACTION_WIDTH}
        widths = {c: vectors.get(c) or VECTORS.get(c) or 1 for c in columns_of(meta)}
        return cls(meta.steps + 1, widths, meta.steps, meta.fps)

    def bytes(self, column: str) -> int:
        """Bytes column ``column`` decodes to (float64 numbers)."""
        return self.rows * self.widths[column] * NUMBER_BYTES

    def allowed_bytes(self, column: str) -> int:
        """Most bytes column ``column``'s pages may declare."""
        return SIZE_MARGIN * self.bytes(column) + SIZE_SLACK_BYTES

    def allowed_values(self, column: str) -> int:
        """Most values column ``column``'s pages may hold."""
        return SIZE_MARGIN * self.rows * self.widths[column] + SIZE_SLACK_BYTES // NUMBER_BYTES

    def file_bytes(self) -> int:
        """Largest ``states.parquet`` these rows can take (uncompressed pages, and the footer)."""
        return sum(self.allowed_bytes(c) for c in self.widths) + MAX_FOOTER_BYTES + 12

    def check_meta(self, file: Path) -> None:
        """Refuse a meta whose steps are more than an episode: longer than :data:`MAX_EPISODE_SECONDS` at its fps,
        or rows decoding to more than :data:`MAX_DECODED_BYTES`."""
        if self.steps > MAX_EPISODE_SECONDS * self.fps:
            raise EpisodeError(f"{file}: field 'steps': {self.steps:,} steps at {self.fps} Hz last "
                               f"{self.steps / self.fps / 3600:,.1f} h, longer than an episode rik reads "
                               f"({MAX_EPISODE_SECONDS // 3600} h)")
        total = sum(self.bytes(c) for c in self.widths)
        if total > MAX_DECODED_BYTES:
            raise EpisodeError(f"{file}: fields 'steps' and 'state_size': {self.rows:,} rows of "
                               f"{sum(self.widths.values()):,} numbers would decode to {total / 2**30:,.1f} GiB, more "
                               f"than rik reads of one episode ({MAX_DECODED_BYTES / 2**30:g} GiB)")


def _read_bytes(file: Path, meta: EpisodeMeta, need: Need) -> bytes:
    """The file's bytes, read only up to what ``need``'s rows can take, checked against the meta's sha256."""
    limit = need.file_bytes()
    try:
        with open(file, "rb") as f:
            data = f.read(limit + 1)
    except FileNotFoundError:
        raise EpisodeError(f"{file}: no such file; the episode is incomplete") from None
    except OSError as exc:
        raise EpisodeError(f"{file}: cannot be read ({exc.strerror})") from None
    if len(data) > limit:
        raise EpisodeError(f"{file}: more than {limit:,} bytes, more than {need.rows:,} rows of this episode (its "
                           "meta.json's steps and state_size) can take; refused unread")
    if hashlib.sha256(data).hexdigest() != meta.states_sha256:
        raise EpisodeError(f"{file}: truncated or corrupt (its sha256 differs from the one in meta.json)")
    return data


def _unreadable(file: Path, exc: BaseException) -> EpisodeError:
    text = str(exc).splitlines()[0] if str(exc) else ""
    return EpisodeError(f"{file}: not a readable Parquet file ({type(exc).__name__}: {text})")


def _open(file: Path, data: bytes) -> pq.ParquetFile:
    """The Parquet file in ``data`` with its footer read (at most :data:`MAX_FOOTER_BYTES`); nothing decoded."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    if len(data) >= 12 and data[-4:] == b"PAR1":  # else pyarrow says what is wrong
        length = int.from_bytes(data[-8:-4], "little")
        if length > MAX_FOOTER_BYTES:
            raise EpisodeError(f"{file}: its Parquet footer declares {length:,} bytes, more than an episode's "
                               f"({MAX_FOOTER_BYTES:,} at most; rik writes a few kB); refused unread")
    try:
        parquet = pq.ParquetFile(pa.BufferReader(data))
        parquet.schema_arrow  # noqa: B018 (read here: a footer whose schema cannot be read is refused here)
    except (pa.ArrowException, OSError) as exc:
        raise _unreadable(file, exc) from None
    return parquet


def _check_layout(file: Path, parquet: pq.ParquetFile, meta: EpisodeMeta, layout: tuple[str, ...]) -> None:
    """The footer's columns, rows and types must be the meta's (read from the footer: nothing decoded)."""
    import pyarrow as pa

    schema, metadata = parquet.schema_arrow, parquet.metadata
    if list(schema.names) != list(layout):
        raise EpisodeError(f"{file}: columns {schema.names}, expected {list(layout)}")
    rows = metadata.num_rows
    groups = sum(metadata.row_group(i).num_rows for i in range(metadata.num_row_groups))
    if rows != groups:
        raise EpisodeError(f"{file}: not a readable Parquet file (its footer declares {rows:,} rows, its row groups "
                           f"{groups:,})")
    if rows != meta.steps + 1:
        raise EpisodeError(f"{file}: its footer declares {rows:,} rows, but meta.json's steps ({meta.steps:,}) make "
                           f"{meta.steps + 1:,} (the state before each step, then the final one); refused before "
                           "decoding")
    for name in layout:
        kind = schema.field(name).type
        if name in VECTORS:
            if not (pa.types.is_list(kind) or pa.types.is_fixed_size_list(kind) or pa.types.is_large_list(kind)) \
                    or not pa.types.is_floating(kind.value_type):
                raise EpisodeError(f"{file}: column '{name}' holds {kind}, expected lists of floats")
        elif not pa.types.is_integer(kind) and not pa.types.is_floating(kind):
            raise EpisodeError(f"{file}: column '{name}' holds {kind}, expected numbers")


@dataclass
class _Declared:
    """What a column's pages declare: data values, and bytes once decompressed."""

    values: int = 0
    bytes: int = 0


def _check_sizes(file: Path, data: bytes, metadata: pq.FileMetaData, need: Need) -> None:
    """Every column's pages (their headers walked, and the footer's sizes) must hold at most what ``need`` allows,
    and all of them at most :data:`MAX_DECODED_BYTES`."""
    import pyarrow as pa

    try:
        declared = _declared(data, metadata)
    except (pa.ArrowException, OSError, ValueError) as exc:
        raise _unreadable(file, exc) from None
    for name, d in declared.items():
        width = need.widths[name]
        if d.values > need.allowed_values(name):
            raise EpisodeError(f"{file}: column '{name}' declares {d.values:,} numbers, more than {need.rows:,} rows "
                               f"of {width} can hold ({need.allowed_values(name):,} at most); refused before decoding")
        if d.bytes > need.allowed_bytes(name):
            raise EpisodeError(f"{file}: column '{name}' declares {d.bytes:,} bytes decoded, more than {need.rows:,} "
                               f"rows of {width} numbers need ({need.allowed_bytes(name):,} at most); refused before "
                               "decoding")
    total = sum(max(d.bytes, d.values * NUMBER_BYTES) for d in declared.values())
    if total > MAX_DECODED_BYTES:
        raise EpisodeError(f"{file}: its columns declare {total:,} bytes decoded, more than rik reads of one episode "
                           f"({MAX_DECODED_BYTES:,}); refused before decoding")


def _declared(data: bytes, metadata: pq.FileMetaData) -> dict[str, _Declared]:
    """What each top-level column declares over its row groups (its one leaf's pages); ValueError when a column
    chunk is not where the footer says, or its pages do not add up to the values the footer declares."""
    end_of_pages = len(data) - 8 - int.from_bytes(data[-8:-4], "little")
    out: dict[str, _Declared] = {}
    pages = 0
    for g in range(metadata.num_row_groups):
        group = metadata.row_group(g)
        for c in range(group.num_columns):
            chunk = group.column(c)
            name = chunk.path_in_schema.split(".")[0]
            if name in out and g == 0:
                raise ValueError(f"column '{name}' has more than one leaf")
            d = out.setdefault(name, _Declared())
            values, size, walked = _walk_pages(data, chunk, end_of_pages, MAX_PAGES - pages)
            if values != chunk.num_values:
                raise ValueError(f"the pages of column '{name}' hold {values:,} values, its footer says "
                                 f"{chunk.num_values:,}")
            pages += walked
            d.values += values
            d.bytes += max(size, chunk.total_uncompressed_size)
    return out


def _walk_pages(data: bytes, chunk: Any, end_of_pages: int, most: int) -> tuple[int, int, int]:
    """(data values, decompressed bytes, pages) of one column chunk, from its page headers: the bytes Arrow reads
    for it, ``total_compressed_size`` from its first page. At most ``most`` pages."""
    start = chunk.data_page_offset
    if chunk.has_dictionary_page and 0 < chunk.dictionary_page_offset < start:
        start = chunk.dictionary_page_offset
    end = start + chunk.total_compressed_size
    if not 4 <= start <= end <= end_of_pages:
        raise ValueError(f"column chunk '{chunk.path_in_schema}' lies outside the file's pages")
    view = memoryview(data)
    pos, values, size, pages = start, 0, 0, 0
    while pos < end:
        if pages >= most:
            raise ValueError(f"more than {MAX_PAGES:,} pages")
        reader = _Thrift(view, pos, end)
        header = reader.struct()
        compressed, uncompressed = header.get(3), header.get(2)
        if not isinstance(compressed, int) or not isinstance(uncompressed, int) or min(compressed, uncompressed) < 0:
            raise ValueError(f"a page header of '{chunk.path_in_schema}' has no sizes")
        body = header.get(5) or header.get(8)  # a data page (v1 or v2): its values
        if isinstance(body, dict):
            values += max(int(body.get(1) or 0), 0)
        size += uncompressed
        pos = reader.pos + compressed
        pages += 1
    if pos != end:
        raise ValueError(f"the last page of '{chunk.path_in_schema}' runs past its column chunk")
    return values, size, pages


class _Thrift:
    """Thrift's compact protocol over ``data[pos:end]``: enough to read a Parquet page header (a struct) and skip
    what it does not need. Integers come back as ints, structs as {field id: value}, the rest as None; ValueError
    where the bytes end or are no compact Thrift."""

    def __init__(self, data: memoryview, pos: int, end: int) -> None:
        self.data, self.pos, self.end = data, pos, end

    def byte(self) -> int:
        if self.pos >= self.end:
            raise ValueError("a page header runs past its column chunk")
        self.pos += 1
        return int(self.data[self.pos - 1])

    def skip(self, n: int) -> None:
        if n < 0 or self.pos + n > self.end:
            raise ValueError("a page header runs past its column chunk")
        self.pos += n

    def varint(self) -> int:
        value = 0
        for shift in range(0, 70, 7):
            b = self.byte()
            value |= (b & 0x7F) << shift
            if not b & 0x80:
                return value
        raise ValueError("a page header holds a varint over 10 bytes")

    def zigzag(self) -> int:
        n = self.varint()
        return (n >> 1) ^ -(n & 1)

    def struct(self, depth: int = 0) -> dict[int, Any]:
        if depth > MAX_THRIFT_DEPTH:
            raise ValueError("a page header is nested too deeply")
        fields: dict[int, Any] = {}
        last = 0
        while (b := self.byte()) & 0x0F:
            last = last + (b >> 4) if b >> 4 else self.zigzag()
            fields[last] = self.value(b & 0x0F, depth)
        return fields

    def value(self, kind: int, depth: int, element: bool = False) -> Any:
        if kind in (1, 2):  # a bool: in the field header, or a byte of its own in a collection
            return self.byte() == 1 if element else kind == 1
        if kind == 3:
            return self.byte()
        if kind in (4, 5, 6):
            return self.zigzag()
        if kind == 12:
            return self.struct(depth + 1)
        if kind == 7:
            self.skip(8)
        elif kind == 8:
            self.skip(self.varint())
        elif kind in (9, 10):
            b = self.byte()
            self.items(self.varint() if b >> 4 == 15 else b >> 4, [b & 0x0F], depth)
        elif kind == 11:
            n = self.varint()
            if n:
                b = self.byte()
                self.items(n, [b >> 4, b & 0x0F], depth)
        else:
            raise ValueError(f"a page header holds an unknown Thrift type {kind}")
        return None

    def items(self, n: int, kinds: list[int], depth: int) -> None:
        if n > self.end - self.pos:  # every item takes a byte at least
            raise ValueError("a page header declares more items than it holds")
        for _ in range(n):
            for kind in kinds:
                self.value(kind, depth + 1, element=True)


def _decode(file: Path, parquet: pq.ParquetFile, columns: tuple[str, ...]) -> pa.Table:
    """Decode ``columns`` (their sizes checked)."""
    import pyarrow as pa

    try:
        return parquet.read(columns=list(columns))
    except (pa.ArrowException, OSError) as exc:
        raise _unreadable(file, exc) from None


def _check_widths(file: Path, table: pa.Table, meta: EpisodeMeta) -> None:
    """The decoded vector columns must be as wide as the meta says (an action of pose: all the same width)."""
    joints = len(meta.robot_joints)
    widths = {"state": meta.state_size, "action": joints if meta.action_kind == "joints" else None, "tcp": 3,
              "tcp_quat": 4, "robot_joints": joints, "robot_targets": joints, EXECUTED: 7}
    for name in VECTORS:
        if name in table.column_names:
            _check_vectors(file, table, name, widths[name])


def _check_vectors(file: Path, table: pa.Table, name: str, width: int | None) -> None:
    """Column ``name`` (lists of floats) must hold vectors all ``width`` long (``None``: all the same length)."""
    import numpy as np
    import pyarrow.compute as pc

    lengths = pc.list_value_length(table.column(name)).to_numpy(zero_copy_only=False)
    want = width if width is not None else (int(lengths[0]) if len(lengths) else 0)
    if len(lengths) and (lengths.min() != want or lengths.max() != want):
        row = int(np.argmax(lengths != want))
        raise EpisodeError(f"{file}: column '{name}' has {int(lengths[row])} numbers in row {row}, expected {want}"
                           + (" (meta.json's state_size)" if name == "state" else ""))
