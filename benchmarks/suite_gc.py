"""What Python's cyclic garbage collector costs the test suite's workers, with Python's own thresholds (700, 10, 10)
against the suite's (``tests/conftest.py``: ``GC_THRESHOLDS``), side by side in one run, alternating.

A pytest-xdist worker imports torch, LeRobot, MuJoCo and Mitsuba and holds its tests' fixtures: 2.7-3.8 GB. Each
full collection walks every object of it; with Python's thresholds a worker made 15-18 of them in the whole suite and
16 in the everyday tier, 0.4-0.8 s each. The suite's thresholds collect the young generations less often and look at
the oldest every 100 collections of the middle one rather than 10 (Python still skips a full collection until a
quarter of the long-lived objects are new), so cyclic garbage is still collected, later.

Each run is ``bash scripts/test.sh -q -p no:cacheprovider ARGS`` (default: the everyday tier, ``-m "not slow"``)
with the suite's CPU log on (``RIK_TEST_CPU_LOG``), which also records each test process's time in the collector
and its peak memory. Printed per run: pytest's own wall time, the collector's CPU-s summed over the workers, the
workers' CPU-s, and the largest worker's peak resident memory; then the medians' ratios.

Run: ``uv run python benchmarks/suite_gc.py [--rounds 2] [-- PYTEST ARGS]`` (about 3 minutes a round for the
everyday tier on 2 cores; nothing else should run).
"""

from __future__ import annotations

import argparse
import os
import re
import statistics
import subprocess
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PYTHONS = "700,10,10"
"""Python's own thresholds (``gc.get_threshold()`` of a fresh 3.12 interpreter)."""


def run_suite(thresholds: str | None, args: list[str]) -> dict[str, float]:
    """One run of the suite with ``thresholds`` (None: the suite's own); its wall s, the collector's CPU-s and the
    workers' CPU-s (summed over the test processes), the largest peak RSS (MB)."""
    with tempfile.TemporaryDirectory(prefix="rik-suite-gc-") as log:
        env = {**os.environ, "RIK_TEST_CPU_LOG": log}
        if thresholds:
            env["RIK_TEST_GC"] = thresholds
        res = subprocess.run(["bash", "scripts/test.sh", "-q", "-p", "no:cacheprovider", *args], cwd=ROOT, env=env,
                             capture_output=True, text=True)
        if res.returncode != 0:
            raise SystemExit(f"the suite failed ({thresholds or 'conftest'}):\n{res.stdout[-3000:]}{res.stderr[-900:]}")
        wall = float(re.findall(r" in ([0-9.]+)s", res.stdout)[-1])
        rows = [line.split("\t") for f in Path(log).glob("*.gc") for line in f.read_text().splitlines()]
    return {"wall": wall, "gc": sum(float(r[0]) for r in rows), "cpu": sum(float(r[2]) for r in rows),
            "rss": max(float(r[3]) for r in rows)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=2, help="runs of each setting, alternating")
    parser.add_argument("pytest_args", nargs="*", default=["-m", "not slow"], help="after --: pytest's arguments")
    opts = parser.parse_args()
    results: dict[str, list[dict[str, float]]] = {"python": [], "suite": []}
    print(f"{'thresholds':<24} {'wall s':>8} {'GC CPU-s':>9} {'workers CPU-s':>14} {'peak RSS MB':>12}")
    for _ in range(opts.rounds):
        for name, thresholds in (("python", PYTHONS), ("suite", None)):
            r = run_suite(thresholds, opts.pytest_args)
            results[name].append(r)
            label = f"{name} ({thresholds or 'conftest'})"
            print(f"{label:<24} {r['wall']:8.1f} {r['gc']:9.2f} {r['cpu']:14.1f} {r['rss']:12.0f}", flush=True)
    med = {name: {k: statistics.median(r[k] for r in rs) for k in ("wall", "gc", "cpu", "rss")}
           for name, rs in results.items()}
    ratios = {k: med["suite"][k] / med["python"][k] for k in ("wall", "gc", "cpu", "rss")}
    print(f"median ratios, suite's / Python's: wall {ratios['wall']:.3f}, GC CPU-s {ratios['gc']:.3f}, workers' "
          f"CPU-s {ratios['cpu']:.3f}, peak RSS {ratios['rss']:.3f}")


if __name__ == "__main__":
    main()
