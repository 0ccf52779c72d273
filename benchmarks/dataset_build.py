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

**Plan size** (``--plan-sizes 1000,10000,100000``, with ``--plan-only`` alone): ``make_plan`` of a spec of one
variant (``drawer-chest-80__two_point-bow-128__normal``) x one operator x N episodes, streams ``sim`` and
``rerendered``, 16 episodes per shard. The variant is built and checked once before (not timed), so ``make_plan``
only re-reads its report: what is timed is the plan itself (selection, checks, one key per episode, render and
shard), which is all ``rik dataset plan --sample 0`` and a build do before their first unit, besides loading the
catalog. Columns: ``make_plan`` now; its unit layout alone (``rik.dataset.plan.lay_out_units``), and the layout as
it was before (``_quadratic_layout`` below: each shard took its renders by scanning every render unit of the plan,
comparing whole episode units), run on the same plan up to ``--old-max`` episodes (10,000: the old layout is
quadratic, ~1 h at 100,000), with its keys compared to the new ones (byte-identical, or the run stops).
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
    from rik.exporters.lerobot_export import aggregate_shards as _aggregate

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


def _quadratic_layout(plan: Any, fronts: dict[str, str]) -> None:
    """``make_plan``'s unit layout before it was made linear (b352c43), kept here only to measure against: the
    shard loop scans every render unit for each shard (``r.episode in chunk``: dataclass equality of whole units)."""
    from rik.dataset.plan import EpisodeUnit, RenderUnit, ShardUnit, export_settings
    from rik.dataset.spec import library_versions
    from rik.paths import json_sha256

    spec = plan.spec
    record_versions = library_versions("mujoco")
    for v, front in fronts.items():
        for op in spec.operators:
            for k in range(spec.episodes_per_variant):
                seed = spec.seed + k
                key = json_sha256({"stage": "record", "variant": v, "variant_hash": plan.variants[v],
                                   "front": front, "strategy": op.strategy, "params": op.params, "label": op.label,
                                   "seed": seed, "max_seconds": spec.max_seconds, "gripper": spec.robot,
                                   "versions": record_versions})
                plan.episodes.append(EpisodeUnit(len(plan.episodes), v, front, op, seed, key, spec.robot))
    render_versions = library_versions("mujoco", "mitsuba")
    for e in plan.episodes:
        for s in spec.streams:
            key = json_sha256({"stage": "render", "record": e.key, "stream": plan.stream_spec(s).key,
                               "cameras": list(spec.cameras), "versions": render_versions})
            plan.renders.append(RenderUnit(e, s, key))
    export_versions = library_versions("lerobot", "av")
    size = spec.shard_episodes
    for i in range(0, len(plan.episodes), size):
        chunk = tuple(plan.episodes[i:i + size])
        key = json_sha256({"stage": "shard", "episodes": [e.key for e in chunk],
                           "renders": [r.key for r in plan.renders if r.episode in chunk],
                           "export": export_settings(spec), "versions": export_versions})
        plan.shards.append(ShardUnit(len(plan.shards), chunk, key))


def plan_sizes(catalog: Any, base: Path, sizes: list[int], old_max: int) -> None:
    """Time ``make_plan`` at each size, and the unit layout now and before (see the module docstring)."""
    import dataclasses

    from rik.dataset.plan import lay_out_units, make_plan
    from rik.dataset.spec import load_spec

    variant = "drawer-chest-80__two_point-bow-128__normal"
    variants = base / "plan-variants"

    def spec_of(n: int) -> Any:
        path = base / f"plan-{n}.yaml"
        path.write_text(f"repo_id: {REPO}\nvariants:\n  ids: [{variant}]\noperators:\n  - strategy: contact_rich\n"
                        f"episodes_per_variant: {n}\nstreams: [sim, rerendered]\nshard_episodes: 16\n",
                        encoding="utf-8")
        return load_spec(path)

    t = time.perf_counter()
    make_plan(catalog, spec_of(1), variants_dir=variants)
    print(f"\nplan size: variant built and checked in {time.perf_counter() - t:.1f} s (not timed); load {load()}")
    rows = []
    for n in sizes:
        spec = spec_of(n)
        t = time.perf_counter()
        plan = make_plan(catalog, spec, variants_dir=variants)
        total = time.perf_counter() - t
        fronts = {e.variant: e.front for e in plan.episodes[:1]}
        shell = dataclasses.replace(plan, episodes=[], renders=[], shards=[])
        t = time.perf_counter()
        lay_out_units(shell, fronts)
        layout = time.perf_counter() - t
        old: float | None = None
        same = "-"
        if n <= old_max:
            before = dataclasses.replace(plan, episodes=[], renders=[], shards=[])
            t = time.perf_counter()
            _quadratic_layout(before, fronts)
            old = time.perf_counter() - t
            keys = [[u.key for u in units] for units in (plan.episodes, plan.renders, plan.shards)]
            if keys != [[u.key for u in units] for units in (before.episodes, before.renders, before.shards)]:
                raise SystemExit(f"{n} episodes: the old layout gives other keys")
            same = "yes"
        units = len(plan.episodes) + len(plan.renders) + len(plan.shards)
        rows.append((n, units, total, layout, old, same))
        print(f"  {n} episodes planned; load {load()}")
    print(f"\n{'episodes':>9}{'units':>9}{'make_plan s':>13}{'layout s':>10}{'before s':>10}{'same keys':>11}"
          f"{'us/episode':>12}")
    for n, units, total, layout, old, same in rows:
        before_text = f"{old:.2f}" if old is not None else "not run"
        print(f"{n:>9}{units:>9}{total:>13.2f}{layout:>10.2f}{before_text:>10}{same:>11}{1e6 * total / n:>12.1f}")


def load() -> str:
    return ", ".join(f"{x:.2f}" for x in os.getloadavg())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--variants", type=int, default=4)
    ap.add_argument("--episodes", type=int, default=2, help="episodes per variant")
    ap.add_argument("--size", type=int, default=64, help="image side, px")
    ap.add_argument("--max-seconds", type=float, default=2.0, help="longest episode, simulated s")
    ap.add_argument("--skip-ray", action="store_true")
    ap.add_argument("--plan-sizes", default="", help="episode counts to plan, comma-separated (1000,10000,100000)")
    ap.add_argument("--old-max", type=int, default=10_000, help="largest plan laid out the old way too")
    ap.add_argument("--plan-only", action="store_true", help="only the plan-size table, no build")
    args = ap.parse_args()
    sizes = [int(x) for x in args.plan_sizes.split(",") if x.strip()]
    if args.plan_only:
        from rik.registry.load import load_catalog

        print(f"load average at start: {load()} ({os.cpu_count()} CPU cores)")
        with tempfile.TemporaryDirectory(prefix="dataset-plan-") as tmp:
            plan_sizes(load_catalog(), Path(tmp), sizes or [1000, 10_000, 100_000], args.old_max)
        print(f"load average now {load()}")
        return

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
    if sizes:
        with tempfile.TemporaryDirectory(prefix="dataset-plan-") as tmp:
            plan_sizes(catalog, Path(tmp), sizes, args.old_max)
    print(f"\ntotal run time {time.perf_counter() - started:.0f} s; load average now {load()} (other work on the "
          "machine skews every number)")


if __name__ == "__main__":
    main()
