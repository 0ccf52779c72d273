"""``rik visual-gap``: FID, KID and EMD between real, simulated and re-rendered images. Only parsing and printing
here; :mod:`rik.render.visual_gap` does the work."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from rik.cli.common import console, progress_bar
from rik.outputs import RECORDED, check_destination, write_text

if TYPE_CHECKING:
    from rich.progress import TaskID

    from rik.render.visual_gap import VisualGapResult


def visual_gap(
        real: Annotated[Path, typer.Option("--real", file_okay=False, show_default=False,
                                           help="Folder of real images (PNG/JPEG, searched recursively).")],
        sim: Annotated[Path | None, typer.Option("--sim", file_okay=False, show_default=False,
                                                 help="Folder of simulator images.")] = None,
        rerendered: Annotated[Path | None, typer.Option("--rerendered", file_okay=False, show_default=False,
                                                        help="Folder of re-rendered images.")] = None,
        encoder: Annotated[list[str] | None, typer.Option(
            "--encoder", "-e", show_default=False,
            help="NAME[:WEIGHTS], repeatable (default resnet18). Names: resnet18, resnet50, clip-vit-b-32, "
                 "clip-vit-b-32-gelu. Without WEIGHTS the encoder is randomly initialised (a random-feature "
                 "baseline only).")] = None,
        n: Annotated[int | None, typer.Option("--n", min=4, show_default=False,
                                              help="Subsample every folder to N images (seeded); needed when the "
                                                   "folders hold different numbers of images.")] = None,
        bootstrap: Annotated[int, typer.Option("--bootstrap", min=1, help="Bootstrap resamples per row.")] = 200,
        seed: Annotated[int, typer.Option("--seed", help="Seed of subsampling, halves and bootstrap.")] = 0,
        json_path: Annotated[Path | None, typer.Option("--json", dir_okay=False, show_default=False,
                                                       help="Write the results as JSON to this file.")] = None,
        out: Annotated[Path | None, typer.Option("--out", "-o", file_okay=False, show_default=False,
                                                 help="Write visual_gap.json and visual_gap.md into this "
                                                      "folder.")] = None,
) -> None:
    """The visual gap between real and simulated (and/or re-rendered) images: FID, KID and EMD in an image
    encoder's features, every comparison at the same size (split halves of N images), with the real-vs-real
    split-half floor and bootstrap intervals. docs/visual-gap.md explains the protocol and where to get weights."""
    from rik.render.visual_gap import results_json, results_markdown
    from rik.render.visual_gap import visual_gap as run

    if json_path is not None:  # before the work: a file of the user's there is never replaced
        check_destination(json_path, RECORDED, "--json")
    if out is not None:
        for name in ("visual_gap.json", "visual_gap.md"):
            check_destination(out / name, RECORDED, "--out")
    results = []
    with progress_bar() as progress:
        for spec in encoder or ["resnet18"]:
            task = progress.add_task(f"encoding ({spec.partition(':')[0]})", total=None, last="")

            def step(done: int, total: int, name: str, task: TaskID = task) -> None:
                progress.update(task, completed=done, total=total, last=name)

            results.append(run(real, sim, rerendered, encoder_spec=spec, n=n, bootstrap=bootstrap, seed=seed,
                               progress=step))
    for r in results:
        print_result(r)
    if json_path is not None:
        write_text(json_path, results_json(results), RECORDED)
        console().print(f"JSON: {json_path}")
    if out is not None:
        write_text(out / "visual_gap.json", results_json(results), RECORDED)
        write_text(out / "visual_gap.md", results_markdown(results), RECORDED)
        console().print(f"reports: {out / 'visual_gap.md'} and {out / 'visual_gap.json'}")


def print_result(r: VisualGapResult) -> None:
    """One encoder's rich table: rows sim / rerendered / the real split-half floor; FID, KID, EMD with intervals."""
    from rich.table import Table

    from rik.render.visual_gap import cell, encoder_label, protocol_line

    pct = f"{r.level:.0%} CI"
    table = Table(title=f"visual gap, encoder {encoder_label(r)}", caption=protocol_line(r), caption_justify="left")
    table.add_column("set")
    table.add_column("images per side", justify="right")
    for metric in ("FID", "KID", "EMD"):
        table.add_column(f"{metric} [{pct}]", justify="right")
    for row in r.rows:
        table.add_row(row.name, str(row.n), cell(row.fid), cell(row.kid), cell(row.emd),
                      style="dim" if row.name.startswith("real") else None)
    con = console()
    con.print(table)
    if r.note:
        con.print(f"[yellow]note: {r.note}[/]")
