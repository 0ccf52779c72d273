"""A teleoperation session: the state that every teleop front-end shares (the viewer window, the browser
station). Devices set a velocity command and a grip; :meth:`TeleopSession.tick` advances one control step.

- the gripper starts at rest in front of the operated handle (:func:`rik.sim.scene.start_pose`), in view of the
  front camera, and recording starts with the operator's first input (no idle frames before it);
- the target moves at the commanded velocity per *control step* and never runs more than
  :data:`rik.teleop.keys.LEAD` ahead of the gripper, so a slow frame or a blocked gripper never turns into
  a jump;
- every episode gets its own id: the seed advances to the next one with no episode (nor draft) in ``out`` that no
  other session holds (a lock per id in rik's cache, held while the episode is recorded), and a
  Save takes the id exclusively (another writer's episode of that id moves this one to the next free seed), so
  two stations on one folder never write over each other; saving writes ``out/<id>``, discarding writes nothing,
  and a draft (a connection lost mid-episode) goes to ``out/.drafts/<id>``, which ``rik export-lerobot`` and
  ``rik replay out/`` skip;
- an optional time limit (simulated s) stops the episode, which the operator then saves or discards;
- a saved episode ends :data:`IDLE_KEPT_S` after the last input (``trim_idle``): the idle time before the save
  (reaching for Enter) is not recorded, nor replayed, nor learned from.
"""

from __future__ import annotations

import contextlib
import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from rik.errors import RikError
from rik.outputs import NameTaken, remove_directory
from rik.paths import cache_dir
from rik.sim.pose import nearest_angles
from rik.teleop.feedback import BLOCKED_LEAD, GraspWatch, front_path_step, grasp_hint, grasp_text
from rik.teleop.keys import ANGULAR_SPEED, LEAD, LINEAR_SPEED

if TYPE_CHECKING:
    from rik.episodes.episode import EpisodeRecorder
    from rik.schemas.episodes import EpisodeMeta
    from rik.sim.scene import SimScene

DRAFTS = ".drafts"
"""Folder of draft episodes inside the episodes folder (hidden: exports and ``rik replay DIR`` skip it)."""
MAX_FREE_SEEDS = 100_000
"""How many seeds past the requested one are searched for a free episode id."""
IDLE_KEPT_S = 0.5
"""Simulated seconds kept after the operator's last input when an episode is saved (a front still moving, jaws
still closing); the idle rest (the person reaching for Enter) is trimmed."""
LEADER_MOVED = (math.radians(1.0), 0.02)
"""How far a leader arm must move (a joint rad, the grip's 0..1) to count as the operator's input: recording starts
with it and a saved episode keeps :data:`IDLE_KEPT_S` after the last one. A still leader's reading wanders by an
encoder step or two (0.09 deg each), well under 1 deg."""
MOTION_MODES = ("path", "frame")
"""How W/S move the target: along the front's own path while the jaws hold its handle (a door's arc, a flap's, a
drawer's slide), frame-fixed otherwise; or always frame-fixed (towards / away from the furniture)."""


def check_time_limit(max_seconds: float | None) -> None:
    """A time limit is positive, finite simulated seconds, or None for none."""
    if max_seconds is not None and not (max_seconds > 0 and math.isfinite(max_seconds)):

        raise RikError(f"--max-seconds {max_seconds}: a time limit must be a positive, finite number of seconds (or "
                       "none at all)")


def _claim_path(episode: Path) -> Path:
    """Where the lock of a session recording ``episode`` (an episode folder's path) lives: in rik's cache, so that
    a session writes nothing into the episodes folder before a Save or a draft."""
    import hashlib


    key = hashlib.sha256(str(episode.absolute()).encode("utf-8", "surrogateescape")).hexdigest()
    return cache_dir() / "claims" / key[:32]


@dataclass(frozen=True)
class Saved:
    """What :meth:`TeleopSession.save` wrote."""

    path: Path
    meta: EpisodeMeta


