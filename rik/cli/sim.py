"""``rik record``, ``rik teleop``, ``rik replay`` and ``rik bench``: simulation, teleoperation and the resistance
benchmark. Only parsing and printing here; :mod:`rik.sim` does the work."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import typer

from rik.cli.common import (
    DEFAULT_ROBOT,
    DEFAULT_WORKERS,
    CatalogOption,
    HandleTypeOpt,
    JointsOpt,
    RobotOpt,
    WorkersOpt,
    _check_workers,
    console,
    overlays,
    progress_bar,
    robot_entry,
)
from rik.errors import RikError
from rik.outputs import write_text
from rik.paths import check_folder

VariantArg = Annotated[str, typer.Argument(help="Variant id, e.g. drawer-chest-80__two_point-bow-128__normal "
                                           "(built into --variants first if needed).", show_default=False)]
FrontOpt = Annotated[str | None, typer.Option("--front", help="Front to open (default: the variant's first).")]
EpisodesOutOpt = Annotated[Path, typer.Option("--out", "-o", help="Directory of episodes.")]
VariantsOpt = Annotated[Path, typer.Option("--variants", help="Directory of built variants.")]


def _strategies_help() -> str:
    return "grasp_horizontal, grasp_vertical, grasp_natural or contact_rich"


ALL_SPLIT = "all"
"""``rik record --split all``: draw from every handle of the catalog (``rik.episodes.draw.ALL_SPLIT``, spelled here so
that the help text needs no import of the simulator's modules)."""


def record(variant: Annotated[str | None, typer.Argument(
               help="Variant id, e.g. drawer-chest-80__two_point-bow-128__normal (built into --variants first if "
               "needed); or none, with --split.", show_default=False)] = None,
           strategy: Annotated[str, typer.Option("--strategy", "-s", help=f"Scripted strategy: {_strategies_help()}.")
                               ] = ...,  # type: ignore[assignment]
           episodes: Annotated[int, typer.Option("--episodes", "-n", min=1, help="Episodes to record.")] = 1,
           seed: Annotated[int, typer.Option("--seed", help="Seed of the first episode (then +1 each).")] = 0,
           front: FrontOpt = None, out: EpisodesOutOpt = Path("episodes"), variants: VariantsOpt = Path("variants"),
           split: Annotated[str | None, typer.Option("--split", help="Instead of a VARIANT: draw each episode's "
                                                     "variant and front from its seed among the handles of this "
                                                     f"catalog split (train, val, test; {ALL_SPLIT}: every handle), "
                                                     "as the gym environment and rik eval do.",
                                                     show_default=False)] = None,
           types: Annotated[str | None, typer.Option("--types", help="With --split: comma-separated handle types "
                                                     "(default knob,finger_pull,two_point).", show_default=False)]
           = None,
           presets: Annotated[str | None, typer.Option("--presets", help="With --split: comma-separated presets "
                                                       "(default smooth,normal,high).", show_default=False)] = None,
           kinds: Annotated[str | None, typer.Option("--kinds", help="With --split: comma-separated front kinds "
                                                     "(default drawer).", show_default=False)] = None,
           joints: Annotated[str | None, typer.Option("--joints", help="With --split: the hinges of doors, "
                                                      "paper (default) or measured (the split's real doors).",
                                                      show_default=False)] = None,
           workers: Annotated[int, typer.Option("--workers", "-j", callback=_check_workers,
                                                help="With --split: episodes in this many processes.")] = 1,
           action_noise: Annotated[float, typer.Option("--action-noise", min=0.0, max=0.05,
                                                       help="DART-style demonstrations: the robot runs the "
                                                       "strategy's target plus correlated noise of this standard "
                                                       "deviation (m; angles 5 rad per m) while the episode "
                                                       "records the strategy's own action.")] = 0.0,
           robot: RobotOpt = DEFAULT_ROBOT, catalog: CatalogOption = None) -> None:
    """Record episodes of a scripted strategy on a variant, or on variants drawn from a catalog split (--split),
    into --out/<id>/ (meta.json, states.parquet)."""
    from rik.episodes.record import record as run
    from rik.episodes.record import record_split
    from rik.registry.load import load_catalog

    if variant is not None and split is not None:
        raise RikError(f"give a VARIANT or --split, not both (got {variant} and --split {split})")
    if variant is None and split is None:
        raise RikError(f"give a VARIANT to record, or --split SPLIT (train, val, test or {ALL_SPLIT}) to draw "
                       "each episode's variant from its seed")
    if split is None and (types, presets, kinds, joints) != (None, None, None, None):
        raise RikError("--types, --presets, --kinds and --joints choose the variants of --split; give --split "
                       "too, or drop them")
    if split is not None and front is not None:
        raise RikError(f"--front {front}: with --split each episode's front is drawn from its seed; drop --front")
    cat = load_catalog(overlays(catalog))
    arm: Any = robot_entry(cat, robot)
    params = {"action_noise": action_noise} if action_noise > 0 else None
    con = console()
    skipped: list[tuple[int, str, str]] = []
    with progress_bar() as progress:
        task = progress.add_task("episodes", total=episodes, last="")

        def report(m: Any) -> None:
            progress.update(task, advance=1, last=f"{m.id} {m.outcome}")

        if split is not None:
            from rik.episodes.draw import Draw

            metas = record_split(cat, Draw.parse(split, types, presets, kinds, joints), strategy, episodes=episodes,
                                 seed=seed, out=out, variants=variants, workers=workers, overlays=overlays(catalog),
                                 progress=report, skipped=skipped, robot=arm, params=params)
        else:
            assert variant is not None
            metas = run(cat, variant, strategy, episodes=episodes, seed=seed, out=out, variants=variants,
                        front=front, robot=arm, progress=report, params=params)
    for m in metas:
        con.print(f"{out / m.id}: {m.outcome} (opened {m.final_opening:.0%}, {m.steps} steps at {m.fps} Hz)")
    for s, _, reason in skipped:
        con.print(f"[yellow]seed {s} skipped[/]: {reason}")
    if skipped:
        con.print(f"{len(metas)} episodes recorded, {len(skipped)} skipped (their variants fail their checks here)")


def teleop(variant: VariantArg,
           device: Annotated[str, typer.Option("--device", "-d", help="keyboard, spacemouse, or a real LeRobot leader "
                                               "arm: so101-leader (--robot so101) or so100-leader (--robot so100), "
                                               "with --port (the viewer window).")]
           = "keyboard",
           web: Annotated[bool, typer.Option("--web", help="Serve the browser teleop station instead of opening a "
                                             "window (keyboard, gamepad; works headless, e.g. over an SSH "
                                             "tunnel).")] = False,
           port: Annotated[str | None, typer.Option("--port", help="With --web: the station's port (default 8765; 0: "
                                                    "a free one). With a leader arm: its serial port, e.g. "
                                                    "/dev/ttyACM0.")] = None,
           leader_id: Annotated[str | None, typer.Option("--leader-id", help="The leader arm's LeRobot id (its "
                                                         "calibration file <id>.json; default: the only one "
                                                         "there).")] = None,
           calibration_dir: Annotated[Path | None, typer.Option("--calibration-dir", help="Folder of the leader's "
                                                                "LeRobot calibration (default: LeRobot's, "
                                                                "~/.cache/huggingface/lerobot/calibration/"
                                                                "teleoperators/so_leader).")] = None,
           host: Annotated[str, typer.Option("--host", help="Address the station listens on with --web (default: "
                                             "this machine only).")] = "127.0.0.1",
           front: FrontOpt = None, out: EpisodesOutOpt = Path("episodes"), variants: VariantsOpt = Path("variants"),
           seed: Annotated[int, typer.Option("--seed", help="First episode's seed; each episode takes the next seed "
                                             "with no episode in --out, so nothing is overwritten.")] = 0,
           max_seconds: Annotated[float | None, typer.Option("--max-seconds", help="Time limit of an episode, "
                                                             "simulated s (default: none).")] = None,
           robot: RobotOpt = DEFAULT_ROBOT, catalog: CatalogOption = None) -> None:
    """Teleoperate a variant and record episodes: in a window (keymap on screen and in docs/teleop.md) or, with
    --web, in the browser; --robot picks the robot that opens it (an arm that cannot reach the handle is refused
    before anything opens)."""
    from rik.registry.load import load_catalog

    con = console()
    cat = load_catalog(overlays(catalog))
    arm: Any = robot_entry(cat, robot)  # an unknown robot fails here, before any window or port
    if web:
        from rik.web.app import AppConfig, serve_station

        if device != "keyboard":
            raise RikError(f"--device {device}: the browser station takes the browser's keyboard and gamepads; "
                           "--device is for the viewer window")
        if leader_id is not None or calibration_dir is not None:
            raise RikError("--leader-id and --calibration-dir are for a leader arm in the viewer window, not --web")
        if not (port or "8765").isdigit() or int(port or "8765") > 65535:
            raise RikError(f"--port {port}: with --web, the station's port is a number 0..65535")
        config = AppConfig(cat, variants=variants, episodes=out, overlays=tuple(overlays(catalog)),
                           max_seconds=max_seconds, seed=seed, front=front, robot=robot)
        serve_station(config, variant, host=host, port=int(port or "8765"),
                      on_ready=lambda url: con.print(f"teleop station: [bold]{url}[/] (Ctrl+C to stop; from another "
                                                     f"machine: ssh -L {url.rsplit(':', 1)[1].split('/')[0]}:"
                                                     f"localhost:{url.rsplit(':', 1)[1].split('/')[0]} THIS_HOST)",
                                                     soft_wrap=True))
        return
    from rik.teleop.desktop import teleoperate

    saved = teleoperate(cat, variant, device, out=out, variants=variants, front=front, seed=seed,
                        max_seconds=max_seconds, on_message=con.print, robot=arm, port=port, leader_id=leader_id,
                        calibration_dir=calibration_dir)
    if not saved:
        con.print("no episode saved")
    for meta in saved:
        con.print(f"{out / meta.id}: {meta.outcome} (opened {meta.final_opening:.0%}, {meta.steps} steps)")


def replay(episodes: Annotated[list[Path], typer.Argument(help="Episode directories, or directories of them.",
                                                          show_default=False)],
           variants: VariantsOpt = Path("variants"), catalog: CatalogOption = None) -> None:
    """Check recorded episodes: each loads whole, and setting its recorded states back and stepping on with its
    actions reproduces the recording bit for bit."""
    from rik.episodes.episode import find_episodes
    from rik.episodes.replay import verify_episode
    from rik.registry.load import load_catalog

    cat = load_catalog(overlays(catalog))
    con = console()
    bad = 0
    for d in find_episodes(episodes):
        result = verify_episode(cat, d, variants)
        bad += not result.exact
        con.print(f"{d}: {'exact' if result.exact else '[red]differs[/]'} ({result.rows} states, "
                  f"largest difference {result.max_difference:g})")
    if bad:
        raise typer.Exit(1)


def bench(types: Annotated[list[HandleTypeOpt] | None, typer.Option("--types", "-t", help="Handle types "
                                                                    "(repeatable; default: all three).")] = None,
          presets: Annotated[str, typer.Option("--presets", help="Comma-separated presets.")] = "smooth,normal,high",
          strategies: Annotated[str, typer.Option("--strategies", help="Comma-separated strategies.")] =
          "grasp_horizontal,grasp_vertical,contact_rich",
          per_cell: Annotated[int, typer.Option("--episodes-per-cell", "-n", min=1,
                                                help="Episodes per handle type x preset x strategy.")] = 10,
          sweep: Annotated[str | None, typer.Option("--sweep", help="grip-force: repeat every episode at "
                                                    "several grip forces and plot success against the friction "
                                                    "capacity ratio.")] = None,
          seed: Annotated[int, typer.Option("--seed")] = 0,
          kinds: Annotated[str, typer.Option("--kinds", help="Comma-separated front kinds: drawer, door, flap; "
                                             "all for every kind.")] = "drawer",
          joints: JointsOpt = "paper",
          out: Annotated[Path, typer.Option("--out", "-o", help="Where results.csv, table.md (and sweep.png) go.")]
          = Path("bench"),
          workers: WorkersOpt = DEFAULT_WORKERS, variants: VariantsOpt = Path("variants"),
          robot: RobotOpt = DEFAULT_ROBOT, catalog: CatalogOption = None) -> None:
    """The resistance benchmark: randomised opening episodes of drawers, doors or flaps (--kinds), F/P/S per front,
    handle type, strategy and preset (the paper's Table 3) with the misses' reasons, with the paper's presets or
    real doors' hinges (--joints measured), with the Hand-E or an arm (--robot)."""
    from rik.benchmark import bench as b
    from rik.registry.load import load_catalog
    from rik.tables import rows_csv

    check_folder(out, "--out")  # before the episodes, not after them
    b.check_bench_out(out)
    cat = load_catalog(overlays(catalog))
    robot_entry(cat, robot)  # an unknown robot (or its model's package missing): one line, before any work
    grip_forces: tuple[Any, ...] = (None,)
    if sweep is not None:
        if sweep != "grip-force":
            raise RikError(f"unknown sweep '{sweep}' (sweeps: grip-force)")
        grip_forces = b.SWEEP_GRIP_FORCES
    type_names = [t.value for t in types] if types else list(b.DEFAULT_TYPES)
    preset_names = [p.strip() for p in presets.split(",") if p.strip()]
    kind_names = (list(dict.fromkeys(f.kind for u in cat.base_units.values() for f in u.fronts))
                  if kinds.strip() == "all"
                  else [k.strip() for k in kinds.split(",") if k.strip()])
    tasks = b.plan_tasks(cat, types=type_names, presets=preset_names,
                         strategies=[s.strip() for s in strategies.split(",") if s.strip()], per_cell=per_cell,
                         seed=seed, grip_forces=grip_forces, robot=robot, kinds=kind_names, joints=joints.strip())
    with progress_bar() as progress:
        task = progress.add_task("episodes", total=len(tasks), last="")
        rows = b.run_bench(cat, tasks, workers=workers, variants=variants, overlays=overlays(catalog),
                           progress=lambda r: progress.update(task, advance=1, last=f"{r['variant']} {r['outcome']}"))
    out.mkdir(parents=True, exist_ok=True)
    write_text(out / "results.csv", rows_csv(rows), b.bench_file())
    table = b.layout_tables(rows, preset_names)
    write_text(out / "table.md", table, b.bench_file())
    con = console()
    if sweep is not None:
        png = b.sweep_plot(rows, out / "sweep.png")
        write_text(out / "sweep.md", b.sweep_markdown(rows), b.bench_file())
        con.print(b.sweep_markdown(rows))
        con.print(f"plot: {png}")
    else:
        con.print(table)
    con.print(f"{len(rows)} episodes; results in {out / 'results.csv'} and {out / 'table.md'}")


def robot_check(variant: VariantArg, robot: RobotOpt = DEFAULT_ROBOT, front: FrontOpt = None,
                variants: VariantsOpt = Path("variants"), catalog: CatalogOption = None) -> None:
    """Check a robot on a variant: it starts clear, reaches the handle over the front's travel, has the joint
    torque to hold the preset's resistance, and grips hard enough. Exit 1 when a check fails."""
    from rik.combinator.build import ensure_variant
    from rik.registry.load import load_catalog
    from rik.sim.build import build_scene
    from rik.sim.robots.checks import run_checks

    cat = load_catalog(overlays(catalog))
    arm: Any = robot_entry(cat, robot)
    scene = build_scene(ensure_variant(cat, variant, variants), front, robot=arm)
    con = console()
    failed = 0
    for result in run_checks(scene):
        failed += not result.passed
        mark = "[green]pass[/]" if result.passed else "[red]FAIL[/]"
        con.print(f"{mark} {result.name}: {result.reason}")
    if failed:
        raise typer.Exit(1)
