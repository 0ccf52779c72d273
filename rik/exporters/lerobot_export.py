"""``rik export-lerobot``: recorded episodes to a LeRobot v3.0 dataset, written by lerobot's own writer.

Crash safety. Work goes into ``<out>.partial/`` (its ``plan.json`` says which episodes with which settings):
episodes are cut into shards of ``shard_episodes``, each written as a dataset of its own and marked done
(``DONE``) only after ``finalize()`` and a frame-count check; the finished shards are merged with lerobot's
``aggregate_datasets``, the merge is checked and gets a dataset card, and only then is it renamed to ``<out>``.
Running again with ``resume`` after a crash skips finished shards and redoes the unfinished one, so the result
equals an uninterrupted run. lerobot 0.6.1 cannot recover a dataset whose writer was killed before
``finalize()``, hence shards rather than one long writer.

Traps of lerobot 0.6.1 avoided here (../shared/notes/research-lerobot.md): no batched encoding (crashes), no
streaming encoder (drops frames under load), no ``vcodec="auto"`` (picks NVENC without a GPU), images always
8-bit sRGB, episode metadata as ``meta/episodes`` columns rather than ``info.json`` keys (dropped on load).
"""

from __future__ import annotations

import json
import multiprocessing
import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rik.errors import RikError
from rik.exporters import lerobot_card, lerobot_check  # called through the modules, so that tests can replace them
from rik.exporters.layout import DATASET_FILE, MERGED_FILE, MERGING
from rik.exporters.lerobot_frames import (
    LAYOUT,
    LAYOUT_1_STATE_NAMES,
    EpisodeSource,
    LoadedEpisode,
    episode_frames,
    episode_layout,
    episode_metadata,
    load_episode,
)
from rik.exporters.spec import ENCODER_OPTIONS, ExportSpec, check_codec_size, check_spec, keep_outcomes
from rik.lerobot.arrow_cache import scratch_arrow_cache
from rik.lerobot.features import TASK, dataset_features
from rik.lerobot.policy_io import POLICY_IO_FILE, PolicyIO, io_of_info
from rik.outputs import (
    PRIVATE,
    MadeFolder,
    NameTaken,
    Replaces,
    holds_only,
    publish_new_directory,
    remove_directory,
    tree_holds_only,
    write_text,
)
from rik.paths import check_folder, json_object
from rik.scheduling import normal_scheduling

if TYPE_CHECKING:
    from rik.registry.catalog import Catalog
    from rik.schemas.episodes import EpisodeMeta
    from rik.sim.robots.layout import RobotLayout

DONE = "DONE"
PLAN = "plan.json"
SHARD_FOLDER = MadeFolder("a shard rik was writing", lambda d: holds_only(d, {"ds", DONE}), "delete it yourself")
"""A shard's folder (lerobot's dataset in ``ds/``, then rik's ``DONE``): an unfinished one is redone from scratch."""


@dataclass
class ExportResult:
    root: Path
    repo_id: str
    episodes: int
    frames: int
    fps: int
    features: list[str]
    shards_written: int
    shards_skipped: int
    checks: dict[str, Any] = field(default_factory=dict)
    robot: str = "hand-e"
    """The catalog robot whose episodes the dataset holds."""
    robot_type: str = "rik_hand_e"
    """``info.json``'s ``robot_type``."""


def _episode_fps(metas: dict[Path, EpisodeMeta], spec: ExportSpec) -> int:
    rates = {m.fps for m in metas.values()}
    if spec.fps is not None:
        return spec.fps
    if len(rates) > 1:
        listing = ", ".join(f"{d.name}: {m.fps} Hz" for d, m in list(metas.items())[:4])
        raise RikError(f"the episodes were recorded at different rates ({listing}, ...); pass --fps to resample "
                       "them all to one")
    return rates.pop()


