"""Dataset build speed: ``rik dataset build`` of one small spec on this process, on 2 local worker processes and on
a 2-node Ray cluster, against the same stages run bare, side by side in one run.

The spec (written by the benchmark): ``--variants N`` drawer variants (``drawer/chest-80``, preset ``normal``,
drawn with the spec's seed) x ``--episodes`` episodes of ``contact_rich``, at most ``--max-seconds`` simulated
seconds each, the ``sim`` stream (MuJoCo, both cameras) at ``--size`` px, h264, one shard per 4 episodes.

Set-up, not timed: the variants are built once into one folder all builds share; a warm-up records and renders one
episode and writes a one-episode shard in a throwaway folder (imports of MuJoCo, lerobot and PyAV, EGL/llvmpipe
start-up), so neither side below pays them in this process.

Timed, each in a fresh work and out folder:

- bare: the stage functions of :mod:`rik.dataset.build` (``run_record``, ``run_render``, ``run_shard``) called
  directly in this process, one after the other in plan order, then lerobot's ``aggregate_datasets`` over the
  shards (``rik.exporters.lerobot_export._aggregate``). This is the work itself with nothing around it: no
  scheduler, no engine, no marker look-ups, no checks of the merged dataset, no card, checksums or registry.
  (The stage functions write their own marker file, a few hundred bytes each; that is counted as work.)
- (b) ``build_dataset`` with the inline engine (1 worker, this process): bare + rik's orchestration (scheduling,
  marker reads, the merged dataset loaded and its frame counts checked, card, checksums of every file, publish by
  rename, registry). Ratio (b) / bare: rik's overhead, target at most 1.1.
- (c) ``build_dataset`` on local processes, 2 workers (spawned: each pays its imports and catalog load, counted).
- (d) ``build_dataset`` on ``RayEngine(cluster.address)`` with ``ray.cluster_utils.Cluster``: a head with
  ``num_cpus=0`` and two worker nodes with ``num_cpus=1`` on loopback. The cluster's start-up (and the driver's
  connection, which ``RayEngine`` makes) is reported apart and not counted in (d)'s wall time; the workers' first
  imports are (Ray starts its worker processes lazily).

Printed: wall s, episodes per hour, seconds inside each stage summed over workers, the ratio (b)/bare and the
speed-up of (c) and (d) over (b); then whether the datasets of (b), (c), (d) are byte-identical (sha256 of every
file but ``meta/rik_build.json``). The machine's load average before and after is printed: other work on the two
cores skews every number. Ray is always shut down at the end.

Run: ``uv run python benchmarks/dataset_build.py [--variants 4] [--episodes 2] [--size 64] [--max-seconds 2]
[--skip-ray]`` (5 to 8 minutes on 2 cores shared with other work, with the defaults; ~20 s of it starting
Ray).
"""

from __future__ import annotations

import argparse
import hashlib
import os
import tempfile
import time
from pathlib import Path
from typing import Any

for _name, _value in (("MUJOCO_GL", "egl"), ("HF_HUB_OFFLINE", "1"), ("SVT_LOG", "1"), ("TQDM_DISABLE", "1"),
                      ("RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER", "0"), ("RAY_AUTH_MODE", "disabled")):
    os.environ.setdefault(_name, _value)

REPO = "local/dataset-build-speed"
STAGE_COLS = ("record", "render", "shard", "merge")


def write_spec(path: Path, args: argparse.Namespace) -> None:
    text = f"""repo_id: {REPO}
variants:
  base_units: [drawer/chest-80]
  presets: [normal]
  sample: {args.variants}
operators:
  - strategy: contact_rich
episodes_per_variant: {args.episodes}
seed: 7
max_seconds: {args.max_seconds}
streams: [sim]
resolution: {args.size}
codec: h264
shard_episodes: 4
"""
    path.write_text(text, encoding="utf-8")


def dataset_digest(root: Path) -> str:
    """sha256 over every file of a built dataset but ``meta/rik_build.json`` (the build's own statistics)."""
    h = hashlib.sha256()
    for path in sorted(p for p in root.rglob("*") if p.is_file()):
        rel = path.relative_to(root).as_posix()
        if rel == "meta/rik_build.json":
            continue
        h.update(rel.encode() + b"\0" + hashlib.sha256(path.read_bytes()).digest())
    return h.hexdigest()


