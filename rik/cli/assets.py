"""``rik assets``: build meshes and collision, measure collision fidelity, print mesh statistics, import meshes.

Only parsing and printing here; :mod:`rik.assets` does the work (heavy libraries load inside it).
"""

from __future__ import annotations

from enum import StrEnum
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

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
from rik.outputs import check_destination
from rik.paths import check_folder

if TYPE_CHECKING:
    from rik.assets.build import BuildResult

app = typer.Typer(help="Meshes, CoACD collision, collision fidelity and mesh statistics of handles and base units.",
                  no_args_is_help=True)

IdsArg = Annotated[list[str] | None, typer.Argument(help="Handle or base-unit ids, e.g. two_point/bow-128.",
                                                    show_default=False)]
AllOpt = Annotated[bool, typer.Option("--all", help="Every handle (and, for build, every base unit).")]
SeedOpt = Annotated[int, typer.Option(help="Seed of CoACD and of the surface sampling.")]


def _print_csv(rows: list[dict[str, Any]], columns: list[str]) -> None:
    import csv
    import sys

    writer = csv.DictWriter(sys.stdout, fieldnames=columns, lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)


def print_demo_assets(overlay_paths: list[Path]) -> None:
    """Build the demo's assets (:func:`rik.demo.build_assets`) and print their collision fidelity and the finger
    test of the two-point handle."""
    from rik.assets.finger import FINGER_RADIUS
    from rik.demo import FINGER_HANDLE, build_assets

    con = console()
    with con.status("building sample assets (CoACD) ..."):
        made = build_assets(overlay_paths)
    for asset_id, asset in made.parts.items():
        con.print(f"asset {asset_id}: {len(asset.parts)} rigid part(s), "
                  f"{sum(len(p.hulls) for p in asset.parts)} convex parts, "
                  f"{sum(len(p.visual.faces) for p in asset.parts)} visual triangles")
    for r in made.fidelity:
        con.print(f"fidelity {r['id']}: E_Q->P {r['eqp_mean_mm']:.2f} mm with CoACD, {r['hull_eqp_mean_mm']:.2f} mm "
                  f"with one convex hull ({r['hull_over_coacd']:.1f}x)")
    con.print(f"finger test {FINGER_HANDLE} ({2 * FINGER_RADIUS * 1e3:.0f} mm finger through the loop): "
              f"{'passes' if made.finger_coacd.passes else 'BLOCKED'} with CoACD, "
              f"{'blocked' if not made.finger_hull.passes else 'passes'} by the convex hull")
    con.print(f"assets are cached in {made.cache}; next: rik assets build --all, rik assets fidelity --all")


@app.command()
def build(ids: IdsArg = None, everything: AllOpt = False, workers: WorkersOpt = DEFAULT_WORKERS,
          seed: SeedOpt = 0, catalog: CatalogOption = None) -> None:
    """Generate visual meshes and CoACD collision into the cache ($RIK_CACHE); cached assets are not rebuilt."""
    from rik.assets.build import build_assets, resolve_ids
    from rik.assets.cache import AssetCache
    from rik.registry.load import load_catalog

    cat = load_catalog(overlays(catalog))
    wanted = resolve_ids(cat, ids or [], everything)
    cache = AssetCache()
    notes = []
    with progress_bar() as progress:
        task = progress.add_task("assets", total=len(wanted), last="")

        def advance(result: BuildResult) -> None:
            if result.note:
                notes.append(result.note)
            progress.update(task, advance=1, last=f"{result.id} ({result.status})")

        results = build_assets(cat, wanted, overlays=overlays(catalog), seed=seed, workers=workers, cache=cache,
                               on_result=advance)
    counts = {s: sum(r.status == s for r in results) for s in ("built", "rebuilt", "cached")}
    for note in notes:
        console().print(f"[yellow]note:[/] {note}")
    rebuilt = f", {counts['rebuilt']} rebuilt after a failed hash check" if counts["rebuilt"] else ""
    console().print(f"{len(results)} assets: {counts['built']} built{rebuilt}, {counts['cached']} from the cache; "
                    f"{sum(r.hulls for r in results)} convex parts in all. Cache: {cache.root}")


