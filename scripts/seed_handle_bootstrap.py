"""A success rate's interval over training seeds and handles, not only over episodes.

    uv run python scripts/seed_handle_bootstrap.py RUN_S0/episodes.csv RUN_S1/episodes.csv ... [--resamples 10000]

Each file is one training seed's ``rik eval`` of the same episodes. The Wilson interval of the pooled rate treats
every episode as independent, but the episodes of four seeds are the same 90 episodes run four times, and 90
episodes hold a handful of handles: the rate varies with the seed drawn and with the handles drawn. This resamples
both (seeds with replacement; handles with replacement, each with all its episodes) and prints the pooled rate, the
per-seed rates and the 2.5-97.5 percentiles of the resampled rates. Deterministic (the resampling's seed is 0).
"""

from __future__ import annotations

import argparse
import csv
from pathlib import Path

import numpy as np

from rik.tables import seed_handle_interval


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("episodes", type=Path, nargs="+", help="episodes.csv of each training seed")
    parser.add_argument("--resamples", type=int, default=10_000)
    args = parser.parse_args()
    runs = [list(csv.DictReader(path.open(encoding="utf-8"))) for path in args.episodes]
    seeds = [[int(row["seed"]) for row in run] for run in runs]
    if any(s != seeds[0] for s in seeds):
        raise SystemExit("seed_handle_bootstrap.py: the files do not hold the same episodes in the same order")
    success = np.array([[row["outcome"] == "S" for row in run] for run in runs], dtype=float)
    handles = [row["variant"].split("__")[1] for row in runs[0]]
    lo, hi = seed_handle_interval(success, handles, args.resamples)
    names = set(handles)
    print(f"{int(success.sum())} of {success.size}: {success.mean():.1%} pooled over {len(runs)} seeds, "
          f"{len(names)} handles, {success.shape[1]} episodes each")
    print("per seed: " + ", ".join(f"{r:.1%}" for r in success.mean(axis=1)))
    print(f"95 % interval over seeds and handles ({args.resamples} resamples): [{lo:.1%}, {hi:.1%}]")


if __name__ == "__main__":
    main()
