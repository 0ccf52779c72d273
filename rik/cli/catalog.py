"""``rik catalog``: browse handles, designs, base units, presets and finishes; generate CATALOG.md.

Only parsing and printing here; the registry does the work. Nothing heavy is imported: this group must
start as fast as a plain pydantic program.
"""

from __future__ import annotations

import sys
from enum import StrEnum
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from rik.cli.common import CatalogOption, HandleTypeOpt, OutputFormat, console, overlays, print_json
from rik.errors import RikError
from rik.outputs import Replaces, check_destination, write_text

if TYPE_CHECKING:
    from rich.tree import Tree

    from rik.outputs import Replaces

app = typer.Typer(help="Browse the catalog of handles, base units, resistance presets and robots.",
                  no_args_is_help=True)


class Kind(StrEnum):
    handles = "handles"
    designs = "designs"
    bases = "bases"
    presets = "presets"
    finishes = "finishes"
    robots = "robots"


class JointOpt(StrEnum):
    slide = "slide"
    hinge = "hinge"


@app.command("list")
def list_entries(
    kind: Annotated[Kind, typer.Option("--kind", "-k", help="What to list.")] = Kind.handles,
    type: Annotated[HandleTypeOpt | None, typer.Option("--type", "-t", help="Handle type (handles, designs).")] = None,
    design: Annotated[str | None, typer.Option(help="Design id, for example two_point/bow (handles).")] = None,
    joint: Annotated[JointOpt | None, typer.Option(help="Joint type of a front (bases).")] = None,
    min_length: Annotated[float | None, typer.Option(help="Minimum overall handle length, m.")] = None,
    max_length: Annotated[float | None, typer.Option(help="Maximum overall handle length, m.")] = None,
    split: Annotated[str | None, typer.Option(help="Split: train, val or test (handles, designs).")] = None,
    format: Annotated[OutputFormat, typer.Option("--format", "-f", help="table for people; json or csv "
                                                 "(SI units) for scripts.")] = OutputFormat.table,
    catalog: CatalogOption = None,
) -> None:
    """List catalog entries, filtered."""
    from rik.registry.index import catalog_index
    from rik.registry.views import KINDS

    section = KINDS[kind.value]
    _check_filters(kind.value, type=type, design=design, joint=joint, min_length=min_length, max_length=max_length,
                   split=split)
    rows = catalog_index(overlays(catalog)).select(
        section, type=type and type.value, design=design, joint=joint and joint.value,
        min_length=min_length, max_length=max_length, split=split)
    if format is OutputFormat.json:
        print_json(rows)
    elif format is OutputFormat.csv:
        _print_csv(rows)
    else:
        _print_table(section, rows, title=f"{len(rows)} {kind.value}")


#: Which kinds (CLI names) each filter applies to.
FILTER_KINDS = {"type": ("handles", "designs"), "design": ("handles",), "joint": ("bases",),
                "min_length": ("handles",), "max_length": ("handles",), "split": ("handles", "designs")}


def _check_filters(kind: str, **given: object) -> None:
    """Reject filters that do not apply to the kind listed (rather than silently ignoring them)."""
    for name, value in given.items():
        if value is not None and kind not in FILTER_KINDS[name]:
            option = "--" + name.replace("_", "-")
            raise RikError(f"{option} filters {' and '.join(FILTER_KINDS[name])}, not {kind}")


@app.command()
def show(
    entry_id: Annotated[str, typer.Argument(metavar="ID", help="Any catalog id: handle, design, base unit, "
                                                                "preset, finish or robot.")],
    format: Annotated[OutputFormat, typer.Option("--format", "-f", help="table (readable) or json.")] =
        OutputFormat.table,
    catalog: CatalogOption = None,
) -> None:
    """Show one entry in full."""
    from rik.registry.index import catalog_index

    index = catalog_index(overlays(catalog))
    section, entry = index.lookup(entry_id)
    if format is OutputFormat.json:
        print_json(entry)
        return
    if format is OutputFormat.csv:
        _print_csv([entry])
        return
    from rich.tree import Tree

    from rik.registry.sources import NOUNS

    tree = Tree(f"[bold]{entry['id']}[/]  [dim]({NOUNS[section]})[/]")
    _add_branches(tree, {k: v for k, v in entry.items() if k != "id"})
    if section == "designs":
        tree.add("handles: " + ", ".join(h["id"] for h in index.select("handles", design=entry["id"])))
    console().print(tree)
    if section == "robots":
        print("Lengths in m, forces in N, torques in N·m, angles in rad, speeds in rad/s (joints) and m/s (fingers); "
              "stiffness N·m/rad, damping N·m·s/rad, armature kg·m² (SI).")
    else:
        print("Lengths in m, masses in kg, angles in rad (SI).")


