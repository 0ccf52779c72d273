"""``rik dataset build``: run a plan's units (record -> render -> export shard) on an engine, then merge the shards
with lerobot's ``aggregate_datasets`` and publish the dataset at ``out`` by renaming it into place.

The work folder (default ``<out>.work``) holds ``episodes/``, ``renders/``, ``shards/`` and ``units/``: one marker
per finished unit, ``units/<stage>/<key>.json``, written atomically after the unit's output is in place. Keys are
content hashes (:mod:`rik.dataset.plan`), so a rerun of the same spec, after a crash or a ``kill -9``, does only the
units without a marker, and another spec that shares episodes reuses them. A unit that fails is retried up to
``retries`` times, then recorded in ``units/failed/<key>.json`` with its message; the others go on. The dataset is
published only when every unit succeeded.
"""

from __future__ import annotations

import json
import os
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rik.dataset.engines import Done, Engine, Job
from rik.dataset.meta import BUILD_META, DATASET_META, read_dataset_meta
from rik.dataset.plan import EpisodeUnit, Plan, RenderUnit, ShardUnit, export_settings
from rik.dataset.registry import register_dataset
from rik.dataset.spec import library_versions, policy_io
from rik.errors import RikError
from rik.outputs import Replaces, remove_directory, remove_file, write_text
from rik.paths import inside, read_json

if TYPE_CHECKING:

    from rik.exporters.spec import ExportSpec
    from rik.registry.catalog import Catalog

STAGES = ("record", "render", "shard")
DEFAULT_RETRIES = 2
MARKER_FIELDS: dict[str, tuple[tuple[str, type | tuple[type, ...]], ...]] = {
    "record": (("output", str), ("episode", str), ("outcome", str), ("states_sha256", str)),
    "render": (("output", str),), "shard": (("output", (str, type(None))),)}
"""The fields of a unit's marker the build reads back, and their types; a marker without them is damaged and its
unit runs again. A shard's output is None where the spec's outcomes left out all its episodes."""


@dataclass
class Failure:
    stage: str
    key: str
    what: str
    """The unit, as a person reads it (episode id, stream, shard number)."""
    message: str
    attempts: int


@dataclass
class BuildResult:
    out: Path
    work: Path
    spec_hash: str
    up_to_date: bool = False
    """The dataset at ``out`` was already built from this spec: nothing was run."""
    ran: dict[str, int] = field(default_factory=lambda: dict.fromkeys(STAGES, 0))
    reused: dict[str, int] = field(default_factory=lambda: dict.fromkeys(STAGES, 0))
    seconds: dict[str, float] = field(default_factory=lambda: dict.fromkeys(STAGES, 0.0))
    """Time spent inside the units of each stage, summed over workers, s."""
    frames: dict[str, int] = field(default_factory=lambda: dict.fromkeys(STAGES, 0))
    wall_seconds: float = 0.0
    failures: list[Failure] = field(default_factory=list)
    episodes: int = 0
    dataset_frames: int = 0
    outcomes: dict[str, int] = field(default_factory=dict)
    constant: dict[str, list[str]] = field(default_factory=dict)
    """Feature -> dimensions that never change in the dataset
    (:func:`rik.exporters.lerobot_check.constant_dimensions`)."""


def default_work(out: Path) -> Path:
    return Path(out).with_name(f"{Path(out).name}.work")


# ---- the units, as they run in a worker -------------------------------------------------------------------------
@dataclass(frozen=True)
class Folders:
    """Absolute folders every unit reads and writes (the same on every node of a cluster)."""

    work: Path
    variants: Path

    @property
    def episodes(self) -> Path:
        return self.work / "episodes"

    @property
    def renders(self) -> Path:
        return self.work / "renders"

    @property
    def shards(self) -> Path:
        return self.work / "shards"

    def marker(self, stage: str, key: str) -> Path:
        return self.work / "units" / stage / f"{key}.json"

    def failed(self, key: str) -> Path:
        return self.work / "units" / "failed" / f"{key}.json"


