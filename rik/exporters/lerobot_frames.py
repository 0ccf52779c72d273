"""What a rik episode becomes in a LeRobot dataset: the per-frame dicts (resampled to the dataset's rate) of the
features of its contract (:meth:`rik.lerobot.policy_io.PolicyIO.features`) and the per-episode metadata.

Features follow LeRobot's conventions: ``observation.state`` (the robot's state) and
``observation.environment_state`` (the front's state), named, as the gym environment's ``agent_pos`` and
``environment_state`` (:mod:`rik.sim.observation`); ``action``, and one video feature per camera and stream:
``observation.images.<camera>`` for the sim stream, ``observation.images.<camera>_rerendered`` for the Mitsuba one.
What ``observation.state`` and ``action`` hold is the episode's robot's layout (:mod:`rik.sim.robots.layout`): for
the Hand-E its pose state and the recorded absolute target pose and gripper command (what the environment takes
with ``action_mode="absolute"``); for an arm its joint positions and the joint targets its servos were given, in
LeRobot's names and units for that robot, with ``observation.ee_pose`` where the robot's entry asks for it. A
dataset holds one robot. Episode metadata are not features (policies take every ``observation.*`` feature): they are
columns ``rik/<field>`` of ``meta/episodes``, which survive loading, ``episode_filter``, resuming and merging.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, cast

import numpy as np

from rik.episodes.recorded import RecordedEpisode
from rik.errors import RikError
from rik.lerobot.features import ACTION, EE_POSE, OBS_ENV_STATE, OBS_STATE, image_key

if TYPE_CHECKING:
    import pyarrow as pa

    from rik.registry.catalog import Catalog
    from rik.schemas.episodes import EpisodeMeta
    from rik.sim.robots.layout import RobotLayout

ACTION_NAMES = ("target_x", "target_y", "target_z", "target_pitch", "target_yaw", "target_roll", "gripper")
"""The recorded action (``states.parquet``'s ``action``, every robot's): target pose of the gripper base (m, rad) and
gripper command (0 open, 1 closed); the Hand-E's exported ``action`` too."""
META_PREFIX = "rik/"
META_FIELDS = ("episode_id", "variant", "base_unit", "handle", "handle_type", "preset", "front", "operator",
               "operator_kind", "outcome", "seed", "final_opening", "source_fps")
ROBOT_TYPE = "rik_hand_e"
"""``info.json``'s ``robot_type`` of the Hand-E's exports (an arm's is its catalog entry's ``lerobot.robot_type``)."""
EXPORT_COLUMNS = ("state", "action", "robot_targets")
"""The columns of ``states.parquet`` an export decodes (an episode before format 3 has no ``robot_targets``)."""
LAYOUT = 2
"""Version of the state layout an export writes: 2 is ``observation.state`` (the robot's state,
:data:`rik.sim.observation.ROBOT_STATE_NAMES`) beside ``observation.environment_state`` (the front's state); 1 was
one 14-number ``observation.state`` (:data:`LAYOUT_1_STATE_NAMES`), exports made before the split."""
LAYOUT_1_STATE_NAMES = ("x", "y", "z", "pitch", "yaw", "roll", "jaw_opening", "front_qpos", "front_qvel", "tcp_x",
                        "tcp_y", "tcp_z", "opening", "contact_normal_force")
"""The single state vector of layout 1."""


def episode_layout(catalog: Catalog, directory: Path, meta: EpisodeMeta, action_frame: str = "world"
                   ) -> RobotLayout:
    """The LeRobot layout of an episode's robot (:func:`rik.sim.robots.layout.robot_layout`), its pose action in
    ``action_frame``; an arm's recorded joints must be its catalog entry's, as the layout reads them by name, and
    its action has no handle frame (one line, naming the episode)."""
    from rik.episodes.replay import episode_robot
    from rik.sim.robots.layout import robot_layout

    robot = episode_robot(catalog, directory, meta)
    try:
        layout = robot_layout(robot.as_arm, action_frame)
    except RikError as exc:  # a handle frame for an arm's joint action
        raise RikError(f"{Path(directory) / 'meta.json'}: {exc}; export it with --action-frame world") from None
    if robot.as_arm is None:
        return layout
    expected = (*robot.joint_names, "gripper")
    if tuple(meta.robot_joints) != expected:
        raise RikError(f"{Path(directory) / 'meta.json'}: field 'robot_joints': the episode recorded joints "
                       f"{', '.join(meta.robot_joints) or '(none)'}, but robot '{robot.id}' of the catalog has "
                       f"{', '.join(expected)}; export it with the catalog it was recorded with (--catalog)")
    return layout


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
    """A recorded episode and the finished stream folders its images come from (what a shard is given: a worker
    process takes it whole, and reads the episode itself). ``rik export-lerobot`` gives none: its shards render
    the streams from their own read (:func:`~rik.exporters.lerobot_export.write_shard`'s ``renders``)."""

    directory: Path
    streams: dict[str, Path]
    """Stream kind -> finished stream folder (see :mod:`rik.render.streams`); empty where the shard renders them."""


