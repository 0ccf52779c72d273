"""The joints ablation's analysis, fixed before its results: Newcombe's interval, the seeds-and-handles interval
and scripts/joints_report.py on evaluation folders laid out as the ablation's test stage writes them."""

from __future__ import annotations

import csv
import importlib.util
from pathlib import Path

import pytest

from rik.tables import newcombe, seed_handle_interval

ROOT = Path(__file__).resolve().parents[1]


def test_newcombe_matches_the_published_example() -> None:
    """Newcombe (1998), example (a): 56/70 against 48/80, method 10: 0.0524 to 0.3339."""
    low, high = newcombe(56, 70, 48, 80)
    assert (round(low, 4), round(high, 4)) == (0.0524, 0.3339)
    assert newcombe(0, 10, 0, 10)[0] < 0 < newcombe(0, 10, 0, 10)[1]


def test_the_seed_and_handle_interval_is_wider_than_the_episodes_say() -> None:
    # two seeds that disagree and handles that differ: the rate depends on which are drawn
    handles = [f"h{i // 10}" for i in range(40)]
    success = [[i < 30 for i in range(40)], [i < 10 for i in range(40)]]
    low, high = seed_handle_interval(success, handles, resamples=2000)
    assert (low, high) == seed_handle_interval(success, handles, resamples=2000)  # deterministic
    assert low < 0.35 and high > 0.65
    assert seed_handle_interval([[True] * 6] * 3, ["a", "a", "b", "b", "c", "c"], resamples=200) == (1.0, 1.0)


def _episodes(path: Path, outcomes: list[str]) -> None:
    rows = [("door-base-60-left__knob-mushroom-30__real-hai-freezer", "door"),
            ("drawer-chest-80__two_point-bow-128__normal", "drawer-1"),
            ("door-double-80__knob-mushroom-30__real-hai-freezer", "door-right"),
            ("flap-lift-up-60__knob-mushroom-30__normal", "door")]
    path.parent.mkdir(parents=True)
    with path.open("w", newline="") as handle:
        out = csv.writer(handle)
        out.writerow(["seed", "variant", "front", "outcome", "final_opening", "max_opening"])
        for i, ((variant, front), outcome) in enumerate(zip(rows, outcomes, strict=True)):
            final, peak = {"S": (0.95, 0.95), "P": (0.3, 0.32), "F": (0.01, 0.4)}[outcome]  # F: it fell back
            out.writerow([1000 + i, variant, front, outcome, final, peak])


def test_the_report_computes_the_planned_comparison(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    spec = importlib.util.spec_from_file_location("joints_report", ROOT / "scripts" / "joints_report.py")
    report = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(report)
    assert report.main([str(tmp_path)]) == 2  # no choice yet: nothing to report
    (tmp_path / "chosen.txt").write_text("mean\n")
    # arm (a) opens no door on the measured draw, arm (b) both in each seed; the paper draw: all of them
    for draw in ("measured", "paper"):
        for seed in (0, 1):
            _episodes(tmp_path / f"eval/test/mean-{draw}/act-jp-s{seed}-mean/episodes.csv",
                      ["F", "S", "F", "S"] if draw == "measured" else ["S"] * 4)
            _episodes(tmp_path / f"eval/test/mean-{draw}/act-jm-s{seed}-mean/episodes.csv", ["S"] * 4)
    assert report.main([str(tmp_path), "--out", str(tmp_path / "report.md")]) == 0
    text = (tmp_path / "report.md").read_text()
    assert "| (a) paper presets in training | 2 | 4 of 8: 50% [22%, 78%] | 50%, 50% |" in text
    assert "| 2/2 | 0/2 | 0/2 | 2/2 | - |" in text  # (a) on the measured draw: drawer, door-left, door-right, lift-up
    assert ("Doors of the measured test draw: (a) 0 of 4: 0% [0%, 49%], (b) 4 of 4: 100% [51%, 100%]; difference "
            "(b) - (a) +100%") in text and "paired by training seed: +100%, +100%" in text
    # the misses on the real doors (both are a catch: the freezer of the test split), each one that fell back
    assert "| (a) paper presets in training | catch | 4 | 0 | 4 | 0 | 0 |" in text
    assert "| (b) real doors in training | catch | 4 | 4 | 0 | 0 | 0 |" in text
    assert "| (a) paper presets in training | self-closing | 0 | 0 | 0 | 0 | 0 |" in text
    assert "| (a) paper presets in training | door-left | 2 | 0 | 2 | 0 | 0 |" in text  # per layout, every kind
    assert "| (b) real doors in training | flap-lift-up | 2 | 2 | 0 | 0 | 0 |" in text
    assert [report.miss({"outcome": o, "final_opening": str(f), "max_opening": str(m)})
            for o, f, m in (("P", 0.5, 0.55), ("F", 0.0, 0.04), ("P", 0.2, 0.3), ("F", 0.01, 0.11))] == [
        "stalled", "never opened", "fell back", "fell back"]


def test_the_validation_table_sums_what_the_rule_counts(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Each run's candidates on both draws, and each candidate's sum over runs and draws; a run not yet evaluated
    shows as missing, and no choice is claimed before chosen.txt."""
    spec = importlib.util.spec_from_file_location("joints_report", ROOT / "scripts" / "joints_report.py")
    report = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(report)
    for run, outcomes in (("act-jp-s0", ["S", "S", "F", "P"]), ("act-jm-s0", ["S", "F", "F", "F"])):
        for candidate in ("mean", "40000"):
            for draw in ("measured", "paper"):
                _episodes(tmp_path / f"eval/val/{candidate}-{draw}/{run}-{candidate}/episodes.csv", outcomes)
    _episodes(tmp_path / "eval/val/mean-paper/act-jp-s1-mean/episodes.csv", ["S"] * 4)
    assert report.main([str(tmp_path), "--validation", "--out", str(tmp_path / "val.md")]) == 0
    text = (tmp_path / "val.md").read_text()
    assert "| act-jp-s0 | 2/4 | 2/4 | 2/4 | 2/4 |" in text and "| act-jm-s0 | 1/4 | 1/4 | 1/4 | 1/4 |" in text
    assert "| act-jp-s1 | - | 4/4 | - | - |" in text
    assert "| mean | 10/20 | 5 |" in text and "| 40000 | 6/16 | 4 |" in text and "No choice yet" in text
    (tmp_path / "chosen.txt").write_text("mean\n")
    assert report.main([str(tmp_path), "--validation"]) == 0
    assert "Chosen: `mean`" in capsys.readouterr().out