def work_file(work: Path) -> Replaces:
    """What a file the build writes into its work folder ``work`` may replace: any file there (the folder was
    checked to be a build's work folder, :func:`check_destination`, and is locked while the build runs)."""
    root = Path(work).absolute()
    return Replaces("a file of rik dataset build's work folder", lambda p: Path(p).absolute().is_relative_to(root))


def _mark(folders: Folders, stage: str, key: str, record: dict[str, Any]) -> dict[str, Any]:
    path = folders.marker(stage, key)
    path.parent.mkdir(parents=True, exist_ok=True)
    write_text(path, json.dumps({"stage": stage, "key": key, **record}, indent=1) + "\n", work_file(folders.work))
    return record


def read_marker(folders: Folders, stage: str, key: str) -> dict[str, Any] | None:
    """The record of a finished unit whose output is still in place, else None."""

    try:
        data = read_json(folders.marker(stage, key))
    except (OSError, ValueError):
        return None
    if not isinstance(data, dict) or not all(isinstance(data.get(f), t) for f, t in MARKER_FIELDS[stage]):
        return None  # a damaged marker: the unit runs again
    output = data["output"]
    if output is None:
        return data  # a shard whose episodes the spec's outcomes all left out
    parts = output.split("/")
    if output.startswith("/") or any(p in ("", ".", "..") for p in parts) or not (folders.work / output).exists():
        return None  # its output is gone, or the marker points outside the work folder
    if stage == "record" and not _states_intact(folders.work / output, data.get("states_sha256")):
        return None  # an episode changed or truncated since it was recorded is recorded again
    return data


def _states_intact(episode: Path, sha256: object) -> bool:
    """Whether the episode's ``states.parquet`` still has the sha256 its marker recorded."""
    from rik.assets.cache import file_sha256
    from rik.episodes.episode import STATES

    try:
        return file_sha256(episode / STATES) == sha256
    except OSError:
        return False


def run_record(catalog: Catalog, arg: tuple[Folders, EpisodeUnit, float]) -> dict[str, Any]:
    """Record one episode (a job); returns its marker record."""
    from rik.episodes.record import record_one

    folders, unit, max_seconds = arg
    t0 = time.perf_counter()
    robot = catalog.robot(unit.robot)
    meta = record_one(inside(folders.variants, unit.variant, what="variant id"), unit.operator.strategy, unit.seed,
                      folders.episodes, front=unit.front, max_seconds=max_seconds, params=unit.operator.params,
                      label=unit.operator.label, robot=robot.as_arm)
    return _mark(folders, "record", unit.key, {
        "output": f"episodes/{meta.id}", "episode": meta.id, "outcome": meta.outcome, "steps": meta.steps,
        "states_sha256": meta.states_sha256, "seconds": time.perf_counter() - t0})


def run_render(catalog: Catalog, arg: tuple[Folders, RenderUnit, Any, tuple[str, ...]]) -> dict[str, Any]:
    """Render one stream of one episode (a job); returns its marker record."""
    from rik.render.episodes import render_episode

    folders, unit, stream_spec, cameras = arg
    t0 = time.perf_counter()
    r = render_episode(catalog, folders.episodes / unit.episode.episode_id, stream_spec, renders=folders.renders,
                       variants=folders.variants, cameras=cameras or None)
    return _mark(folders, "render", unit.key, {
        "output": str(r.directory.relative_to(folders.work)), "frames": r.frames * len(r.cameras),
        "cameras": list(r.cameras), "seconds": time.perf_counter() - t0})