def bare(catalog: Any, plan: Any, root: Path, variants: Path) -> dict[str, Any]:
    """The stages called directly, in plan order, then the merge; seconds per stage and wall seconds."""
    from rik.dataset.build import Folders, export_spec, run_record, run_render, run_shard
    from rik.exporters.lerobot_export import _aggregate

    folders = Folders(root / "work", variants.absolute())
    seconds = dict.fromkeys(STAGE_COLS, 0.0)
    frames = 0
    t0 = time.perf_counter()
    for e in plan.episodes:
        t = time.perf_counter()
        run_record(catalog, (folders, e, plan.spec.max_seconds))
        seconds["record"] += time.perf_counter() - t
    outputs: dict[str, str] = {}
    for r in plan.renders:
        t = time.perf_counter()
        rec = run_render(catalog, (folders, r, plan.stream_spec(r.stream), plan.spec.cameras))
        seconds["render"] += time.perf_counter() - t
        frames += int(rec["frames"])
        outputs[f"{r.episode.key}/{r.stream}"] = rec["output"]
    xspec = export_spec(plan)
    roots = []
    for s in plan.shards:
        t = time.perf_counter()
        streams = {k: v for k, v in outputs.items() if k.split("/")[0] in {e.key for e in s.episodes}}
        rec = run_shard(catalog, (folders, s, xspec, streams))
        seconds["shard"] += time.perf_counter() - t
        roots.append(folders.work / rec["output"] / "ds")
    t = time.perf_counter()
    _aggregate(plan.spec.repo_id, roots, root / "out")
    seconds["merge"] = time.perf_counter() - t
    return {"wall": time.perf_counter() - t0, "seconds": seconds, "frames": frames}


def built(catalog: Any, plan: Any, root: Path, variants: Path, engine: Any) -> dict[str, Any]:
    from rik.dataset.build import build_dataset

    result = build_dataset(catalog, plan, root / "out", engine, work=root / "work", variants=variants,
                           register=False)
    if result.failures:
        raise SystemExit(f"{engine.name}: {len(result.failures)} units failed, e.g. {result.failures[0]}")
    if result.ran["record"] != len(plan.episodes):
        raise SystemExit(f"{engine.name}: ran {result.ran['record']} of {len(plan.episodes)} episodes (reused?)")
    return {"wall": result.wall_seconds, "seconds": {k: result.seconds.get(k, 0.0) for k in STAGE_COLS},
            "frames": result.frames["render"], "digest": dataset_digest(root / "out"), "workers": engine.workers}


def warm_up(catalog: Any, plan: Any, root: Path, variants: Path) -> float:
    """One episode through record, render and shard in a throwaway folder (imports, renderer start-up)."""
    from rik.dataset.build import Folders, export_spec, run_record, run_render, run_shard
    from rik.dataset.plan import ShardUnit

    t0 = time.perf_counter()
    folders = Folders(root, variants.absolute())
    e = plan.episodes[0]
    run_record(catalog, (folders, e, plan.spec.max_seconds))
    outputs = {}
    for r in (r for r in plan.renders if r.episode is e):
        outputs[f"{e.key}/{r.stream}"] = run_render(catalog, (folders, r, plan.stream_spec(r.stream),
                                                               plan.spec.cameras))["output"]
    run_shard(catalog, (folders, ShardUnit(0, (e,), "warmup"), export_spec(plan), outputs))
    return time.perf_counter() - t0