def one_robot(metas: dict[Path, EpisodeMeta]) -> str:
    """The robot of the episodes, which must all have the same one: a dataset holds one robot's state and action
    layout. Read from meta.json alone, before any other work."""
    first_dir, first = next(iter(metas.items()))
    for d, m in metas.items():
        if m.robot != first.robot:
            raise RikError(f"{d / 'meta.json'}: robot '{m.robot}' differs from robot '{first.robot}' of "
                           f"{first_dir / 'meta.json'}; a dataset holds one robot's state and action layout, so "
                           "export each robot's episodes to a dataset of its own")
    return first.robot


def _plan(metas: dict[Path, EpisodeMeta], spec: ExportSpec, fps: int, robot: str = "hand-e") -> dict[str, Any]:
    return {"spec": {**spec.plan_data(), "fps": fps, "layout": LAYOUT, "robot": robot},
            "encoder_options": ENCODER_OPTIONS.get(spec.codec, {}),
            "episodes": [[m.id, m.states_sha256] for m in metas.values()]}  # an older partial export is not mixed in


def _check_layout(partial_dir: Path, plan: Any) -> None:
    """An interrupted export of an older state layout (before :data:`LAYOUT`) cannot be continued."""
    layout = plan.get("spec", {}).get("layout", 1) if isinstance(plan, dict) else None
    if layout is not None and layout != LAYOUT:
        raise RikError(f"{partial_dir}: the interrupted export there has rik's state layout {layout} (one "
                       f"{len(LAYOUT_1_STATE_NAMES)}-number observation.state) and this rik writes layout {LAYOUT} "
                       "(observation.state and observation.environment_state); delete it and export again without "
                       "--resume (the episodes are unchanged)")


def _shards(items: list[Path], size: int) -> list[list[Path]]:
    return [items[i:i + size] for i in range(0, len(items), size)]


def quiet_encoders() -> None:
    """Keep FFmpeg's per-video notes, SVT-AV1's banner and Hugging Face datasets' progress bars off the
    terminal (in this process: lerobot restores FFmpeg's own printing after each video, so the level is set where the
    encoding happens)."""
    os.environ.setdefault("SVT_LOG", "1")
    import importlib

    import av.logging

    # lerobot's loads and merges would draw "Map: ..." bars of their own. By name: a `datasets/` folder in the
    # working directory (rik demo writes one) would otherwise stand for Hugging Face's package in mypy's eyes.
    importlib.import_module("datasets").disable_progress_bars()

    av.logging.set_level(av.logging.ERROR)
    av.logging.set_libav_level(av.logging.ERROR)


def shard_layout(catalog: Catalog, metas: dict[Path, EpisodeMeta], action_frame: str = "world") -> RobotLayout:
    """The robot layout of a shard's episodes (their metas), which share one robot (:func:`one_robot` checks that
    they do), its pose action in ``action_frame``."""
    one_robot(metas)
    directory, meta = next(iter(metas.items()))
    return episode_layout(catalog, directory, meta, action_frame)


def render_streams(catalog: Catalog, episode: LoadedEpisode, spec: ExportSpec, cameras: Sequence[str],
                   renders: Path, variants: Path) -> dict[str, Path]:
    """The finished folder of each of ``spec``'s image streams of ``episode``, rendered (or resumed) into ``renders``
    where missing, from the episode as it was read: its states and scene are not read or built again."""
    from rik.render.episodes import render_episode

    return {kind: render_episode(catalog, episode.recorded, spec.stream(kind), renders=renders, variants=variants,
                                 cameras=cameras).directory for kind in spec.io.streams}