def run_shard(catalog: Catalog, arg: tuple[Folders, ShardUnit, ExportSpec, dict[str, str]]) -> dict[str, Any]:
    """Write one shard dataset (a job); returns its marker record."""
    from rik.episodes.episode import read_meta
    from rik.exporters.lerobot_export import write_shard
    from rik.exporters.lerobot_frames import EpisodeSource
    from rik.render.streams import read_manifest

    folders, unit, spec, stream_dirs = arg
    t0 = time.perf_counter()
    sources = []
    for e in unit.episodes:
        if read_meta(folders.episodes / e.episode_id).outcome not in spec.outcomes:
            continue  # left out of the dataset by the spec's outcomes
        streams = {s: folders.work / stream_dirs[f"{e.key}/{s}"] for s in spec.io.streams}
        sources.append(EpisodeSource(folders.episodes / e.episode_id, streams))
    if not sources:  # a shard whose episodes are all left out: nothing to write, nothing to merge
        return _mark(folders, "shard", unit.key, {"output": None, "episodes": 0, "frames": 0, "fps": None,
                                                  "seconds": time.perf_counter() - t0})
    cameras = list(spec.io.cameras)
    if not cameras and spec.io.streams:
        first = next(iter(sources[0].streams.values()))
        cameras = list((read_manifest(first) or {}).get("cameras", []))
    fps = spec.fps or read_meta(sources[0].directory).fps
    root = folders.shards / unit.key[:32]
    frames = write_shard(catalog, root, f"{spec.repo_id}-shard-{unit.index:04d}", sources, cameras, spec, fps,
                         folders.variants)
    return _mark(folders, "shard", unit.key, {"output": str(root.relative_to(folders.work)), "frames": frames,
                                              "episodes": len(sources), "fps": fps,
                                              "seconds": time.perf_counter() - t0})


def export_spec(plan: Plan) -> ExportSpec:
    """The export settings of a plan's shards: its spec's contract (:func:`rik.dataset.spec.policy_io`) and
    encoding."""
    from rik.exporters.spec import ExportSpec

    s = plan.spec
    return ExportSpec(s.repo_id, policy_io(s), fps=s.fps, codec=s.codec, spp=s.render.spp, denoise=s.render.denoise,
                      variant=s.render.variant, shard_episodes=s.shard_episodes, outcomes=tuple(s.outcomes))


