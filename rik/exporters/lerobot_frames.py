"""What a rik episode becomes in a LeRobot dataset: the feature schema, the per-frame dicts (resampled to the
dataset's rate) and the per-episode metadata.

Features follow LeRobot's conventions: ``observation.state`` (the robot's state) and
``observation.environment_state`` (the front's state), named, as the gym environment's ``agent_pos`` and
``environment_state`` (:mod:`rik.sim.observation`); ``action`` (the recorded absolute target pose and gripper
command, named: what the environment takes with ``action_mode="absolute"``), and one video feature per camera and
stream: ``observation.images.<camera>`` for the sim stream, ``observation.images.<camera>_rerendered`` for the
Mitsuba one. Episode metadata are not features (policies take every ``observation.*`` feature): they are columns
``rik/<field>`` of ``meta/episodes``, which survive loading, ``episode_filter``, resuming and merging.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from rik.errors import RikError
from rik.sim.observation import image_name

if TYPE_CHECKING:
    import pyarrow as pa

    from rik.registry.catalog import Catalog
    from rik.schemas.episodes import EpisodeMeta

ACTION_NAMES = ("target_x", "target_y", "target_z", "target_pitch", "target_yaw", "target_roll", "gripper")
"""The recorded action: target pose of the gripper base (m, rad) and gripper command (0 open, 1 closed)."""
META_PREFIX = "rik/"
META_FIELDS = ("episode_id", "variant", "base_unit", "handle", "handle_type", "preset", "front", "operator",
               "operator_kind", "outcome", "seed", "final_opening", "source_fps")
ROBOT_TYPE = "rik_hand_e"
LAYOUT = 2
"""Version of the state layout an export writes: 2 is ``observation.state`` (the robot's state,
:data:`rik.sim.observation.ROBOT_STATE_NAMES`) beside ``observation.environment_state`` (the front's state); 1 was
one 14-number ``observation.state`` (:data:`LAYOUT_1_STATE_NAMES`), exports made before the split."""
LAYOUT_1_STATE_NAMES = ("x", "y", "z", "pitch", "yaw", "roll", "jaw_opening", "front_qpos", "front_qvel", "tcp_x",
                        "tcp_y", "tcp_z", "opening", "contact_normal_force")
"""The single state vector of layout 1."""


def image_key(camera: str, stream: str) -> str:
    """The dataset feature of a camera's stream, e.g. ``observation.images.front_rerendered``."""
    return f"observation.images.{image_name(camera, stream)}"


def features(cameras: Sequence[str], streams: Sequence[str], width: int, height: int) -> dict[str, dict[str, Any]]:
    """The LeRobot feature dict of an export."""
    from rik.sim.observation import ENV_STATE_NAMES, ROBOT_STATE_NAMES

    out: dict[str, dict[str, Any]] = {
        "observation.state": {"dtype": "float32", "shape": (len(ROBOT_STATE_NAMES),),
                              "names": list(ROBOT_STATE_NAMES)},
        "observation.environment_state": {"dtype": "float32", "shape": (len(ENV_STATE_NAMES),),
                                          "names": list(ENV_STATE_NAMES)},
        "action": {"dtype": "float32", "shape": (len(ACTION_NAMES),), "names": list(ACTION_NAMES)},
    }
    for cam in cameras:
        for stream in streams:
            out[image_key(cam, stream)] = {"dtype": "video", "shape": (height, width, 3),
                                           "names": ["height", "width", "channels"]}
    return out


def task_text(catalog: Catalog, meta: EpisodeMeta, front_kind: str) -> str:
    """A natural instruction, e.g. "open the drawer by its bow handle" (the environment's task description)."""
    from rik.sim.observation import instruction

    return instruction(catalog, meta.handle, front_kind)


def episode_metadata(meta: EpisodeMeta) -> dict[str, object]:
    """The ``rik/...`` columns of one episode's row in ``meta/episodes``."""
    values = {"episode_id": meta.id, "source_fps": int(meta.fps)}
    for name in META_FIELDS:
        values.setdefault(name, getattr(meta, name, None))
    return {f"{META_PREFIX}{k}": (float(v) if isinstance(v, float) else v) for k, v in values.items()}


def resample_indices(rows: int, source_fps: int, fps: int) -> np.ndarray:
    """Row of the recording shown at each frame of a ``fps`` dataset (the latest row at or before the frame's
    time: a zero-order hold, so actions stay the targets that were commanded)."""
    if fps == source_fps:
        return np.arange(rows)
    duration = (rows - 1) / source_fps
    times = np.arange(int(np.floor(duration * fps + 1e-9)) + 1) / fps
    return np.minimum(np.floor(times * source_fps + 1e-9).astype(int), rows - 1)


@dataclass(frozen=True)
class EpisodeSource:
    """A recorded episode and the finished stream folders its images come from."""

    directory: Path
    streams: dict[str, Path]
    """Stream kind -> finished stream folder (see :mod:`rik.render.streams`)."""


def episode_frames(catalog: Catalog, source: EpisodeSource, cameras: Sequence[str], fps: int,
                   variants: Path) -> tuple[EpisodeMeta, str, Iterator[dict[str, np.ndarray]], int]:
    """(meta, task, frame dicts for ``add_frame`` without the task, frame count) of one episode."""
    from rik.render.streams import read_frame
    from rik.sim.episode import read_episode, states
    from rik.sim.observation import state_observation
    from rik.sim.replay import episode_scene

    meta, table = read_episode(source.directory)
    scene = episode_scene(catalog, source.directory, variants, meta)
    recorded = states(table)
    actions = cast("pa.ListArray", table.column("action").combine_chunks()).values.to_numpy().reshape(len(recorded), -1)
    if actions.shape[1] != len(ACTION_NAMES):
        raise RikError(f"{source.directory / 'states.parquet'}: column 'action' has {actions.shape[1]} numbers "
                       f"per row; rik exports {len(ACTION_NAMES)} ({', '.join(ACTION_NAMES)})")
    picks = resample_indices(len(recorded), meta.fps, fps)
    task = task_text(catalog, meta, scene.front.kind)

    def frames() -> Iterator[dict[str, np.ndarray]]:
        for k in picks:
            scene.restore(recorded[k])
            state = state_observation(scene)
            frame: dict[str, np.ndarray] = {"observation.state": state["agent_pos"],
                                            "observation.environment_state": state["environment_state"],
                                            "action": actions[k].astype(np.float32)}
            for stream, folder in source.streams.items():
                for cam in cameras:
                    frame[image_key(cam, stream)] = read_frame(folder, cam, int(k))
            yield frame

    return meta, task, frames(), len(picks)
