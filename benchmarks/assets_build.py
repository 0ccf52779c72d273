"""Cold and warm ``rik assets build`` of the catalog in one run, into a fresh temporary cache.

Prints the cold build time, the warm rebuild time and their ratio (target: at most 0.02: a warm rebuild does no
decomposition), the convex-part and collision-vertex counts per handle, and the peak resident memory of this
process and of its worker processes. Run: ``uv run python benchmarks/assets_build.py [--workers N] [IDS...]``
(default: every handle and base unit).
"""

from __future__ import annotations

import argparse
import os
import resource
import tempfile
import time
from pathlib import Path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("ids", nargs="*", help="asset ids (default: all handles and base units)")
    parser.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    args = parser.parse_args()

    from rik.assets.build import build_assets
    from rik.assets.cache import AssetCache
    from rik.registry.load import load_catalog

    catalog = load_catalog()
    ids = args.ids or [*catalog.handles, *catalog.base_units]
    with tempfile.TemporaryDirectory() as tmp:
        cache = AssetCache(Path(tmp) / "assets")
        start = time.perf_counter()
        cold = build_assets(catalog, ids, workers=args.workers, cache=cache)
        cold_s = time.perf_counter() - start
        start = time.perf_counter()
        warm = build_assets(catalog, ids, workers=args.workers, cache=cache)
        warm_s = time.perf_counter() - start
    assert all(r.status == "built" for r in cold) and all(r.status == "cached" for r in warm)
    kib = 1024
    own = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / kib
    workers = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / kib
    print(f"{'asset':32} {'hulls':>6} {'collision vertices':>19} {'build s':>8}")
    for r in cold:
        print(f"{r.id:32} {r.hulls:6d} {r.collision_vertices:19d} {r.seconds:8.2f}")
    handles = [r for r in cold if r.kind == "handle"]
    if handles:
        print(f"handles: {len(handles)}, hulls per handle mean {sum(r.hulls for r in handles) / len(handles):.1f} "
              f"(max {max(r.hulls for r in handles)}), collision vertices per handle mean "
              f"{sum(r.collision_vertices for r in handles) / len(handles):.0f} "
              f"(max {max(r.collision_vertices for r in handles)})")
    print(f"assets: {len(ids)}, workers: {args.workers}")
    print(f"cold build: {cold_s:.1f} s; warm rebuild: {warm_s:.3f} s; warm/cold ratio: {warm_s / cold_s:.4f} "
          "(target <= 0.02)")
    print(f"peak memory: {own:.0f} MiB this process, {workers:.0f} MiB largest worker")


if __name__ == "__main__":
    main()
