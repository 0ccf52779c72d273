"""Count an arm's bench misses by their first reason (docs/benchmark.md, "Why the SO arms miss").

    uv run python scripts/bench_miss_reasons.py docs/bench/robots/so101/results.csv [--variants variants]

Every P and F row of a `rik bench --robot` results.csv gets the first of four reasons that applies, in this order:
reach (the row's reachable_opening, from the arm's reach profile, is below S's opening), torque (`rik robot-check`'s
torque_headroom fails on that variant and front), grip (the pinch's friction capacity is below the preset's
resistance), planner (none of these). Also counted: the rows that never moved the front (max_opening below P's
opening) although the arm reaches the closed handle, and how many of them pass the torque and grip checks.
Prints the totals, one markdown table row and every planner miss.
"""

from __future__ import annotations

import argparse
import csv
from collections import Counter
from pathlib import Path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("results", type=Path)
    parser.add_argument("--variants", type=Path, default=Path("variants"))
    args = parser.parse_args()

    from rik.registry.load import load_catalog
    from rik.sim.build import build_scene
    from rik.sim.outcome import PARTIAL_OPENING, SUCCESS_OPENING
    from rik.sim.robots.checks import run_checks

    rows = list(csv.DictReader(args.results.open()))
    robot = rows[0]["robot"]
    catalog = load_catalog()
    torque_ok: dict[tuple[str, str], bool] = {}
    reasons: Counter[str] = Counter()
    by_preset: Counter[tuple[str, str]] = Counter()
    limits: Counter[str] = Counter()
    never: Counter[str] = Counter()
    for r in rows:
        if r["outcome"] == "S":
            continue
        key = (r["variant"], r["front"])
        if key not in torque_ok:
            scene = build_scene(args.variants / r["variant"], r["front"], robot=catalog.robot(robot).as_arm)
            check = next((c for c in run_checks(scene) if c.name == "torque_headroom"), None)
            torque_ok[key] = check is None or check.passed  # none: not even the closed handle is reached
        reach = float(r["reachable_opening"]) < SUCCESS_OPENING
        torque = not torque_ok[key]
        grip = float(r["friction_capacity"]) < float(r["resistance"])
        limits.update(name for name, hit in (("reach", reach), ("torque", torque), ("grip", grip)) if hit)
        first = "reach" if reach else "torque" if torque else "grip" if grip else "planner"
        reasons[first] += 1
        if float(r["max_opening"]) < PARTIAL_OPENING and float(r["reachable_opening"]) >= 0.0:
            never["all"] += 1
            never["holdable"] += not torque and not grip  # the checks say a hold could have moved it
        by_preset[(first, r["preset"])] += 1
    outcomes = Counter(r["outcome"] for r in rows)
    presets = ("smooth", "normal", "high")
    s_by_preset = {p: sum(1 for r in rows if r["preset"] == p and r["outcome"] == "S") for p in presets}
    print(f"{robot}: {outcomes['S']} S / {outcomes['P']} P / {outcomes['F']} F; S by preset {s_by_preset}; "
          f"never moved (max below {PARTIAL_OPENING:.0%}) with the closed handle in reach: {never['all']}, "
          f"of them with the torque and grip checks passed: {never['holdable']}")
    print("| robot | S / P / F | misses | reach (smooth, normal, high) | torque (normal, high) | grip | planner "
          "| each limit, overlapping: reach / torque / grip |")
    print(f"| {robot} | {outcomes['S']} / {outcomes['P']} / {outcomes['F']} | {sum(reasons.values())} "
          f"| {reasons['reach']} ({', '.join(str(by_preset[('reach', p)]) for p in presets)}) "
          f"| {reasons['torque']} ({by_preset[('torque', 'normal')]}, {by_preset[('torque', 'high')]}) "
          f"| {reasons['grip']} | {reasons['planner']} | {limits['reach']} / {limits['torque']} / {limits['grip']} |")
    for r in rows:
        if r["outcome"] == "S":
            continue
        key = (r["variant"], r["front"])
        if float(r["reachable_opening"]) >= SUCCESS_OPENING and torque_ok[key] \
                and float(r["friction_capacity"]) >= float(r["resistance"]):
            print(f"planner miss: {r['variant']} {r['front']} {r['strategy']} {r['outcome']} "
                  f"{float(r['final_opening']):.0%} (max {float(r['max_opening']):.0%}): {r['log']}")


if __name__ == "__main__":
    main()
