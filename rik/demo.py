"""The main job on built-in defaults (``rik demo``), stage by stage: each function does one stage's work and returns
what it made; the CLI (:mod:`rik.cli.app`'s ``demo`` and the ``print_demo_*`` functions of its modules) prints it.

The stages, in the order the demo runs them: sample assets with their collision fidelity and the finger test
(:func:`build_assets`), three variants (:func:`build_variants`), scripted episodes checked to replay exactly
(:func:`record_episodes`), both image streams (:func:`render_kind`) and their alignment
(:func:`align_and_compare`), a LeRobot dataset
loaded back (:func:`export_dataset`) and model discovery on simulated measurements (:func:`discover_sysid`). Each
replaces only the demo's own earlier output (:mod:`rik.outputs`)."""

from __future__ import annotations

import json
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rik.lerobot.arrow_cache import scratch_arrow_cache
from rik.outputs import MadeFolder, check_replaceable, holds_only, remove_directory, staged_directory

if TYPE_CHECKING:
    from rik.assets.build import Asset
    from rik.assets.finger import FingerResult
    from rik.combinator.build import VariantResult
    from rik.episodes.replay import ReplayCheck
    from rik.exporters.lerobot_export import ExportResult
    from rik.registry.catalog import Catalog
    from rik.render.episodes import StreamResult
    from rik.render.streams import StreamSpec
    from rik.schemas.episodes import EpisodeMeta

DEMO_ASSETS = ("knob/mushroom-30", "two_point/bow-128", "finger_pull/edge-lip-100", "drawer/chest-80")
"""The assets the demo builds: one handle of each type and a chest of drawers."""
FINGER_HANDLE = "two_point/bow-128"
"""The two-point handle of the finger test."""
DEMO_VARIANTS = ("drawer-chest-80__two_point-bow-128__normal", "door-base-60-left__knob-mushroom-30__high",
                 "flap-lift-up-60__finger_pull-edge-lip-100__smooth")
"""The variants the demo builds; it records episodes of the first."""
DEMO_RES = 128
"""Image size of the demo's streams, px (small, so the re-render takes about a minute on two cores)."""
DEMO_DATASET = Path("datasets/rik-demo")
DEMO_REPO_ID = "local/rik-demo"
DEMO_DATA, DEMO_REPORT, DEMO_CATALOG = Path("sysid-data"), Path("sysid-report"), Path("sysid-catalog")
DEMO_PRESET = "demo-measured"
DEMO_ADVICE = "run the demo in another folder"


# ---- assets and variants -----------------------------------------------------------------------------------------
@dataclass(frozen=True)
class DemoAssets:
    parts: dict[str, Asset]
    """Each of :data:`DEMO_ASSETS`, built (or from the cache)."""
    fidelity: list[dict[str, Any]]
    """The handles' collision-fidelity rows (:func:`rik.assets.report.fidelity_row`)."""
    finger_coacd: FingerResult
    finger_hull: FingerResult
    """The finger test of :data:`FINGER_HANDLE` through its CoACD parts and through one convex hull."""
    cache: Path


def build_assets(overlay_paths: Sequence[Path]) -> DemoAssets:
    """Build :data:`DEMO_ASSETS`, measure the handles' collision fidelity and run the finger test."""
    from rik.assets.build import build_asset
    from rik.assets.cache import AssetCache
    from rik.assets.finger import finger_test
    from rik.assets.report import fidelity_row
    from rik.registry.load import load_catalog

    cat = load_catalog(list(overlay_paths))
    cache = AssetCache()
    parts = {i: build_asset(cat, i, cache=cache)[0] for i in DEMO_ASSETS}
    rows = [fidelity_row(cat, i, cache=cache) for i in DEMO_ASSETS if i in cat.handles]
    bow = parts[FINGER_HANDLE].part("handle")
    geometry = cat.handles[FINGER_HANDLE].geometry
    return DemoAssets(parts, rows, finger_test(bow.hulls, geometry), finger_test(bow.baseline, geometry), cache.root)