def write_shard(catalog: Catalog, root: Path, repo_id: str, sources: list[EpisodeSource], cameras: list[str],
                spec: ExportSpec, fps: int, variants: Path, renders: Path | None = None,
                progress: Callable[[], None] | None = None) -> int:
    """Write one shard dataset at ``root`` through lerobot's writer, in its episodes' robot's layout; returns its
    frame count. Marked done only after ``finalize()`` and the frame-count check. Each episode is read once
    (:func:`~rik.exporters.lerobot_frames.load_episode`: sha256, rows, action width), all of the shard's before any
    work; with ``renders``, its image streams are rendered there from that read where missing (else the sources'
    finished folders are used).
    ``progress()`` is called as each episode is saved."""
    from lerobot.configs import RGBEncoderConfig
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    from rik.episodes.episode import read_meta

    check_codec_size(spec)  # rik dataset's shards come here without export_lerobot's checks
    quiet_encoders()
    metas = {s.directory: read_meta(s.directory) for s in sources}
    layout = shard_layout(catalog, metas, spec.io.action_frame)
    # every episode of the shard read and checked (its one read) before anything is rendered or written: bad input
    # costs no render; the shard holds its episodes' states (shard_episodes of them) until each is saved
    loaded: list[LoadedEpisode | None] = [load_episode(catalog, s.directory, metas[s.directory],
                                                       spec.io.action_frame) for s in sources]
    remove_directory(root, SHARD_FOLDER)  # an unfinished shard is redone from scratch
    root.parent.mkdir(parents=True, exist_ok=True)
    features = dataset_features(layout, spec.io.handle_shape, cameras, spec.io.streams, spec.io.image_size,
                                environment_state=spec.io.environment_state)
    ds = LeRobotDataset.create(repo_id=repo_id, fps=fps, features=features,
                               root=root / "ds", robot_type=layout.robot_type, use_videos=bool(spec.io.streams),
                               video_backend="pyav",
                               rgb_encoder=RGBEncoderConfig(vcodec=spec.codec,
                                                             extra_options=dict(ENCODER_OPTIONS.get(spec.codec, {}))),
                               image_writer_threads=4)
    extra: dict[str, Any] = {}
    save_meta = ds.meta.save_episode

    def save_episode_with_rik_columns(index: int, length: int, tasks: list[str], stats: dict, metadata: dict
                                      ) -> None:
        save_meta(index, length, tasks, stats, {**metadata, **extra})

    ds.meta.save_episode = save_episode_with_rik_columns  # the documented-in-issues way to add episode columns
    frames_total = 0
    try:
        for n, source in enumerate(sources):
            episode, loaded[n] = loaded[n], None  # let go once it is saved
            assert episode is not None
            streams = source.streams if renders is None else render_streams(catalog, episode, spec, cameras,
                                                                            renders, variants)
            task, frames, count = episode_frames(catalog, episode, streams, cameras, fps, variants,
                                                   spec.io.handle_shape, spec.io.environment_state)
            for frame in frames:
                ds.add_frame({**frame, TASK: task})
            extra.clear()
            extra.update(episode_metadata(episode.meta))
            # lerobot encodes each camera in a process of its own: cheap where processes fork (measured faster for
            # h264), but in a spawned worker (rik dataset build -j N) each would be a fresh interpreter importing
            # lerobot again, per episode; there the worker encodes itself (the workers already run side by side).
            with normal_scheduling():  # SVT-AV1 leaves an encoding thread at real-time priority when run as root
                ds.save_episode(parallel_encoding=multiprocessing.get_start_method() == "fork")
            frames_total += count
            if progress:
                progress()
    finally:
        ds.finalize()
    lerobot_check.check_frame_counts(root / "ds")
    write_text(root / DONE, json.dumps([s.directory.name for s in sources]) + "\n", Replaces.in_folder(SHARD_FOLDER))
    return frames_total


def export_lerobot(catalog: Catalog, episodes: Sequence[Path], out: Path, spec: ExportSpec, *,
                   renders: Path = Path("renders"), variants: Path = Path("variants"), resume: bool = False,
                   workers: int = 1, overlays: Sequence[Path] = (),
                   progress: Callable[[str, int, int], None] | None = None) -> ExportResult:
    """Export ``episodes`` (episode folders) to a LeRobot v3.0 dataset at ``out``, reading each episode once; its
    image streams missing from ``renders`` are rendered there from that read. ``progress(stage, done, total)`` reports
    stages ``episodes`` (one process) and ``shards``. One export at a time writes ``out`` (a lock beside it,
    :mod:`rik.locks`); a second one is refused at once."""
    from rik.locks import exclusive
    from rik.workers import check_workers

    check_spec(spec)
    check_workers(workers)
    check_folder(renders, "--renders")
    check_folder(variants, "--variants")
    quiet_encoders()
    out = Path(out)
    _check_out_free(out, resume)
    with exclusive(out, "rik export-lerobot"):
        return _export_locked(catalog, episodes, out, spec, renders=renders, variants=variants, resume=resume,
                              workers=workers, overlays=overlays, progress=progress)


