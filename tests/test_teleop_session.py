"""The teleop session that the viewer window and the browser station share: recording starts with the operator's
first input, a held key moves the target at a bounded speed and never far ahead of the gripper, every episode gets
a new id (nothing is overwritten), drafts and discards, the time limit, and bad input."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from shared import BOW, builtin_catalog

from rik.episodes.episode import read_meta
from rik.episodes.replay import verify_episode
from rik.errors import RikError
from rik.sim.build import build_scene
from rik.teleop.keys import LEAD, LINEAR_SPEED, MOTION_KEYS, keymap_rows, velocity
from rik.teleop.session import DRAFTS, TeleopSession

CAT = builtin_catalog()


@pytest.fixture(scope="module")
def variants(bow_variants: Path) -> Path:
    return bow_variants  # the demo variant, built once per test process (conftest)


def _session(variants: Path, out: Path, **kw) -> TeleopSession:
    return TeleopSession(build_scene(variants / BOW), out, **kw)


def _open_the_drawer(s: TeleopSession) -> None:
    """What a person does: roll the fingers across the bar, move in to the handle, close, pull back."""
    s.set_input([0, 0, 0, 0, 0, 1])
    while s.scene.pose()[5] < np.pi / 2 - 0.02:
        assert s.tick()
    s.set_input([0, -1, 0, 0, 0, 0])
    while s.status()["handle"]["ahead"] > 0.0:
        assert s.tick() and s.recorder.steps < 400
    s.set_input(np.zeros(6), grip=1.0)
    for _ in range(20):
        s.tick()
    s.set_input([0, 1, 0, 0, 0, 0])
    while s.scene.opening() < 0.9:
        assert s.tick() and s.recorder.steps < 800


def test_keymap_is_one_table_of_held_keys() -> None:
    assert len({k.code for k in MOTION_KEYS}) == len(MOTION_KEYS) == 12
    assert np.array_equal(velocity({"KeyW"}), [0, -1, 0, 0, 0, 0])  # towards the furniture: -y
    assert np.array_equal(velocity({"KeyW", "KeyS"}), np.zeros(6))  # opposite keys cancel
    assert np.allclose(velocity({"KeyA", "KeyR"}, fine=True), [0.25, 0, 0.25, 0, 0, 0])
    assert ("W / S", "towards the furniture / away from the furniture") in keymap_rows()


def test_a_person_opens_the_drawer_and_the_episode_replays_exactly(variants: Path, tmp_path: Path) -> None:
    s = _session(variants, tmp_path)
    start = s.status()
    assert start["state"] == "waiting for input" and start["handle"]["ahead"] == pytest.approx(0.25, abs=1e-3)
    for _ in range(10):
        assert not s.tick()  # no input yet: nothing is recorded
    assert s.recorder.steps == 0
    _open_the_drawer(s)
    saved = s.save()
    assert saved is not None and saved.meta.outcome == "S" and saved.meta.final_opening >= 0.9
    assert verify_episode(CAT, saved.path, variants).exact
    assert s.status()["state"] == "waiting for input" and s.seed == 1  # the next episode is ready


def test_a_saved_episode_ends_half_a_second_after_the_last_input_and_replays_exactly(variants: Path,
                                                                                   tmp_path: Path) -> None:
    """The idle time before Enter is not recorded: 10 steps of a held key, 40 idle, saved as 10 + 10 (0.5 s kept for
    what still moves); the scene is set back to the kept end, so the episode replays bit for bit. With
    ``trim_idle=False`` every step is kept."""
    from rik.teleop.session import IDLE_KEPT_S

    kept = round(IDLE_KEPT_S * 20)
    for trim, steps in ((True, 10 + kept), (False, 50)):
        s = _session(variants, tmp_path / str(trim), trim_idle=trim)
        s.set_input([1, 0, 0, 0, 0, 0])
        for _ in range(10):
            s.tick()
        s.set_input(np.zeros(6))
        for _ in range(40):
            s.tick()
        saved = s.save()
        assert saved is not None and saved.meta.steps == steps, saved
        assert ("idle after the last input trimmed" in s.message) is trim
        assert verify_episode(CAT, saved.path, variants).exact


def test_a_held_key_moves_the_target_at_most_its_speed_and_never_far_ahead(variants: Path, tmp_path: Path) -> None:
    """A slow frame never turns into a jump: the target moves per control step, and a gripper blocked by the front
    does not let the target run away (reversing would take as long as the push)."""
    s = _session(variants, tmp_path)
    s.set_input([0, -1, 0, 0, 0, 0])
    targets = []
    for _ in range(120):  # 6 s towards the front: the gripper hits the bar after ~2 s
        pose = s.scene.pose()
        s.tick()
        targets.append(s.target[:3].copy())
        assert np.linalg.norm(s.target[:3] - pose[:3]) <= LEAD[0] + 1e-9
    steps = np.linalg.norm(np.diff(targets, axis=0), axis=1)
    assert steps.max() <= LINEAR_SPEED / s.scene.control_fps + 1e-9


def test_an_arm_turned_past_its_angles_wrap_follows_the_keys_without_a_jump(variants: Path, tmp_path: Path) -> None:
    """An arm's pose gives principal Euler angles (roll wraps at +-180 deg; past a yaw of 90 deg pitch and roll flip
    by 180 deg), while a held key moves the target on: rolling the Panda past 180 deg and yawing it past 90 deg
    moves the target at the keys' speed and no faster, the gripper follows within a few degrees and comes back to
    rest where it started, and its episode id names the robot."""
    from rik.sim.pose import gripper_rotation
    from rik.teleop.keys import ANGULAR_SPEED

    s = TeleopSession(build_scene(variants / BOW, robot=CAT.robot("panda-2f85")), tmp_path)
    assert ".panda-2f85__" in s.episode and s.status()["robot"] == "panda-2f85"
    start = s.scene.pose()

    def lag() -> float:  # the angle between the gripper's rotation and the target's, rad
        r = s.scene.gripper_rotation().T @ gripper_rotation(s.target[3:6])
        return float(np.arccos(np.clip((np.trace(r) - 1) / 2, -1.0, 1.0)))

    for key, steps in (("KeyQ", 100), ("ArrowLeft", 60), (None, 20)):  # 4.0 rad of roll, 2.4 rad of yaw, rest
        s.set_input(velocity({key} if key else set()))
        for _ in range(steps):
            before = s.target.copy()
            assert s.tick()
            assert np.abs(s.target[:6] - before[:6]).max() <= ANGULAR_SPEED / s.scene.control_fps + 1e-9
            assert lag() < 0.1, (key, s.target, s.scene.pose())
    assert s.target[5] > np.pi and s.target[4] > np.pi / 2  # the target went on past both wraps
    assert lag() < 0.01 and np.linalg.norm(s.scene.pose()[:3] - start[:3]) < 0.005


def test_every_episode_gets_a_new_id_and_nothing_is_overwritten(variants: Path, tmp_path: Path) -> None:
    first = _session(variants, tmp_path, seed=3)
    first.set_input([0, -1, 0, 0, 0, 0])
    for _ in range(5):
        first.tick()
    a = first.save()
    assert a is not None and a.meta.seed == 3
    before = (a.path / "meta.json").read_bytes()
    second = _session(variants, tmp_path, seed=3)  # a new session on the same folder and seed: 3 is saved, and the
    assert second.seed == 5 and second.episode.endswith("__s0005")  # first session holds 4, its next episode
    second.set_input([0, 1, 0, 0, 0, 0])
    second.tick()
    b = second.save()
    first.set_input([0, 1, 0, 0, 0, 0])
    first.tick()
    c = first.save()
    assert b is not None and c is not None and len({a.path, b.path, c.path}) == 3
    assert (a.path / "meta.json").read_bytes() == before and c.meta.seed == 4 and read_meta(b.path).seed == 5


def test_discard_writes_nothing_and_a_draft_is_kept_until_saved(variants: Path, tmp_path: Path) -> None:
    s = _session(variants, tmp_path)
    assert s.keep_draft() is None  # nothing recorded yet
    s.set_input([0, -1, 0, 0, 0, 0])
    for _ in range(5):
        s.tick()
    s.discard()
    assert not any(tmp_path.iterdir()) and s.recorder.steps == 0 and s.seed == 0
    s.set_input([0, -1, 0, 0, 0, 0])
    for _ in range(8):
        s.tick()
    draft = s.keep_draft()
    assert draft == tmp_path / DRAFTS / s.episode and read_meta(draft).steps == 8
    for _ in range(4):
        s.tick()
    saved = s.save()
    assert saved is not None and saved.meta.steps == 12 and not draft.exists()
    assert verify_episode(CAT, saved.path, variants).exact


def test_the_time_limit_stops_the_episode_and_bad_input_is_refused(variants: Path, tmp_path: Path) -> None:
    s = _session(variants, tmp_path, max_seconds=0.5)
    s.set_input([np.nan, -1, 0, 0, 0, 5.0], grip=np.nan)  # NaN and out-of-range input is cleaned, not stepped
    assert np.array_equal(s.command, [0, -1, 0, 0, 0, 1]) and s.grip == 0.0
    while s.tick():
        pass
    st = s.status()
    assert st["state"] == "time up" and st["steps"] == 10 and st["time_left"] == 0.0
    for bad in (-1, float("inf"), float("nan")):  # inf was taken, and ended the episode at once
        with pytest.raises(RikError, match=f"--max-seconds {bad}: a time limit must be a positive, finite number"):
            _session(variants, tmp_path, max_seconds=bad)
    with pytest.raises(RikError, match="--seed -2: seeds must lie in 0"):
        _session(variants, tmp_path, seed=-2)


def test_the_teleop_docs_show_the_keymap_the_code_uses() -> None:
    """docs/teleop.md's key table is the keymap of rik.teleop.keys, row for row (no drift)."""
    from conftest import REPO

    text = (REPO / "docs" / "teleop.md").read_text(encoding="utf-8")
    table = text.split("| keys | what they do |\n|---|---|\n", 1)[1].split("\n\n", 1)[0]
    rows = [tuple(c.strip() for c in line.strip("|").split("|")) for line in table.splitlines()]
    assert rows == keymap_rows()


def test_a_station_whose_thread_fails_keeps_its_episode_as_a_draft(variants: Path, tmp_path: Path) -> None:
    """The station thread's last words when it fails (a render error, not a command): the steps recorded so far are
    kept as a draft and the page is told where, instead of going with the thread."""
    from rik.teleop.station import Station

    s = _session(variants, tmp_path)
    assert Station._draft_after_failure(s) == ""  # nothing recorded: nothing to keep
    s.set_input([0, -1, 0, 0, 0, 0])
    for _ in range(6):
        s.tick()
    said = Station._draft_after_failure(s)
    draft = tmp_path / DRAFTS / s.episode
    assert said == f"; its 6 recorded steps were kept as a draft: {draft}" and read_meta(draft).steps == 6