@app.command()
def fidelity(ids: IdsArg = None, everything: AllOpt = False,
             out: Annotated[Path, typer.Option(help="Where fidelity.csv and the per-handle pictures go.")] = Path(
                 "fidelity"),
             points: Annotated[int, typer.Option(min=1000, help="Surface samples per shell.")] = 20_000,
             workers: WorkersOpt = DEFAULT_WORKERS, seed: SeedOpt = 0,
             format: Annotated[OutputFormat, typer.Option("--format", "-f")] = OutputFormat.table,
             catalog: CatalogOption = None) -> None:
    """Collision fidelity (paper 3.2): E_Q->P and E_P->Q in mm for CoACD and the convex-hull baseline.

    Writes OUT/fidelity.csv (merged with rows already there), and OUT/<id>/fidelity.png (heatmaps as in the
    paper's Figure 5) and thumbnail.png. The repository's pictures are made with --out docs/catalog."""
    from rik.assets.fidelity import check_points
    from rik.assets.report import (
        FIDELITY_COLUMNS,
        csv_table,
        fidelity_row,
        handle_ids,
        merge_csv,
        run_rows,
        summarise_fidelity,
    )
    from rik.registry.load import load_catalog

    check_points(points)
    check_folder(out, "--out")
    check_destination(out / "fidelity.csv", csv_table(FIDELITY_COLUMNS), "--out")  # before any work
    cat = load_catalog(overlays(catalog))
    wanted = handle_ids(cat, ids or [], everything)
    with progress_bar() as progress:
        task = progress.add_task("fidelity", total=len(wanted), last="")
        rows = run_rows(fidelity_row, cat, wanted, workers=workers, overlays=overlays(catalog),
                        on_row=lambda r: progress.update(task, advance=1, last=r["id"]), out=out, points=points,
                        seed=seed)
    merge_csv(rows, FIDELITY_COLUMNS, out / "fidelity.csv")
    summary = summarise_fidelity(rows)
    if format is OutputFormat.json:
        print_json({"handles": rows, "summary": summary})
        return
    if format is OutputFormat.csv:
        _print_csv(rows, FIDELITY_COLUMNS)
        return
    from rich.table import Table

    table = Table(title="Collision fidelity, mm (Q: CoACD shell, Q': convex hull, P: visual surface)")
    for col in ("handle", "hulls", "E_Q->P mean", "p95", "max", "E_P->Q mean", "E_Q'->P mean", "E_P->Q' mean",
                "hull / CoACD"):
        table.add_column(col, justify="left" if col == "handle" else "right")
    for r in rows:
        table.add_row(r["id"], str(r["hulls"]), f"{r['eqp_mean_mm']:.2f}", f"{r['eqp_p95_mm']:.2f}",
                      f"{r['eqp_max_mm']:.2f}", f"{r['epq_mean_mm']:.2f}", f"{r['hull_eqp_mean_mm']:.2f}",
                      f"{r['hull_epq_mean_mm']:.2f}", f"{r['hull_over_coacd']:.1f}x")
    con = console()
    con.print(table)
    for name, s in summary.items():
        con.print(f"{name}: {s['handles']} handles, mean E_Q->P {s['eqp_mean_mm']:.2f} mm (convex hull "
                  f"{s['hull_eqp_mean_mm']:.2f} mm, {s['hull_over_coacd']:.1f}x), mean E_P->Q "
                  f"{s['epq_mean_mm']:.2f} mm (convex hull {s['hull_epq_mean_mm']:.2f} mm)")
    con.print(f"wrote {out / 'fidelity.csv'} and pictures under {out}/")


@app.command()
def stats(ids: IdsArg = None, everything: AllOpt = False, workers: WorkersOpt = DEFAULT_WORKERS,
          seed: SeedOpt = 0, out: Annotated[Path | None, typer.Option(help="Also write the rows as CSV here.")] = None,
          format: Annotated[OutputFormat, typer.Option("--format", "-f")] = OutputFormat.table,
          catalog: CatalogOption = None) -> None:
    """Mesh statistics per handle (paper Figure 3): vertices, faces, mean edge length, mean face area."""
    from rik.assets.report import STATS_COLUMNS, csv_table, handle_ids, run_rows, stats_row, write_csv
    from rik.registry.load import load_catalog

    if out is not None and out.is_dir():
        raise RikError(f"--out {out}: a folder is there; give the path of the CSV file to write")
    if out is not None:  # before any work: a file of the user's there is never replaced
        check_destination(out, csv_table(STATS_COLUMNS), "--out")

    cat = load_catalog(overlays(catalog))
    wanted = handle_ids(cat, ids or [], everything)
    rows = run_rows(stats_row, cat, wanted, workers=workers, overlays=overlays(catalog), seed=seed)
    if out is not None:
        write_csv(rows, STATS_COLUMNS, out)
    if format is OutputFormat.json:
        print_json(rows)
        return
    if format is OutputFormat.csv:
        _print_csv(rows, STATS_COLUMNS)
        return
    from rich.table import Table

    table = Table(title="Mesh statistics of the visual meshes")
    for col in ("handle", "vertices", "faces", "mean edge mm", "mean face area mm²", "watertight", "hulls",
                "collision vertices"):
        table.add_column(col, justify="left" if col == "handle" else "right")
    for r in rows:
        table.add_row(r["id"], str(r["vertices"]), str(r["faces"]), f"{r['mean_edge_mm']:.3f}",
                      f"{r['mean_face_area_mm2']:.4f}", "yes" if r["watertight"] else "no", str(r["hulls"]),
                      str(r["collision_vertices"]))
    console().print(table)