def load() -> str:
    return ", ".join(f"{x:.2f}" for x in os.getloadavg())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--variants", type=int, default=4)
    ap.add_argument("--episodes", type=int, default=2, help="episodes per variant")
    ap.add_argument("--size", type=int, default=64, help="image side, px")
    ap.add_argument("--max-seconds", type=float, default=2.0, help="longest episode, simulated s")
    ap.add_argument("--skip-ray", action="store_true")
    args = ap.parse_args()

    from rik.dataset.engines import local_engine
    from rik.dataset.plan import make_plan
    from rik.dataset.spec import load_spec
    from rik.registry.load import load_catalog

    started = time.perf_counter()
    print(f"load average at start: {load()} ({os.cpu_count()} CPU cores)")
    with tempfile.TemporaryDirectory(prefix="dataset-build-") as tmp:
        base = Path(tmp)
        spec_path = base / "spec.yaml"
        write_spec(spec_path, args)
        catalog = load_catalog()
        variants = base / "variants"
        t = time.perf_counter()
        plan = make_plan(catalog, load_spec(spec_path), source=str(spec_path), variants_dir=variants, workers=2)
        print(f"set-up (not timed): plan and {len(plan.variants)} variants built in {time.perf_counter() - t:.1f} s "
              f"({len(plan.rejected)} rejected); {len(plan.episodes)} episodes, {len(plan.renders)} renders, "
              f"{len(plan.shards)} shards")
        print(f"warm-up (not timed): one episode through every stage in {warm_up(catalog, plan, base / 'warm',
                                                                                  variants):.1f} s")

        rows: dict[str, dict[str, Any]] = {}
        rows["bare (stage functions)"] = {**bare(catalog, plan, base / "bare", variants), "workers": 1}
        print(f"bare done ({rows['bare (stage functions)']['wall']:.1f} s); load {load()}")
        rows["(b) inline"] = built(catalog, plan, base / "inline", variants, local_engine(catalog, 1))
        print(f"(b) done ({rows['(b) inline']['wall']:.1f} s); load {load()}")
        rows["(c) local processes"] = built(catalog, plan, base / "local2", variants, local_engine(catalog, 2))
        print(f"(c) done ({rows['(c) local processes']['wall']:.1f} s); load {load()}")

        ray_start = None
        if not args.skip_ray:
            from ray.cluster_utils import Cluster

            from rik.dataset.engines import RayEngine

            cluster = None
            try:
                t = time.perf_counter()
                cluster = Cluster(initialize_head=True, head_node_args={"num_cpus": 0, "include_dashboard": False})
                for _ in range(2):
                    cluster.add_node(num_cpus=1)
                cluster.wait_for_nodes()
                engine = RayEngine(cluster.address)
                ray_start = time.perf_counter() - t
                print(f"Ray cluster up and connected in {ray_start:.1f} s (not counted); load {load()}")
                rows["(d) Ray, 2 nodes"] = built(catalog, plan, base / "ray", variants, engine)
                print(f"(d) done ({rows['(d) Ray, 2 nodes']['wall']:.1f} s); load {load()}")
            finally:
                import ray

                ray.shutdown()
                if cluster is not None:
                    cluster.shutdown()

    n = len(plan.episodes)
    frames = rows["(b) inline"]["frames"]
    print(f"\n{n} episodes ({len(plan.variants)} variants x {args.episodes}, contact_rich, <= {args.max_seconds} s), "
          f"sim stream, 2 cameras, {args.size} px, {frames} MuJoCo frames; stage seconds are summed over workers")
    head = f"{'engine':<24}{'workers':>8}{'wall s':>9}{'episodes/h':>12}" + "".join(f"{s + ' s':>10}"
                                                                                      for s in STAGE_COLS)
    print(head)
    for name, r in rows.items():
        print(f"{name:<24}{r['workers']:>8}{r['wall']:>9.1f}{3600 * n / r['wall']:>12.0f}"
              + "".join(f"{r['seconds'][s]:>10.2f}" for s in STAGE_COLS))
    b, bare_row = rows["(b) inline"], rows["bare (stage functions)"]
    ratio = b["wall"] / bare_row["wall"]
    print(f"\nrik overhead (b)/bare: {ratio:.3f} ({'met' if ratio <= 1.1 else 'NOT met'}, target <= 1.1)")
    for name in ("(c) local processes", "(d) Ray, 2 nodes"):
        if name in rows:
            print(f"speed-up of {name} over (b): {b['wall'] / rows[name]['wall']:.2f}x")
    if ray_start is not None:
        print(f"Ray start-up (cluster of 3 nodes + connect), not counted above: {ray_start:.1f} s")
    per = bare_row["seconds"]
    print(f"bare per episode: record {per['record'] / n:.3f} s, MuJoCo frames {per['render'] / n:.3f} s "
          f"({frames / per['render']:.1f} frames/s at {args.size} px), shard {per['shard'] / n:.3f} s, "
          f"merge {per['merge']:.2f} s per dataset")
    digests = {name: r["digest"] for name, r in rows.items() if "digest" in r}
    same = len(set(digests.values())) == 1
    print(f"datasets of {', '.join(digests)}: {'byte-identical' if same else 'DIFFER'} "
          f"(sha256 of every file but meta/rik_build.json: "
          + ", ".join(f"{k.split()[0]} {v[:12]}" for k, v in digests.items()) + ")")
    print(f"\ntotal run time {time.perf_counter() - started:.0f} s; load average now {load()} (other work on the "
          "machine skews every number)")


if __name__ == "__main__":
    main()
