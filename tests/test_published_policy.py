"""The published policy (issue 53): the joints ablation's policy trained on every front with the train split's real
doors, chosen on the validation split and copied into the repository by ``scripts/joints_ablation.sh``'s publish
stage (docs/policies.md). From a fresh clone it loads and runs an episode of ``rik eval``; its folder holds weights,
not a training run's state.

Until the ablation's publish stage has run there is no folder, and the test says so (skipped)."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
PUBLISHED = REPO / "docs" / "policies" / "joints" / "best"
FILES = {"config.json", "model.safetensors", "policy_preprocessor.json", "policy_postprocessor.json",
         "rik_policy_io.json", "SOURCE.txt"}
"""What the publish stage copies (besides the processors' statistics): no optimizer state, no training config."""
MAX_BYTES = 20_000_000
"""A state-only ACT's weights are about 7.5 MB; more means something else was copied."""

pytestmark = [pytest.mark.slow,
              pytest.mark.skipif(not PUBLISHED.is_dir(), reason="no published policy yet (docs/policies/joints/best: "
                                 "the joints ablation's publish stage, issue 53)")]


def test_the_published_folder_holds_weights_and_the_contract_only() -> None:
    names = {p.name for p in PUBLISHED.iterdir()}
    assert FILES <= names, FILES - names
    assert not {"optimizer_state.safetensors", "training_state", "train_config.json"} & names
    assert sum(p.stat().st_size for p in PUBLISHED.iterdir()) < MAX_BYTES
    io = json.loads((PUBLISHED / "rik_policy_io.json").read_text(encoding="utf-8"))
    assert io["streams"] == [] and io["robot"] == "hand-e"  # state only, the Hand-E: runs on a CPU
    assert "act-jm-s" in (PUBLISHED / "SOURCE.txt").read_text(encoding="utf-8")


def test_the_published_policy_runs_an_episode_of_rik_eval(rik, bow_variants: Path, tmp_path: Path) -> None:
    """One short episode on the suite's bow drawer (the train split's draw of seed 22 with these options), whose
    variant the suite has built: no decomposition to wait for."""
    import shutil

    from shared import BOW

    out, variants = tmp_path / "eval", tmp_path / "variants"
    shutil.copytree(bow_variants, variants)
    r = rik("eval", str(PUBLISHED), "--split", "train", "--kinds", "drawer", "--types", "two_point", "--presets",
            "normal", "--seed", "22", "-n", "1", "--episode-length", "30", "--videos", "0", "--workers", "1",
            "--out", str(out), "--variants", str(variants))
    assert r.code == 0, r.out + r.err
    (episodes,) = out.rglob("episodes.csv")
    rows = list(csv.DictReader(episodes.open(encoding="utf-8")))
    assert len(rows) == 1 and rows[0]["outcome"] in {"S", "P", "F"} and rows[0]["variant"] == BOW