class UnitsArg(StrEnum):
    auto = "auto"
    m = "m"
    cm = "cm"
    mm = "mm"
    inch = "in"


class AxisArg(StrEnum):
    px, nx, py, ny, pz, nz = "+x", "-x", "+y", "-y", "+z", "-z"


@app.command("import")
def import_(
    file: Annotated[Path, typer.Argument(help="Mesh file: .stl, .obj, .ply, .off, .glb or .gltf.")],
    design_id: Annotated[str, typer.Option("--id", help="New id: a design (two_point/my-bar) or, with --base-unit, "
                                           "a base unit (drawer/my-chest).")],
    handle_type: Annotated[HandleTypeOpt | None, typer.Option("--type", help="Handle type (handles).")] = None,
    handle: Annotated[bool, typer.Option("--handle", help="Import a handle (the default).")] = True,
    base_unit: Annotated[bool, typer.Option("--base-unit", help="Import a base unit from a GLB with named nodes "
                                            "(needs --parts).")] = False,
    parts: Annotated[Path | None, typer.Option(help="YAML mapping GLB nodes to the carcass and fronts, with their "
                                               "joints (base units; format: rik/schemas/imports.py).")] = None,
    size: Annotated[str | None, typer.Option(help="Size label; the handle id is <id>-<size>. Default: hole "
                                             "spacing (two-point) or length, in mm.")] = None,
    name: Annotated[str | None, typer.Option(help="Display name of the design.")] = None,
    finish: Annotated[str, typer.Option(help="Finish id (rik catalog list --kind finishes).")] = "metal/brushed-steel",
    units: Annotated[UnitsArg, typer.Option(help="Units of the file; auto = metres, refusing sizes that cannot "
                                            "be a handle.")] = UnitsArg.auto,
    out_axis: Annotated[AxisArg, typer.Option("--out", help="The file's axis that points out of the front.")] = (
        AxisArg.pz),
    long_axis: Annotated[AxisArg, typer.Option("--long", help="The file's axis along the handle.")] = AxisArg.px,
    hole_spacing: Annotated[float | None, typer.Option(help="Screw centre-to-centre, m (two-point).")] = None,
    clearance: Annotated[tuple[float, float] | None, typer.Option(help="Finger clearance DEPTH WIDTH, m "
                                                                  "(finger-pulls; measured for two-point).")] = None,
    mass: Annotated[float | None, typer.Option(help="Mass, kg (default: volume x zinc density).")] = None,
    catalog_dir: Annotated[Path, typer.Option(help="User overlay catalog to register the handle in.")] = Path(
        "rik-catalog"),
    # the default is rik.assets.importer.MAX_FACES, written out so that `rik --help` does not import the importer
    max_faces: Annotated[int, typer.Option(min=1, help="Refuse files with more triangles than this (CoACD and the "
                                           "checks would run for minutes and may run out of memory), and files "
                                           "larger than 512 bytes per triangle plus 64 MiB (unread).")] = 500_000,
    seed: SeedOpt = 0,
    catalog: CatalogOption = None,
) -> None:
    """Import a real handle mesh (or a base unit): clean it, normalise units and frame, decompose it with CoACD,
    measure its collision fidelity (and the finger test for two-point handles), then register it in a user
    catalog. Nothing is registered unless every step succeeds."""
    from rik.assets.importer import import_handle
    from rik.assets.report import fidelity_row, picture_dir
    from rik.registry.load import load_catalog

    del handle
    if base_unit:
        _import_base_unit(file, parts, design_id, catalog_dir, overlays(catalog), seed, max_faces)
        return
    if handle_type is None:
        raise RikError("--type is required for a handle: knob, two_point or finger_pull")
    size_label = size
    if size_label is None:
        size_label = f"{round(hole_spacing * 1000)}" if hole_spacing else "imported"
    handle_id = f"{design_id}-{size_label}"
    done: dict[str, Any] = {}

    def decompose(staged: Path) -> None:
        """CoACD, the fidelity figures and pictures (into the staging directory) and the finger test, before
        anything is registered."""
        cat = load_catalog([*overlays(catalog), catalog_dir, staged])
        with console().status("decomposing with CoACD and measuring its fidelity ..."):
            done["row"] = fidelity_row(cat, handle_id, out=staged / "pictures", seed=seed)
        if handle_type is HandleTypeOpt.two_point:
            from rik.assets.build import build_asset
            from rik.assets.finger import finger_test

            asset, _ = build_asset(cat, handle_id, seed)
            done["finger"] = finger_test(asset.part("handle").hulls, cat.handles[handle_id].geometry)

    imported = import_handle(file, handle_type=handle_type.value, design_id=design_id, size=size_label,
                             catalog_dir=catalog_dir, name=name, finish=finish, units=units.value,
                             out_axis=out_axis.value, long_axis=long_axis.value, hole_spacing=hole_spacing,
                             clearance=clearance, mass=mass, max_faces=max_faces, prepare=decompose,
                             extras=picture_dir(Path("pictures"), handle_id))
    con = console()
    g = imported.geometry
    con.print(f"registered {imported.handle_id} in {imported.yaml_path} (mesh {imported.mesh_path}): "
              f"{g['length'] * 1e3:.1f} x {g['width'] * 1e3:.1f} mm, projection {g['projection'] * 1e3:.1f} mm"
              + (f", clearance {g['clearance']['depth'] * 1e3:.1f} x {g['clearance']['width'] * 1e3:.1f} mm"
                 if "clearance" in g else ""))
    row = done["row"]
    con.print(f"collision: {row['hulls']} convex parts; E_Q->P mean {row['eqp_mean_mm']:.2f} mm, E_P->Q mean "
              f"{row['epq_mean_mm']:.2f} mm (convex hull: {row['hull_eqp_mean_mm']:.2f} mm, "
              f"{row['hull_over_coacd']:.1f}x); pictures in {picture_dir(catalog_dir / 'pictures', handle_id)}")
    if "finger" in done:
        result = done["finger"]
        verdict = "passes through the loop" if result.passes else "is blocked"
        con.print(f"finger test: a 10 mm finger {verdict} (closest {result.min_distance * 1e3:.1f} mm)")
    con.print(f"use it with --catalog {catalog_dir} (or RIK_CATALOG={catalog_dir})")


