"""``rik dataset verify DIR``: re-check a built dataset against its own record: every file's sha256, each
episode's frame counts (videos decoded), and that LeRobot loads it and reads each episode's first and last frame."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from rik.dataset.engines import error_line
from rik.dataset.meta import DATASET_META, read_dataset_meta
from rik.errors import RikError
from rik.lerobot.arrow_cache import scratch_arrow_cache


@dataclass
class VerifyResult:
    root: Path
    files: int
    episodes: int
    frames: int
    problems: list[str] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return not self.problems


def verify_dataset(root: Path) -> VerifyResult:
    """Check the dataset at ``root``; problems are listed, not raised (a folder that is no built dataset is)."""
    from rik.dataset.build import file_checksums

    root = Path(root)
    meta = read_dataset_meta(root)
    if meta is None:
        raise RikError(f"{root}: not a dataset built by rik dataset build (no readable meta/{DATASET_META})")
    recorded: dict[str, str] = meta.get("files", {})
    now = file_checksums(root)
    problems = [f"{rel}: missing" for rel in sorted(set(recorded) - set(now))]
    problems += [f"{rel}: not in the build's record (added after the build)"
                 for rel in sorted(set(now) - set(recorded))]
    problems += [f"{rel}: sha256 differs from the build's record (changed or corrupt)" for rel in sorted(recorded)
                 if rel in now and now[rel] != recorded[rel]]
    counts = meta.get("counts", {})
    episodes = frames = 0
    if not problems:
        try:
            episodes, frames = _load(root, meta, counts)
        except Exception as exc:  # whatever lerobot or the decoder raise is a problem of this dataset

            problems.append(f"does not load with LeRobotDataset: {error_line(exc)}")
    return VerifyResult(root, len(now), episodes, frames, problems)


@scratch_arrow_cache()
def _load(root: Path, meta: dict[str, Any], counts: dict[str, Any]) -> tuple[int, int]:
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    from rik.exporters.lerobot_check import check_frame_counts

    check_frame_counts(root)
    ds = LeRobotDataset(meta["spec"]["repo_id"], root=root, video_backend="pyav")
    if ds.meta.total_episodes != counts.get("episodes") or ds.meta.total_frames != counts.get("frames"):
        raise RikError(f"holds {ds.meta.total_episodes} episodes and {ds.meta.total_frames} frames, its record says "
                       f"{counts.get('episodes')} and {counts.get('frames')}")
    for e in range(ds.meta.total_episodes):
        row = ds.meta.episodes[e]
        for index in (row["dataset_from_index"], row["dataset_to_index"] - 1):
            ds[int(index)]
    return ds.meta.total_episodes, ds.meta.total_frames