def _add_branches(tree: Tree, data: dict[str, Any]) -> None:
    from rich.markup import escape

    for key, value in data.items():
        if isinstance(value, dict):
            _add_branches(tree.add(f"[cyan]{key}[/]"), value)
        elif isinstance(value, list) and value and isinstance(value[0], dict):
            branch = tree.add(f"[cyan]{key}[/]")
            for item in value:
                label = "id" if "id" in item else "name" if "name" in item else None  # a robot's joints: by name
                rest = {k: v for k, v in item.items() if k != label}
                _add_branches(branch.add(f"[bold]{escape(str(item[label])) if label else ''}[/]"), rest)
        else:
            tree.add(f"[cyan]{key}[/]: {escape(str(value))}")


@app.command()
def stats(catalog: CatalogOption = None,
          format: Annotated[OutputFormat, typer.Option("--format", "-f")] = OutputFormat.table) -> None:
    """Counts per handle type, base units per joint, presets, and how many pairings fit."""
    from rik.registry.index import catalog_index
    from rik.registry.stats import catalog_stats

    numbers = catalog_stats(catalog_index(overlays(catalog)))
    if format is OutputFormat.json:
        print_json(numbers)
    else:
        print_summary(numbers)


@app.command()
def splits(catalog: CatalogOption = None,
           format: Annotated[OutputFormat, typer.Option("--format", "-f")] = OutputFormat.table) -> None:
    """The named splits (train, val, test): designs and handles per handle type, the measured presets (real doors)
    of each, and the split version."""
    from rik.registry.index import catalog_index
    from rik.registry.load import load_catalog
    from rik.registry.splits import SPLITS, split_presets
    from rik.registry.stats import HANDLE_TYPES, split_stats
    from rik.registry.views import format_columns
    from rik.schemas.joints import MECHANISMS

    numbers = split_stats(catalog_index(overlays(catalog)))
    cat = load_catalog(overlays(catalog))
    numbers["presets"] = {name: {p: cat.presets[p].hinge.mechanism() for p in split_presets(cat, name)}
                          for name in SPLITS}
    if format is OutputFormat.json:
        print_json(numbers)
        return
    if format is OutputFormat.csv:
        _print_csv([{"split": name, **row} for name, row in numbers["splits"].items()])
        return
    headers = ["split", *(f"{t} designs / handles" for t in HANDLE_TYPES), "designs", "handles"]
    rows = [[name, *(f"{row['by_type'][t]['designs']} / {row['by_type'][t]['handles']}" for t in HANDLE_TYPES),
             str(row["designs"]), str(row["handles"])] for name, row in numbers["splits"].items()]
    print(format_columns(headers, rows))
    print(format_columns(["split", *(f"real doors: {m}" for m in MECHANISMS)],
                         [[name, *(str(list(doors.values()).count(m)) for m in MECHANISMS)]
                          for name, doors in numbers["presets"].items()]))
    print(f"splits v{numbers['version']}: whole designs and whole real doors held out; every split spans all base "
          "units and the paper's presets (list one with `rik catalog list --split test`; draw a split's real doors "
          "with --joints measured)")


