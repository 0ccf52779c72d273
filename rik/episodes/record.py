"""Record episodes of a variant with a scripted strategy: ``rik record``."""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from rik.combinator.build import ensure_variant
from rik.episodes.episode import DEFAULT_EPISODES, EpisodeRecorder, episode_id, run_operator, write_episode
from rik.episodes.operators import make_operator
from rik.errors import RikError
from rik.paths import check_folder, inside
from rik.sim.build import build_scene
from rik.sim.robots.gripper import HAND_E, GripperSpec
from rik.sim.scene import SimScene, start_pose

if TYPE_CHECKING:
    from rik.episodes.draw import Draw
    from rik.registry.catalog import Catalog
    from rik.schemas.robots import Robot

MAX_SECONDS = 30.0
"""Longest episode, simulated s."""
START_JITTER = (0.03, 0.03, 0.03, 0.08, 0.08, 0.08)
"""Half-widths of the uniform random offset of the gripper's start pose: m for x, y, z; rad for the angles."""


MAX_EPISODES = 1_000_000
"""Most episodes one ``rik record`` writes (a million episodes is about a terabyte and years of a core): a
larger ``--episodes`` is a typo, refused before anything is drawn or recorded."""


def check_seeds(seed: int, episodes: int) -> None:
    """Seeds ``seed`` .. ``seed + episodes - 1`` must lie in 0 .. 2^63 - 1 (stored as signed 64-bit integers), and
    ``episodes`` in 1 .. :data:`MAX_EPISODES`."""
    from rik.schemas.episodes import MAX_SEED

    if not 1 <= episodes <= MAX_EPISODES:
        raise RikError(f"--episodes {episodes}: give 1 to {MAX_EPISODES:,} episodes per command")
    if seed < 0 or seed + episodes - 1 > MAX_SEED:
        last = f", and the last of {episodes} episodes takes seed {seed + episodes - 1}" if seed >= 0 else ""
        raise RikError(f"--seed {seed}: seeds must lie in 0 .. {MAX_SEED} (2^63 - 1){last}")


def randomise_start(scene: SimScene, rng: np.random.Generator) -> None:
    """Put the gripper at its start pose plus a uniform random offset (:data:`START_JITTER`), open."""
    scene.set_pose(start_pose(scene) + rng.uniform(-1.0, 1.0, 6) * np.asarray(START_JITTER))


def record(catalog: Catalog, variant: str, strategy: str, *, episodes: int = 1, seed: int = 0,
           out: Path = DEFAULT_EPISODES, variants: Path = Path("variants"), front: str | None = None,
           gripper: GripperSpec = HAND_E, max_seconds: float = MAX_SECONDS, robot: Robot | None = None,
           progress: Callable[[Any], None] | None = None,
           params: Mapping[str, float | int] | None = None) -> list[Any]:
    """Record ``episodes`` episodes of ``strategy`` (with its ``params``) on ``variant`` (seeds ``seed``,
    ``seed + 1``, ...) into ``out`` with the Hand-E ``gripper`` or an arm (``robot``, a catalog entry); returns
    their metas. An arm that cannot reach the variant's handle is refused before anything is recorded."""
    check_seeds(seed, episodes)
    check_folder(out, "--out")
    make_operator(strategy, params)  # unknown strategy or parameter: fail before building anything
    directory = ensure_variant(catalog, variant, variants)
    if robot is not None:
        from rik.sim.robots.checks import require_reach

        require_reach(build_scene(directory, front, gripper, robot=robot))
    metas = []
    for k in range(episodes):
        meta = record_one(directory, strategy, seed + k, out, front=front, gripper=gripper, max_seconds=max_seconds,
                          robot=robot, params=params)
        metas.append(meta)
        if progress is not None:
            progress(meta)
    return metas


