"""``rik eval``: a saved LeRobot policy, or a scripted strategy, on rik's benchmark. Only parsing and printing
here; :mod:`rik.evaluation.evaluate` does the work."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Annotated, Any

import typer

from rik.cli.common import (
    DEFAULT_ROBOT,
    DEFAULT_WORKERS,
    CatalogOption,
    JointsOpt,
    RobotOpt,
    WorkersOpt,
    console,
    overlays,
    progress_bar,
)
from rik.errors import RikError


def _advance(progress: Any, label: str, total: int) -> Callable[[dict[str, Any]], None]:
    """A progress callback for one operator's episodes."""
    task = progress.add_task(label, total=total, last="")
    return lambda r: progress.update(task, advance=1, last=f"seed {r['seed']} {r['variant']} {r['outcome']}")


def _given(ctx: typer.Context) -> list[str]:
    """The options of :data:`rik.evaluation.protocol.DRAW_OPTIONS` given on the command line (or, for --catalog,
    through RIK_CATALOG)."""
    from rik.evaluation.protocol import DRAW_OPTIONS

    said = ("COMMANDLINE", "ENVIRONMENT")  # by name: typer carries click's ParameterSource in a copy of its own
    return [flag for name, flag in DRAW_OPTIONS.items()
            if getattr(ctx.get_parameter_source(name), "name", None) in said]


