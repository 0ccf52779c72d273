"""A user's own doors take rik's path: their profiles -> a preset in their catalog -> the simulator's force error
against their held-out openings -> drawn as measured joints; nothing of rik's own files rewritten."""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from rik.episodes.draw import Draw
from rik.registry.load import load_catalog

ROOT = Path(__file__).resolve().parents[1]


def _profiles(path: Path, nan: bool = False) -> Path:
    """Four openings of one door in the study's CSV format: 3 N of friction and a 12 N catch falling over 3 degrees,
    with noise (seeded)."""
    rng = np.random.default_rng(1)
    rows = ["trial,mechanism,class,angle bin,force [N]"]
    for trial in range(4):
        for degree in range(60):
            force = 3.0 + 12.0 / (1 + math.radians(degree) / math.radians(3)) ** 2 + rng.normal(0, 0.2)
            rows.append(f"{trial},my_pantry,Cabinet,{degree},{'nan' if nan and degree == 7 else f'{force:.4f}'}")
    path.write_text("\n".join(rows) + "\n")
    return path


def _script(name: str, *args: str | Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, str(ROOT / "scripts" / name), *map(str, args)], capture_output=True,
                          text=True, timeout=600, cwd=ROOT)


@pytest.mark.slow
def test_a_users_doors_become_presets_measured_against_their_held_out_openings(tmp_path: Path) -> None:
    data = _profiles(tmp_path / "my-doors.csv")
    mine = tmp_path / "mine.yaml"
    made = _script("real_door_presets.py", data, "--out", mine)
    assert made.returncode == 0, made.stderr
    catalog = load_catalog([mine])
    preset = catalog.presets["real-my-pantry"]
    assert preset.hinge.mechanism() == "catch" and preset.source.data == "my-doors.csv"
    assert "Jain" not in preset.description and catalog.preset_splits["real-my-pantry"] == "train"
    assert abs(preset.hinge.frictionloss / 0.40 - 3.0) < 0.3  # the fit finds the 3 N of friction
    assert "real-my-pantry" in Draw("train", kinds=("door",), joints="measured").door_presets(catalog)
    error = _script("real_door_sim_error.py", data, "--catalog", mine, "--variants", tmp_path / "variants",
                    "--table", tmp_path / "error.md")
    assert error.returncode == 0, error.stderr
    row = next(line for line in (tmp_path / "error.md").read_text().splitlines() if line.startswith("| my_pantry"))
    paper_rms, fitted_rms = float(row.split("|")[5]), float(row.split("|")[7])
    assert fitted_rms < 0.5 < paper_rms  # the door's own preset against the nearest paper preset, held out
    again = _script("real_door_presets.py", data, "--out", mine)  # its own file: written again
    assert again.returncode == 0, again.stderr


@pytest.mark.slow
def test_a_users_door_file_is_checked_and_nothing_else_is_overwritten(tmp_path: Path) -> None:
    data = _profiles(tmp_path / "my-doors.csv")
    theirs = tmp_path / "notes.yaml"
    theirs.write_text("my own notes\n")
    refused = _script("real_door_presets.py", data, "--out", theirs)
    assert refused.returncode == 2 and theirs.read_text() == "my own notes\n"
    assert refused.stderr.count("\n") == 1 and "exists and is not a presets file this script wrote" in refused.stderr
    unknown = _script("real_door_sim_error.py", data, "--variants", tmp_path / "variants")  # without --catalog
    assert unknown.returncode == 2 and unknown.stderr.strip().endswith(
        "write the doors' presets with scripts/real_door_presets.py DATA.csv --out FILE and give the file with "
        "--catalog (rik's own doors: regenerate rik/registry/data/presets_measured.yaml)")


@pytest.mark.slow
def test_nan_in_a_users_profiles_is_one_line(tmp_path: Path) -> None:
    bad = _script("real_door_presets.py", _profiles(tmp_path / "bad.csv", nan=True), "--out", tmp_path / "m.yaml")
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1 and "bad.csv" in bad.stderr
    assert not (tmp_path / "m.yaml").exists()


@pytest.mark.slow
def test_a_pipe_for_profiles_is_one_line_not_a_blocked_read(tmp_path: Path) -> None:
    import os

    os.mkfifo(tmp_path / "pipe.csv")
    bad = _script("real_door_presets.py", tmp_path / "pipe.csv", "--out", tmp_path / "m.yaml")
    assert bad.returncode == 2 and bad.stderr == (f"real_door_presets: error: {tmp_path / 'pipe.csv'}: not a regular "
                                                  "file (a folder, a pipe or a device)\n")


@pytest.mark.slow
@pytest.mark.parametrize("text", ["", "trial,mechanism\n0,x\n", "\x00\x01binary"])
def test_a_malformed_profiles_file_is_one_line(tmp_path: Path, text: str) -> None:
    (tmp_path / "p.csv").write_text(text)
    bad = _script("real_door_presets.py", tmp_path / "p.csv", "--out", tmp_path / "m.yaml")
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1 and "p.csv" in bad.stderr
    assert not (tmp_path / "m.yaml").exists()
