"""Replaying recorded episodes: set each recorded state back, and check that stepping on from it with the
recorded action reproduces the next recorded state bit for bit."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, cast

import numpy as np

from rik.combinator.build import ensure_variant
from rik.episodes.episode import EXECUTED, EpisodeError, columns_of, read_episode, read_meta, states
from rik.errors import UnknownIdError

if TYPE_CHECKING:
    import pyarrow as pa

    from rik.registry.catalog import Catalog
    from rik.schemas.episodes import EpisodeMeta
    from rik.schemas.robots import Robot
    from rik.sim.scene import SimScene


@dataclass(frozen=True)
class ReplayCheck:
    exact: bool
    rows: int
    max_difference: float
    """Largest absolute difference between a re-simulated and a recorded state."""


def episode_robot(catalog: Catalog, directory: Path, meta: EpisodeMeta) -> Robot:
    """The catalog entry of the robot an episode was recorded with (``meta.robot``); an id the catalog lacks is one
    line naming the episode's meta.json."""

    try:
        return catalog.robot(meta.robot)
    except UnknownIdError as exc:
        raise EpisodeError(f"{Path(directory) / 'meta.json'}: field 'robot': {exc} (give the catalog it was "
                           "recorded with, --catalog)") from None


def episode_scene(catalog: Catalog, directory: Path, variants: Path, meta: EpisodeMeta) -> SimScene:
    """The scene an episode was recorded in (its variant is built first if missing), with its gripper."""
    from rik.sim.build import build_scene
    from rik.sim.robots.gripper import HAND_E

    g = meta.gripper
    gripper = HAND_E.with_(name=g.name, stroke=g.stroke, grip_force=g.grip_force, pad_friction=g.pad_friction,
                           arm_force=g.arm_force)
    robot = episode_robot(catalog, directory, meta).as_arm if meta.robot != "hand-e" else None
    scene = build_scene(ensure_variant(catalog, meta.variant, variants), meta.front, gripper, meta.fps, robot=robot)
    collision = scene.info.get("collision", "coacd")
    if collision != meta.collision:
        raise EpisodeError(f"{Path(directory) / 'meta.json'}: field 'collision': {meta.collision}, but {variants} "
                           f"holds {collision} collision variants (pass --variants with a {meta.collision} folder)")
    friction = scene.info.get("joint_friction", "held")
    if friction != meta.joint_friction:
        raise EpisodeError(f"{Path(directory) / 'meta.json'}: field 'joint_friction': {meta.joint_friction}, but "
                           f"{variants} holds variants whose joint friction is {friction} (pass --variants with a "
                           f"{meta.joint_friction} folder)")
    import mujoco

    size = mujoco.mj_stateSize(scene.model, mujoco.mjtState.mjSTATE_INTEGRATION)
    if size != meta.state_size:
        raise EpisodeError(f"{Path(directory) / 'meta.json'}: field 'state_size': {meta.state_size}, but the scene of "
                           f"{meta.variant} has states of {size} numbers (recorded with another rik or MuJoCo?)")
    return scene


def verify_episode(catalog: Catalog, directory: Path, variants: Path = Path("variants")) -> ReplayCheck:
    """Re-simulate every recorded step from its recorded state and action; compare with the next state."""
    meta = read_meta(directory)
    sent = EXECUTED if EXECUTED in columns_of(meta) else "action"  # the action the robot ran
    _, table = read_episode(directory, ("state", sent), meta)  # only these two columns are decoded
    scene = episode_scene(catalog, directory, variants, meta)
    recorded = states(table)
    actions = cast("pa.ListArray", table.column(sent).combine_chunks()).values.to_numpy().reshape(len(recorded), -1)
    worst = 0.0
    for k in range(len(recorded) - 1):
        scene.restore(recorded[k])
        if meta.action_kind == "joints":  # an arm driven joint by joint: its targets (rad), then the grip
            scene.step_joints(actions[k][:-1], float(actions[k][-1]))
        else:
            scene.step(actions[k])
        worst = max(worst, float(np.max(np.abs(scene.state() - recorded[k + 1]))))
    return ReplayCheck(worst == 0.0, len(recorded), worst)