# ---- the scheduler ----------------------------------------------------------------------------------------------
class _Schedule:
    """Which units are done, running or failed, and what becomes ready when one finishes."""

    def __init__(self, plan: Plan, folders: Folders, engine: Engine, retries: int, result: BuildResult,
                 progress: Callable[[str, int, int], None] | None):
        self.plan, self.folders, self.engine, self.retries = plan, folders, engine, retries
        self.result, self.progress = result, progress
        self.done: dict[str, dict[str, Any]] = {}
        self.attempts: dict[str, int] = {}
        self.shard_of = {e.key: s for s in plan.shards for e in s.episodes}
        self.missing = [len(s.episodes) * (1 + len(plan.streams)) for s in plan.shards]
        """Per shard, its episodes and renders not yet done: a countdown, so a finished unit costs O(1) here."""
        self.totals = {"record": len(plan.episodes), "render": len(plan.renders), "shard": len(plan.shards)}
        self.counts = dict.fromkeys(STAGES, 0)
        self.ready: deque[Job] = deque()
        self.window = 2 * engine.workers + len(getattr(engine, "actors", ()))
        self.xspec = export_spec(plan)

    def _tick(self, stage: str) -> None:
        self.counts[stage] += 1
        if self.progress:
            self.progress(stage, self.counts[stage], self.totals[stage])

    def _job(self, stage: str, unit: Any) -> Job:
        f = self.folders
        if stage == "record":
            return Job(unit.key, stage, run_record, (f, unit, self.plan.spec.max_seconds))
        if stage == "render":
            return Job(unit.key, stage, run_render, (f, unit, self.plan.stream_spec(unit.stream),
                                                     self.plan.spec.cameras), renders=True)
        streams = {f"{e.key}/{r.stream}": self.done[r.key]["output"] for e in unit.episodes
                   for r in self.plan.episode_renders(e)}
        return Job(unit.key, stage, run_shard, (f, unit, self.xspec, streams))

    def _finish(self, stage: str, unit: Any, record: dict[str, Any], reused: bool) -> None:
        self.done[unit.key] = record
        (self.result.reused if reused else self.result.ran)[stage] += 1
        if not reused:
            self.result.seconds[stage] += float(record.get("seconds", 0.0))
            self.result.frames[stage] += int(record.get("frames", record.get("steps", 0)))
        self._tick(stage)
        if stage == "record":
            for r in self.plan.episode_renders(unit):
                self._offer("render", r)
            self._input_done(self.shard_of[unit.key])
        elif stage == "render":
            self._input_done(self.shard_of[unit.episode.key])

    def _input_done(self, shard: ShardUnit) -> None:
        """One of the shard's episodes or renders is done (each reports once); the last one offers the shard."""
        self.missing[shard.index] -= 1
        if not self.missing[shard.index]:
            self._offer("shard", shard)

    def _offer(self, stage: str, unit: Any) -> None:
        """Take a unit whose inputs are done: reuse its marker, or run it."""
        if unit.key in self.done or unit.key in self.attempts:
            return
        record = read_marker(self.folders, stage, unit.key)
        if record is not None:
            self._finish(stage, unit, record, reused=True)
            return
        self.attempts[unit.key] = 1
        remove_file(self.folders.failed(unit.key), work_file(self.folders.work))
        job = self._job(stage, unit)
        if stage == "record":
            self.ready.append(job)
        else:  # an episode's renders and a shard go before new episodes: finished shards early, little work on disk
            self.ready.appendleft(job)

    def _fill(self) -> None:
        """Keep the engine's queue short (twice its workers): the rest waits here, in order."""
        while self.ready and self.engine.pending() < self.window:
            self.engine.submit(self.ready.popleft())

    def run(self) -> None:
        everything: list[Any] = [*self.plan.episodes, *self.plan.renders, *self.plan.shards]
        units = {u.key: u for u in everything}
        for e in self.plan.episodes:
            self._offer("record", e)
        self._fill()
        while self.engine.pending():
            for done in self.engine.wait():
                self._handle(done, units[done.job.key])
            self._fill()

    def _handle(self, done: Done, unit: Any) -> None:
        stage = done.job.stage
        if done.error is None:
            self._finish(stage, unit, done.value, reused=False)
            return
        n = self.attempts[unit.key]
        if n <= self.retries:
            self.attempts[unit.key] = n + 1
            self.ready.appendleft(done.job)
            return
        what = describe(stage, unit)
        failure = Failure(stage, unit.key, what, done.error, n)
        self.result.failures.append(failure)
        path = self.folders.failed(unit.key)
        path.parent.mkdir(parents=True, exist_ok=True)
        write_text(path, json.dumps(failure.__dict__, indent=1) + "\n", work_file(self.folders.work))


def describe(stage: str, unit: Any) -> str:
    """How a person reads a unit: the episode id, the episode's stream, or the shard's number and size."""
    if stage == "record":
        return f"episode {unit.episode_id}"
    if stage == "render":
        return f"{unit.stream} frames of {unit.episode.episode_id}"
    return f"shard {unit.index} ({len(unit.episodes)} episodes)"


