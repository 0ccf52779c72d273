"""Recording and reading episodes: ``<out>/<id>/meta.json`` and ``states.parquet``.

Each row of ``states.parquet`` holds the full integration state (``mj_getState``, ``mjSTATE_INTEGRATION``), so
setting it back reproduces every body pose bit for bit, and stepping on from it with the row's action reproduces
the next row. An episode is written to a staging directory and renamed into place when complete: an
interrupted recording leaves nothing that looks like an episode. ``meta.json`` records the sha256 of
``states.parquet``, so a truncated or edited file is refused when read.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from rik.episodes.states import COLUMNS as COLUMNS
from rik.episodes.states import COLUMNS_2 as COLUMNS_2
from rik.episodes.states import EXECUTED as EXECUTED
from rik.episodes.states import META as META
from rik.episodes.states import STATES as STATES
from rik.episodes.states import VECTORS as VECTORS
from rik.episodes.states import EpisodeError as EpisodeError
from rik.episodes.states import columns_of as columns_of
from rik.episodes.states import read_states
from rik.errors import RikError
from rik.outputs import (
    NEW,
    MadeFolder,
    Replaces,
    check_replaceable,
    make_stage,
    publish_new_directory,
    remove_stage,
    replace_directory,
    tree_holds_only,
    write_text,
    writing,
)
from rik.paths import inside, json_object, json_sha256, read_json
from rik.sim.outcome import classify
from rik.sim.scene import SimScene

if TYPE_CHECKING:
    import pyarrow as pa

    from rik.episodes.operators import Operator
    from rik.schemas.episodes import EpisodeMeta

DEFAULT_EPISODES = Path("episodes")
MAX_META_BYTES = 2**20
"""Largest ``meta.json`` read (:func:`read_meta`): rik writes a few kB."""


def is_episode(directory: Path) -> bool:
    """Whether ``directory`` is an episode rik recorded: its ``meta.json`` (an object) and ``states.parquet``,
    nothing else, at any depth."""
    return json_object(Path(directory) / META) is not None and tree_holds_only(directory, {META, STATES})


EPISODE_FOLDER = MadeFolder("an episode rik recorded", is_episode, "choose another --out")
"""An episode's folder: recorded again, it is replaced, and only if :func:`is_episode` recognises it."""

def _versions() -> dict[str, str]:
    import mujoco

    from rik import __version__

    return {"rik": __version__, "mujoco": mujoco.__version__}


