"""scripts/policy_experiment.sh runs as committed: its first stage (the demonstrations, from the specs of
examples/policies) at a reduced size, in a folder of its own.

The draw starts at seed 378 (``SEED``): seeds 378 and 379 of the train split draw drawers with the knob
``knob-mushroom-30``, whose collision the suite builds anyway (``knob_recording``), so the test adds recording and
export, not a new handle's CoACD decomposition (about 4 CPU-minutes each)."""

from __future__ import annotations

import json
import os
import subprocess
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow  # end-to-end runs: out of the everyday tier (-m "not slow")

ROOT = Path(__file__).parents[1]
DATASETS = ("pl", "pl-quarter", "hull", "cm")


def test_the_experiments_data_stage_builds_every_data_set(tmp_path: Path) -> None:
    # the handle-frame exports (plh, plah) and the data sets of planned_above, planned_typed and DART noise (pla,
    # plt, pln) are made by the same steps as cm and pl from specs test_example_specs loads: left out to save the
    # suite an export and a recording each (about 6 CPU-s: lerobot's import in a fresh process)
    # JOBS=2: the data sets after the first are built two at a time, as the reduced size runs them
    env = {**os.environ, "STAGES": "data", "DEMOS": "2", "SEED": "378", "WORKERS": "1", "JOBS": "2",
           "DATASETS": " ".join(DATASETS)}
    r = subprocess.run(["bash", str(ROOT / "scripts" / "policy_experiment.sh"), str(tmp_path / "exp")], cwd=ROOT,
                       env=env, capture_output=True, text=True, timeout=900)
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    exp = tmp_path / "exp"
    episodes = {name: json.loads((exp / f"ds-{name}" / "meta" / "info.json").read_text())["total_episodes"]
                for name in DATASETS}
    assert episodes == {"pl": 2, "pl-quarter": 1, "hull": 2, "cm": 2}
    # the specs the stage built from are examples/policies' own, with the reduced draw and the first seed
    spec = (exp / "specs" / "pl.yaml").read_text()
    assert "  draw: 2 " in spec and "\nseed: 378\n" in spec
    assert "2 drawn episodes (" in r.stdout and "seeds 378..379" in r.stdout  # the build's plan, as drawn
    assert json.loads((exp / "variants-hull" / "collision.json").read_text())["collision"] == "hull"


def test_a_step_that_fails_beside_others_stops_the_experiment(tmp_path: Path) -> None:
    # the evaluation stage of a folder with no trainings: its first phase (the weight means, two at a time) fails
    # in every step; the script must stop there with an error, not go on to evaluate
    env = {**os.environ, "STAGES": "eval", "JOBS": "2"}
    r = subprocess.run(["bash", str(ROOT / "scripts" / "policy_experiment.sh"), str(tmp_path / "exp")], cwd=ROOT,
                       env=env, capture_output=True, text=True, timeout=600)
    assert r.returncode == 1
    assert "policy_experiment.sh: a step failed (see the logs in " in r.stderr
    assert "no checkpoints/ folder here" in r.stderr
    assert not (tmp_path / "exp" / "eval").exists()