class TeleopSession:
    """One operator on one variant's scene, episode after episode (see the module docstring)."""

    def __init__(self, scene: SimScene, out: Path, *, operator: str = "keyboard", seed: int = 0,
                 max_seconds: float | None = None, trim_idle: bool = True) -> None:
        from rik.episodes.record import check_seeds

        check_seeds(seed, 1)
        check_time_limit(max_seconds)
        self.scene = scene
        self.out = Path(out)
        self.operator = operator
        self.max_seconds = max_seconds
        self.seed = seed
        self.trim_idle = trim_idle
        """Save an episode up to :data:`IDLE_KEPT_S` after its last input (else up to the save)."""
        self.command: np.ndarray = np.zeros(6)
        """Velocity command in [-1, 1] per axis (x, y, z, pitch, yaw, roll)."""
        self.grip = 0.0
        """Gripper command: 0 open, 1 closed with full force."""
        self.last_saved: Saved | None = None
        self.message = ""
        """The last thing worth telling the operator (saved, discarded, draft kept)."""
        self.motion_mode = MOTION_MODES[0]
        """One of :data:`MOTION_MODES` (kept from episode to episode)."""
        self._claim = contextlib.ExitStack()
        """The lock on the current episode's id (:meth:`_take_free_seed`)."""
        self._start()
        self.hint = grasp_hint(scene)
        """How to grasp the operated handle (:func:`rik.teleop.feedback.grasp_hint`), shown before the first input."""

    # ---- episodes ---------------------------------------------------------------------------------------------
    @property
    def episode(self) -> str:
        from rik.episodes.episode import episode_id

        return episode_id(self.scene.info["id"], self.scene.front.id, self.operator, self.seed, self.scene.robot_id)

    def _taken(self, seed: int) -> bool:
        """Whether an episode or a draft of ``seed``'s id is in ``out`` already."""
        from rik.episodes.episode import episode_id

        name = episode_id(self.scene.info["id"], self.scene.front.id, self.operator, seed, self.scene.robot_id)
        return os.path.lexists(self.out / name) or os.path.lexists(self.out / DRAFTS / name)

    def _take_free_seed(self, start: int) -> int:
        """The first seed from ``start`` whose id is free (:meth:`_taken`) and that no other session holds; its lock
        is held (released by the next call, :meth:`close` or the process's end, however it ends)."""
        from rik.episodes.episode import episode_id
        from rik.locks import LockedError, exclusive

        self._claim.close()
        for seed in range(start, start + MAX_FREE_SEEDS):
            if self._taken(seed):
                continue
            name = episode_id(self.scene.info["id"], self.scene.front.id, self.operator, seed, self.scene.robot_id)
            try:
                self._claim.enter_context(exclusive(_claim_path(self.out / name), "teleop session"))
            except LockedError:
                continue
            if not self._taken(seed):  # saved by another session between the check and the lock
                return seed
            self._claim.close()
        raise RikError(f"{self.out}: no free episode id among {MAX_FREE_SEEDS} seeds from {start}")

    def close(self) -> None:
        """Release the current episode's id (the session records nothing more)."""
        self._claim.close()

    def _start(self) -> None:
        """A new episode: the next free seed, the scene at its start pose, nothing recorded."""
        from rik.episodes.episode import EpisodeRecorder
        from rik.episodes.record import check_seeds

        seed = self._take_free_seed(self.seed)
        check_seeds(seed, 1)
        self.seed = seed
        self.scene.reset()
        self.recorder: EpisodeRecorder = EpisodeRecorder(self.scene)
        self.target = np.concatenate([self.scene.pose(), [0.0]])
        self.command = np.zeros(6)
        self.grip = 0.0
        self.grasp = GraspWatch()
        self.blocked = False
        """The last step's target leads the gripper by more than :data:`BLOCKED_LEAD` while a motion key is held."""
        self.on_path = False
        """The last step moved along the front's path (:data:`MOTION_MODES`)."""
        self.last_input_step = 0
        """Recorded steps up to and including the last one with an input (a motion command or a grip change)."""
        self.joint_input: tuple[np.ndarray, float] | None = None
        """A leader arm's joint targets (rad, the robot's joint order) and grip (0..1), when one drives the arm."""
        self._leader_moved_from: tuple[np.ndarray, float] | None = None
        """The leader's input at the episode's start, then at its last move (:data:`LEADER_MOVED`)."""

    @property
    def recording(self) -> bool:
        return self.recorder.steps > 0

    @property
    def time_up(self) -> bool:
        return self.max_seconds is not None and self.recorder.steps >= round(self.max_seconds * self.scene.control_fps)

    def save(self) -> Saved | None:
        """Write the episode to ``out/<id>`` (up to :data:`IDLE_KEPT_S` after its last input, with ``trim_idle``)
        and start the next one; None (and nothing written) when nothing was recorded yet."""
        from rik.episodes.episode import write_episode

        if not self.recording:
            self.message = "nothing recorded yet: move first"
            return None
        trimmed = 0
        if self.trim_idle:
            keep = self.last_input_step + round(IDLE_KEPT_S * self.scene.control_fps)
            trimmed = max(0, self.recorder.steps - keep)
            self.recorder.truncate(keep)
        while True:
            try:
                meta = write_episode(self.recorder, self.out, episode=self.episode, operator=self.operator,
                                     operator_kind="device", seed=self.seed, replace=False)
                break
            except NameTaken:  # another writer, not a session (they lock ids), saved this id: take the next one
                self.seed = self._take_free_seed(self.seed + 1)
        self._remove_draft(meta.id)
        self.last_saved = Saved(self.out / meta.id, meta)
        self.message = f"saved {meta.id}: {meta.outcome}, opened {meta.final_opening:.0%}, {meta.steps} steps"
        if trimmed:
            self.message += f" ({trimmed / self.scene.control_fps:.1f} s idle after the last input trimmed)"
        self.seed += 1
        self._start()
        return self.last_saved

    def discard(self) -> None:
        """Drop the episode (and its draft, if one was kept) and start again from the start pose."""
        self._remove_draft(self.episode)
        self.message = f"discarded {self.recorder.steps} steps" if self.recording else "back at the start pose"
        self._start()

    def _remove_draft(self, episode: str) -> None:
        """Remove the draft of ``episode`` if one was kept (only an episode folder rik wrote: anything else stays)."""
        from rik.episodes.episode import EPISODE_FOLDER

        with contextlib.suppress(RikError, OSError):
            remove_directory(self.out / DRAFTS / episode, EPISODE_FOLDER)

    def keep_draft(self) -> Path | None:
        """Write the episode so far to ``out/.drafts/<id>`` (replaced by each later draft, removed on save or
        discard); the session goes on. None when nothing was recorded."""
        from rik.episodes.episode import write_episode

        if not self.recording:
            return None
        write_episode(self.recorder, self.out / DRAFTS, episode=self.episode, operator=self.operator,
                      operator_kind="device", seed=self.seed)
        path = self.out / DRAFTS / self.episode
        self.message = f"draft kept: {path} ({self.recorder.steps / self.scene.control_fps:.1f} s)"
        return path

    # ---- control ----------------------------------------------------------------------------------------------
    def set_input(self, command: np.ndarray | list[float], grip: float | None = None) -> None:
        """The device's velocity command (6 numbers in [-1, 1]) and, when given, the grip (0 open .. 1 closed)."""
        c = np.nan_to_num(np.asarray(command, np.float64).reshape(6), nan=0.0)
        self.command = np.clip(c, -1.0, 1.0)
        if grip is not None:
            self.grip = float(np.clip(np.nan_to_num(grip), 0.0, 1.0))

    def set_joints(self, targets: np.ndarray, grip: float) -> None:
        """A leader arm's reading: the arm's joint targets (rad, the robot's joint order) and grip (0 open ..
        1 closed); from now on :meth:`tick` drives the arm joint by joint."""
        t = np.asarray(targets, np.float64).reshape(-1)
        if t.shape != (len(self.scene.robot_drive.joint_names) - 1,) or not np.all(np.isfinite(t)):

            raise RikError(f"joint targets {t.tolist()}: robot {self.scene.robot_id} takes "
                           f"{len(self.scene.robot_drive.joint_names) - 1} finite numbers (rad)")
        self.joint_input = (t, float(np.clip(np.nan_to_num(grip), 0.0, 1.0)))
        if self._leader_moved_from is None:
            self._leader_moved_from = self.joint_input

    def _leader_moved(self) -> bool:
        """Whether the leader moved by more than :data:`LEADER_MOVED` since the episode's start or its last move."""
        assert self.joint_input is not None and self._leader_moved_from is not None
        (t, g), (t0, g0) = self.joint_input, self._leader_moved_from
        moved = float(np.max(np.abs(t - t0))) > LEADER_MOVED[0] or abs(g - g0) > LEADER_MOVED[1]
        if moved:
            self._leader_moved_from = self.joint_input
        return moved

    def _tick_joints(self) -> bool:
        """One control step driven by the leader (:meth:`tick` with a joint input)."""
        assert self.joint_input is not None
        moved = self._leader_moved()
        if not self.recording and not moved:
            return False  # waiting for the leader to move: nothing recorded
        if moved:
            self.last_input_step = self.recorder.steps + 1
        targets, self.grip = self.joint_input
        self.recorder.step_joints(targets, self.grip)
        self.grasp.update(self.scene.handle_contact(), self.grip)
        return True

    def toggle_grip(self) -> None:
        self.grip = 0.0 if self.grip >= 0.5 else 1.0

    def toggle_motion_mode(self) -> None:
        """Switch between motion along the front's path and frame-fixed motion (:data:`MOTION_MODES`)."""
        self.motion_mode = MOTION_MODES[1 - MOTION_MODES.index(self.motion_mode)]
        self.message = f"motion: {self.motion_mode}"

    def tick(self) -> bool:
        """One control step when the operator has moved (or moves now) and the time limit is not reached: the
        target advances by the velocity command, held within :data:`LEAD` of the gripper, and the step is
        recorded. Returns whether the scene stepped."""
        if self.time_up:
            return False
        if self.joint_input is not None:
            return self._tick_joints()
        if not self.recording and not np.any(self.command) and self.grip == self.target[6]:
            return False  # waiting for the first input: nothing recorded
        dt = 1.0 / self.scene.control_fps
        speed = np.array([LINEAR_SPEED] * 3 + [ANGULAR_SPEED] * 3)
        pose = self.scene.pose()
        pose[3:] = nearest_angles(pose[3:], self.target[3:6])
        command = self.command.copy()
        target = self.target[:6].copy()
        self.on_path = bool(self.motion_mode == "path" and self.grasp.state == "holding" and command[1])
        if self.on_path:  # S opens along the front's path, W closes; the other axes stay frame-fixed
            target = front_path_step(self.scene, target, float(command[1]) * LINEAR_SPEED * dt)
            command[1] = 0.0
        target += command * speed * dt
        if np.any(self.command[:3]):  # a target left behind while not moving stays: the servos pull back to it
            lead = target[:3] - pose[:3]
            norm = float(np.linalg.norm(lead))
            if norm > LEAD[0]:
                target[:3] = pose[:3] + lead * (LEAD[0] / norm)
        if np.any(self.command[3:]) or self.on_path:
            target[3:] = pose[3:] + np.clip(target[3:] - pose[3:], -LEAD[1], LEAD[1])
        if np.any(self.command) or self.grip != self.target[6]:
            self.last_input_step = self.recorder.steps + 1
        self.target = np.concatenate([target, [self.grip]])
        self.recorder.step(self.target.copy())
        self.grasp.update(self.scene.handle_contact(), self.grip)
        after = self.scene.pose()
        self.blocked = bool(np.any(self.command[:3])
                            and np.linalg.norm(self.target[:3] - after[:3]) > BLOCKED_LEAD)
        return True

    # ---- what the operator sees -------------------------------------------------------------------------------
    def status(self) -> dict[str, Any]:
        """The live status: episode id, robot (catalog id), state, time (s) and time left, opening (fraction), grip,
        where the handle is from the pads' centre (m: ahead, left, up as the operator faces the front), the gripper
        base's pose (x, y, z m; pitch, yaw, roll rad; yaw and roll also in degrees), the grasp, the motion, the front's
        angle or travel and the hint."""
        from rik.sim.outcome import classify

        s = self.scene
        fps = s.control_fps
        elapsed = self.recorder.steps / fps
        offset = s.grasp_point() - s.tcp()
        pose = s.pose()
        state = "time up" if self.time_up else "recording" if self.recording else "waiting for input"
        return {
            "episode": self.episode, "variant": s.info["id"], "front": s.front.id, "robot": s.robot_id,
            "seed": self.seed,
            "state": state, "steps": self.recorder.steps, "time": round(elapsed, 2),
            "time_left": None if self.max_seconds is None else round(max(0.0, self.max_seconds - elapsed), 2),
            "opening": round(s.opening(), 4), "max_opening": round(self.recorder.max_opening, 4),
            "outcome": classify(s.opening()), "grip": "closed" if self.grip >= 0.5 else "open",
            "grip_command": round(self.grip, 3),
            "handle": {"ahead": round(float(-offset[1]), 4), "left": round(float(offset[0]), 4),
                       "up": round(float(offset[2]), 4)},
            "pose": [round(float(v), 4) for v in pose],
            "contacts": int(s.contact_summary()["contacts"]), "message": self.message,
            "grasp": self.grasp.state, "blocked": self.blocked, "hint": self.hint,
            "motion": {"mode": self.motion_mode, "on_path": self.on_path},
            "front_position": front_reading(s),
            "yaw_deg": round(math.degrees(float(pose[4])), 1), "roll_deg": round(math.degrees(float(pose[5])), 1),
            "last_saved": None if self.last_saved is None else self.last_saved.meta.id,
        }

    def status_line(self) -> str:
        """The status in one line for a terminal."""
        st = self.status()
        return (f"{st['episode']} | {st['state']} | {time_text(st)} | open {st['opening']:.0%} | grip {st['grip']} | "
                f"handle {handle_text(st)} | grasp {grasp_text(st)}")


def front_reading(scene: SimScene) -> dict[str, Any]:
    """The operated front's position for the operator: a hinge's angle (degrees) or a slide's travel (mm)."""
    q = scene.front_q()[0]
    if scene.front.motion == "slide":
        return {"kind": scene.front.kind, "travel_mm": round(q * 1000.0, 1)}
    return {"kind": scene.front.kind, "angle_deg": round(math.degrees(q), 1)}


def time_text(status: dict[str, Any]) -> str:
    """The episode's time and what is left of it, from :meth:`TeleopSession.status`: ``3.3 s (no limit)``."""
    left = "no limit" if status["time_left"] is None else f"{status['time_left']:.0f} s left"
    return f"{status['time']:.1f} s ({left})"


def handle_text(status: dict[str, Any]) -> str:
    """Where the handle is from the pads, from :meth:`TeleopSession.status`: ``+0.150 ahead +0.000 left ... m``."""
    h = status["handle"]
    return f"{h['ahead']:+.3f} ahead {h['left']:+.3f} left {h['up']:+.3f} up m"