def is_rik_export(folder: Path) -> bool:
    """Whether ``folder`` holds a finished rik export: lerobot's ``meta/info.json`` and rik's card fields
    (``meta/rik_card.json``), each a JSON object."""
    return json_object(folder / "meta" / "info.json") is not None and \
        json_object(folder / "meta" / lerobot_card.CARD_FIELDS) is not None


def is_exported_dataset(folder: Path) -> bool:
    """Whether ``folder`` is a dataset rik exported (:func:`is_rik_export`) holding nothing but a dataset's files
    (:data:`DATASET_FILE`), at any depth: the test before rik replaces one (the demo's)."""
    return is_rik_export(folder) and tree_holds_only(folder, lambda rel: DATASET_FILE.fullmatch(rel) is not None)


def _check_out_free(out: Path, resume: bool) -> None:
    """``--out`` must not exist yet (an export publishes it whole, at the end); nor be a link, even one that leads
    nowhere (checked before any work)."""
    if out.is_symlink():
        raise RikError(f"{out}: is a symbolic link; an export is published as a new folder there, never through a "
                       "link: choose another --out")
    if not out.exists():
        return
    if not resume:
        raise RikError(f"{out}: already exists; choose another --out (or delete it)")
    if is_rik_export(out):
        raise RikError(f"{out}: the export is already complete (nothing to resume); choose another --out to export "
                       "again")
    raise RikError(f"{out}: exists and is not a rik export (no meta/info.json and meta/rik_card.json), so there is "
                   "nothing to resume there; choose another --out")


