"""Checks of a written LeRobot dataset: every episode's decoded video frames equal its table rows (nobody else
checks this, and lerobot's streaming encoder can drop frames silently), it loads offline with its metadata, and
which of rik's state layouts it holds (:data:`rik.exporters.lerobot_frames.LAYOUT`)."""

from __future__ import annotations

import json
from collections import defaultdict
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rik.errors import RikError
from rik.exporters.lerobot_frames import LAYOUT, LAYOUT_1_STATE_NAMES
from rik.lerobot.arrow_cache import scratch_arrow_cache
from rik.lerobot.features import ACTION, EE_POSE, OBS_ENV_STATE, OBS_STATE

if TYPE_CHECKING:
    from rik.sim.robots.layout import RobotLayout

TOLERANCE_S = 1e-4
CONSTANT_STD = 1e-6
"""A dimension of a state or action feature whose standard deviation over the dataset is below this (its own units:
m, rad, N, ...) never changes: normalisation divides by about zero there (LeRobot's ``MEAN_STD`` adds 1e-8)."""


def constant_dimensions(root: Path) -> dict[str, list[str]]:
    """Feature -> names of its dimensions that never change in the dataset at ``root`` (from ``meta/stats.json``):
    on a dataset of one variant the handle's pose is one number, and a policy normalised on it sees every other
    handle as millions of standard deviations away."""
    stats_file, info_file = root / "meta" / "stats.json", root / "meta" / "info.json"
    if not stats_file.is_file():
        return {}
    stats = json.loads(stats_file.read_text(encoding="utf-8"))
    features = json.loads(info_file.read_text(encoding="utf-8"))["features"]
    out: dict[str, list[str]] = {}
    for key in (OBS_STATE, OBS_ENV_STATE, EE_POSE, ACTION):
        std = (stats.get(key) or {}).get("std")
        if key not in features or std is None:
            continue
        names = features[key].get("names") or [str(i) for i in range(len(std))]
        flat = list(names) if isinstance(names, list) else [str(i) for i in range(len(std))]
        constant = [flat[i] if i < len(flat) else str(i) for i, v in enumerate(std) if float(v) < CONSTANT_STD]
        if constant:
            out[key] = constant
    return out


def constant_warning(constant: dict[str, list[str]]) -> str | None:
    """One line for :func:`constant_dimensions`' result (None when nothing is constant)."""
    if not constant:
        return None
    count = sum(len(names) for names in constant.values())
    parts = "; ".join(f"{key}: {', '.join(names)}" for key, names in constant.items())
    return (f"{count} dimension{'s' if count != 1 else ''} never change in this dataset ({parts}): normalisation "
            "divides by about zero there, so a policy trained on it reads any other value as far out of its "
            "training range (train on data where they vary, more variants or front kinds, or leave those dimensions "
            "out)")


def _episodes_table(root: Path) -> list[dict[str, Any]]:
    import pyarrow.parquet as pq

    rows: list[dict[str, Any]] = []
    for f in sorted((root / "meta" / "episodes").rglob("*.parquet")):
        rows += pq.read_table(f).to_pylist()
    return sorted(rows, key=lambda r: r["episode_index"])


def _frame_times(path: Path) -> list[float]:
    import av

    with av.open(str(path)) as container:
        stream = container.streams.video[0]
        base = stream.time_base
        times = [float(frame.pts * base) for frame in container.decode(stream)
                 if frame.pts is not None and base is not None]  # frames without a timestamp cannot be checked
    return sorted(times)


def check_frame_counts(root: Path) -> dict[str, int]:
    """Decode every video file of the dataset at ``root`` and check that each episode has exactly as many frames
    in its time range as rows in the table; returns frames decoded per video key. A RikError names the first
    episode and key that disagree."""
    info = json.loads((root / "meta" / "info.json").read_text(encoding="utf-8"))
    keys = [k for k, f in info["features"].items() if f.get("dtype") == "video"]
    episodes = _episodes_table(root)
    decoded: dict[str, int] = {}
    for key in keys:
        by_file: dict[tuple[int, int], list[dict[str, Any]]] = defaultdict(list)
        for ep in episodes:
            by_file[(ep[f"videos/{key}/chunk_index"], ep[f"videos/{key}/file_index"])].append(ep)
        decoded[key] = 0
        for (chunk, file), eps in sorted(by_file.items()):
            path = root / info["video_path"].format(video_key=key, chunk_index=chunk, file_index=file)
            times = _frame_times(path)
            decoded[key] += len(times)
            for ep in eps:
                start, end = ep[f"videos/{key}/from_timestamp"], ep[f"videos/{key}/to_timestamp"]
                count = sum(start - TOLERANCE_S <= t < end - TOLERANCE_S for t in times)
                if count != ep["length"]:
                    raise RikError(f"{path}: episode {ep['episode_index']} of '{key}' decodes to {count} frames but "
                                   f"has {ep['length']} rows; the video is incomplete")
    return decoded


