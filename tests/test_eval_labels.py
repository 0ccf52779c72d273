"""``rik eval A B --out OUT`` writes each operator into a folder of OUT named by its label: a label is made into a
plain folder name of its own, or refused (one line naming the labels, exit 2) before any evaluation: two labels never
share a folder (``run:1`` and ``run/1`` both became ``run-1``), ``.`` is not OUT itself (the side-by-side table
overwrote that policy's), ``..`` not the folder above it."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

DRAW = ("--types", "knob", "--presets", "smooth", "-n", "1", "--videos", "0", "--workers", "1",
        "--episode-length", "5")
OPERATORS = ("strategy:contact_rich", "strategy:grasp_vertical")


def _refused(rik, tmp_path: Path, *args: str) -> str:
    """``rik eval ARGS`` into ``tmp_path/out``: exit 2, one line, nothing written; returns the line."""
    out, variants = tmp_path / "out", tmp_path / "variants"
    r = rik("eval", *args, *DRAW, "--out", str(out), "--variants", str(variants))
    lines = r.err.strip().splitlines()
    assert r.code == 2 and len(lines) == 1 and "Traceback" not in r.err, r.err[-3000:]
    assert not out.exists() and not variants.exists() and not (tmp_path / "table.md").exists()
    return lines[0].removeprefix("rik: error: ")


@pytest.mark.parametrize(("first", "second", "folder"), [
    ("run:1", "run/1", "run-1"),
    ("a b", "a\tb", "a-b"),
    ("mine", "mine", "mine"),
    ("x\x00y", "x?y", "x-y"),
])
def test_labels_that_make_one_folder_are_refused(rik, tmp_path: Path, first: str, second: str, folder: str) -> None:
    msg = _refused(rik, tmp_path, *OPERATORS, "--label", first, "--label", second)
    assert msg == (f"labels {first!r} and {second!r} would share the folder {tmp_path / 'out' / folder} (characters "
                   "other than letters, digits, '-', '_' and '.' become '-'): give the policies labels that differ "
                   "there (--label), or each its own --out")


@pytest.mark.parametrize("label", [".", "..", "table.md", "videos", "x" * 256])
def test_label_that_is_no_folder_of_its_own_is_refused(rik, tmp_path: Path, label: str) -> None:
    """``.`` would be OUT itself (the side-by-side table.md over the policy's), ``..`` the folder above OUT,
    ``table.md`` a folder where the table goes; a name over 255 bytes no file system takes."""
    msg = _refused(rik, tmp_path, *OPERATORS, "--label", "gv", "--label", label)
    assert msg.startswith(f"label {label!r}: its folder in {tmp_path / 'out'} would be {label!r}, which is not a "
                          "folder of its own (not empty, '.', '..', table.md, "), msg


def test_labels_that_differ_in_case_are_two_folders() -> None:
    """Compared as written: ``Run`` and ``run`` are two folders (on a case-insensitive file system they would be
    one, which rik does not guess)."""
    from rik.evaluation.evaluate import label_folders

    assert label_folders(Path("out"), ["Run", "run", "act:x.y", "ü"]) == ["Run", "run", "act-x.y", "ü"]


@pytest.fixture(scope="module")
def tiny_policy(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A tiny state-only ACT policy for the Hand-E, saved by LeRobot with its processors."""
    from shared import tiny_act

    return tiny_act(tmp_path_factory.mktemp("tiny") / "policy")


def test_default_labels_of_two_policies_that_make_one_folder_are_refused(rik, tiny_policy: Path,
                                                                          tmp_path: Path) -> None:
    """Policies named by their type and run folder, ``act:run:1`` and ``act:run?1``: both would be ``act-run-1``."""
    a, b = tmp_path / "run:1", tmp_path / "run?1"
    shutil.copytree(tiny_policy, a)
    shutil.copytree(tiny_policy, b)
    msg = _refused(rik, tmp_path, str(a), str(b))
    assert msg.startswith(f"labels 'act:run:1' and 'act:run?1' would share the folder {tmp_path / 'out' / 'act-run-1'} "
                          "("), msg
