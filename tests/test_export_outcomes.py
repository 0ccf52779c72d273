"""Exporting only some outcomes: ``rik export-lerobot --outcomes S`` and a dataset spec's ``outcomes: [S]`` keep the
successful demonstrations (every episode is still recorded and counted); an export left with nothing is one line."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
from shared import BOW

SPEC = f"""repo_id: local/rik-outcomes
variants:
  ids: [{BOW}]
operators:
  - strategy: planned
episodes_per_variant: 2
max_seconds: 0.5
streams: []
shard_episodes: 1
"""


def test_export_outcomes_keeps_the_chosen_episodes_and_refuses_none(rik, knob_recording: Path, tmp_path: Path) -> None:
    shutil.copytree(knob_recording, tmp_path / "in")
    episodes, variants = tmp_path / "in" / "episodes", tmp_path / "in" / "variants"
    r = rik("export-lerobot", str(episodes), "--out", str(tmp_path / "s"), "--repo-id", "local/s", "--streams",
            "none", "--outcomes", "S", "--variants", str(variants))
    assert r.code == 2 and r.err.strip() == (f"rik: error: {episodes}: none of the 1 episodes has outcome S (they are "
                                             "F 1): nothing to export")
    assert not (tmp_path / "s").exists() and not (tmp_path / "s.partial").exists()
    r = rik("export-lerobot", str(episodes), "--out", str(tmp_path / "x"), "--repo-id", "local/x", "--streams",
            "none", "--outcomes", "S,X", "--variants", str(variants))
    assert r.code == 2 and r.err.strip() == ("rik: error: --outcomes S,X: give some of F, P, S (failed, partly "
                                             "opened, succeeded), comma-separated; 'X' is none of them")
    r = rik("export-lerobot", str(episodes), "--out", str(tmp_path / "f"), "--repo-id", "local/f", "--streams",
            "none", "--outcomes", "f,p", "--variants", str(variants))
    assert r.code == 0, r
    assert json.loads((tmp_path / "f" / "meta" / "info.json").read_text(encoding="utf-8"))["total_episodes"] == 1


def test_a_spec_keeps_its_outcomes_and_refuses_a_build_left_empty(rik, bow_variants: Path, tmp_path: Path) -> None:
    from rik.dataset.spec import load_spec, spec_hash

    variants = tmp_path / "variants"
    shutil.copytree(bow_variants, variants)
    every = tmp_path / "every.yaml"
    every.write_text(SPEC)
    listed = tmp_path / "listed.yaml"
    listed.write_text(SPEC + "outcomes: [F, P, S]\n")
    assert spec_hash(load_spec(every)) == spec_hash(load_spec(listed))  # the default hashes as before
    only_s = tmp_path / "s.yaml"
    only_s.write_text(SPEC + "outcomes: [S]\n")
    r = rik("dataset", "build", str(only_s), "--out", str(tmp_path / "ds-s"), "-j", "1", "--variants", str(variants))
    assert r.code == 2 and r.err.strip() == ("rik: error: no episode of the build has outcome S (outcomes: F 2); "
                                             "nothing to publish: record more episodes, or widen the spec's outcomes")
    assert not (tmp_path / "ds-s").exists()



@pytest.mark.slow
def test_a_spec_with_outcomes_s_publishes_only_the_successful_episode(rik, bow_variants: Path, tmp_path: Path) -> None:
    """A pinch that opens the drawer (S) and a demonstrator drowned in action noise (F), one shard each: the
    dataset holds the first; the build still records and counts both."""
    variants = tmp_path / "variants"
    shutil.copytree(bow_variants, variants)
    spec = tmp_path / "mixed.yaml"
    spec.write_text(f"""repo_id: local/rik-mixed
variants:
  ids: [{BOW}]
operators:
  - strategy: grasp_vertical
  - strategy: planned
    name: drowned
    action_noise: 0.05
max_seconds: 10
streams: []
shard_episodes: 1
outcomes: [S]
""")
    r = rik("dataset", "build", str(spec), "--out", str(tmp_path / "ds"), "-j", "1", "--variants", str(variants))
    assert r.code == 0, r
    assert "1 episodes" in r.out and "(outcomes F 1, S 1)" in r.out
    import pyarrow.parquet as pq

    info = json.loads((tmp_path / "ds" / "meta" / "info.json").read_text(encoding="utf-8"))
    assert info["total_episodes"] == 1
    [episodes] = list((tmp_path / "ds" / "meta" / "episodes").rglob("*.parquet"))
    assert pq.read_table(episodes).column("rik/outcome").to_pylist() == ["S"]
