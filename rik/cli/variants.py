"""``rik variants``: list, build, validate and look at base unit x handle x preset variants (MJCF).

Only parsing and printing here; :mod:`rik.combinator` does the work (MuJoCo loads inside it).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from rik.cli.common import (
    DEFAULT_WORKERS,
    CatalogOption,
    HandleTypeOpt,
    OutputFormat,
    WorkersOpt,
    console,
    overlays,
    print_json,
    progress_bar,
)
from rik.errors import RikError
from rik.outputs import RECORDED, check_destination
from rik.paths import check_folder

if TYPE_CHECKING:
    from rik.combinator.build import VariantResult
    from rik.registry.catalog import Catalog
    from rik.registry.ids import VariantKey

app = typer.Typer(help="Validated MuJoCo variants: every base unit x handle x resistance preset.",
                  no_args_is_help=True)

BaseOpt = Annotated[list[str] | None, typer.Option("--base", "-b", help="Base unit id (repeatable).")]
TypeOpt = Annotated[list[HandleTypeOpt] | None, typer.Option("--handle-type", "-t", help="Handle type (repeatable).")]
HandleOpt = Annotated[list[str] | None, typer.Option("--handle", help="Handle id (repeatable).")]
PresetOpt = Annotated[list[str] | None, typer.Option("--preset", "-p", help="Resistance preset id (repeatable; "
                                                     "default: every preset but the measured ones, which are "
                                                     "built when named).")]
OutOpt = Annotated[Path, typer.Option("--out", "-o", help="Directory of built variants.")]
DirOpt = Annotated[Path, typer.Option("--dir", "-d", help="Directory of built variants.")]


def print_demo_variants(overlay_paths: list[Path], out: Path = Path("variants")) -> None:
    """Build the demo's variants into ``out`` (:func:`rik.demo.build_variants`) and print what each check found."""
    from rik.demo import build_variants

    con = console()
    with con.status("building sample variants (MuJoCo) ..."):
        results = build_variants(overlay_paths, out)
    for r, report in results:
        if report is None:
            con.print(f"variant {r.id}: [red]rejected[/] by {r.failed_check}: {r.reason}")
            continue
        pulls = ", ".join(f"{f['id']} {f['force_to_open_n']:.0f} N" for f in report["fronts"])
        con.print(f"variant {r.id}: valid ({len(report['checks'])} checks), {report['hulls']} convex handle parts; "
                  f"force to open at the handle: {pulls}")
    con.print(f"variants are in {out}/ (model.xml, scene.xml, meshes/, report.json); next: "
              "rik variants build --all --preset normal")


def print_demo_episode(overlay_paths: list[Path], out: Path = Path("episodes"), variants: Path = Path("variants"),
                       episodes: int = 2) -> list[Path]:
    """Record the demo's episodes (:func:`rik.demo.record_episodes`), print how each went and replayed, and return
    their directories."""
    from rik.demo import record_episodes

    con = console()
    with con.status("recording scripted episodes (MuJoCo) ..."):
        recorded = record_episodes(overlay_paths, out, variants, episodes)
    for meta, check in recorded:
        con.print(f"episode {out / meta.id}: {meta.outcome} (opened {meta.final_opening:.0%} in "
                  f"{meta.steps / meta.fps:.1f} s; {'; '.join(meta.log)}); replay "
                  f"{'exact' if check.exact else 'NOT exact'} over {check.rows} states")
    con.print("next: rik bench (the resistance benchmark), rik teleop VARIANT --device keyboard")
    return [out / meta.id for meta, _ in recorded]


def _select(cat: Catalog, base: list[str] | None, handle_type: list[HandleTypeOpt] | None, handle: list[str] | None,
            preset: list[str] | None) -> list[VariantKey]:
    from rik.registry.ids import select_variants

    return select_variants(cat, bases=base or (), handle_types=[t.value for t in handle_type or ()],
                           handles=handle or (), presets=preset or ())


@app.command("list")
def list_variants(base: BaseOpt = None, handle_type: TypeOpt = None, handle: HandleOpt = None,
                  preset: PresetOpt = None, directory: DirOpt = Path("variants"),
                  format: Annotated[OutputFormat, typer.Option("--format", "-f", help="table, json or csv.")] =
                  OutputFormat.table, catalog: CatalogOption = None) -> None:
    """List variant ids (every pairing of the filters), with their status in --dir when built there."""
    from rik.combinator.build import read_manifest
    from rik.registry.load import load_catalog

    cat = load_catalog(overlays(catalog))
    keys = _select(cat, base, handle_type, handle, preset)
    built = read_manifest(directory)["variants"]
    rows = [{"id": k.id, "base_unit": k.base, "handle": k.handle,
             "handle_type": cat.handle_type(cat.handles[k.handle]).value, "preset": k.preset,
             "status": built.get(k.id, {}).get("status") or _status_on_disk(directory / k.id)} for k in keys]
    if format is OutputFormat.json:
        print_json(rows)
        return
    if format is OutputFormat.csv:
        import csv
        import sys

        writer = csv.DictWriter(sys.stdout, fieldnames=list(rows[0]) if rows else ["id"], lineterminator="\n")
        writer.writeheader()
        writer.writerows(rows)
        return
    from rich.table import Table

    table = Table(title=f"{len(rows)} variants", title_justify="left")
    for column in ("id", "base unit", "handle", "type", "preset", "status"):
        table.add_column(column)
    for r in rows:
        table.add_row(*(str(v) for v in r.values()))
    console().print(table)


