"""``rik export-lerobot``: recorded episodes to a LeRobot v3.0 dataset with the sim and re-rendered image
streams. Only parsing and printing here; :mod:`rik.exporters.lerobot_export` does the work."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from rik.cli.common import (
    CatalogOption,
    WorkersOpt,
    console,
    overlays,
    progress_bar,
    quiet_writers,
    stage_progress,
)
from rik.cli.rerender import CamerasOpt, EpisodesArg, ResOpt
from rik.cli.sim import VariantsOpt
from rik.demo import DEMO_DATASET, DEMO_RES

if TYPE_CHECKING:
    pass


def export_lerobot(
        episodes: EpisodesArg,
        out: Annotated[Path, typer.Option("--out", "-o", help="Folder of the dataset (must not exist, unless "
                                          "--resume).", show_default=False)],
        repo_id: Annotated[str, typer.Option("--repo-id", help="Dataset id, OWNER/NAME (e.g. local/rik-drawers).",
                                             show_default=False)],
        streams: Annotated[str, typer.Option("--streams", help="Comma-separated image streams: sim (MuJoCo), "
                                             "rerendered (Mitsuba 3); or none: state-only, nothing rendered.")]
        = "sim,rerendered",
        cameras: CamerasOpt = None, res: ResOpt = "256",
        fps: Annotated[int | None, typer.Option("--fps", help="Dataset rate, Hz (default: the episodes' own; "
                                                "other rates are resampled).", show_default=False)] = None,
        codec: Annotated[str, typer.Option("--codec", help="Video codec: libsvtav1 (AV1, LeRobot's default), "
                                           "h264 or hevc.")] = "libsvtav1",
        spp: Annotated[int, typer.Option("--spp", min=1, help="Samples per pixel of the re-render.")] = 16,
        denoise: Annotated[bool, typer.Option("--denoise/--no-denoise", help="Denoise the re-render.")] = True,
        variant: Annotated[str, typer.Option("--variant", help="Mitsuba variant (auto, cuda_ad_rgb, llvm_ad_rgb, "
                                             "scalar_rgb).")] = "auto",
        shard_episodes: Annotated[int, typer.Option("--shard-episodes", min=1, help="Episodes per shard (the "
                                                    "unit of resuming).")] = 16,
        outcomes: Annotated[str, typer.Option("--outcomes", help="Export only episodes with these outcomes, "
                                              "comma-separated (S: the successful demonstrations; F failed, P "
                                              "partly opened).")] = "F,P,S",
        action_frame: Annotated[str, typer.Option("--action-frame", help="The Hand-E's action position: world; "
                                                  "handle (target minus the handle's grasp point: "
                                                  "target_dx, target_dy, target_dz); or gripper (target minus the "
                                                  "gripper base's position, with the grasp point from the gripper "
                                                  "in observation.environment_state).")] = "world",
        handle_shape: Annotated[str, typer.Option("--handle-shape", help="End observation.environment_state with "
                                                  "the handle's shape: none; kind (its type and mount, 5 "
                                                  "numbers); full (and its grasp dimensions, 11).")] = "none",
        environment_state: Annotated[bool, typer.Option(
            "--environment-state/--no-environment-state", help="Write observation.environment_state, the "
            "simulator's state of the front and its handle; without it a policy learns from the robot's own state "
            "and the images only, as a real robot would (needs --streams).")] = True,
        resume: Annotated[bool, typer.Option("--resume", help="Continue an interrupted export into --out.")] = False,
        push_to_hub: Annotated[bool, typer.Option("--push-to-hub", help="Upload the finished dataset to the "
                                                  "Hugging Face Hub as --repo-id (needs a login).")] = False,
        renders: Annotated[Path, typer.Option("--renders", help="Root of rendered streams (reused; missing ones "
                                              "are rendered).")] = Path("renders"),
        workers: WorkersOpt = 1, variants: VariantsOpt = Path("variants"), catalog: CatalogOption = None) -> None:
    """Export recorded episodes of one robot to a LeRobot v3.0 dataset through lerobot's own writer: observation.state
    and action in the robot's layout (an arm's joints in LeRobot's names for it), observation.environment_state, one
    video per camera and stream (none with --streams none), a task string and rik's metadata per episode, a dataset
    card. Renders missing image streams first; crash-safe (sharded, --resume); checks every episode's frame count."""
    from rik.exporters.lerobot_export import export_lerobot as run
    from rik.exporters.spec import EXPORT_IO, LABELS, ExportSpec, parse_outcomes, parse_streams
    from rik.registry.load import load_catalog
    from rik.render.streams import parse_resolution

    quiet_writers()
    width, height = parse_resolution(res)
    io = EXPORT_IO.with_options({"streams": parse_streams(streams), "cameras": cameras or "",
                                 "image_size": (height, width), "action_frame": action_frame,
                                 "handle_shape": handle_shape, "environment_state": environment_state},
                                LABELS)  # the contract, once
    spec = ExportSpec(repo_id, io, fps=fps, codec=codec, spp=spp, denoise=denoise, variant=variant,
                      shard_episodes=shard_episodes, outcomes=parse_outcomes(outcomes))
    cat = load_catalog(overlays(catalog))
    with progress_bar() as progress:
        report = stage_progress(progress)

        result = run(cat, episodes, out, spec, renders=renders, variants=variants, resume=resume, workers=workers,
                     overlays=overlays(catalog), progress=report)
    con = console()
    con.print(f"dataset {result.root} ({result.repo_id}): {result.episodes} episodes, {result.frames} frames at "
              f"{result.fps} Hz; shards written {result.shards_written}, reused {result.shards_skipped}")
    con.print(f"robot: {result.robot} (robot_type {result.robot_type}); features: {', '.join(result.features)}")
    con.print(f"checked: loads offline with LeRobotDataset; state layout {result.checks['layout']}; "
              + result.checks["frame_counts"])
    from rik.exporters.lerobot_check import constant_warning

    if (warning := constant_warning(result.checks.get("constant", {}))) is not None:
        con.print(f"[yellow]warning[/]: {warning}", soft_wrap=True)
    con.print(f'load it: LeRobotDataset("{result.repo_id}", root="{result.root}")')
    if push_to_hub:
        from rik.exporters.lerobot_export import push

        con.print(f"pushed: {push(result.root, result.repo_id)}")