def _export_locked(catalog: Catalog, episodes: Sequence[Path], out: Path, spec: ExportSpec, *, renders: Path,
                   variants: Path, resume: bool, workers: int, overlays: Sequence[Path],
                   progress: Callable[[str, int, int], None] | None) -> ExportResult:
    """:func:`export_lerobot` once it holds the lock of ``out``."""
    from rik.episodes.episode import find_episodes, read_meta
    from rik.render.episodes import check_renders_outside

    _check_out_free(out, resume)  # again, now that it is ours: another export may have finished it meanwhile
    partial_dir = out.with_name(f"{out.name}.partial")
    if partial_dir.exists() and not resume:
        raise RikError(f"{partial_dir}: an interrupted export is there; run again with --resume to continue it, or "
                       "delete it")
    # 1. What can be checked from meta.json alone, before any work: outcomes, one robot and its joints, one rate.
    # The states are read once per episode, where its shard writes it (with its renders, which come from that read).
    metas = keep_outcomes({d: read_meta(d) for d in find_episodes(list(episodes))}, spec.outcomes,
                          ", ".join(str(e) for e in episodes))
    dirs = list(metas)
    robot = one_robot(metas)
    layout = [episode_layout(catalog, d, m, spec.io.action_frame) for d, m in metas.items()][0]  # in the catalog
    fps = _episode_fps(metas, spec)
    plan = _plan(metas, spec, fps, robot)
    if partial_dir.exists():
        try:
            old = json.loads((partial_dir / PLAN).read_text(encoding="utf-8"))
        except (OSError, ValueError):
            old = None
        _check_layout(partial_dir, old)
        if isinstance(old, dict) and isinstance(old.get("spec"), dict):
            old["spec"].setdefault("robot", "hand-e")  # plans written before robots were the Hand-E's
            old["spec"].setdefault("action_frame", "world")  # and before the handle frame
            old["spec"].setdefault("handle_shape", "none")  # and before the handle's shape
        if old != json.loads(json.dumps(plan)):
            raise RikError(f"{partial_dir}: the interrupted export there was of other episodes or settings; delete "
                           "it, or run it again with the same ones")
    # the cameras asked for, or those of rik's scenes (front, wrist), as rik dataset build takes them; each
    # episode's render checks that its scene has them. No scene is built before the shards read the episodes.
    cams = list(spec.exported_cameras())
    if spec.io.streams:
        check_renders_outside(renders, {d: m.id for d, m in metas.items()}, "--renders")
    created = not partial_dir.exists()
    partial_dir.mkdir(parents=True, exist_ok=True)
    write_text(partial_dir / PLAN, json.dumps(plan, indent=1) + "\n", PRIVATE)

    # 2. Shards, each finished and checked before it counts; finished ones are never redone. A shard reads each of
    # its episodes once, renders the image streams missing from renders/ (resumable per frame) from that read, and
    # writes its frames.
    shard_root = partial_dir / "shards"
    jobs, skipped = [], 0
    for i, chunk in enumerate(_shards(dirs, max(1, spec.shard_episodes))):
        root = shard_root / f"shard-{i:04d}"
        names = [d.name for d in chunk]
        try:
            done = json.loads((root / DONE).read_text()) == names
        except (OSError, ValueError):
            done = False
        if done:
            skipped += 1
            continue
        jobs.append((root, f"{spec.repo_id}-shard-{i:04d}", [EpisodeSource(d, {}) for d in chunk], cams, spec, fps,
                     variants, renders))
    if progress:
        progress("shards", skipped, skipped + len(jobs))
    try:
        if workers > 1 and len(jobs) > 1:
            from rik.workers import map_ids

            job_of = {str(j[0]): j for j in jobs}
            for n, _ in enumerate(map_ids(partial(_shard_by_name, job_of), catalog, list(job_of), workers=workers,
                                          overlays=overlays)):
                if progress:
                    progress("shards", skipped + n + 1, skipped + len(jobs))
        else:
            saved = [0]
            total = sum(len(j[2]) for j in jobs)

            def episode_saved() -> None:
                saved[0] += 1
                if progress:
                    progress("episodes", saved[0], total)

            for n, job in enumerate(jobs):
                write_shard(catalog, *job, progress=episode_saved)
                if progress:
                    progress("shards", skipped + n + 1, skipped + len(jobs))
    except RikError:
        # an episode found bad where it is read (sha256, rows, action width, scene): the partial export this call
        # began goes with it, so bad input leaves nothing behind; an older interrupted one stays for --resume
        if created:
            remove_partial(partial_dir)
        raise

    # 3. Merge, check, card, then publish by renaming.
    merged = partial_dir / "merged"
    remove_directory(merged, MERGING)
    shard_dirs = sorted(p for p in shard_root.iterdir() if p.is_dir())
    aggregate_shards(spec.repo_id, [p / "ds" for p in shard_dirs], merged)
    order_stats(merged)
    checks = lerobot_check.check_dataset(merged, spec.repo_id, len(dirs), layout)
    lerobot_card.write_card(catalog, merged, spec, fps, checks, robot=robot,
                            joint_driven=sum(m.action_kind == "joints" for m in metas.values()))
    contract = write_contract(catalog, merged, robot)
    publish(merged, out)
    remove_partial(partial_dir)
    return ExportResult(out, spec.repo_id, checks["episodes"], checks["frames"], fps, sorted(contract.features(layout)),
                        len(jobs), skipped, checks, robot, layout.robot_type)


def write_contract(catalog: Catalog, root: Path, robot: str) -> PolicyIO:
    """Write the contract with the policies trained on the dataset being merged at ``root`` (of ``robot``'s
    episodes) into its ``meta/rik_policy_io.json`` (:mod:`rik.lerobot.policy_io`): what the dataset's own
    ``meta/info.json`` says (:func:`rik.lerobot.policy_io.io_of_info`), in a file of its own, beside lerobot's and
    rik's card, so that no other file of the dataset changes."""
    contract = io_of_info(root, robot, catalog)
    write_text(root / "meta" / POLICY_IO_FILE, contract.to_json(), MERGED_FILE)
    return contract


