"""Build every variant of one preset with a warm asset cache, and compare with MuJoCo compiling the same files.

Prints, side by side in one run:

- rik's build: assemble the MjSpec, run every check (geometry, compile, collision sweep, stepping, test pulls)
  and write the files, in variants per second (one process, so the comparison with MuJoCo is like for like;
  ``--workers`` adds a parallel run);
- the part of it that materialises the model (assemble + ``MjSpec.compile`` + writing), from the reports;
- MuJoCo's own ``MjModel.from_xml_path`` of every written ``model.xml`` (parse, read meshes, compile);
- the ratios of rik's build time to MuJoCo's compile time (target: at most 2), and peak memory.

Run: ``uv run python benchmarks/variants_build.py [--preset normal] [--limit N] [--workers N]``.
"""

from __future__ import annotations

import argparse
import json
import resource
import tempfile
import time
from pathlib import Path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--preset", default="normal")
    parser.add_argument("--limit", type=int, default=0, help="only the first N variants (0: all)")
    parser.add_argument("--workers", type=int, default=1, help="also time a parallel build with N processes")
    args = parser.parse_args()

    import mujoco

    from rik.assets.build import build_assets
    from rik.combinator.build import build_variants
    from rik.registry.ids import select_variants
    from rik.registry.load import load_catalog

    catalog = load_catalog()
    keys = select_variants(catalog, presets=[args.preset])
    keys = keys[: args.limit] if args.limit else keys
    start = time.perf_counter()
    build_assets(catalog, [*catalog.handles, *catalog.base_units], workers=args.workers)
    warmup = time.perf_counter() - start
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "variants"
        start = time.perf_counter()
        results = build_variants(catalog, keys, out, workers=1)
        rik_s = time.perf_counter() - start
        rejected = [r for r in results if r.status != "built"]
        reports = [json.loads((out / r.id / "report.json").read_text()) for r in results if r.status == "built"]
        start = time.perf_counter()
        for r in results:
            if r.status == "built":
                mujoco.MjModel.from_xml_path(str(out / r.id / "model.xml"))
        mujoco_s = time.perf_counter() - start
        parallel_s = None
        if args.workers > 1:
            start = time.perf_counter()
            build_variants(catalog, keys, Path(tmp) / "parallel", workers=args.workers)
            parallel_s = time.perf_counter() - start
        disk = sum(p.stat().st_size for p in out.rglob("*") if p.is_file() and ".meshes" in p.parts)
    compile_s = sum(r["compile_seconds"] for r in reports)
    n = len(keys)
    own = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    children = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
    print(f"variants: {n} ({args.preset}), valid {n - len(rejected)}, rejected {len(rejected)}; "
          f"asset cache check {warmup:.1f} s")
    print(f"rik build (assemble, check, write), 1 process: {rik_s:.1f} s, {n / rik_s:.1f} variants/s")
    if parallel_s:
        print(f"rik build, {args.workers} processes: {parallel_s:.1f} s, {n / parallel_s:.1f} variants/s")
    print(f"  of which MjSpec.compile: {compile_s:.1f} s; checks and writing: {rik_s - compile_s:.1f} s")
    print(f"MuJoCo from_xml_path of the same {len(reports)} model.xml files: {mujoco_s:.1f} s "
          f"({1000 * mujoco_s / max(len(reports), 1):.1f} ms each)")
    print(f"ratio rik build / MuJoCo compile: {rik_s / mujoco_s:.2f} (target <= 2)")
    print(f"ratio rik's compile step alone / MuJoCo compile: {compile_s / mujoco_s:.2f}")
    print(f"mean per variant: build {1000 * rik_s / n:.1f} ms, hulls {sum(r['hulls'] for r in reports) / n:.1f}, "
          f"collision vertices {sum(r['collision_vertices'] for r in reports) / n:.0f}, "
          f"step {1e6 * sum(r['step_seconds'] for r in reports) / n:.1f} us")
    print(f"mesh store on disk: {disk / 2**20:.1f} MiB for {n} variants (hard links)")
    print(f"peak memory: {own:.0f} MiB this process, {children:.0f} MiB largest worker")


if __name__ == "__main__":
    main()