def _import_base_unit(file: Path, parts: Path | None, unit_id: str, catalog_dir: Path, overlay_paths: list[Path],
                      seed: int, max_faces: int) -> None:
    from rik.assets.build import build_asset
    from rik.assets.importer import import_base_unit
    from rik.registry.load import load_catalog

    if parts is None:
        raise RikError("--base-unit needs --parts PARTS.yaml: which node is the carcass and each front, and how "
                       "each front moves (format: rik/schemas/imports.py)")
    con = console()
    built: dict[str, Any] = {}

    def decompose(staged: Path) -> None:
        """CoACD on every rigid part, before anything is registered."""
        with con.status("decomposing every rigid part with CoACD ..."):
            built["asset"], _ = build_asset(load_catalog([*overlay_paths, catalog_dir, staged]), unit_id, seed)

    unit_id, yaml_path = import_base_unit(file, parts, unit_id=unit_id, catalog_dir=catalog_dir,
                                          max_faces=max_faces, prepare=decompose)
    cat = load_catalog([*overlay_paths, catalog_dir])
    unit = cat.base_units[unit_id]
    c = unit.carcass
    con.print(f"registered {unit_id} in {yaml_path}: carcass {c.width * 1e3:.0f} x {c.height * 1e3:.0f} x "
              f"{c.depth * 1e3:.0f} mm (w x h x d), fronts: "
              + ", ".join(f"{f.id} ({f.kind}, {f.joint.type})" for f in unit.fronts))
    for p in built["asset"].parts:
        con.print(f"  {p.name}: {len(p.visual.faces)} triangles, {len(p.hulls)} convex parts")
    con.print(f"use it with --catalog {catalog_dir} (or RIK_CATALOG={catalog_dir})")