@dataclass(frozen=True)
class LoadedEpisode:
    """One episode as the export takes it, read once by :func:`load_episode`: its recording (meta, states table and
    array, the scene built on first use: :class:`~rik.render.episodes.RecordedEpisode`, which the render takes), its
    robot's layout, and its recorded actions and servo targets as arrays (the actions checked to be the ones rik
    exports). :func:`episode_frames` takes it whole."""

    recorded: RecordedEpisode
    layout: RobotLayout
    actions: np.ndarray
    """The recorded ``action`` rows, (rows, :data:`ACTION_NAMES`); a joint-driven episode's joint actions (meta
    ``action_kind``: targets rad, then the grip)."""
    targets: np.ndarray
    """An arm's recorded joint targets (``robot_targets``), (rows, joints); (rows, 0) for the Hand-E; a joint-driven
    episode's ``actions`` (the targets as commanded, before the servos held them within reach)."""

    @property
    def directory(self) -> Path:
        return self.recorded.directory

    @property
    def meta(self) -> EpisodeMeta:
        return self.recorded.meta


def load_episode(catalog: Catalog, directory: Path, meta: EpisodeMeta | None = None, action_frame: str = "world"
                 ) -> LoadedEpisode:
    """Read the episode in ``directory`` for the export: ``meta.json`` (unless given) and the :data:`EXPORT_COLUMNS`
    of ``states.parquet`` (:func:`rik.episodes.states.read_states`: bounded before decoding, and checked), its
    robot's layout (:func:`episode_layout`) and its action rows, refused (one line) when they are not the
    :data:`ACTION_NAMES` rik exports: the export's one check of their width."""
    recorded = RecordedEpisode(directory, meta, EXPORT_COLUMNS)
    table = recorded.table
    layout = episode_layout(catalog, recorded.directory, recorded.meta, action_frame)
    rows = len(recorded.states)
    actions = _rows(table, "action", rows)
    if recorded.meta.action_kind == "joints":  # a leader's joint targets as commanded (rad) and the grip: exported
        return LoadedEpisode(recorded, layout, actions, actions)  # as LeRobot's follower action (the leader's)
    if actions.shape[1] != len(ACTION_NAMES):
        raise RikError(f"{recorded.directory / 'states.parquet'}: column 'action' has {actions.shape[1]} numbers per "
                       f"row where the other episodes have {len(ACTION_NAMES)} ({', '.join(ACTION_NAMES)}); export "
                       "it to a separate dataset")
    # an arm's action is what its servos were commanded: the recorded joint targets (format 3 episodes)
    targets = np.zeros((rows, 0)) if layout.is_pose else _rows(table, "robot_targets", rows)
    return LoadedEpisode(recorded, layout, actions, targets)


def episode_frames(catalog: Catalog, episode: LoadedEpisode, streams: Mapping[str, Path], cameras: Sequence[str],
                   fps: int, variants: Path, handle_shape: str = "none", environment_state: bool = True
                   ) -> tuple[str, Iterator[dict[str, np.ndarray]], int]:
    """(task, frame dicts for ``add_frame`` without the task, frame count) of one episode read by
    :func:`load_episode`, resampled to ``fps``, its images read from ``streams`` (stream kind -> finished stream
    folder); the front's state followed by the grasp point from the gripper (a gripper-frame layout's) and the
    handle's shape ``handle_shape`` (none of them with ``environment_state`` False)."""
    from rik.render.streams import read_frame
    from rik.sim.observation import environment_state as front_state
    from rik.sim.observation import handle_shape_state

    meta, layout, actions, targets = episode.meta, episode.layout, episode.actions, episode.targets
    scene = episode.recorded.scene(catalog, variants)
    recorded = episode.recorded.states
    picks = resample_indices(len(recorded), meta.fps, fps)
    task = task_text(catalog, meta, scene.front.kind)
    shape = handle_shape_state(catalog, meta.handle, handle_shape)

    def frames() -> Iterator[dict[str, np.ndarray]]:
        for k in picks:
            scene.restore(recorded[k])
            frame: dict[str, np.ndarray] = {OBS_STATE: layout.state(scene).astype(np.float32)}
            if layout.ee_pose:
                frame[EE_POSE] = layout.ee(scene).astype(np.float32)
            if environment_state:
                env_state = front_state(scene, shape, layout.action_frame == "gripper")
                frame[OBS_ENV_STATE] = env_state.astype(np.float32)
            action = (layout.joint_action(targets[k], float(targets[k][-1])) if meta.action_kind == "joints"
                      else layout.action(actions[k], targets[k], layout.frame_origin(scene)))
            frame[ACTION] = action.astype(np.float32)
            for stream, folder in streams.items():
                for cam in cameras:
                    frame[image_key(cam, stream)] = read_frame(folder, cam, int(k))
            yield frame

    return task, frames(), len(picks)


def _rows(table: pa.Table, column: str, rows: int) -> np.ndarray:
    """A vector column of ``states.parquet`` as a (rows, width) array."""
    return cast("pa.ListArray", table.column(column).combine_chunks()).values.to_numpy().reshape(rows, -1)