def state_layout(features: dict[str, Any], robot: RobotLayout | None = None) -> int | None:
    """rik's state layout of a dataset's ``features`` (info.json) for the robot of ``robot`` (None: the Hand-E): 2
    (``observation.state`` of the robot in its layout, ``observation.environment_state`` of the front, with or
    without the handle's shape, or none in an export with ``--no-environment-state``), 1 (one
    14-number ``observation.state``, Hand-E exports made before the split), or None (not a rik layout)."""
    from rik.lerobot.features import ENV_STATE_LAYOUTS
    from rik.sim.robots.layout import robot_layout

    robot = robot or robot_layout(None)

    def names(key: str) -> tuple[str, ...] | None:
        return tuple(features[key].get("names") or ()) if key in features else None

    if names(OBS_STATE) == LAYOUT_1_STATE_NAMES and OBS_ENV_STATE not in features:
        return 1
    if names(OBS_STATE) == robot.state_names and (OBS_ENV_STATE not in features
                                                  or names(OBS_ENV_STATE) in ENV_STATE_LAYOUTS.values()):
        return 2  # without the front's state: an export of the robot's state and images only
    return None


def describe_layout(layout: int | None, robot: RobotLayout | None = None) -> str:
    """A state layout in words (``robot``: the robot's layout; None: the Hand-E's)."""
    if layout == 2:
        who = "the robot's" if robot is None or robot.is_pose else f"robot {robot.robot_id}'s"
        n = 11 if robot is None else len(robot.state_names)
        return (f"2 (observation.state: {who} {n} numbers; observation.environment_state: the front's 13, and the "
                "handle's shape's 5 or 11 where exported with --handle-shape kind or full; none with "
                "--no-environment-state)")
    if layout == 1:
        return ("1 (one 14-number observation.state, no observation.environment_state: an export made before the "
                "state split; export the episodes again for layout 2)")
    return "unknown (not one of rik's layouts)"


def check_robot(root: Path, robot_type: str | None, feats: dict[str, Any], robot: RobotLayout) -> None:
    """The dataset's ``robot_type`` and its features ``action`` and ``observation.ee_pose`` are those of
    ``robot``'s layout."""
    from rik.sim.robots.layout import EE_NAMES

    if robot_type != robot.robot_type:
        raise RikError(f"{root}: robot_type is {robot_type!r}, robot {robot.robot_id}'s is {robot.robot_type!r}")
    action = tuple(feats.get(ACTION, {}).get("names") or ())
    if action != robot.action_names:
        raise RikError(f"{root}: action holds {', '.join(action)}; robot {robot.robot_id}'s layout is "
                       f"{', '.join(robot.action_names)}")
    ee = tuple(feats[EE_POSE].get("names") or ()) if EE_POSE in feats else None
    if ee != (EE_NAMES if robot.ee_pose else None):
        raise RikError(f"{root}: {EE_POSE} is {'missing' if ee is None else ', '.join(ee)}; robot "
                       f"{robot.robot_id}'s layout {'has' if robot.ee_pose else 'has none'}"
                       + (f" ({', '.join(EE_NAMES)})" if robot.ee_pose else ""))


@scratch_arrow_cache()
def check_dataset(root: Path, repo_id: str, episodes: int, robot: RobotLayout | None = None) -> dict[str, Any]:
    """Load the dataset offline with ``LeRobotDataset``, check its episode count, rik's metadata columns, its
    robot's layout (``robot``; None: the Hand-E's) and its frame counts; returns a summary."""
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    ds = LeRobotDataset(repo_id, root=root, video_backend="pyav")
    if ds.meta.total_episodes != episodes:
        raise RikError(f"{root}: holds {ds.meta.total_episodes} episodes, {episodes} were exported")
    columns = set(ds.meta.episodes.column_names)
    missing = [c for c in ("rik/variant", "rik/outcome", "rik/seed") if c not in columns]
    if missing:
        raise RikError(f"{root}: meta/episodes lacks rik's columns {missing}")
    from rik.sim.robots.layout import robot_layout

    robot = robot or robot_layout(None)
    layout = state_layout(ds.meta.features, robot)
    if layout != LAYOUT:
        raise RikError(f"{root}: holds rik's state layout {describe_layout(layout)}, not layout {LAYOUT} of robot "
                       f"{robot.robot_id}")
    check_robot(root, ds.meta.robot_type, ds.meta.features, robot)
    decoded = check_frame_counts(root)
    counts = ("every episode's video frames equal its rows" if decoded else
              "no video features to check (a state-only export)")
    return {"episodes": ds.meta.total_episodes, "frames": ds.meta.total_frames, "fps": ds.meta.fps,
            "layout": layout, "layout_text": describe_layout(layout, robot), "video_frames_decoded": decoded,
            "frame_counts": counts, "constant": constant_dimensions(root)}