def print_demo_export(overlay_paths: list[Path], episodes: list[Path], out: Path = DEMO_DATASET,
                      renders: Path = Path("renders"), variants: Path = Path("variants"),
                      res: int = DEMO_RES) -> None:
    """Export the demo episodes to a LeRobot dataset, load it back (:func:`rik.demo.export_dataset`) and print what
    it holds."""
    from rik.demo import DEMO_REPO_ID, export_dataset

    quiet_writers()
    con = console()
    with con.status("exporting to a LeRobot v3.0 dataset (lerobot's writer, AV1 video) ..."):
        made = export_dataset(overlay_paths, episodes, out, renders, variants, res)
    result, ep = made.export, made.episode
    con.print(f"dataset {result.root}: {result.episodes} episodes, {result.frames} frames at {result.fps} Hz, "
              f"{len(result.features)} features; every episode's video frames checked against its rows")
    con.print(f'loaded with LeRobotDataset("{DEMO_REPO_ID}", root="{out}"): {made.frames} frames; one frame: '
              f'{made.shapes}; task "{made.task}"')
    con.print(f"episode 0 metadata: variant {ep['rik/variant']}, preset {ep['rik/preset']}, operator "
              f"{ep['rik/operator']}, outcome {ep['rik/outcome']}, seed {ep['rik/seed']}; card: {out / 'README.md'}")
    con.print("next: rik export-lerobot episodes/ --out DIR --repo-id OWNER/NAME (docs/lerobot.md)")
