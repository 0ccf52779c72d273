"""Where rik keeps files of its own (the cache directory), how it writes files (atomically) and folders (staged,
then renamed into place), and which folders it may replace: only those it made (:class:`MadeFolder`)."""

from __future__ import annotations

import os
from collections.abc import Callable, Collection, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from types import ModuleType

    import numpy as np
    from matplotlib.figure import Figure
    from pydantic import BaseModel


def cache_dir() -> Path:
    """``$RIK_CACHE``, else ``$XDG_CACHE_HOME/rik``, else ``~/.cache/rik``."""
    if env := os.environ.get("RIK_CACHE"):
        return Path(env).expanduser()
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "rik"


def inside(root: Path, *parts: str, what: str = "path") -> Path:
    """``root / part / ...``, checked to stay inside ``root`` (no '..', no absolute part, no symlink out of it).

    ``parts`` come from data rik reads (episode and variant ids, stream keys); one that would lead elsewhere
    raises :class:`rik.errors.RikError` naming it: rik never writes outside the folder it was given."""
    from rik.errors import RikError

    path = Path(root).joinpath(*parts)
    base = Path(root).resolve()
    if not path.resolve().is_relative_to(base) or any(p in ("", ".", "..") or "/" in p or "\\" in p for p in parts):
        raise RikError(f"{what} {'/'.join(parts)!r} would lead outside {root}; refusing to write there")
    return path


def check_folder(path: Path, what: str) -> Path:
    """``path``, a folder a command reads or creates, unless it or the nearest existing folder above it is a file
    (or another non-folder): then a :class:`RikError` naming the option, checked before any work is done."""
    from rik.errors import RikError

    path = Path(path)
    for p in (path, *path.parents):
        if p.is_dir():
            return path
        if p.exists() or p.is_symlink():
            where = "" if p == path else f" ({p} is not a folder)"
            raise RikError(f"{what} {path}: a file is there, where a folder is expected{where}")
    return path


