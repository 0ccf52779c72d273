"""A dataset whose state dimensions never change (one variant: the handle's pose is one number) says so: the
export and the build print a warning naming them, and the card explains what it does to normalisation."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

from rik.exporters.lerobot_check import CONSTANT_STD, constant_dimensions


def test_an_export_of_one_variant_names_its_constant_dimensions(rik, knob_recording: Path, tmp_path: Path) -> None:
    shutil.copytree(knob_recording, tmp_path / "in")
    out = tmp_path / "ds"
    r = rik("export-lerobot", str(tmp_path / "in" / "episodes"), "--out", str(out), "--repo-id", "local/one",
            "--streams", "none", "--variants", str(tmp_path / "in" / "variants"))
    assert r.code == 0, r
    constant = constant_dimensions(out)
    # the handle's grasp point, orientation and pull direction are fixed on one variant
    assert {"grasp_x", "grasp_z", "pull_y"} <= set(constant["observation.environment_state"])
    line = next(ln for ln in r.out.splitlines() if ln.startswith("warning: "))
    assert " never change in this dataset (" in line and "observation.environment_state: " in line and "grasp_x" in line
    assert line.endswith("(train on data where they vary, more variants or front kinds, or leave those dimensions out)")
    stats = json.loads((out / "meta" / "stats.json").read_text(encoding="utf-8"))
    std = stats["observation.environment_state"]["std"]
    names = json.loads((out / "meta" / "info.json").read_text(encoding="utf-8"))["features"][
        "observation.environment_state"]["names"]
    assert [n for n, s in zip(names, std, strict=True) if s < CONSTANT_STD] == constant["observation.environment_state"]
    card = (out / "README.md").read_text(encoding="utf-8")
    assert "**Constant dimensions**" in card and "`grasp_x`" in card