def _status_on_disk(path: Path) -> str:
    """A variant's status from its report when the manifest does not list it."""
    import json

    try:
        return json.loads((path / "report.json").read_text(encoding="utf-8"))["status"]
    except (OSError, ValueError, KeyError, TypeError):
        return "not built"


@app.command()
def build(ids: Annotated[list[str] | None, typer.Argument(help="Variant ids, e.g. "
                                                           "drawer-chest-60__two_point-bow-128__normal.",
                                                           show_default=False)] = None,
          everything: Annotated[bool, typer.Option("--all", help="Every pairing of the filters.")] = False,
          base: BaseOpt = None, handle_type: TypeOpt = None, handle: HandleOpt = None, preset: PresetOpt = None,
          workers: WorkersOpt = DEFAULT_WORKERS, out: OutOpt = Path("variants"),
          force: Annotated[bool, typer.Option("--force", help="Rebuild variants that are already valid.")] = False,
          collision: Annotated[str | None, typer.Option(
              "--collision", metavar="coacd|hull", show_default=False,
              help="Handle collision: coacd (its CoACD hulls) or hull (its single convex hull, the baseline). "
                   "Default: the --out folder's mode (its collision.json), coacd for a new folder. Keep hull "
                   "builds in their own folder.")] = None,
          joint_friction: Annotated[str | None, typer.Option(
              "--joint-friction", metavar="held|creeping", show_default=False,
              help="How the fronts' joint friction holds: held (rik's: a front loaded below breakaway stays put) or "
                   "creeping (MuJoCo's default impedance: it creeps at mm/s; the fidelity ablation's other side). "
                   "Default: the --out folder's mode (its joint_friction.json), held for a new folder.")] = None,
          catalog: CatalogOption = None) -> None:
    """Build variants into --out/<id>/ (model.xml, scene.xml, meshes/, report.json); valid ones are skipped."""
    from rik.combinator.build import JOINT_FRICTION, MANIFEST, build_variants, resolve_collision
    from rik.registry.ids import parse_variant_id
    from rik.registry.load import load_catalog

    check_folder(out, "--out")
    collision = resolve_collision(out, collision)  # a bad mode or a folder of the other mode: fail first
    joint_friction = JOINT_FRICTION.resolve(out, joint_friction)
    cat = load_catalog(overlays(catalog))
    filters = any((base, handle_type, handle, preset))
    if ids and (everything or filters):
        raise RikError("name variant ids, or select them with --all and the filters, not both")
    if ids:
        keys = list(dict.fromkeys(parse_variant_id(cat, i) for i in ids))
    elif everything or filters:
        keys = _select(cat, base, handle_type, handle, preset)
    else:
        raise RikError("name at least one variant id, or pass --all (with --base, --handle-type, --handle or "
                       "--preset to narrow it)")
    con = console()
    with progress_bar() as progress:
        task = progress.add_task("variants", total=len(keys), last="")

        def advance(result: VariantResult) -> None:
            progress.update(task, advance=1, last=f"{result.id} ({result.status})")

        def assets_done(built: int) -> None:
            if built:
                progress.console.print(f"{built} assets built into the cache first")

        results = build_variants(cat, keys, out, workers=workers, overlays=overlays(catalog), force=force,
                                 on_result=advance, on_assets=assets_done, collision=collision,
                                 joint_friction=joint_friction)
    rejected = [r for r in results if r.status == "rejected"]
    counts = {s: sum(r.status == s for r in results) for s in ("built", "skipped")}
    for r in rejected:
        con.print(f"[red]rejected[/] {r.id}: check {r.failed_check}: {r.reason}")
    con.print(f"{len(results)} variants: {counts['built'] + counts['skipped']} valid ({counts['built']} built, "
              f"{counts['skipped']} already valid), {len(rejected)} rejected; handle collision: {collision}, joint "
              f"friction: {joint_friction}. "
              f"Manifest: {out / MANIFEST}")
    if rejected:
        if len(results) == 1:
            raise RikError(f"variant {rejected[0].id} rejected by check {rejected[0].failed_check}: "
                           f"{rejected[0].reason}")
        raise RikError(f"{len(rejected)} of {len(results)} variants rejected (listed above); nothing was written "
                       "for them")