@dataclass
class EpisodeRecorder:
    """Records a scene control step by control step: ``step(action)`` stores the state and the action, then
    advances the physics by one control step."""

    scene: SimScene
    rows: dict[str, list[Any]] = field(default_factory=lambda: {c: [] for c in (*COLUMNS, EXECUTED)})
    max_opening: float = 0.0
    perturbed: bool = False
    """Whether any step executed another action than the one recorded (the table then has :data:`EXECUTED`)."""
    action_kind: str = "pose"
    """What the recorded actions are (meta.json's ``action_kind``): ``pose`` (:meth:`step`) or ``joints``
    (:meth:`step_joints`); one episode holds one kind."""

    def _store(self, action: np.ndarray, targets: np.ndarray | None = None,
               executed: np.ndarray | None = None) -> None:
        s = self.scene
        q, qd = s.front_q()
        contact = s.contact_summary()
        r = self.rows
        r["step"].append(len(r["step"]))
        r["time"].append(float(s.data.time))
        r["state"].append(s.state())
        r["action"].append(np.asarray(action, np.float64).copy())
        r["front_qpos"].append(q)
        r["front_qvel"].append(qd)
        r["opening"].append(s.opening())
        r["gripper_opening"].append(s.finger_opening())
        r["tcp"].append(s.tcp())
        r["contacts"].append(int(contact["contacts"]))
        r["contact_normal_force"].append(contact["normal_force"])
        r["contact_tangential_force"].append(contact["tangential_force"])
        r["tcp_quat"].append(s.tcp_quat())
        r["robot_joints"].append(s.robot_joints())
        r["robot_targets"].append(targets)
        r[EXECUTED].append(np.asarray(action if executed is None else executed, np.float64).copy())
        self.max_opening = max(self.max_opening, s.opening())

    def step(self, action: np.ndarray, executed: np.ndarray | None = None) -> None:
        """Record ``action`` and run ``executed`` (default: the same action) for one control step."""
        if executed is not None:
            self.perturbed = True
        self._kind("pose")
        self._store(action, executed=executed)
        sent = np.asarray(action if executed is None else executed, np.float64)
        self.scene.step(sent)
        self.rows["robot_targets"][-1] = self.scene.robot_drive.targets(self.scene, sent)

    def step_joints(self, targets: np.ndarray, grip: float) -> None:
        """Record and run one control step of an arm driven joint by joint (:meth:`SimScene.step_joints`): the
        action stored is the joint ``targets`` as commanded (rad, the robot's joint order) and then ``grip`` (0 open
        .. 1 closed), which a replay runs again the same way."""
        self._kind("joints")
        s = self.scene
        action = np.concatenate([np.asarray(targets, np.float64).reshape(-1), [float(grip)]])
        self._store(action)
        s.step_joints(action[:-1], float(action[-1]))
        goal, _ = s.robot_drive.jaw(s, float(action[-1]))
        self.rows["robot_targets"][-1] = np.concatenate([s.data.ctrl[s.robot_drive.arm_ctrl], [goal]])

    def _kind(self, kind: str) -> None:
        if self.steps and self.action_kind != kind:
            raise RikError(f"an episode records one kind of action: it holds {self.action_kind} actions, not {kind}")
        self.action_kind = kind

    @property
    def steps(self) -> int:
        return len(self.rows["step"])

    def truncate(self, steps: int) -> None:
        """Keep the first ``steps`` steps: the scene goes back to the state after the last kept one (recorded as the
        next row's state), so the episode ends there and replays exactly."""
        if not 0 < steps < self.steps:
            return
        self.scene.restore(self.rows["state"][steps])
        for rows in self.rows.values():
            del rows[steps:]
        self.max_opening = max(max(self.rows["opening"]), self.scene.opening())

    def table(self) -> pa.Table:
        """The rows so far plus the final state, as a pyarrow table."""
        import pyarrow as pa

        r = self.rows
        last = r["action"][-1] if r["action"] else np.zeros(7)
        sent = r[EXECUTED][-1] if r[EXECUTED] else last
        held = r["robot_targets"][-1] if r["robot_targets"] else self.scene.robot_drive.targets(self.scene, sent)
        self._store(last, held, sent)
        columns = (*COLUMNS, EXECUTED) if self.perturbed else COLUMNS
        try:
            def vectors(name: str) -> pa.Array:
                return pa.FixedSizeListArray.from_arrays(pa.array(np.concatenate(r[name]), pa.float64()),
                                                         len(r[name][0]))

            arrays = {
                "step": pa.array(r["step"], pa.int32()),
                "time": pa.array(r["time"], pa.float64()),
                "contacts": pa.array(r["contacts"], pa.int32()),
                **{name: vectors(name) for name in VECTORS if name in columns},
            }
            for c in columns:
                if c not in arrays:
                    arrays[c] = pa.array(r[c], pa.float64())
            return pa.table({c: arrays[c] for c in columns})
        finally:
            for rows in self.rows.values():
                rows.pop()


def episode_id(variant: str, front: str, operator: str, seed: int, robot: str = "hand-e") -> str:
    """``<variant>__<front>__<operator>__s<seed>``; an arm's operator carries ``.<robot>``
    (``contact_rich.so100``), so the robots' episodes of one seed live side by side."""
    who = operator if robot == "hand-e" else f"{operator}.{robot}"
    return f"{variant}__{front}__{who}__s{seed:04d}"


