"""``rik dataset plan|build|list|show|verify``: datasets as specs, built on local processes or a Ray cluster."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from rik.cli.common import (
    DEFAULT_WORKERS,
    CatalogOption,
    check_at_least_one_worker,
    console,
    overlays,
    print_json,
    progress_bar,
    quiet_writers,
    stage_progress,
)
from rik.errors import RikError

if TYPE_CHECKING:
    from rik.dataset.plan import Plan
    from rik.registry.catalog import Catalog
    from rik.schemas.dataset import DatasetSpec

app = typer.Typer(help="Datasets as specs: plan one, build it (local processes or Ray), list, show and verify "
                       "what was built.", no_args_is_help=True)

SpecArg = Annotated[Path, typer.Argument(help="The dataset spec (YAML; docs/datasets.md describes its fields).",
                                         show_default=False)]
VariantsOpt = Annotated[Path, typer.Option("--variants", help="Folder of built variants (missing ones are built "
                                           "there first).")]
WorkersOpt = Annotated[int, typer.Option("--workers", "-j", callback=check_at_least_one_worker,
                                         help="Local worker processes.")]
JsonOpt = Annotated[bool, typer.Option("--json", help="Print JSON instead of a table.")]


def _human_bytes(n: float) -> str:
    for unit in ("B", "kB", "MB", "GB", "TB"):
        if abs(n) < 1000 or unit == "TB":
            return f"{n:.0f} {unit}" if unit == "B" else f"{n:.1f} {unit}"
        n /= 1000
    return f"{n:.1f} TB"


def _hours(h: float) -> str:
    if h < 1 / 60:
        return f"{h * 3600:.0f} s"
    if h < 1:
        return f"{h * 60:.1f} min"
    if h < 48:
        return f"{h:.1f} h"
    return f"{h / 24:.1f} days"


def _plan(spec_path: Path, variants: Path, workers: int, catalog_paths: list[Path] | None,
          spec: DatasetSpec | None = None) -> tuple[Catalog, Plan]:
    """The catalog and the plan of the spec at ``spec_path`` (``spec``: it, when already read)."""
    from rik.dataset.plan import make_plan
    from rik.dataset.spec import load_spec
    from rik.registry.load import load_catalog
    from rik.registry.sources import display_path

    spec = spec if spec is not None else load_spec(spec_path)
    catalog = load_catalog(overlays(catalog_paths))
    return catalog, make_plan(catalog, spec, source=display_path(spec_path), variants_dir=variants, workers=workers,
                              overlays=overlays(catalog_paths))


def _print_plan(plan: Plan) -> None:
    s = plan.spec
    w, h = s.size
    ops = ", ".join(o.label + (f" {o.params}" if o.params else "") for o in s.operators)
    print(f"{plan.source}: {s.repo_id} (spec hash {plan.spec_hash[:12]})")
    print(f"  robot: {s.robot}")
    shape = (f"{s.variants.draw} drawn episodes ({len(plan.variants)} variants) x {len(s.operators)} operators "
             f"({ops})" if s.variants.draw is not None  # one episode per drawn seed, on the variant it draws
             else f"{len(plan.variants)} variants x {len(s.operators)} operators ({ops}) x {s.episodes_per_variant} "
             "episodes")
    seeds = [e.seed for e in plan.episodes] or [s.seed]
    print(f"  {shape} = {len(plan.episodes)} episodes, seeds {min(seeds)}..{max(seeds)}")
    streams = ", ".join(s.streams) or "none (state only)"
    print(f"  streams: {streams}; cameras: {', '.join(s.cameras) or 'all'}; {w}x{h} px; codec {s.codec}; "
          f"{len(plan.shards)} shards of up to {s.shard_episodes} episodes")
    if plan.rejected:
        first = next(iter(plan.rejected.items()))
        print(f"  left out: {len(plan.rejected)} selected variants fail their checks (e.g. {first[0]}: {first[1]})")


@app.command("plan")
def plan_command(spec: SpecArg, sample: Annotated[int, typer.Option("--sample", min=0, help="Episodes to time "
                                                                      "through every stage for the cost estimate "
                                                                      "(0: no estimate).")] = 2,
                 workers: WorkersOpt = DEFAULT_WORKERS, variants: VariantsOpt = Path("variants"),
                 catalog: CatalogOption = None) -> None:
    """Print what SPEC makes (variants, episodes, shards) and what it costs, per stage, from a short timed sample:
    episodes and frames per worker-hour, worker-hours, wall time on --workers workers, and disk."""
    from rich.table import Table

    cat, plan = _plan(spec, variants, workers, catalog)
    _print_plan(plan)
    if not sample:
        return
    from rik.dataset.estimate import estimate

    with progress_bar() as bar:
        bar.add_task(f"timing {min(sample, len(plan.episodes))} sample episodes", total=None, last="")
        est = estimate(cat, plan, sample=sample, variants=variants)
    table = Table(title=f"estimate from {est.sample} sampled episodes, timed in one worker after a warm-up "
                        "(MuJoCo's llvmpipe and Mitsuba's LLVM back end use several threads of it)")
    for col in ("stage", "s / episode", "episodes / worker-h", "frames / worker-h", "worker-hours", "disk"):
        table.add_column(col, justify="left" if col == "stage" else "right")
    for c in est.stages:
        frames = f"{c.frames_per_worker_hour:,.0f}" if c.frames_per_episode else "-"
        table.add_row(c.stage, f"{c.seconds_per_episode:.2f}", f"{c.episodes_per_worker_hour:,.0f}", frames,
                      f"{c.worker_hours:.3g}", _human_bytes(c.total_bytes))
    table.add_row("total", "", "", "", f"{est.worker_hours:.3g}", _human_bytes(est.total_bytes))
    console().print(table)
    print(f"wall time: about {_hours(est.wall_hours(workers))} on {workers} local workers; renders (PNG frames) are "
          "work files, the export row is the dataset itself")


@app.command("build")
def build_command(spec: SpecArg,
                  out: Annotated[Path, typer.Option("--out", "-o", help="Folder of the dataset (a LeRobot v3.0 "
                                                    "dataset when done).", show_default=False)] = ...,  # type: ignore[assignment]
                  workers: WorkersOpt = DEFAULT_WORKERS,
                  ray: Annotated[str | None, typer.Option("--ray", help="Run on a Ray cluster: auto (the one this "
                                                          "machine is part of), local (start one here) or "
                                                          "HOST:PORT. Needs the ray extra.", show_default=False)]
                  = None,
                  render_actors: Annotated[int | None, typer.Option("--render-actors", min=0, help="With --ray: "
                                                                    "long-lived render actors (default: 4 per GPU "
                                                                    "of the cluster, none without GPUs).",
                                                                    show_default=False)] = None,
                  work: Annotated[Path | None, typer.Option("--work", help="Work folder (episodes, renders, shards, "
                                                            "unit markers); default OUT.work.", show_default=False)]
                  = None,
                  retries: Annotated[int, typer.Option("--retries", min=0, help="Retries of a failing unit.")] = 2,
                  variants: VariantsOpt = Path("variants"), catalog: CatalogOption = None) -> None:
    """Build SPEC into --out: record -> render -> export per episode, in shards merged at the end. A rerun does only
    what is missing (after a crash, a kill, or failures)."""
    quiet_writers()
    from rik.dataset.build import build_dataset, check_destination
    from rik.dataset.engines import check_ray, local_engine
    from rik.dataset.spec import load_spec, spec_hash

    if ray is not None:
        check_ray()  # before any work: a missing extra is found at once
    if render_actors is not None and ray is None:
        raise RikError("--render-actors: render actors are Ray's; give --ray too")
    loaded = load_spec(spec)
    out_dir, work_dir = check_destination(out, work, spec_hash(loaded), spec_file=spec, variants=variants)
    engine: Any = None
    if ray is not None:  # before the plan, which may build variants: a cluster that does not answer writes nothing
        from rik.dataset.engines import RayEngine

        engine = RayEngine(ray, overlays(catalog), render_actors=render_actors)
    try:
        cat, plan = _plan(spec, variants, workers, catalog, loaded)
    except BaseException:
        if engine is not None:
            engine.close()
        raise
    _print_plan(plan)
    if engine is None:
        engine = local_engine(cat, workers, overlays(catalog))
    print(f"  engine: {engine.name}, {engine.workers} workers; work folder {work_dir}")
    with progress_bar() as bar:
        result = build_dataset(cat, plan, out_dir, engine, work=work_dir, variants=variants, retries=retries,
                               progress=stage_progress(bar))
    if result.up_to_date:
        print(f"{out}: already built from this spec; nothing to do ({result.episodes} episodes)")
        return
    ran = ", ".join(f"{k} {result.ran[k]}" for k in result.ran)
    reused = sum(result.reused.values())
    print(f"ran {ran} units ({reused} reused) in {result.wall_seconds:.1f} s")
    if result.failures:
        for f in result.failures[:20]:
            print(f"  failed: {f.what} after {f.attempts} attempts: {f.message}")
        more = f" (and {len(result.failures) - 20} more)" if len(result.failures) > 20 else ""
        raise RikError(f"{len(result.failures)} units failed{more}, listed above (and in {result.work}/units/failed); "
                       f"the dataset was not published; rerun the same command to retry them")
    from rik.exporters.lerobot_check import constant_warning

    if (warning := constant_warning(result.constant)) is not None:
        print(f"warning: {warning}")
    outcomes = ", ".join(f"{k} {v}" for k, v in result.outcomes.items())
    print(f"{out}: {result.episodes} episodes, {result.dataset_frames} frames (outcomes {outcomes}); load it with "
          f"LeRobotDataset('{plan.spec.repo_id}', root='{out}')")


@app.command("list")
def list_command(as_json: JsonOpt = False) -> None:
    """The datasets built on this machine (a registry in the cache folder), as they are now."""
    from rich.table import Table

    from rik.dataset.registry import list_datasets, registry_file

    rows = list_datasets()
    if as_json:
        print_json(rows)
        return
    if not rows:
        print(f"no datasets built yet (registry: {registry_file()})")
        return
    table = Table()
    for col in ("path", "repo id", "spec hash", "episodes", "outcomes", "size"):
        table.add_column(col)
    for r in rows:
        if not r["present"] or r.get("damaged"):
            table.add_row(r["path"], "(damaged)" if r.get("damaged") else "(gone)", "", "", "", "")
            continue
        outcomes = " ".join(f"{k}{v}" for k, v in r["outcomes"].items())
        table.add_row(r["path"], str(r["repo_id"]), str(r["spec_hash"])[:12], str(r["episodes"]), outcomes,
                      _human_bytes(r["bytes"]))
    console().print(table)
    for r in rows:
        if r.get("damaged"):
            print(f"damaged: {r['damaged']}")


@app.command("show")
def show_command(root: Annotated[Path, typer.Argument(help="A built dataset's folder.", show_default=False)],
                 as_json: JsonOpt = False) -> None:
    """A built dataset: its spec, hash, counts, outcomes, size and the build's statistics."""
    from rik.dataset.meta import DATASET_META
    from rik.dataset.registry import describe_dataset

    info = describe_dataset(root)
    if not info["present"]:
        raise RikError(f"{root}: not a dataset built by rik dataset build (no readable meta/{DATASET_META})")
    if as_json:
        print_json(info)
        return
    b = info["build"]
    print(f"{info['path']}: {info['repo_id']}, spec hash {info['spec_hash'][:12]} (from {info['source']})")
    print(f"  {info['episodes']} episodes, {info['frames']} frames, {info['variants']} variants; streams "
          f"{', '.join(info['streams'] or []) or 'none'}; outcomes "
          + ", ".join(f"{k} {v}" for k, v in info["outcomes"].items()))
    print(f"  size {_human_bytes(info['bytes'])}; built by rik {info['rik']}")
    if b:
        secs = ", ".join(f"{k} {v:.1f} s" for k, v in b.get("seconds", {}).items())
        print(f"  build: {b.get('engine')} with {b.get('workers')} workers, {b.get('wall_seconds')} s wall; "
              f"time in units: {secs}")


@app.command("verify")
def verify_command(root: Annotated[Path, typer.Argument(help="A built dataset's folder.", show_default=False)]
                   ) -> None:
    """Re-check a built dataset: every file's sha256 against the build's record, each episode's frame counts
    (videos decoded), and that LeRobotDataset loads it and reads each episode's first and last frame."""
    from rik.dataset.verify import verify_dataset

    r = verify_dataset(root)
    if not r.ok:
        for p in r.problems[:20]:
            print(f"  {p}")
        n = len(r.problems)
        raise RikError(f"{root}: {n} problem{'s' if n != 1 else ''}, listed above")
    print(f"{root}: ok: {r.files} files match their sha256; {r.episodes} episodes, {r.frames} frames load")
