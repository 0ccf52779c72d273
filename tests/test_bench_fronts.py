"""``rik bench`` over every front kind: doors on the paper's presets and on real doors' on the same draws,
Table 3 per front layout, and why each miss missed."""

from __future__ import annotations

import csv
from pathlib import Path

import pytest
from shared import builtin_catalog

from rik.benchmark.bench import MISS_REASONS, layout_tables, miss_reason, plan_tasks
from rik.errors import RikError


def test_measured_tasks_are_the_paper_tasks_with_real_hinges() -> None:
    catalog = builtin_catalog()
    kw = dict(types=["knob", "two_point"], presets=["normal"], strategies=["grasp_vertical", "planned"], per_cell=4,
              kinds=["drawer", "door", "flap"])
    paper, measured = plan_tasks(catalog, **kw), plan_tasks(catalog, **kw, joints="measured")
    assert len(paper) == len(measured) == 16
    for a, b in zip(paper, measured, strict=True):
        assert (a.seed, a.front, a.strategy) == (b.seed, b.front, b.strategy)
        base_a, preset_b = a.variant.rsplit("__", 1)[0], b.variant.rsplit("__", 1)[1]
        assert b.variant.startswith(base_a + "__")
        assert preset_b in catalog.preset_splits if a.variant.startswith("door-") else preset_b == "normal"
    with pytest.raises(RikError, match="real doors' presets go on doors"):
        plan_tasks(catalog, kinds=["drawer", "flap"], joints="measured")
    with pytest.raises(RikError, match=r"unknown front kind 'doors' \(kinds: door, drawer, flap\)"):
        plan_tasks(catalog, kinds=["doors"])


@pytest.mark.parametrize(("row", "reason"), [
    ({"outcome": "S", "log": "attempt 1: pinch | opened 95%"}, ""),
    ({"outcome": "F", "log": "no grasp found"}, "no grasp found"),
    ({"outcome": "P", "log": "attempt 1: hook below | slip at 40% open | attempt 2: pinch | no grasp found"},
     "no grasp found"),
    ({"outcome": "F", "log": "attempt 1: pinch | slip at 0% open"}, "slipped"),
    ({"outcome": "P", "log": "attempt 1: pinch | stall at 30% open"}, "stalled"),
    ({"outcome": "F", "log": "attempt 1: pinch", "seconds": 30.0}, "time out, lost"),
    ({"outcome": "P", "log": "attempt 1: pinch", "seconds": 30.0, "held_at_end": True}, "time out, held"),
    ({"outcome": "F", "log": "attempt 1: pinch", "seconds": 12.0}, "stopped early"),
    ({"outcome": "P", "log": "attempt 1: pinch", "reachable_opening": 0.6}, "out of reach"),
])
def test_miss_reasons(row: dict, reason: str) -> None:
    assert miss_reason(row) == reason and (reason == "" or reason in MISS_REASONS)


@pytest.mark.slow
def test_bench_over_a_door_with_a_real_hinge_tables_it_per_layout(rik, tmp_path: Path) -> None:
    """One knob on a door per preset and joints: results.csv names the real door and the front's layout; table.md
    has a section per layout with a measured column and the misses' reasons."""
    out = tmp_path / "bench"
    r = rik("bench", "-n", "1", "-t", "knob", "--presets", "normal", "--kinds", "door", "--joints", "measured",
            "--strategies", "grasp_vertical", "--workers", "1", "--variants", str(tmp_path / "variants"),
            "--out", str(out))
    assert r.code == 0, r.err
    (row,) = list(csv.DictReader((out / "results.csv").open()))
    assert row["preset"] in builtin_catalog().preset_splits and row["cell_preset"] == "normal"
    assert row["joints"] == "measured" and row["front_layout"] in ("door-left", "door-right")
    assert row["miss"] == miss_reason({**row, "seconds": float(row["seconds"]),
                                       "reachable_opening": float(row["reachable_opening"])})
    assert row["held_at_end"] in ("True", "False")
    table = (out / "table.md").read_text()
    assert f"### {row['front_layout']} (1 episodes)" in table and "measured F | measured P | measured S" in table
    assert ("No misses." in table) == (row["outcome"] == "S")
    r = rik("bench", "--kinds", "drawer", "--joints", "measured", "--out", str(tmp_path / "no"))
    assert r.code == 2 and r.err.startswith("rik: error: joints 'measured': real doors' presets go on doors")
    assert not (tmp_path / "no").exists()


def test_layout_tables_keep_the_paper_columns_apart_from_the_measured() -> None:
    rows = [{"handle_type": "knob", "strategy": "planned", "preset": p, "joints": j, "front_layout": lay,
             "outcome": o, "miss": m}
            for p, j, lay, o, m in [("high", "paper", "door-left", "S", ""),
                                    ("real-hai-freezer", "measured", "door-left", "F", "slipped"),
                                    ("smooth", "paper", "drawer", "S", "")]]
    table = layout_tables(rows, ["smooth", "normal", "high"])
    assert table.index("### drawer") < table.index("### door-left")
    door = table[table.index("### door-left"):]
    assert "| planned | 0.00 | 0.00 | 1.00 | 1.00 | 0.00 | 0.00 | 1 |" in door  # high S, measured F
    assert "| planned | measured |  | 1 |" in door
    summary = table[:table.index("### drawer")]
    assert "| strategy | drawer | door-left | door-left (real doors) |" in summary
    assert "| planned | 1/1: 100% [21%, 100%] | 1/1: 100% [21%, 100%] | 0/1: 0% [0%, 79%] |" in summary
