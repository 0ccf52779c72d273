"""Speed of the fidelity metric's distance queries (``rik assets fidelity``): the nearest-sample distances of
:func:`rik.assets.fidelity.measure` with the k-d tree split at sliding midpoints (``balanced_tree=False``, what rik
uses) against scipy's default balanced tree (what it used before 2026-11-29), side by side on the same samples.

Set-up, not timed: each handle's asset is built (CoACD) in a temporary cache and its shells sampled as ``measure``
samples them at the default 20,000 points (200,000 reference samples). Timed, best of ``--repeats``, CPU seconds
of this process: the four queries of one handle with each tree; printed with the ratio and whether the distances
are identical.

Run: ``uv run python benchmarks/fidelity_speed.py [--repeats 3] [HANDLE ...]``.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time

import numpy as np

HANDLES = ("knob/mushroom-30", "two_point/bow-128", "finger_pull/edge-lip-100", "knob/ring-pull-35")


def _best(fn, repeats: int) -> tuple[float, list[np.ndarray]]:
    best, out = float("inf"), []
    for _ in range(repeats):
        start = time.process_time()
        out = fn()
        best = min(best, time.process_time() - start)
    return best, out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("handles", nargs="*", default=list(HANDLES))
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    os.environ["RIK_CACHE"] = tempfile.mkdtemp(prefix="rik-fidelity-bench-")

    from scipy.spatial import cKDTree

    from rik.assets.build import build_asset
    from rik.assets.cache import AssetCache
    from rik.assets.fidelity import DEFAULT_POINTS, REFERENCE_FACTOR, distance_to_samples, sample_shell, sample_surface
    from rik.registry.load import load_catalog

    catalog, cache = load_catalog(), AssetCache()
    total_old = total_new = 0.0
    print(f"{'handle':28} {'balanced':>9} {'midpoint':>9} {'ratio':>6}  same")
    for handle in args.handles:
        part = build_asset(catalog, handle, cache=cache)[0].part("handle")
        dense = DEFAULT_POINTS * REFERENCE_FACTOR
        p, p_ref = sample_surface(part.visual, DEFAULT_POINTS, 0), sample_surface(part.visual, dense, 10)
        q, q_ref = sample_shell(part.hulls, DEFAULT_POINTS, 1), sample_shell(part.hulls, dense, 11)
        qb, qb_ref = sample_shell(part.baseline, DEFAULT_POINTS, 2), sample_shell(part.baseline, dense, 12)
        queries = [(q, p_ref), (qb, p_ref), (p, q_ref), (p, qb_ref)]
        old, d_old = _best(lambda qs=queries: [cKDTree(s).query(x)[0] for x, s in qs], args.repeats)
        new, d_new = _best(lambda qs=queries: [distance_to_samples(x, s) for x, s in qs], args.repeats)
        same = all(np.array_equal(a, b) for a, b in zip(d_old, d_new, strict=True))
        total_old, total_new = total_old + old, total_new + new
        print(f"{handle:28} {old:8.3f}s {new:8.3f}s {old / new:5.1f}x  {same}")
    print(f"{'all':28} {total_old:8.3f}s {total_new:8.3f}s {total_old / total_new:5.1f}x")


if __name__ == "__main__":
    main()