@app.command()
def validate(target: Annotated[str, typer.Argument(metavar="PATH|ID", help="A variant directory (or its "
                                                   "model.xml), or a variant id.")],
             directory: DirOpt = Path("variants"),
             format: Annotated[OutputFormat, typer.Option("--format", "-f", help="table or json.")] =
             OutputFormat.table, catalog: CatalogOption = None) -> None:
    """Run every check on a variant: its written files when it is built, else assembled in memory."""
    from rik.combinator.inspect import validate_variant
    from rik.registry.load import load_catalog

    result = validate_variant(load_catalog(overlays(catalog)), target, directory)
    if format is OutputFormat.json:
        print_json({"id": result.key.id, "source": result.source, "passed": result.passed, "notes": result.notes,
                    "checks": [c.as_dict() for c in result.checks]})
    else:
        from rich.markup import escape

        con = console()
        con.print(f"[bold]{result.key.id}[/] (checked from {result.source})")
        for c in result.checks:
            con.print(f"  {'[green]pass[/]' if c.passed else '[red]FAIL[/]'}  {c.name:20s} {escape(c.reason)}")
        for note in result.notes:
            con.print(f"[yellow]note:[/] {note}")
    if not result.passed:
        failed = next(c for c in result.checks if not c.passed)
        raise RikError(f"variant {result.key.id} fails check {failed.name}: {failed.reason}")


@app.command()
def show(variant: Annotated[str, typer.Argument(metavar="ID", help="A variant id.")],
         png: Annotated[Path, typer.Option("--png", help="Where to write the picture.")],
         open_fraction: Annotated[float, typer.Option("--open", help="Open every front to this fraction of its "
                                                      "range.")] = 0.5,
         width: Annotated[int, typer.Option(min=64, max=4096, help="Pixels.")] = 960,
         height: Annotated[int, typer.Option(min=64, max=4096, help="Pixels.")] = 720,
         directory: DirOpt = Path("variants"), catalog: CatalogOption = None) -> None:
    """Render a variant's scene through its front camera (MuJoCo, headless) into a PNG."""
    from rik.combinator.inspect import render_variant
    from rik.registry.ids import parse_variant_id
    from rik.registry.load import load_catalog

    if png.is_dir():
        raise RikError(f"--png {png}: a folder is there; give the path of the PNG file to write")
    cat = load_catalog(overlays(catalog))
    path = render_variant(cat, parse_variant_id(cat, variant), png, out=directory, open_fraction=open_fraction,
                          width=width, height=height)
    console().print(f"wrote {path}")



@app.command()
def probe(variant: Annotated[str, typer.Argument(metavar="ID", help="A variant id (built into --dir if needed).")],
          front: Annotated[str | None, typer.Option("--front", help="Front id (default: the variant's first).")] = None,
          speed: Annotated[float | None, typer.Option("--speed", help="Opening speed: mm/s for a drawer, deg/s for a "
                                                      "door or flap (default 5).")] = None,
          stroke: Annotated[float | None, typer.Option("--stroke", help="How far to open: mm or deg (default 100 mm "
                                                       "or 36 deg).")] = None,
          csv: Annotated[Path | None, typer.Option("--csv", help="Write the profile here, as a file rik sysid fit "
                                                   "--quasi-static reads (a hinge's as the force at the handle).")]
          = None,
          directory: DirOpt = Path("variants"), catalog: CatalogOption = None) -> None:
    """Pull a front open through its handle, slowly, as a force gauge measures a real drawer or door, and print the
    force it took against the opening (rik.sim.pull)."""
    import math

    import numpy as np
    from rich.table import Table

    from rik.combinator.build import ensure_variant
    from rik.registry.load import load_catalog
    from rik.sim.pull import front_joint, pull_profile, write_profiles

    if csv is not None:  # before the pull: a folder, a link or a file of the user's there is refused
        check_destination(csv, RECORDED, "--csv")
    folder = ensure_variant(load_catalog(overlays(catalog)), variant, directory)
    slide = front_joint(folder, front) == "slide"
    to_si = 1e-3 if slide else math.pi / 180  # mm -> m, deg -> rad
    unit = "mm" if slide else "deg"
    pull = pull_profile(folder, front, speed=None if speed is None else speed * to_si,
                        stroke=None if stroke is None else stroke * to_si)
    table = Table(title=f"{pull.variant} / {pull.front}: opened at {pull.speed / to_si:.3g} {unit}/s")
    table.add_column(f"opening ({unit})", justify="right")
    table.add_column("force at the handle (N)", justify="right")
    if not slide:
        table.add_column("torque (N·m)", justify="right")
    picks = np.unique(np.linspace(0, len(pull.q) - 1, min(len(pull.q), 12)).round().astype(int))
    for i in picks:
        row = [f"{pull.q[i] / to_si:.1f}", f"{pull.force[i]:.2f}"]
        table.add_row(*(row if slide else [*row, f"{pull.joint_force[i]:.3f}"]))
    console().print(table)
    lever = "" if pull.lever is None else f" (lever arm {float(np.median(pull.lever)):.3f} m)"
    console().print(f"force at the handle: first {pull.force[0]:.2f} N, median {float(np.median(pull.force)):.2f} N, "
                    f"largest {float(np.max(pull.force)):.2f} N{lever}")
    if csv is not None:
        console().print(f"wrote {write_profiles(csv, [pull], at_handle=True)}")
