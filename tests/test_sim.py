"""Simulation: the gripper scene, strategies, the outcome, episodes (exact replay, corrupt files, interrupted
recordings), the gymnasium environment, the benchmark and the CLI's messages."""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pytest
from shared import builtin_catalog

from rik.combinator.build import ensure_variant
from rik.episodes.episode import EpisodeError, EpisodeRecorder, read_episode, replay, run_operator, write_episode
from rik.episodes.operators import make_operator
from rik.episodes.record import randomise_start, record
from rik.errors import RikError
from rik.sim.build import build_scene
from rik.sim.outcome import classify
from rik.sim.robots.gripper import HAND_E

CAT = builtin_catalog()
BOW_HIGH = "drawer-chest-80__two_point-bow-128__high"
KNOB = "drawer-bedside-45__knob-mushroom-30__normal"


@pytest.fixture(scope="module")
def variants(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("variants")
    for v in (BOW_HIGH, KNOB):
        ensure_variant(CAT, v, out)
    return out


def _run(variants: Path, variant: str, strategy: str, grip_force: float = HAND_E.grip_force, seed: int = 0):
    scene = build_scene(variants / variant, None, HAND_E.with_(grip_force=grip_force))
    rng = np.random.default_rng(seed)
    randomise_start(scene, rng)
    operator = make_operator(strategy)
    run_operator(scene, operator, rng, 30.0)
    return scene, operator


def test_outcome_thresholds() -> None:
    assert [classify(x) for x in (0.0, 0.049, 0.05, 0.5, 0.899, 0.9, 1.0)] == ["F", "F", "P", "P", "P", "S", "S"]


def test_scene_has_cameras_gripper_and_solver_settings(variants: Path) -> None:
    import mujoco

    scene = build_scene(variants / BOW_HIGH, "drawer-2")
    m = scene.model
    assert {m.camera(i).name for i in range(m.ncam)} == {"front", "wrist"}
    assert m.opt.cone == mujoco.mjtCone.mjCONE_ELLIPTIC and m.opt.impratio == 10
    assert scene.front.id == "drawer-2" and scene.opening() == 0.0
    # the jaw servo and the arm servos are force-limited at the gripper's figures
    assert m.actuator_forcerange[6].tolist() == [-130.0, 130.0]
    assert m.actuator_forcerange[0].tolist() == [-150.0, 150.0]
    assert HAND_E.friction_capacity() == pytest.approx(2 * 0.3 * 130)


def test_strong_pinch_opens_a_high_resistance_drawer(variants: Path) -> None:
    scene, op = _run(variants, BOW_HIGH, "grasp_vertical")
    assert classify(scene.opening()) == "S", op.log


def test_weak_grip_friction_fails_where_a_hook_succeeds(variants: Path) -> None:
    """At 20 N of grip a pinch carries 2 x 0.3 x 20 = 12 N by friction, less than the high preset's 30 N of
    friction: it cannot open the drawer. A finger hooked behind the bar pushes it by normal force and can."""
    scene, op = _run(variants, BOW_HIGH, "grasp_vertical", grip_force=20.0)
    assert classify(scene.opening()) == "F", op.log
    scene, op = _run(variants, BOW_HIGH, "contact_rich", grip_force=20.0)
    assert classify(scene.opening()) == "S", op.log
    assert op.log[0].startswith("attempt 1: hook_"), op.log


def test_horizontal_jaws_cannot_pinch_a_long_bar(variants: Path) -> None:
    scene, op = _run(variants, BOW_HIGH, "grasp_horizontal")
    assert classify(scene.opening()) == "F"


def test_recorded_episode_replays_bit_for_bit(variants: Path, tmp_path: Path) -> None:
    import mujoco

    from rik.episodes.replay import verify_episode

    scene = build_scene(variants / KNOB, None)
    rng = np.random.default_rng(3)
    randomise_start(scene, rng)
    operator = make_operator("contact_rich")
    operator.reset(scene, rng)
    recorder = EpisodeRecorder(scene)
    poses = []

    def pose() -> tuple[np.ndarray, np.ndarray]:
        # the body poses of the live state (after mj_step, data.xpos still holds the previous step's kinematics)
        mujoco.mj_kinematics(scene.model, scene.data)
        return scene.data.xpos.copy(), scene.data.xquat.copy()

    for _ in range(60):
        poses.append(pose())
        recorder.step(operator.act(scene))
    poses.append(pose())
    meta = write_episode(recorder, tmp_path, episode="e", operator="contact_rich", operator_kind="strategy", seed=3)
    assert meta.steps == 60
    got, table = read_episode(tmp_path / "e")
    assert got == meta and table.num_rows == 61
    fresh = build_scene(variants / KNOB, None)
    for i in replay(fresh, table):
        assert np.array_equal(fresh.data.xpos, poses[i][0]) and np.array_equal(fresh.data.xquat, poses[i][1])
    check = verify_episode(CAT, tmp_path / "e", variants)
    assert check.exact and check.rows == 61


def test_record_writes_whole_episodes_and_is_deterministic(variants: Path, tmp_path: Path) -> None:
    a = record(CAT, KNOB, "grasp_vertical", episodes=2, seed=5, out=tmp_path / "a", variants=variants,
               max_seconds=3.0)
    b = record(CAT, KNOB, "grasp_vertical", episodes=1, seed=5, out=tmp_path / "b", variants=variants,
               max_seconds=3.0)
    assert [m.seed for m in a] == [5, 6]
    assert (tmp_path / "a" / a[0].id / "states.parquet").read_bytes() == \
        (tmp_path / "b" / b[0].id / "states.parquet").read_bytes()
    assert a[0].handle == "knob/mushroom-30" and a[0].operator_kind == "strategy"


def test_interrupted_recording_leaves_no_episode(variants: Path, tmp_path: Path) -> None:
    def interrupt(meta) -> None:
        raise KeyboardInterrupt

    scene = build_scene(variants / KNOB, None)
    with pytest.raises(KeyboardInterrupt):
        run_operator(scene, make_operator("grasp_vertical"), np.random.default_rng(0), 3.0,
                     on_step=lambda s: interrupt(None) if s.data.time > 1 else None)
    with pytest.raises(KeyboardInterrupt):
        record(CAT, KNOB, "grasp_vertical", episodes=3, out=tmp_path, variants=variants, max_seconds=1.0,
               progress=interrupt)
    names = sorted(p.name for p in tmp_path.iterdir())
    assert len(names) == 1 and not names[0].startswith(".")  # the first episode whole, nothing half-written


@pytest.fixture(scope="module")
def episode(variants: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("episodes")
    meta = record(CAT, KNOB, "grasp_vertical", out=out, variants=variants, max_seconds=1.0)[0]
    return out / meta.id


def _copy(src: Path, dst: Path) -> Path:
    import shutil

    shutil.copytree(src, dst)
    return dst


def test_truncated_states_are_refused(episode: Path, tmp_path: Path) -> None:
    bad = _copy(episode, tmp_path / "ep")
    data = (bad / "states.parquet").read_bytes()
    (bad / "states.parquet").write_bytes(data[: len(data) // 2])
    with pytest.raises(EpisodeError, match=r"states.parquet: truncated or corrupt \(its sha256 differs"):
        read_episode(bad)


def test_missing_and_malformed_meta_are_refused(episode: Path, tmp_path: Path) -> None:
    bad = _copy(episode, tmp_path / "ep")
    meta = json.loads((bad / "meta.json").read_text())
    meta["outcome"] = "X"
    (bad / "meta.json").write_text(json.dumps(meta))
    with pytest.raises(EpisodeError, match=r"meta.json: field 'outcome': Input should be 'F', 'P' or 'S'"):
        read_episode(bad)
    (bad / "meta.json").write_text("{")
    with pytest.raises(EpisodeError, match=r"meta.json: not valid JSON"):
        read_episode(bad)
    (bad / "meta.json").unlink()
    with pytest.raises(EpisodeError, match=r"meta.json: no such file; .* is not a recorded episode"):
        read_episode(bad)


def test_gymnasium_env_passes_the_checker(variants: Path) -> None:
    import gymnasium as gym
    from gymnasium.utils.env_checker import check_env

    import rik.envs.open_front  # noqa: F401  (registers rik/OpenFront-v0)

    env = gym.make("rik/OpenFront-v0", variant=KNOB, images=True, image_size=(24, 32),
                   variants_dir=str(variants)).unwrapped
    check_env(env, skip_render_check=True)
    obs, info = env.reset(seed=1, options={"preset": "high"})
    assert obs["agent_pos"].shape == (11,) and obs["environment_state"].shape == (13,)
    assert obs["pixels"]["front"].shape == (24, 32, 3) and obs["pixels"]["wrist"].dtype == np.uint8
    assert info["variant"] == KNOB.replace("__normal", "__high") and info["outcome"] == "F"
    obs, reward, terminated, truncated, info = env.step(np.array([0, -1, 0, 0, 0, 0, 0], np.float32))
    assert not terminated and info["outcome"] == "F"
    env.close()


def test_an_environment_that_draws_builds_no_variant_before_its_first_reset(tmp_path: Path) -> None:
    """A state-only environment drawing from a split builds the variant of each episode at its reset, none as it is
    made (it used to build its draw's seed 0, which no episode need use); asked for its scene before, it says why."""
    from rik.envs.open_front import OpenFrontEnv

    variants = tmp_path / "variants"
    env = OpenFrontEnv(split="train", handle_types=("two_point",), presets=("normal",), variants_dir=str(variants))
    assert not variants.exists() or not [p for p in variants.iterdir() if p.is_dir() and p.name[0] != "."]
    with pytest.raises(RikError, match=r"no scene before its first reset\(\)"):
        env.scene  # noqa: B018
    assert env.observation_space["agent_pos"].shape == (11,)
    env.close()


def test_policy_operator_plugs_into_the_recorder(variants: Path) -> None:
    from rik.episodes.operators import PolicyOperator

    scene = build_scene(variants / KNOB, None)
    op = PolicyOperator(lambda obs: np.array([0.0, -0.5, 0.0, 0.0, 0.0, 0.0, 0.0]))
    rec = run_operator(scene, op, np.random.default_rng(0), 0.5)
    assert rec.steps == 10 and scene.tcp()[1] < scene.grasp_point()[1] + 0.25  # it moved towards the front


def test_bench_small_table(variants: Path, tmp_path: Path) -> None:
    from rik.benchmark.bench import plan_tasks, run_bench
    from rik.tables import summarise, table_markdown

    # seed 35 draws drawer-bedside-45__knob-mushroom-30__high: the knob whose collision the suite builds anyway
    # (knob_recording), where seed 2's fluted knob cost its CoACD decomposition (7 CPU-s) to this test alone
    tasks = plan_tasks(CAT, types=["knob"], presets=["high"], strategies=["grasp_vertical", "contact_rich"],
                       per_cell=1, seed=35)
    assert [t.variant for t in tasks][0] == tasks[1].variant  # strategies compared on the same draw
    rows = run_bench(CAT, tasks, variants=variants)
    assert {r["strategy"] for r in rows} == {"grasp_vertical", "contact_rich"}
    assert summarise(rows)[("knob", "contact_rich", "high")]["n"] == 1
    assert "| contact_rich |" in table_markdown(rows)


def test_cli_messages(rik, episode: Path, tmp_path: Path) -> None:
    r = rik("record", KNOB, "--strategy", "contact_rish", "--out", str(tmp_path))
    assert r.code == 2 and "unknown strategy 'contact_rish'" in r.err and "did you mean 'contact_rich'?" in r.err
    r = rik("record", "drawer-chest-80__two_point-bow-12__normal", "--strategy", "contact_rich")
    assert r.code == 2 and "no handle 'two_point-bow-12'" in r.err
    r = rik("teleop", KNOB, "--device", "spacemouse")
    assert r.code == 2 and ("SpaceMouse" in r.err) and "Traceback" not in r.err
    env = os.environ.pop("DISPLAY", None)
    try:
        r = rik("teleop", KNOB, "--device", "keyboard")
    finally:
        if env is not None:
            os.environ["DISPLAY"] = env
    assert r.code == 2 and "teleoperation needs a display" in r.err
    r = rik("bench", "--sweep", "grip-strength")
    assert r.code == 2 and "unknown sweep 'grip-strength' (sweeps: grip-force)" in r.err
    r = rik("replay", str(tmp_path / "nothing"))
    assert r.code == 2 and "nothing: no such episode or directory" in r.err


def test_unknown_front_is_named(variants: Path) -> None:
    with pytest.raises(RikError, match="has no front 'drawer-9' \\(fronts: drawer-1"):
        build_scene(variants / BOW_HIGH, "drawer-9")


def test_a_new_scene_starts_in_front_of_the_handle(variants: Path) -> None:
    """The start pose is computed from positions MuJoCo has computed: before the fix the handle read (0, 0, 0) and
    the gripper started near the floor, 65 cm below it (what teleoperation starts from)."""
    scene = build_scene(variants / BOW_HIGH, None)
    grasp, tcp = scene.grasp_point(), scene.tcp()
    assert grasp[2] > 0.3  # the handle is on the chest, not at the origin
    assert np.allclose(tcp, grasp + [0.0, 0.25, 0.0], atol=1e-3)


@pytest.mark.parametrize("seed", [0, 7])
def test_env_reset_reproduces_the_first_state_of_rik_record(variants: Path, tmp_path: Path, seed: int) -> None:
    """gym's reset(seed=S) starts exactly where ``rik record --seed S`` started, so learned and scripted runs can
    be compared pair by pair (also after other episodes have run in the same environment)."""
    import gymnasium as gym

    import rik.envs.open_front  # noqa: F401  (registers rik/OpenFront-v0)

    meta = record(CAT, KNOB, "grasp_vertical", seed=seed, out=tmp_path, variants=variants, max_seconds=0.2)[0]
    first = read_episode(tmp_path / meta.id)[1].column("state")[0].as_py()
    env = gym.make("rik/OpenFront-v0", variant=KNOB, variants_dir=str(variants)).unwrapped
    for _ in range(2):  # a second reset, after steps, gives the same start again
        env.reset(seed=seed)
        assert np.array_equal(env.scene.state(), np.asarray(first))
        env.step(np.array([0, -1, 0, 0, 0, 0, 1], np.float32))
    env.close()
