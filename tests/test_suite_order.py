"""The suite's own scheduling (tests/conftest.py): the files that run in one row on one xdist worker are exactly
the files with tests that drive a browser or a window, so a new such file joins them and a file that stops
waiting on a person's pace leaves them."""

from __future__ import annotations

import re

from conftest import PACED_FILES, REPO

MARK = re.compile(r"pytest\.mark\.(browser|display)\b")


def test_the_paced_files_are_those_with_browser_or_display_tests() -> None:
    marked = {p.name for p in (REPO / "tests").glob("test_*.py") if MARK.search(p.read_text(encoding="utf-8"))}
    assert marked == set(PACED_FILES), (sorted(marked - PACED_FILES), sorted(PACED_FILES - marked))