def _robot_base(scene: SimScene) -> Any:
    """An arm's base placement for meta.json (None for the Hand-E)."""
    from rik.schemas.episodes import RobotBase

    p = scene.robot_drive.mount
    if p is None:
        return None
    return RobotBase(pos=(float(p.pos[0]), float(p.pos[1]), float(p.pos[2])), yaw=float(p.yaw))


def write_episode(recorder: EpisodeRecorder, out: Path, *, episode: str, operator: str, operator_kind: str,
                  seed: int, log: tuple[str, ...] = (), action_noise: float | None = None,
                  replace: bool = True) -> EpisodeMeta:
    """Write the recorded episode to ``out/<episode>`` (through a staging directory of its own); returns its meta.
    ``action_noise``: the operator's noise on the executed action (m), for an episode recorded with it. With
    ``replace``, an episode rik recorded there before is replaced (a recording is deterministic: the same one);
    without, the id is taken exclusively and :class:`rik.outputs.NameTaken` raised when another writer has it."""
    import pyarrow.parquet as pq

    from rik.schemas.episodes import EpisodeMeta, GripperInfo

    s = recorder.scene
    table = recorder.table()
    final = inside(out, episode, what="episode id")  # before any work: an id leading outside ``out`` is refused
    check_replaceable(final, EPISODE_FOLDER)  # and a folder there that is not an episode is never replaced
    staging = make_stage(final)
    try:
        with writing(staging / STATES, NEW) as tmp:
            pq.write_table(table, tmp, compression="zstd")
        digest = hashlib.sha256((staging / STATES).read_bytes()).hexdigest()
        g = s.gripper
        info = s.info
        meta = EpisodeMeta(
            id=episode, variant=info["id"], base_unit=info["base_unit"], handle=info["handle"],
            handle_type=info["handle_type"], preset=info["preset"], collision=info.get("collision", "coacd"),
            joint_friction=info.get("joint_friction", "held"),
            front=s.front.id, operator=operator,
            operator_kind=operator_kind, seed=seed, fps=s.control_fps, timestep=float(s.model.opt.timestep),
            steps=recorder.steps, state_size=len(table.column("state")[0]), outcome=classify(s.opening()),
            final_opening=round(s.opening(), 6), max_opening=round(recorder.max_opening, 6),
            gripper=GripperInfo(name=g.name, stroke=g.stroke, grip_force=g.grip_force, pad_friction=g.pad_friction,
                                arm_force=g.arm_force),
            robot=s.robot_id, robot_base=_robot_base(s), robot_joints=s.robot_drive.joint_names,
            versions=_versions(), log=tuple(log), states_sha256=digest,
            action_noise=action_noise if recorder.perturbed else None, action_kind=recorder.action_kind)
        data = meta.model_dump(mode="json")
        if data["action_noise"] is None:  # episodes without noise keep the meta.json they always had
            del data["action_noise"]
        if data["action_kind"] == "pose":  # and pose-driven ones (every episode before leader arms) too
            del data["action_kind"]
        meta = write_meta(staging, data)
        if replace:
            replace_directory(staging, final, EPISODE_FOLDER)
        else:
            publish_new_directory(staging, final)
    except BaseException:
        remove_stage(staging)
        raise
    return meta


def meta_digest(data: dict[str, Any]) -> str:
    """sha256 of a meta.json's fields other than ``meta_sha256`` (canonical JSON: sorted keys, no spaces)."""
    return json_sha256(data, exclude=("meta_sha256",))


def write_meta(directory: Path, data: dict[str, Any]) -> EpisodeMeta:
    """Write ``directory/meta.json`` sealed with its :func:`meta_digest` (atomically); returns the validated meta.

    The one writer of episode metas: anything that changes a meta on purpose goes through it."""
    from rik.schemas.episodes import EPISODE_FORMAT, EpisodeMeta

    data = {**data, "format": EPISODE_FORMAT}
    data["meta_sha256"] = meta_digest(data)
    meta = EpisodeMeta.model_validate(data)
    write_text(Path(directory) / META, json.dumps(data, indent=2) + "\n", Replaces.in_folder(EPISODE_FOLDER))
    return meta