@contextmanager
def atomic_path(path: Path) -> Iterator[Path]:
    """A temporary path beside ``path`` to write to; renamed onto ``path`` when the block ends without an error,
    removed when it raises (a full disk or a kill of the writer's work leaves no ``*.tmp`` behind). Two processes
    writing the same file do not share a temporary."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        yield tmp
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


@dataclass(frozen=True)
class MadeFolder:
    """A kind of folder that rik makes whole (a report, a stream, simulated trials), and how to tell one from a
    folder of the user's: rik replaces or removes a folder only when it is absent, empty, or ``made`` recognises it.

    ``made(folder)`` reads the file rik writes into every such folder (its marker: a report's ``summary.json``, a
    stream's ``stream.json``, ...) and checks that nothing else is there but the names rik writes, so a folder an
    older rik made (before any marker of its own) is recognised as well, and a user's file added to it stops the
    replacement. ``what`` names the kind in messages ("a report of rik sysid fit"), ``advice`` says where else to
    write ("choose another --report")."""

    what: str
    made: Callable[[Path], bool]
    advice: str = "choose another folder"


def is_temporary(name: str) -> bool:
    """Whether ``name`` is a temporary of :func:`atomic_path` (``.<file>.<pid>.tmp``), which a killed write leaves."""
    return name.startswith(".") and name.endswith(".tmp") and name[:-4].rsplit(".", 1)[-1].isdigit()


def holds_only(folder: Path, names: Callable[[str], bool] | Collection[str]) -> bool:
    """Whether every entry at the top of ``folder`` is one of ``names`` (a set, or a test of a name) or a temporary
    of :func:`atomic_path`: whether it holds nothing rik would not have written there."""
    allowed = names if callable(names) else names.__contains__
    try:
        return all(allowed(e.name) or is_temporary(e.name) for e in os.scandir(folder))
    except OSError:
        return False


MAX_JSON_BYTES = 16 * 2**20
"""Largest JSON file :func:`read_json` reads (rik's own are a few kB to a few MB)."""


def read_json(path: Path, limit: int = MAX_JSON_BYTES) -> Any:
    """The JSON in file ``path`` (UTF-8), read only when it is at most ``limit`` bytes. Raises OSError when it
    cannot be read, and ValueError, with the reason, when it is larger, not UTF-8, not JSON, or nested too deeply
    to parse (which Python's parser reports as a RecursionError)."""
    import json

    with open(path, "rb") as handle:
        raw = handle.read(limit + 1)
    if len(raw) > limit:
        raise ValueError(f"larger than {limit / 2**20:g} MiB")
    try:
        return json.loads(raw.decode("utf-8"))
    except RecursionError:
        raise ValueError("nested too deeply") from None


def json_object(path: Path) -> dict[str, Any] | None:
    """The JSON object in file ``path`` (:func:`read_json`); None when it is missing, unreadable, not JSON or not an
    object."""
    try:
        data = read_json(Path(path))
    except (OSError, ValueError):
        return None
    return data if isinstance(data, dict) else None


def check_replaceable(folder: Path, kind: MadeFolder) -> None:
    """Refuse (:class:`rik.errors.RikError`, one line naming ``folder``) to replace or remove ``folder`` unless
    nothing is there, it is an empty folder, or it is a ``kind`` folder rik made (:class:`MadeFolder`)."""
    from rik.errors import RikError

    folder = Path(folder)
    advice = f"{kind.advice}, or move or remove it yourself"
    if folder.name in ("", ".", "..") or Path.cwd().is_relative_to(folder.resolve()):
        raise RikError(f"{folder}: is the current folder or holds it, and rik writes {kind.what} as a folder of "
                       f"its own: name a new folder inside it")
    if not os.path.lexists(folder):
        return
    if folder.is_symlink() or not folder.is_dir():
        what = "a symbolic link" if folder.is_symlink() else "a file"
        raise RikError(f"{folder}: is {what}, not {kind.what}; rik replaces only folders it made: {advice}")
    try:
        names = sorted(e.name for e in os.scandir(folder))
    except OSError as exc:
        raise RikError(f"{folder}: cannot read this folder ({exc.strerror}); {advice}") from None
    if not names or kind.made(folder):
        return
    shown = ", ".join(names[:3]) + (f" and {len(names) - 3} more" if len(names) > 3 else "")
    raise RikError(f"{folder}: exists and is not {kind.what} (it holds {shown}); rik replaces only folders it made, "
                   f"so nothing was written: {advice}")


def check_own_files(folder: Path, names: Collection[str], made: Callable[[Path], bool], tool: str,
                    mark: str) -> None:
    """Refuse (:class:`rik.errors.RikError`, one line) to write the files ``names`` into ``folder`` when one of them
    is there and ``made(folder)`` does not recognise the folder as ``tool``'s earlier output (by ``mark``, the file
    it writes there): a rerun may write over its own results, never a user's file."""
    from rik.errors import RikError

    taken = [name for name in names if os.path.lexists(Path(folder) / name)]
    if taken and not made(Path(folder)):
        raise RikError(f"{Path(folder) / taken[0]}: exists and was not written by {tool} (no {mark} of its own beside "
                       "it), so nothing was run: choose another --out, or move it away yourself")

def remove_directory(folder: Path, kind: MadeFolder) -> None:
    """Remove ``folder`` (rik's own earlier output) if it is there: only after :func:`check_replaceable`."""
    import shutil

    check_replaceable(folder, kind)
    if os.path.lexists(folder):
        shutil.rmtree(folder)


def replace_directory(stage: Path, final: Path, kind: MadeFolder) -> None:
    """Move the finished directory ``stage`` onto ``final``, replacing what is there if rik made it (a ``kind``
    folder, :func:`check_replaceable`; anything else is refused and ``stage`` left for the caller): the old one is
    renamed aside first and removed after, so ``final`` is at every moment the old directory or the new one, whole."""
    import shutil

    check_replaceable(final, kind)
    if final.exists():
        old = final.with_name(f".{final.name}.old")
        shutil.rmtree(old, ignore_errors=True)
        os.replace(final, old)
        os.replace(stage, final)
        shutil.rmtree(old, ignore_errors=True)
    else:
        os.replace(stage, final)


@contextmanager
def staged_directory(final: Path, kind: MadeFolder) -> Iterator[Path]:
    """A fresh hidden sibling of ``final`` to write a whole directory into; moved onto ``final`` when the block
    ends without an error (:func:`replace_directory`), removed when it raises: ``final`` is never half-written.
    A ``final`` that rik did not make (``kind``) is refused before anything is written."""
    import shutil

    check_replaceable(final, kind)
    stage = final.with_name(f".{final.name}.partial")
    shutil.rmtree(stage, ignore_errors=True)
    stage.mkdir(parents=True)
    try:
        yield stage
        replace_directory(stage, final, kind)
    except BaseException:
        shutil.rmtree(stage, ignore_errors=True)
        raise


def json_sha256(data: Any, exclude: tuple[str, ...] = ()) -> str:
    """sha256 of the canonical JSON of ``data`` (sorted keys, no spaces), leaving out the top-level keys
    ``exclude`` (the checksum field of a file that seals itself, such as ``meta_sha256``)."""
    import hashlib
    import json

    if exclude:
        data = {k: v for k, v in data.items() if k not in exclude}
    return hashlib.sha256(json.dumps(data, sort_keys=True, separators=(",", ":")).encode()).hexdigest()


def write_atomic(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` through a temporary file and a rename (:func:`atomic_path`): never half-written."""
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")


def write_png(path: Path, pixels: np.ndarray, compress_level: int = 6) -> None:
    """Write an (H, W, 3) uint8 image as PNG through a temporary file and a rename (like :func:`write_atomic`)."""
    import numpy as np
    from PIL import Image

    with atomic_path(path) as tmp:
        Image.fromarray(np.ascontiguousarray(pixels, np.uint8)).save(tmp, format="PNG", compress_level=compress_level)


def pyplot() -> ModuleType:
    """matplotlib's pyplot on the headless Agg backend (imported on first use)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def save_figure(fig: Figure, path: Path, dpi: int = 120) -> Path:
    """Save a matplotlib figure as PNG (no timestamp metadata, so reruns are byte-identical) through a temporary
    file and a rename, and close it."""
    path.parent.mkdir(parents=True, exist_ok=True)
    try:
        with atomic_path(path) as tmp:
            fig.savefig(tmp, dpi=dpi, format="png", metadata={"Software": None})
    finally:
        pyplot().close(fig)
    return path


def read_meta_file(path: Path, model: type[BaseModel]) -> dict[str, Any]:
    """The JSON object in ``path``, checked against ``model`` (which says what rik reads of it); a file that cannot
    be read or is damaged raises a :class:`RikError` line naming the file and the field."""
    from pydantic import ValidationError

    from rik.errors import RikError

    try:
        data = read_json(path)
    except OSError as exc:
        raise RikError(f"{path}: cannot read it ({exc.strerror})") from None
    except ValueError as exc:  # too large, not UTF-8, not JSON, nested too deeply
        raise RikError(f"{path}: damaged: not the JSON rik wrote ({str(exc).splitlines()[0]})") from None
    if not isinstance(data, dict):
        raise RikError(f"{path}: damaged: holds a JSON {type(data).__name__}, not the object rik wrote")
    try:
        model.model_validate(data)
    except ValidationError as exc:
        first = exc.errors(include_url=False)[0]
        where = ".".join(str(p) for p in first["loc"])
        raise RikError(f"{path}, field '{where}': damaged: {first['msg'][0].lower()}{first['msg'][1:]}") from None
    return data
