"""``rik eval``: a saved LeRobot policy, or a scripted strategy, on rik's benchmark. Only parsing and printing
here; :mod:`rik.evaluation.evaluate` does the work."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from rik.cli.common import DEFAULT_WORKERS, CatalogOption, WorkersOpt, console, overlays, progress_bar


def _names(text: str) -> tuple[str, ...]:
    return tuple(t.strip() for t in text.split(",") if t.strip())


def eval_policy(
        policy: Annotated[str, typer.Argument(help="A saved LeRobot policy's folder (e.g. outputs/train/<run>/"
                                              "checkpoints/last/pretrained_model), or strategy:<name> for a "
                                              "scripted strategy (strategy:contact_rich).", show_default=False)],
        split: Annotated[str, typer.Option("--split", help="Catalog split of the handles: train, val, test "
                                           "(rik catalog splits), or all.")] = "test",
        presets: Annotated[str, typer.Option("--presets", help="Comma-separated presets.")] = "smooth,normal,high",
        types: Annotated[str, typer.Option("--types", help="Comma-separated handle types.")] =
        "knob,finger_pull,two_point",
        kinds: Annotated[str, typer.Option("--kinds", help="Comma-separated front kinds of the base units.")] =
        "drawer",
        per_cell: Annotated[int, typer.Option("--episodes-per-cell", "-n", min=1,
                                              help="Episodes per handle type x preset.")] = 10,
        seed: Annotated[int, typer.Option("--seed", help="First episode's seed (lerobot-eval's --seed); then +1 "
                                          "each.")] = 1000,
        episode_length: Annotated[int, typer.Option("--episode-length", min=1, help="Control steps before an "
                                                    "episode is cut off (20 per second).")] = 400,
        rerendered: Annotated[bool, typer.Option("--rerendered", help="Render Mitsuba's stream for a policy "
                                                 "trained on _rerendered images (slow without a GPU).")] = False,
        videos: Annotated[int, typer.Option("--videos", min=0, help="Episodes filmed (the first ones).")] = 4,
        label: Annotated[str, typer.Option("--label", help="Name of the policy in the table (default: its type "
                                           "and folder).")] = "",
        out: Annotated[Path, typer.Option("--out", "-o", help="Where table.md, episodes.csv, eval_info.json and "
                                          "videos/ go.")] = Path("eval"),
        workers: WorkersOpt = DEFAULT_WORKERS,
        variants: Annotated[Path, typer.Option("--variants", help="Directory of built variants.")] = Path("variants"),
        catalog: CatalogOption = None) -> None:
    """Evaluate a policy on rik's benchmark: episodes drawn from a split, F/P/S per handle type x preset (the
    paper's Table 3) with Wilson intervals, per-episode rows, videos and lerobot-eval's eval_info.json."""
    from rik.evaluation.evaluate import EvalSpec, prepare, run_eval
    from rik.registry.load import load_catalog

    cat = load_catalog(overlays(catalog))
    spec = prepare(cat, EvalSpec(policy, None if split == "all" else split, _names(types), _names(presets),
                                 _names(kinds), per_cell, seed, episode_length, rerendered, videos, str(variants),
                                 label))
    n = len(spec.seeds())
    with progress_bar() as progress:
        task = progress.add_task(f"{spec.label}", total=n, last="")
        rows = run_eval(cat, spec, out, workers=workers,
                        progress=lambda r: progress.update(task, advance=1,
                                                           last=f"seed {r['seed']} {r['variant']} {r['outcome']}"))
    con = console()
    con.print((out / "table.md").read_text())
    wins = sum(r["success"] for r in rows)
    con.print(f"{len(rows)} episodes, {wins} successes ({100 * wins / len(rows):.1f} %); table.md, episodes.csv, "
              f"eval_info.json in {out}")