# ---- the build --------------------------------------------------------------------------------------------------
def build_dataset(catalog: Catalog, plan: Plan, out: Path, engine: Engine, *, work: Path | None = None,
                  variants: Path = Path("variants"), retries: int = DEFAULT_RETRIES,
                  progress: Callable[[str, int, int], None] | None = None, register: bool = True) -> BuildResult:
    """Build the dataset of ``plan`` at ``out`` on ``engine`` (see the module docstring). ``progress(stage, done,
    total)`` reports stages ``record``, ``render``, ``shard`` and ``merge``. Returns what ran, what was reused and
    what failed; the dataset is published only without failures."""
    from rik.locks import exclusive

    out, work = check_destination(out, work, plan.spec_hash, variants=variants)
    result = BuildResult(out, work, plan.spec_hash)
    if _up_to_date(out, plan, result):
        engine.close()  # (a Ray cluster started for the build stops here too)
        return result
    with exclusive(work, "rik dataset build"):
        if _up_to_date(out, plan, result):  # another build finished it while we waited for nothing
            engine.close()
            return result
        t0 = time.perf_counter()
        folders = Folders(work, Path(variants).absolute())
        work.mkdir(parents=True, exist_ok=True)
        write_text(work / f"spec-{plan.spec_hash[:16]}.json",
                   json.dumps({"source": plan.source, "spec_hash": plan.spec_hash,
                               "spec": plan.spec.model_dump(mode="json")}, indent=1) + "\n", work_file(work))
        schedule = _Schedule(plan, folders, engine, retries, result, progress)
        try:
            schedule.run()
        finally:
            engine.close()
        result.wall_seconds = time.perf_counter() - t0
        if result.failures:
            return result
        outcomes: dict[str, int] = {}
        for e in plan.episodes:
            o = schedule.done[e.key]["outcome"]
            outcomes[o] = outcomes.get(o, 0) + 1
        result.outcomes = dict(sorted(outcomes.items()))
        if progress:
            progress("merge", 0, 1)
        t1 = time.perf_counter()
        _merge(catalog, plan, folders, schedule, out, result)
        result.seconds["merge"] = time.perf_counter() - t1
        result.wall_seconds = time.perf_counter() - t0
        _write_build_meta(out, result, engine)
        if progress:
            progress("merge", 1, 1)
    if register:
        register_dataset(out)
    return result


def check_destination(out: Path, work: Path | None, spec_hash: str, *, spec_file: Path | None = None,
                      variants: Path | None = None) -> tuple[Path, Path]:
    """``(out, work)`` as absolute, normalised paths (``work`` defaults to ``<out>.work``), after refusing with one
    line, before anything is written, every pair a build must not write: ``/``; a file; the current folder, or a
    folder that holds it, the spec or ``variants``, as ``out``; ``out`` and ``work`` the same folder or one inside
    the other, or on two file systems (the dataset is renamed from ``work`` into ``out``); an ``out`` that holds
    something else than this spec's dataset; a ``work`` that holds something else than a build's work."""
    given = {"--out": str(out), "--work": str(work) if work is not None else None}
    out = Path(os.path.abspath(out))
    if out.resolve() == Path(out.resolve().anchor):
        raise RikError(f"--out {given['--out']}: is the root of the file system; give the name of a new folder")
    work = Path(os.path.abspath(work)) if work is not None else default_work(out)
    if given["--work"] is None:
        given["--work"] = f"{given['--out']}.work (the default)"
    paths = {"--out": out, "--work": work}
    real = {opt: p.resolve() for opt, p in paths.items()}
    for opt, p in paths.items():
        shown = given[opt]
        if real[opt] == Path(real[opt].anchor):
            raise RikError(f"{opt} {shown}: is the root of the file system; give the name of a new folder")
        if p.exists() and not p.is_dir():
            raise RikError(f"{opt} {shown}: is a file, not a folder; give the name of a new folder")
        base = _existing_ancestor(p)
        if not base.is_dir():
            raise RikError(f"{opt} {shown}: {base} is a file, not a folder; give a folder's name")
    if real["--out"] == real["--work"]:
        raise RikError(f"--out {given['--out']} and --work {given['--work']}: are the same folder; the work folder "
                       "must be another one (the default is OUT.work, beside the dataset)")
    if real["--work"].is_relative_to(real["--out"]):
        raise RikError(f"--work {given['--work']}: is inside --out {given['--out']}, which receives the finished "
                       "dataset whole; give a work folder outside it (the default is OUT.work, beside it)")
    if real["--out"].is_relative_to(real["--work"]):
        raise RikError(f"--out {given['--out']}: is inside --work {given['--work']}; give a dataset folder outside "
                       "the work folder (the default work folder is OUT.work, beside it)")
    inside_out = [("the current folder", Path.cwd())]
    if spec_file is not None:
        inside_out.append((f"the spec {spec_file}", Path(spec_file)))
    if variants is not None:
        inside_out.append((f"--variants {variants}", Path(variants)))
    for what, p in inside_out:
        if p.resolve().is_relative_to(real["--out"]):
            role = "is" if p.resolve() == real["--out"] else "holds"
            raise RikError(f"--out {given['--out']}: {role} {what}; --out receives the finished dataset whole: "
                           "give the name of a new folder")
    if out.is_dir():
        meta = read_dataset_meta(out)
        if meta is None:
            raise RikError(f"{out}: exists and is not a dataset built by rik dataset build (no meta/{DATASET_META});"
                           " choose another --out")
        if meta.get("spec_hash") != spec_hash:
            raise RikError(f"{out}: holds the dataset of another spec (spec hash {str(meta.get('spec_hash'))[:12]}, "
                           f"this spec's is {spec_hash[:12]}); choose another --out")
    if work.is_dir() and not _is_work_folder(work):
        names = sorted(e.name for e in os.scandir(work))
        shown = ", ".join(names[:3]) + (f" and {len(names) - 3} more" if len(names) > 3 else "")
        raise RikError(f"--work {given['--work']}: exists and is not the work folder of a rik dataset build (it "
                       f"holds {shown}); give a new folder, or one an earlier build used")
    if _existing_ancestor(out.parent).stat().st_dev != _existing_ancestor(work).stat().st_dev:
        raise RikError(f"--out {given['--out']} and --work {given['--work']}: are on two file systems; the finished "
                       "dataset is renamed from the work folder into --out, so give folders on one file system")
    return out, work