def build_variants(overlay_paths: Sequence[Path], out: Path) -> list[tuple[VariantResult, dict[str, Any] | None]]:
    """Build :data:`DEMO_VARIANTS` into ``out`` (valid ones are skipped): each result with its ``report.json``
    (None for a rejected variant)."""
    from rik.combinator.build import build_variant
    from rik.registry.ids import parse_variant_id
    from rik.registry.load import load_catalog

    cat = load_catalog(list(overlay_paths))
    results = [build_variant(cat, parse_variant_id(cat, v), out) for v in DEMO_VARIANTS]
    return [(r, None if r.status == "rejected" else json.loads((out / r.id / "report.json").read_text("utf-8")))
            for r in results]


# ---- episodes, streams, the dataset ------------------------------------------------------------------------------
def record_episodes(overlay_paths: Sequence[Path], out: Path, variants: Path, episodes: int
                    ) -> list[tuple[EpisodeMeta, ReplayCheck]]:
    """Record ``episodes`` contact-rich episodes (seeds 0, 1, ...) of the first demo variant into ``out``, each with
    the check that it replays exactly."""
    from rik.episodes.record import record
    from rik.episodes.replay import verify_episode
    from rik.registry.load import load_catalog

    cat = load_catalog(list(overlay_paths))
    metas = record(cat, DEMO_VARIANTS[0], "contact_rich", episodes=episodes, out=out, variants=variants)
    return [(meta, verify_episode(cat, out / meta.id, variants)) for meta in metas]


DEMO_STREAMS = ("sim", "rerendered")
"""The demo's image streams, in the order it renders them."""


def render_kind(catalog: Catalog, episodes: Sequence[Path], kind: str, out: Path, variants: Path, res: int,
                progress: Callable[[int], None] | None = None) -> list[StreamResult]:
    """Render the ``kind`` stream (``sim`` or ``rerendered``, ``res`` x ``res`` px) of each episode into ``out``;
    ``progress(n)`` as frames are done."""
    from rik.render.episodes import render_episode

    spec = stream_spec(kind, res)
    return [render_episode(catalog, e, spec, renders=out, variants=variants, progress=progress) for e in episodes]


def stream_spec(kind: str, res: int) -> StreamSpec:
    """The demo's ``kind`` stream at ``res`` x ``res`` px."""
    from rik.render.streams import StreamSpec

    return StreamSpec(kind, res, res)  # type: ignore[arg-type]


def frames_of(episodes: Sequence[Path]) -> int:
    """How many frames a stream of the episodes has (a frame per recorded state)."""
    from rik.episodes.episode import read_meta

    return sum(read_meta(e).steps + 1 for e in episodes)


def align_and_compare(catalog: Catalog, episode: Path, streams: Sequence[StreamResult], variants: Path, res: int
                      ) -> tuple[dict[str, float], Path]:
    """How the first two ``streams`` of ``episode`` (sim, then rerendered) agree in silhouette per camera at its first
    state (IoU), and the picture of the two side by side."""
    from rik.episodes.episode import read_episode, states
    from rik.episodes.replay import episode_scene
    from rik.render.align import silhouette_iou
    from rik.render.sheet import contact_sheet

    meta, table = read_episode(episode, ("state",))
    scene = episode_scene(catalog, episode, variants, meta)
    scene.restore(states(table)[0])
    iou = {cam: silhouette_iou(scene.model, scene.data, cam, res, res, catalog.finishes) for cam in streams[0].cameras}
    sheet = contact_sheet([s.directory for s in streams], streams[1].directory.parent / "compare.png")
    return iou, sheet


def demo_folders(out: Path) -> list[tuple[Path, MadeFolder]]:
    """The folders the demo's export replaces: its dataset ``out`` (a finished rik export, nothing in it but a
    dataset's files: :func:`~rik.exporters.lerobot_export.is_exported_dataset`) and ``<out>.partial`` (an
    interrupted one: its plan, shards and merged dataset)."""
    from rik.exporters.lerobot_export import PARTIAL_FOLDER, is_exported_dataset

    return [(out, MadeFolder("a dataset rik export-lerobot made", is_exported_dataset, DEMO_ADVICE)),
            (out.with_name(f"{out.name}.partial"), replace(PARTIAL_FOLDER, advice=DEMO_ADVICE))]


