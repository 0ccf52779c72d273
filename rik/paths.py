"""Where rik keeps files of its own (the cache directory), and how it writes files: atomically."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any


def cache_dir() -> Path:
    """``$RIK_CACHE``, else ``$XDG_CACHE_HOME/rik``, else ``~/.cache/rik``."""
    if env := os.environ.get("RIK_CACHE"):
        return Path(env).expanduser()
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "rik"


def write_atomic(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` through a temporary file and a rename: never half-written, and two processes
    writing the same file do not share a temporary."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    tmp.write_text(text, encoding="utf-8")
    os.replace(tmp, path)


def write_png(path: Path, pixels: Any, compress_level: int = 6) -> None:
    """Write an (H, W, 3) uint8 image as PNG through a temporary file and a rename (like :func:`write_atomic`)."""
    import numpy as np
    from PIL import Image

    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    Image.fromarray(np.ascontiguousarray(pixels, np.uint8)).save(tmp, format="PNG", compress_level=compress_level)
    os.replace(tmp, path)


def pyplot() -> Any:
    """matplotlib's pyplot on the headless Agg backend (imported on first use)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def save_figure(fig: Any, path: Path, dpi: int = 120) -> Path:
    """Save a matplotlib figure as PNG (no timestamp metadata, so reruns are byte-identical) through a temporary
    file and a rename, and close it."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    fig.savefig(tmp, dpi=dpi, format="png", metadata={"Software": None})
    pyplot().close(fig)
    os.replace(tmp, path)
    return path