def order_stats(root: Path) -> None:
    """Rewrite ``meta/stats.json`` of the merged dataset at ``root`` with its features in info.json's order:
    lerobot's aggregation gathers them in a set, whose order changes from one process to the next, and identical
    exports must be byte-identical. Call it after :func:`aggregate_shards`."""
    stats_file, info_file = root / "meta" / "stats.json", root / "meta" / "info.json"
    if not stats_file.is_file():
        return
    stats = json.loads(stats_file.read_text(encoding="utf-8"))
    order = list(json.loads(info_file.read_text(encoding="utf-8"))["features"])
    ordered = {k: stats[k] for k in order if k in stats} | {k: stats[k] for k in sorted(stats) if k not in order}
    write_text(stats_file, json.dumps(ordered, indent=4, ensure_ascii=False), MERGED_FILE)  # lerobot's own layout


def publish(merged: Path, out: Path, what: str = "the export", rerun: str = "run again with --resume") -> None:
    """Rename the finished dataset to ``out``, which must still be free: a folder made there by something else
    while ``what`` ran is never replaced, and the finished dataset stays where it is (``rerun``: how to go on)."""
    try:
        publish_new_directory(merged, out)
    except (NameTaken, OSError):
        raise RikError(f"{out}: was created by something else while {what} ran, so the finished dataset was not "
                       f"moved there (it is kept in {merged}); move {out} away and {rerun}") from None


PARTIAL_FOLDER = MadeFolder("an interrupted export of rik export-lerobot",
                            lambda p: json_object(p / PLAN) is not None and tree_holds_only(p, _partial_file),
                            "delete it yourself")
"""``<out>.partial``: the plan, shards and merged dataset of an export under way."""


def _partial_file(rel: str) -> bool:
    """Whether ``rel`` is a path an export writes into ``<out>.partial``."""
    top = rel.split("/", 1)[0]
    return rel == PLAN or top in ("shards", "merged")


def remove_partial(partial_dir: Path) -> None:
    """Remove ``<out>.partial`` (:data:`PARTIAL_FOLDER`): only a folder an export made."""
    remove_directory(partial_dir, PARTIAL_FOLDER)


def _shard_by_name(jobs: dict[str, tuple], catalog: Catalog, name: str) -> int:
    return write_shard(catalog, *jobs[name])


@scratch_arrow_cache()
def aggregate_shards(repo_id: str, roots: list[Path], out: Path) -> None:
    """Merge the finished shard datasets at ``roots`` (in that order) into one dataset ``repo_id`` at ``out``, with
    lerobot's ``aggregate_datasets``; :func:`order_stats` then makes its ``stats.json`` repeatable."""
    from lerobot.datasets.aggregate import aggregate_datasets

    aggregate_datasets([f"{repo_id}-part-{i}" for i in range(len(roots))], repo_id, roots=roots, aggr_root=out)


@scratch_arrow_cache()
def push(root: Path, repo_id: str, *, private: bool = False) -> str:
    """Upload a finished export through lerobot's ``push_to_hub`` (files, then lerobot's card with rik's
    description, then the ``v3.0`` tag); returns the dataset's URL. Offline or unauthorised: a RikError."""
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    ds = LeRobotDataset(repo_id, root=root, video_backend="pyav")
    try:
        ds.push_to_hub(private=private, tags=["rik", "mujoco", "articulated-furniture"], license="apache-2.0",
                       **lerobot_card.card_fields(root))
    except Exception as exc:  # huggingface_hub raises its own errors for offline mode, auth and network
        first = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise RikError(f"{root}: cannot push {repo_id} to the Hugging Face Hub: {type(exc).__name__}: {first}"
                       ) from None
    return f"https://huggingface.co/datasets/{repo_id}"