def _existing_ancestor(path: Path) -> Path:
    """``path`` itself, or its nearest ancestor that exists."""
    while not path.exists() and path != path.parent:
        path = path.parent
    return path


def _is_work_folder(work: Path) -> bool:
    """Whether ``work`` is empty or holds a build's work: the spec file and unit markers a build writes first."""
    names = {e.name for e in os.scandir(work)}
    return not names or "units" in names or any(n.startswith("spec-") and n.endswith(".json") for n in names)


def _up_to_date(out: Path, plan: Plan, result: BuildResult) -> bool:
    """Whether ``out`` already holds this spec's dataset (then nothing runs); another dataset there is an error."""
    if not out.exists():
        return False
    meta = read_dataset_meta(out)
    if meta is None:
        raise RikError(f"{out}: exists and is not a dataset built by rik dataset build (no meta/{DATASET_META}); "
                       "choose another --out")
    if meta.get("spec_hash") != plan.spec_hash:
        raise RikError(f"{out}: holds the dataset of another spec (spec hash {str(meta.get('spec_hash'))[:12]}, "
                       f"this spec's is {plan.spec_hash[:12]}); choose another --out")
    result.up_to_date = True
    result.episodes = int(meta.get("counts", {}).get("episodes", 0))
    result.dataset_frames = int(meta.get("counts", {}).get("frames", 0))
    result.outcomes = dict(meta.get("outcomes", {}))
    return True


def file_checksums(root: Path) -> dict[str, str]:
    """sha256 of every file of a dataset but rik's two metadata files (the record of a build), by relative path."""
    from rik.assets.cache import file_sha256

    skip = (f"meta/{DATASET_META}", f"meta/{BUILD_META}")
    return {rel: file_sha256(path) for path in sorted(p for p in root.rglob("*") if p.is_file())
            if (rel := path.relative_to(root).as_posix()) not in skip}


