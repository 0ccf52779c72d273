"""Record episodes of a variant with a scripted strategy: ``rik record``."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from rik.errors import RikError
from rik.paths import inside
from rik.sim.episode import DEFAULT_EPISODES, EpisodeRecorder, episode_id, run_operator, write_episode
from rik.sim.gripper import HAND_E, GripperSpec
from rik.sim.operators import make_operator
from rik.sim.scene import SimScene, build_scene, start_pose

if TYPE_CHECKING:
    from rik.registry.catalog import Catalog

MAX_SECONDS = 30.0
"""Longest episode, simulated s."""
START_JITTER = (0.03, 0.03, 0.03, 0.08, 0.08, 0.08)
"""Half-widths of the uniform random offset of the gripper's start pose: m for x, y, z; rad for the angles."""


def variant_dir(catalog: Catalog, variant: str, variants: Path) -> Path:
    """The directory of a built variant, building it (with its checks, in the folder's collision mode:
    :func:`rik.combinator.build.resolve_collision`) first when it is missing or stale."""
    from rik.combinator.build import build_variant
    from rik.combinator.ids import parse_variant_id

    key = parse_variant_id(catalog, variant)
    directory = inside(variants, key.id, what="variant id")
    result = build_variant(catalog, key, variants)
    if result.status == "rejected":
        raise RikError(f"variant {key.id} cannot be simulated: check {result.failed_check} failed: {result.reason}")
    return directory


def check_seeds(seed: int, episodes: int) -> None:
    """Seeds ``seed`` .. ``seed + episodes - 1`` must lie in 0 .. 2^63 - 1 (stored as signed 64-bit integers)."""
    from rik.schemas.episodes import MAX_SEED

    if seed < 0 or seed + episodes - 1 > MAX_SEED:
        last = f", and the last of {episodes} episodes takes seed {seed + episodes - 1}" if seed >= 0 else ""
        raise RikError(f"--seed {seed}: seeds must lie in 0 .. {MAX_SEED} (2^63 - 1){last}")


def randomise_start(scene: SimScene, rng: np.random.Generator) -> None:
    """Put the gripper at its start pose plus a uniform random offset (:data:`START_JITTER`), open."""
    scene.set_pose(start_pose(scene) + rng.uniform(-1.0, 1.0, 6) * np.asarray(START_JITTER))


def record(catalog: Catalog, variant: str, strategy: str, *, episodes: int = 1, seed: int = 0,
           out: Path = DEFAULT_EPISODES, variants: Path = Path("variants"), front: str | None = None,
           gripper: GripperSpec = HAND_E, max_seconds: float = MAX_SECONDS,
           progress: Callable[[Any], None] | None = None) -> list[Any]:
    """Record ``episodes`` episodes of ``strategy`` on ``variant`` (seeds ``seed``, ``seed + 1``, ...) into
    ``out``; returns their metas."""
    check_seeds(seed, episodes)
    make_operator(strategy)  # unknown strategy: fail before building anything
    directory = variant_dir(catalog, variant, variants)
    metas = []
    for k in range(episodes):
        s = seed + k
        scene = build_scene(directory, front, gripper)
        rng = np.random.default_rng(s)
        randomise_start(scene, rng)
        operator = make_operator(strategy)
        recorder = run_operator(scene, operator, rng, max_seconds, EpisodeRecorder(scene))
        meta = write_episode(recorder, out, episode=episode_id(scene.info["id"], scene.front.id, strategy, s),
                             operator=strategy, operator_kind="strategy", seed=s, log=tuple(operator.log))
        metas.append(meta)
        if progress is not None:
            progress(meta)
    return metas
