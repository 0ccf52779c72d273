"""The type checker passes over rik/ (mypy, configured in pyproject.toml's [tool.mypy])."""

from __future__ import annotations

import os
import subprocess
import sys

from conftest import REPO


def test_mypy_passes_on_rik() -> None:
    # --cache-dir to the null device: mypy keeps no cache, so the check writes nothing (in the tree or elsewhere)
    run = subprocess.run([sys.executable, "-m", "mypy", "--cache-dir", os.devnull], cwd=REPO, capture_output=True,
                         text=True, timeout=900)
    assert run.returncode == 0, f"mypy found type errors (exit {run.returncode}):\n{run.stdout}{run.stderr}"