def _merge(catalog: Catalog, plan: Plan, folders: Folders, schedule: _Schedule, out: Path,
           result: BuildResult) -> None:
    """Aggregate the shards (in plan order), check the result, write the card and rik's metadata, publish."""
    from rik.exporters.layout import MERGED_FILE, MERGING
    from rik.exporters.lerobot_card import write_card
    from rik.exporters.lerobot_check import check_dataset
    from rik.exporters.lerobot_export import aggregate_shards, order_stats, publish, quiet_encoders, write_contract

    merged = folders.work / f"merged-{plan.spec_hash[:16]}"
    remove_directory(merged, MERGING)
    done = [schedule.done[s.key] for s in plan.shards]
    roots = [folders.work / d["output"] / "ds" for d in done if d.get("output")]
    if not roots:
        raise RikError(f"no episode of the build has outcome {' or '.join(plan.spec.outcomes)} (outcomes: "
                       f"{', '.join(f'{k} {v}' for k, v in result.outcomes.items())}); nothing to publish: record "
                       "more episodes, or widen the spec's outcomes")
    kept = sum(int(d.get("episodes", len(s.episodes))) for d, s in zip(done, plan.shards, strict=True))
    quiet_encoders()
    aggregate_shards(plan.spec.repo_id, roots, merged)
    order_stats(merged)
    from rik.sim.robots.layout import robot_layout

    robot = catalog.robot(plan.spec.robot)
    checks = check_dataset(merged, plan.spec.repo_id, kept,
                           robot_layout(robot.as_arm, plan.spec.action_frame))
    fps = int(checks["fps"])
    write_card(catalog, merged, schedule.xspec, fps, checks, extra=_card_text(plan), robot=plan.spec.robot)
    write_contract(catalog, merged, plan.spec.robot)
    result.episodes, result.dataset_frames = int(checks["episodes"]), int(checks["frames"])
    result.constant = checks.get("constant", {})
    data = {"format": 1, "spec_hash": plan.spec_hash, "source": plan.source,
            "spec": plan.spec.model_dump(mode="json"), "versions": library_versions("mujoco", "lerobot", "mitsuba"),
            "collision": plan.collision,
            "joint_friction": plan.joint_friction, "variants": plan.variants, "rejected_variants": plan.rejected,
            "counts": {**plan.summary(), "frames": result.dataset_frames, "fps": fps},
            "outcomes": result.outcomes, "export": export_settings(plan.spec),
            "files": file_checksums(merged)}
    write_text(merged / "meta" / DATASET_META, json.dumps(data, indent=1) + "\n", MERGED_FILE)
    publish(merged, out, what="the build", rerun="build again")


def _card_text(plan: Plan) -> str:
    s = plan.spec
    ops = ", ".join(f"`{o.label}`" + (f" ({o.strategy}, {o.params})" if o.params else "") for o in s.operators)
    return (f"**Built from a spec** with `rik dataset build` (spec hash `{plan.spec_hash[:16]}`, in "
            f"`meta/{DATASET_META}` with the variants' content hashes and every file's sha256): "
            f"{len(plan.variants)} variants x {len(s.operators)} operators ({ops}) x {s.episodes_per_variant} "
            f"episodes from seed {s.seed}; `rik dataset verify DIR` re-checks it.")


def _write_build_meta(out: Path, result: BuildResult, engine: Engine) -> None:
    hours = result.wall_seconds / 3600
    stats = {"engine": engine.name, "workers": engine.workers, "wall_seconds": round(result.wall_seconds, 3),
             "ran": result.ran, "reused": result.reused,
             "seconds": {k: round(v, 3) for k, v in result.seconds.items()}, "frames_rendered": result.frames,
             "episodes_per_hour": round(result.ran["record"] / hours, 1) if hours and result.ran["record"] else None}
    ours = Replaces.when("rik's record of a build", lambda p: read_dataset_meta(p.parent.parent) is not None)
    write_text(out / "meta" / BUILD_META, json.dumps(stats, indent=1) + "\n", ours)