def print_summary(numbers: dict[str, Any]) -> None:
    """The catalog summary as people read it (also the demo's output)."""
    from rich.table import Table

    table = Table(title=f"rik catalog: {numbers['handles']} handles in {numbers['designs']} designs")
    for col in ("handle type", "designs", "handles"):
        table.add_column(col, justify="left" if col == "handle type" else "right")
    for name, row in numbers["by_type"].items():
        table.add_row(name, str(row["designs"]), str(row["handles"]))
    out = console()
    out.print(table)
    fronts = ", ".join(f"{n} {k}{'s' if n > 1 else ''}" for k, n in numbers["fronts_by_kind"].items())
    joints = ", ".join(f"{n} with {j} joints" for j, n in numbers["base_units_by_joint"].items())
    out.print(f"base units: {numbers['base_units']} ({joints}); fronts: {fronts}")
    named = numbers.get("named_presets") or []
    more = f" (and {len(named)} measured, built when named: rik catalog list --kind presets)" if named else ""
    out.print(f"resistance presets: {', '.join(numbers['presets'])}{more}; finishes: {numbers['finishes']}")
    out.print(f"pairings that fit: {numbers['pairings']['fit']} of {numbers['pairings']['total']} "
                  "(base units x handles)")
    out.print(f"robots: {', '.join(numbers['robots'])} (rik catalog list --kind robots)")
    if numbers["overlay_entries"]:
        out.print(f"entries from user catalogs: {numbers['overlay_entries']}")




def _catalog_page() -> Replaces:
    """What ``rik catalog doc`` may write over: a page it generated (its first lines say so)."""

    return Replaces.marked("a catalog page rik catalog doc wrote", "<!-- Generated by `rik catalog doc`")


@app.command()
def doc(
    out: Annotated[Path, typer.Option(help="Where to write the page.")] = Path("CATALOG.md"),
    check: Annotated[bool, typer.Option("--check", help="Write nothing; exit 1 if the page is out of date.")] = False,
) -> None:
    """Generate CATALOG.md from the built-in catalog (user catalogs are not included)."""
    from rik.registry.doc import render_catalog_md
    from rik.registry.index import catalog_index

    page = _catalog_page()
    text = render_catalog_md(catalog_index([]), out.parent)
    if check:
        current = out.read_text(encoding="utf-8") if out.is_file() else None
        if current != text:
            state = "missing" if current is None else "out of date"
            print(f"{out} is {state}; run `rik catalog doc` and commit it", file=sys.stderr)
            raise typer.Exit(1)
        print(f"{out} is up to date")
        return
    write_text(check_destination(out, page, "--out"), text, page)
    print(f"wrote {out}")


@app.command("robots-doc")
def robots_doc(
    out: Annotated[Path, typer.Option(help="The page whose generated part to rewrite.")] = Path("docs/robots.md"),
    check: Annotated[bool, typer.Option("--check", help="Write nothing; exit 1 if the figures are out of date.")]
        = False,
) -> None:
    """Write the robots' figures (joints, gripper, mount, sources) into docs/robots.md, between its markers, from
    the built-in catalog (user catalogs are not included)."""
    from rik.registry.index import catalog_index
    from rik.registry.robots_doc import render_robot_figures, splice

    if not out.is_file():
        if check:
            print(f"{out} is missing; restore it and run `rik catalog robots-doc`", file=sys.stderr)
            raise typer.Exit(1)
        raise RikError(f"{out}: no such page; its figures go between markers in a page written by hand")
    current = out.read_text(encoding="utf-8")
    text = splice(current, render_robot_figures(catalog_index([])), str(out))
    if check:
        if current != text:
            print(f"{out}'s robot figures are out of date; run `rik catalog robots-doc` and commit it",
                  file=sys.stderr)
            raise typer.Exit(1)
        print(f"{out} is up to date")
        return
    # the page is a person's; rik rewrites only what is between its markers (splice checked them) and keeps the rest
    write_text(out, text, Replaces.when("a page with rik's figure markers", lambda p: True))
    print(f"wrote the robot figures of {out}")


def _print_table(section: str, rows: list[dict[str, Any]], title: str) -> None:
    from rik.registry.views import format_columns, table

    headers, cells = table(section, rows)
    from rik.registry.views import UNITS

    print(format_columns(headers, cells))
    print(f"{title}; {UNITS.get(section, 'lengths in mm')} (use --format json or csv for SI values)")


def _print_csv(rows: list[dict[str, Any]]) -> None:
    import csv

    from rik.registry.views import flatten

    flat = [flatten(r) for r in rows]
    fields = list(dict.fromkeys(k for r in flat for k in r))
    writer = csv.DictWriter(sys.stdout, fieldnames=fields, lineterminator="\n")
    writer.writeheader()
    writer.writerows(flat)