def eval_policy(
        ctx: typer.Context,
        policies: Annotated[list[str], typer.Argument(help="Saved LeRobot policies' folders (e.g. outputs/train/"
                                                      "<run>/checkpoints/last/pretrained_model), or strategy:<name> "
                                                      "for a scripted strategy (strategy:contact_rich); several are "
                                                      "run on the same episodes and tabled side by side.",
                                                      show_default=False)],
        split: Annotated[str, typer.Option("--split", help="Catalog split of the handles: train, val, test "
                                           "(rik catalog splits), or all.")] = "test",
        presets: Annotated[str, typer.Option("--presets", help="Comma-separated presets.")] = "smooth,normal,high",
        types: Annotated[str, typer.Option("--types", help="Comma-separated handle types.")] =
        "knob,finger_pull,two_point",
        kinds: Annotated[str, typer.Option("--kinds", help="Comma-separated front kinds of the base units.")] =
        "drawer",
        joints: JointsOpt = "paper",
        per_cell: Annotated[int, typer.Option("--episodes-per-cell", "-n", min=1,
                                              help="Episodes per handle type x preset.")] = 10,
        seed: Annotated[int, typer.Option("--seed", help="First episode's seed (lerobot-eval's --seed); then +1 "
                                          "each.")] = 1000,
        episode_length: Annotated[int, typer.Option("--episode-length", min=1, help="Control steps before an "
                                                    "episode is cut off (20 per second).")] = 400,
        rerendered: Annotated[bool, typer.Option("--rerendered", help="Render Mitsuba's stream for a policy "
                                                 "trained on _rerendered images (slow without a GPU).")] = False,
        renderer: Annotated[str, typer.Option("--renderer", help="Draw every image the policy reads with this "
                                              "renderer, sim (MuJoCo) or rerendered (Mitsuba), whatever stream it "
                                              "was trained on: the visual gap it pays (default: each stream its "
                                              "own).", show_default=False)] = "",
        videos: Annotated[int, typer.Option("--videos", min=0, help="Episodes filmed (the first ones).")] = 4,
        labels: Annotated[list[str] | None, typer.Option("--label", help="Name of the policy in the table "
                                                         "(default: its type and training run); with several "
                                                         "policies, once per policy, in their order.",
                                                         show_default=False)] = None,
        outs: Annotated[list[Path] | None, typer.Option("--out", "-o", help="Where table.md, episodes.csv, "
                                                        "eval_info.json and videos/ go (with several policies, a "
                                                        "folder per policy in it and their table side by side); or "
                                                        "once per policy, in their order: each policy's own folder, "
                                                        "many evaluations in one process (default: eval).",
                                                        show_default=False)] = None,
        workers: WorkersOpt = DEFAULT_WORKERS,
        variants: Annotated[Path, typer.Option("--variants", help="Directory of built variants.")] = Path("variants"),
        robot: RobotOpt = DEFAULT_ROBOT,
        action_frame: Annotated[str, typer.Option("--action-frame", help="A Hand-E policy's action position: "
                                                  "world, handle or gripper (an export made with --action-frame "
                                                  "handle or gripper), or auto: what its inputs and training "
                                                  "statistics say.")] = "auto",
        catalog: CatalogOption = None,
        protocol: Annotated[Path | None, typer.Option("--protocol", help="A frozen protocol's YAML (protocols/): "
                                                      "its split, kinds, joints, types, presets, seeds, episodes "
                                                      "and episode length, exactly; the options that would change "
                                                      "them are refused beside it.", show_default=False)] = None
        ) -> None:
    """Evaluate a policy on rik's benchmark: episodes drawn from a split, F/P/S per handle type x preset (the
    paper's Table 3) with Wilson intervals, per-episode rows, videos and lerobot-eval's eval_info.json. A policy
    trained on an arm's export runs with --robot and that arm (its joint actions); scripted strategies run with any
    robot."""
    from rik.evaluation.evaluate import (
        LABELS,
        EvalSpec,
        eval_folders,
        finished_rows,
        out_of_stats_warning,
        prepare,
        run_eval,
        write_tables,
    )
    from rik.lerobot.policy_io import PolicyIO
    from rik.registry.load import load_catalog

    PolicyIO().with_options({"action_frame": action_frame}, auto=True).validate(labels=LABELS)  # a frame, or auto
    request = PolicyIO(robot=robot, action_frame=action_frame)  # the contract asked for: the policy's fills the rest
    labels, outs = labels or [], outs or [Path("eval")]

    def given(flag: str, n: int) -> str:
        return f"{flag} given {n} time{'s' * (n != 1)} for {len(policies)} policies"

    if len(labels) not in (0, len(policies)):
        raise RikError(f"{given('--label', len(labels))}: once per policy, in their order, or not at all (each "
                       "named by its type and training run)")
    if len(outs) not in (1, len(policies)):
        raise RikError(f"{given('--out', len(outs))}: once (their folders in it), or once per policy, in their "
                       "order")
    separate = len(outs) > 1  # each policy's own folder: no table side by side
    if separate and len({o.resolve() for o in outs}) < len(outs):
        raise RikError("two policies have the same --out: give each its own folder")
    from rik.episodes.draw import Draw

    frozen = None
    if protocol is not None:
        from rik.evaluation import protocol as protocols

        frozen = protocols.read_protocol(protocol)
        protocols.check_options(protocol, _given(ctx))
        protocols.check_variants(protocol, variants)
        split, kinds, joints = frozen.split, ",".join(frozen.kinds), frozen.joints
        types, presets = ",".join(frozen.handle_types), ",".join(frozen.presets)
        per_cell, seed, episode_length = frozen.episodes_per_cell, frozen.seed, frozen.episode_length
    cat = load_catalog(overlays(catalog))
    draw = Draw.parse(split, types, presets, kinds, joints)
    specs = [prepare(cat, EvalSpec(p, draw.split, draw.handle_types, draw.presets, draw.kinds, per_cell, seed,
                                   episode_length, rerendered, videos, str(variants),
                                   labels[i] if labels else "", request, joints=draw.joints,
                                   protocol=frozen.name if frozen else "", renderer=renderer))
             for i, p in enumerate(policies)]
    if frozen is not None:
        for spec in specs:
            protocols.check_policy(protocol, frozen, spec)  # type: ignore[arg-type]
    wheres = eval_folders(outs, specs)
    con = console()
    for spec in specs:
        if spec.note:
            con.print(f"[yellow]note[/]: {spec.note}", soft_wrap=True)
    every: list[dict[str, Any]] = []
    for spec, where in zip(specs, wheres, strict=True):
        rows = finished_rows(where, spec)
        if rows is None:
            with progress_bar() as progress:
                rows = run_eval(cat, spec, where, workers=workers, progress=_advance(progress, spec.label,
                                                                                      len(spec.seeds())))
        else:
            con.print(f"{spec.label}: already evaluated on these episodes in {where}")
        if (warning := out_of_stats_warning(spec.label, rows)) is not None:
            con.print(f"[yellow]warning[/]: {warning}", soft_wrap=True)
        wins = sum(r["success"] for r in rows)
        con.print(f"{spec.label}: {len(rows)} episodes, {wins} successes ({100 * wins / len(rows):.1f} %); "
                  f"table.md, episodes.csv, eval_info.json in {where}")
        every += rows
    if separate:
        return
    if len(specs) > 1:
        write_tables(outs[0], specs, every)
    con.print((outs[0] / "table.md").read_text())