@dataclass(frozen=True)
class DemoDataset:
    export: ExportResult
    frames: int
    """Frames of the dataset as ``LeRobotDataset`` loads it."""
    shapes: str
    """The shapes of one frame's features (``observation.state (11,), ...``)."""
    task: str
    episode: dict[str, Any]
    """rik's metadata of the dataset's first episode (``rik/variant``, ``rik/preset``, ...)."""


@scratch_arrow_cache()
def export_dataset(overlay_paths: Sequence[Path], episodes: Sequence[Path], out: Path, renders: Path, variants: Path,
                   res: int) -> DemoDataset:
    """Export the episodes (both streams, ``res`` x ``res`` px as rendered) to a LeRobot dataset at ``out`` and load
    it back with ``LeRobotDataset``. The demo's earlier dataset (and an interrupted export of it) is removed first,
    and only if rik made it (:func:`demo_folders`)."""
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    from rik.exporters.lerobot_export import export_lerobot
    from rik.exporters.spec import ExportSpec
    from rik.registry.load import load_catalog

    for old, kind in demo_folders(out):
        remove_directory(old, kind)  # the demo's own earlier output, never a folder of the user's
    result = export_lerobot(load_catalog(list(overlay_paths)), list(episodes), out,
                            ExportSpec(DEMO_REPO_ID, width=res, height=res), renders=renders, variants=variants)
    ds = LeRobotDataset(DEMO_REPO_ID, root=out, video_backend="pyav")
    item = ds[len(ds) // 2]
    shapes = ", ".join(f"{k} {tuple(v.shape)}" for k, v in item.items() if hasattr(v, "shape") and v.ndim > 0)
    return DemoDataset(result, len(ds), shapes, str(item["task"]), dict(ds.meta.episodes[0]))


# ---- model discovery ---------------------------------------------------------------------------------------------
def _is_demo_catalog(folder: Path) -> bool:
    """Whether ``folder`` is the demo's catalog: the one preset file ``rik sysid apply`` wrote, nothing else."""
    from rik.sysid.preset import preset_file

    file = preset_file(folder, DEMO_PRESET)
    try:
        with file.open(encoding="utf-8") as handle:
            first = handle.readline()
    except (OSError, UnicodeDecodeError):
        return False
    return first.startswith(f"# Resistance preset '{DEMO_PRESET}' fitted") and holds_only(folder, {file.name})


DEMO_CATALOG_FOLDER = MadeFolder("the demo's catalog (its one preset file)", _is_demo_catalog, DEMO_ADVICE)


@dataclass(frozen=True)
class DemoSysid:
    trials: int
    sentence: str
    """What the discovery found, as it says it."""
    preset: Path
    """The fitted joint's preset file."""


def discover_sysid(overlay_paths: Sequence[Path]) -> DemoSysid:
    """Simulated measurements of a drawer with a hidden soft-close damper into :data:`DEMO_DATA`, the fit and its
    report into :data:`DEMO_REPORT`, the fitted joint as a preset in :data:`DEMO_CATALOG`. Each folder replaces the
    demo's earlier one, and only a folder rik made (all three checked before any work)."""
    import numpy as np

    from rik.sysid.discover import discover
    from rik.sysid.preset import apply_report
    from rik.sysid.report import REPORT_FOLDER, write_report
    from rik.sysid.synthetic.generate import random_truth, simulate_trials, write_trials
    from rik.sysid.trials import simulated_folder

    for folder, kind in ((DEMO_DATA, simulated_folder()), (DEMO_REPORT, REPORT_FOLDER),
                         (DEMO_CATALOG, DEMO_CATALOG_FOLDER)):
        check_replaceable(folder, replace(kind, advice=DEMO_ADVICE))
    truth = random_truth("soft_close", "slide", np.random.default_rng(0))
    trials = simulate_trials(truth, n_trials=4, seed=0)
    write_trials(trials, DEMO_DATA, truth)
    found = discover(trials)
    write_report(found, DEMO_REPORT)
    with staged_directory(DEMO_CATALOG, DEMO_CATALOG_FOLDER) as stage:
        preset = DEMO_CATALOG / apply_report(DEMO_REPORT, DEMO_PRESET, stage, overlays=list(overlay_paths)).name
    return DemoSysid(len(trials), found.sentence(), preset)
