"""Where rik keeps files of its own (the cache directory), and how it writes files: atomically."""

from __future__ import annotations

import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from types import ModuleType

    import numpy as np
    from matplotlib.figure import Figure


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


def replace_directory(stage: Path, final: Path) -> None:
    """Move the finished directory ``stage`` onto ``final``, replacing what is there: the old one is renamed
    aside first and removed after, so ``final`` is at every moment the old directory or the new one, whole."""
    import shutil

    if final.exists():
        old = final.with_name(f".{final.name}.old")
        shutil.rmtree(old, ignore_errors=True)
        os.replace(final, old)
        os.replace(stage, final)
        shutil.rmtree(old, ignore_errors=True)
    else:
        os.replace(stage, final)


@contextmanager
def staged_directory(final: Path) -> Iterator[Path]:
    """A fresh hidden sibling of ``final`` to write a whole directory into; moved onto ``final`` when the block
    ends without an error (:func:`replace_directory`), removed when it raises: ``final`` is never half-written."""
    import shutil

    stage = final.with_name(f".{final.name}.partial")
    shutil.rmtree(stage, ignore_errors=True)
    stage.mkdir(parents=True)
    try:
        yield stage
        replace_directory(stage, final)
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