def read_meta(directory: Path) -> EpisodeMeta:
    """The validated meta of the episode in ``directory``; an edited meta.json (its seal differs) is refused."""
    from pydantic import ValidationError

    from rik.schemas.episodes import EpisodeMeta

    file = Path(directory) / META
    if not file.is_file():
        raise EpisodeError(f"{file}: no such file; {directory} is not a recorded episode")
    try:
        data = read_json(file, MAX_META_BYTES)
        meta = EpisodeMeta.model_validate(data)
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        line = f" (line {exc.lineno})" if isinstance(exc, json.JSONDecodeError) else ""
        raise EpisodeError(f"{file}: not valid JSON{line}: {getattr(exc, 'msg', exc)}") from None
    except OSError as exc:
        raise EpisodeError(f"{file}: cannot be read ({exc.strerror})") from None
    except ValidationError as exc:
        err = exc.errors()[0]
        where = ".".join(str(p) for p in err["loc"]) or "(top level)"
        raise EpisodeError(f"{file}: field '{where}': {err['msg']}") from None
    except ValueError as exc:  # larger than MAX_META_BYTES, or nested too deeply: refused before it is read whole
        raise EpisodeError(f"{file}: {exc}, not an episode's meta.json (rik writes a few kB); record the episode "
                           "again, or restore the file") from None
    if meta.format >= 2 and meta.meta_sha256 != meta_digest(data):
        raise EpisodeError(f"{file}: edited or corrupt (its fields no longer match their meta_sha256); record the "
                           "episode again, or restore the file")
    return meta


def read_episode(directory: Path, columns: Sequence[str] | None = None, meta: EpisodeMeta | None = None
                 ) -> tuple[EpisodeMeta, pa.Table]:
    """(meta, states table) of a recorded episode: :func:`rik.episodes.states.read_states`, the one reader of
    ``states.parquet`` (bounded before anything is decoded; its hash, layout and rows checked against the meta);
    ``columns``: only these (all when None); ``meta``: the episode's meta already read."""
    meta = meta if meta is not None else read_meta(directory)
    return meta, read_states(directory, meta, columns)


def find_episodes(paths: list[Path]) -> list[Path]:
    """Episode directories under ``paths`` (each an episode or a directory of episodes), sorted."""
    found: list[Path] = []
    for p in paths:
        p = Path(p)
        if (p / META).is_file():
            found.append(p)
        elif p.is_dir():
            found += sorted(d for d in p.iterdir() if (d / META).is_file() and not d.name.startswith("."))
        else:
            raise EpisodeError(f"{p}: no such episode or directory")
    if not found:
        raise EpisodeError(f"no episodes under {', '.join(str(p) for p in paths)} (each has a {META})")
    return found


def states(table: pa.Table) -> np.ndarray:
    """The ``state`` column as an array, one row per recorded step."""
    col = cast("pa.ListArray", table.column("state").combine_chunks())  # a list column
    return col.values.to_numpy().reshape(len(col), -1)


def replay(scene: SimScene, table: pa.Table) -> Iterator[int]:
    """Set the scene to each recorded state in turn (positions, velocities, everything derived); yields the row."""
    for i, state in enumerate(states(table)):
        scene.restore(state)
        yield i


def run_operator(scene: SimScene, operator: Operator, rng: np.random.Generator, max_seconds: float,
                 recorder: EpisodeRecorder | None = None,
                 on_step: Callable[[SimScene], None] | None = None) -> EpisodeRecorder:
    """Run ``operator`` on ``scene`` until it is done or ``max_seconds`` of simulated time have passed."""
    recorder = recorder or EpisodeRecorder(scene)
    operator.reset(scene, rng)
    perturb = getattr(operator, "perturb", None)  # an operator that records one action and executes another
    for _ in range(int(round(max_seconds * scene.control_fps))):
        if operator.done:
            break
        action = operator.act(scene)
        recorder.step(action, perturb(action) if perturb is not None else None)
        if on_step is not None:
            on_step(scene)
    return recorder
