"""The cost of a plan, from a short timed sample: a few of its episodes recorded, rendered and exported for real
(in a temporary folder, in this process), their per-stage seconds, frames and bytes scaled to the whole plan."""

from __future__ import annotations

import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from rik.dataset.build import Folders, export_spec, run_record, run_render, run_shard
from rik.dataset.plan import EpisodeUnit, Plan, RenderUnit, ShardUnit
from rik.dataset.registry import folder_size

if TYPE_CHECKING:
    from rik.registry.catalog import Catalog


@dataclass(frozen=True)
class StageCost:
    stage: str
    """record, render:<stream>, or export."""
    seconds_per_episode: float
    """One worker's wall time per episode, s."""
    frames_per_episode: float
    """Frames per episode (images of every camera for a render; recorded control steps for a record)."""
    bytes_per_episode: float
    """Disk per episode of the stage's output."""
    episodes: int

    @property
    def episodes_per_worker_hour(self) -> float:
        return 3600.0 / self.seconds_per_episode if self.seconds_per_episode > 0 else float("inf")

    @property
    def frames_per_worker_hour(self) -> float:
        return self.frames_per_episode * self.episodes_per_worker_hour

    @property
    def worker_hours(self) -> float:
        return self.seconds_per_episode * self.episodes / 3600.0

    @property
    def total_bytes(self) -> float:
        return self.bytes_per_episode * self.episodes


@dataclass(frozen=True)
class Estimate:
    sample: int
    stages: list[StageCost]

    @property
    def worker_hours(self) -> float:
        return sum(s.worker_hours for s in self.stages)

    @property
    def total_bytes(self) -> float:
        return sum(s.total_bytes for s in self.stages)

    def wall_hours(self, workers: int) -> float:
        """Wall time on ``workers`` workers, h, if the work spreads evenly."""
        return self.worker_hours / max(1, workers)


def sample_units(plan: Plan, count: int) -> list[int]:
    """Indices of ``count`` episodes spread evenly over the plan (the first, the last and between)."""
    n = len(plan.episodes)
    count = max(1, min(count, n))
    if count == 1:
        return [0]
    return sorted({round(i * (n - 1) / (count - 1)) for i in range(count)})


def estimate(catalog: Catalog, plan: Plan, *, sample: int = 2, variants: Path = Path("variants")) -> Estimate:
    """Time ``sample`` of the plan's episodes through every stage and scale to the plan. The first of them goes
    through every stage once before, untimed: a worker pays its imports (seconds) once, not per episode."""
    picked = [plan.episodes[i] for i in sample_units(plan, sample)]
    with tempfile.TemporaryDirectory(prefix="rik-estimate-warm-") as tmp:
        _time_stages(catalog, plan, picked[:1], Path(tmp), variants)
    with tempfile.TemporaryDirectory(prefix="rik-estimate-") as tmp:
        return Estimate(len(picked), _time_stages(catalog, plan, picked, Path(tmp), variants))


def _time_stages(catalog: Catalog, plan: Plan, picked: list[EpisodeUnit], tmp: Path, variants: Path
                 ) -> list[StageCost]:
    """Record, render and export ``picked`` in ``tmp``: each stage's cost per episode, scaled to the plan."""
    n = len(plan.episodes)
    folders = Folders(tmp, Path(variants).absolute())
    t0 = time.perf_counter()
    steps = 0
    for e in picked:
        steps += int(run_record(catalog, (folders, e, plan.spec.max_seconds))["steps"]) + 1
    stages = [StageCost("record", (time.perf_counter() - t0) / len(picked), steps / len(picked),
                        folder_size(folders.episodes) / len(picked), n)]
    outputs: dict[str, str] = {}
    for stream in plan.streams:
        t0 = time.perf_counter()
        frames = 0
        before = folder_size(folders.renders)
        for e in picked:
            unit = RenderUnit(e, stream, f"{e.key}-{stream}")
            record = run_render(catalog, (folders, unit, plan.stream_spec(stream), plan.spec.cameras))
            frames += int(record["frames"])
            outputs[f"{e.key}/{stream}"] = record["output"]
        stages.append(StageCost(f"render:{stream}", (time.perf_counter() - t0) / len(picked),
                                frames / len(picked), (folder_size(folders.renders) - before) / len(picked), n))
    t0 = time.perf_counter()
    shard = ShardUnit(0, tuple(picked), "estimate")
    run_shard(catalog, (folders, shard, export_spec(plan), outputs))
    stages.append(StageCost("export", (time.perf_counter() - t0) / len(picked), 0.0,
                            folder_size(folders.shards) / len(picked), n))
    return stages
