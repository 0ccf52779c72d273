"""Where rik keeps files of its own (the cache directory), paths checked to stay inside their folder, and bounded
reads of the JSON files rik reads. How rik writes is :mod:`rik.outputs`."""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from types import ModuleType

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


def json_sha256(data: Any, exclude: tuple[str, ...] = ()) -> str:
    """sha256 of the canonical JSON of ``data`` (sorted keys, no spaces), leaving out the top-level keys
    ``exclude`` (the checksum field of a file that seals itself, such as ``meta_sha256``)."""
    import hashlib
    import json

    if exclude:
        data = {k: v for k, v in data.items() if k not in exclude}
    return hashlib.sha256(json.dumps(data, sort_keys=True, separators=(",", ":")).encode()).hexdigest()


def pyplot() -> ModuleType:
    """matplotlib's pyplot on the headless Agg backend (imported on first use)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


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
