"""Where rik keeps files of its own: the cache directory."""

from __future__ import annotations

import os
from pathlib import Path


def cache_dir() -> Path:
    """``$RIK_CACHE``, else ``$XDG_CACHE_HOME/rik``, else ``~/.cache/rik``."""
    if env := os.environ.get("RIK_CACHE"):
        return Path(env).expanduser()
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "rik"