def record_one(directory: Path, strategy: str, seed: int, out: Path, *, front: str | None = None,
               gripper: GripperSpec = HAND_E, max_seconds: float = MAX_SECONDS,
               params: Mapping[str, float | int] | None = None, label: str | None = None,
               robot: Robot | None = None) -> Any:
    """Record one episode of ``strategy`` (with its ``params``) with ``seed`` on the built variant at ``directory``
    into ``out``, as :func:`record` does for each of its seeds; returns its meta. ``label`` names the operator in
    the episode's id and meta (default: the strategy)."""
    scene = build_scene(directory, front, gripper, robot=robot)
    rng = np.random.default_rng(seed)
    randomise_start(scene, rng)
    operator = make_operator(strategy, params)
    recorder = run_operator(scene, operator, rng, max_seconds, EpisodeRecorder(scene))
    name = label or strategy
    return write_episode(recorder, out, episode=episode_id(scene.info["id"], scene.front.id, name, seed,
                                                           scene.robot_id),
                         operator=name, operator_kind="strategy", seed=seed, log=tuple(operator.log),
                         action_noise=operator.action_noise or None)


def _record_drawn(catalog: Catalog, seed: str, *, draw: Draw, strategy: str, out: Path, dirs: dict[str, Path],
                  gripper: GripperSpec, max_seconds: float, robot: Robot | None = None,
                  params: Mapping[str, float | int] | None = None) -> Any:
    """One episode of :func:`record_split` (module level: it runs in worker processes)."""
    episode = draw.episode(catalog, int(seed))
    return record_one(dirs[episode.variant], strategy, int(seed), out, front=episode.front, gripper=gripper,
                      max_seconds=max_seconds, robot=robot, params=params)


def record_split(catalog: Catalog, draw: Draw, strategy: str, *, episodes: int = 1, seed: int = 0,
                 out: Path = DEFAULT_EPISODES, variants: Path = Path("variants"), gripper: GripperSpec = HAND_E,
                 max_seconds: float = MAX_SECONDS, workers: int = 1, overlays: Sequence[Path] = (),
                 progress: Callable[[Any], None] | None = None,
                 skipped: list[tuple[int, str, str]] | None = None, robot: Robot | None = None,
                 params: Mapping[str, float | int] | None = None) -> list[Any]:
    """Record ``episodes`` episodes of ``strategy`` (with its ``params``) whose variant and front come from ``draw``
    (:class:`rik.episodes.draw.Draw`) for seeds ``seed``, ``seed + 1``, ...: each exactly as :func:`record` writes that
    variant, front and seed. Builds the variants first, then records in ``workers`` processes; metas in seed
    order. A seed whose variant fails its checks in ``variants`` (e.g. a handle whose single convex hull sinks
    into the front, in a ``--collision hull`` folder) is not recorded: it is appended to ``skipped`` as (seed,
    variant id, reason); without a ``skipped`` list, or when every seed is skipped, that is an error."""
    import functools

    from rik.combinator.build import rejected_variants
    from rik.workers import check_workers, map_ids

    check_seeds(seed, episodes)
    check_workers(workers)
    check_folder(out, "--out")
    check_folder(variants, "--variants")
    make_operator(strategy, params)  # unknown strategy or parameter: fail before building anything
    draw.check(catalog)
    seeds = list(range(seed, seed + episodes))
    drawn = {s: draw.episode(catalog, s).variant for s in seeds}
    rejected = {r.id: f"variant {r.id} cannot be simulated: check {r.failed_check} failed: {r.reason}"
                for r in rejected_variants(catalog, drawn.values(), variants, workers=workers,
                                           overlays=overlays).values()}
    if rejected:
        if skipped is None:
            raise RikError(next(iter(rejected.values())))
        if all(v in rejected for v in drawn.values()):
            raise RikError(f"every drawn variant was rejected; the first: {next(iter(rejected.values()))}")
        skipped += [(s, v, rejected[v]) for s, v in drawn.items() if v in rejected]
        seeds = [s for s in seeds if drawn[s] not in rejected]
    dirs = {v: inside(variants, v, what="variant id") for v in set(drawn.values()) if v not in rejected}
    fn = functools.partial(_record_drawn, draw=draw, strategy=strategy, out=out, dirs=dirs, gripper=gripper,
                           max_seconds=max_seconds, robot=robot, params=params)
    metas: dict[int, Any] = {}
    for s, meta in map_ids(fn, catalog, [str(s) for s in seeds], workers=workers, overlays=overlays):
        metas[int(s)] = meta
        if progress is not None:
            progress(meta)
    return [metas[s] for s in seeds]
