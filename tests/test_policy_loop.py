"""The policy loop through LeRobot's own tools: rik's demonstrations exported state-only, ``lerobot-train
--env.type=rik`` with evaluation during training, ``lerobot-eval --env.type=rik`` and ``rik eval`` on the same
seeds (the same episodes, bit for bit), the contract carried from the export to the checkpoint and read by both (an
older policy folder without it runs through the fallback, with a note), the ``lerobot_env_rik`` plugin's features,
and ``rik eval``'s bad input."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from shared import builtin_catalog, cli

pytestmark = pytest.mark.slow  # end-to-end runs: out of the everyday tier (-m "not slow")

CAT = builtin_catalog()
BIN = Path(sys.executable).parent
DRAW = ("--types", "knob", "--presets", "smooth")
EPISODE_LENGTH = "30"
EVAL_SEED = 1016
"""The first seed of the episodes both tools run on the test split's knobs: seeds 1016-1019 draw the knobs
``bell-34`` and ``hexagon-28``; from 1000 they drew ``fluted-34`` too, whose CoACD decomposition (7 CPU-s) no other
test needs."""


def _run(*cmd: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "HF_HUB_OFFLINE": "1", "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl")}
    return subprocess.run(list(cmd), cwd=cwd, env=env, capture_output=True, text=True, timeout=900)


@pytest.fixture(scope="module")
def loop(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """Two scripted demonstrations on the train split, exported state-only, and an ACT policy trained on them for
    a few steps by lerobot-train, evaluating in rik's environment during training."""
    root = tmp_path_factory.mktemp("loop")
    variants = root / "variants"
    # rik's own commands in this process (its imports are warm: two fresh processes cost the suite ~8 CPU-s)
    cli("record", "--split", "train", *DRAW, "--episodes", "2", "-s", "contact_rich", "--out", "episodes",
        "--variants", str(variants), cwd=root)
    cli("export-lerobot", "episodes", "--out", "dataset", "--repo-id", "local/loop", "--streams", "none",
        "--variants", str(variants), cwd=root)
    res = _run(str(BIN / "lerobot-train"), "--dataset.repo_id=local/loop", "--dataset.root=dataset",
               "--policy.type=act", "--policy.push_to_hub=false", "--policy.device=cpu",
               "--policy.pretrained_backbone_weights=null", "--policy.dim_model=32", "--policy.dim_feedforward=64",
               "--policy.n_heads=2", "--policy.chunk_size=10", "--policy.n_action_steps=10",
               '--policy.normalization_mapping={"VISUAL": "MEAN_STD", "STATE": "MEAN_STD", "ENV": "MEAN_STD", '
               '"ACTION": "MEAN_STD"}',
               "--env.type=rik", "--env.split=val", "--env.handle_types=knob", "--env.presets=smooth",
               f"--env.episode_length={EPISODE_LENGTH}", f"--env.variants_dir={variants}",
               "--steps=4", "--batch_size=4", "--env_eval_freq=4", "--eval.n_episodes=1", "--eval.batch_size=1",
               "--save_freq=4", "--log_freq=2", "--output_dir=train", "--wandb.enable=false", "--num_workers=0",
               cwd=root)
    assert res.returncode == 0, res.stderr[-3000:]
    return {"root": root, "variants": variants, "policy": root / "train/checkpoints/last/pretrained_model"}


def test_lerobot_train_runs_with_evaluation_in_riks_env(loop: dict[str, Path]) -> None:
    policy = loop["policy"]
    config = json.loads((policy / "config.json").read_text())
    assert set(config["input_features"]) == {"observation.state", "observation.environment_state"}
    assert config["input_features"]["observation.environment_state"]["type"] == "ENV"
    assert config["normalization_mapping"]["ENV"] == "MEAN_STD"  # the front's state is normalised too
    videos = sorted((loop["root"] / "train" / "eval").rglob("*.mp4"))
    assert videos, "evaluation during training wrote no video"
    # the plugin's hook copied the dataset's contract beside the checkpoint (tests/test_policy_io.py)
    contract = json.loads((loop["root"] / "dataset" / "meta" / "rik_policy_io.json").read_text())
    assert json.loads((policy / "rik_policy_io.json").read_text()) == contract


def test_rik_eval_and_lerobot_eval_run_the_same_episodes(loop: dict[str, Path], rik) -> None:
    """Same seeds, same episodes: every step of every episode is the same in both tools, so the rewards (the
    opening gained per step) sum to the same float, and the success and seeds agree."""
    root, policy = loop["root"], loop["policy"]
    res = _run(str(BIN / "lerobot-eval"), f"--policy.path={policy}", "--env.type=rik", "--env.split=test",
               "--env.handle_types=knob", "--env.presets=smooth,high", f"--env.episode_length={EPISODE_LENGTH}",
               f"--env.variants_dir={loop['variants']}", "--eval.n_episodes=4", "--eval.batch_size=1",
               f"--seed={EVAL_SEED}", "--output_dir=lerobot-eval", "--policy.device=cpu", cwd=root)
    assert res.returncode == 0, res.stderr[-3000:]
    assert "guessed" not in res.stderr  # the contract was read from the policy folder
    theirs = json.loads((root / "lerobot-eval" / "eval_info.json").read_text())
    out = root / "rik-eval"
    r = rik("eval", str(policy), "--split", "test", *DRAW[:2], "--presets", "smooth,high", "-n", "2",
            "--episode-length", EPISODE_LENGTH, "--seed", str(EVAL_SEED), "--workers", "1", "--videos", "1", "--out",
            str(out), "--variants", str(loop["variants"]))
    assert r.code == 0, r.err
    assert "note:" not in r.out
    ours = json.loads((out / "eval_info.json").read_text())
    mine, their = ours["per_task"][0]["metrics"], theirs["per_task"][0]["metrics"]
    assert mine["sum_rewards"] == their["sum_rewards"]
    assert mine["successes"] == their["successes"]
    assert ours["overall"]["n_episodes"] == theirs["overall"]["n_episodes"] == 4
    assert set(theirs["overall"]) - {"predicted_video_paths"} <= set(ours["overall"])
    rows = ours["rik"]["per_episode"]
    assert [r["seed"] for r in rows] == [EVAL_SEED + k for k in range(4)]
    assert [r["preset"] for r in rows] == ["smooth", "high", "smooth", "high"]  # seeds cycle through the cells
    from rik.registry.splits import split_handles

    assert {_handle_of(r["variant"]) for r in rows} <= set(split_handles(CAT, "test"))
    table = (out / "table.md").read_text()
    assert "**knob**" in table and "smooth S" in table and "high S" in table
    # the rewards are zero while the drawer is not moved; the films show the gripper: frame by frame the same
    theirs_film = _frames(root / "lerobot-eval" / "videos" / "rik_0" / "eval_episode_0.mp4")
    (film,) = (out / "videos").glob("*.mp4")
    mine_film = _frames(film)
    assert mine_film.shape == theirs_film.shape and len(mine_film) > 5
    assert np.abs(mine_film.astype(int) - theirs_film).mean(axis=(1, 2, 3)).max() < 1.0
    assert np.abs(mine_film[-1].astype(int) - mine_film[0]).mean() > 1.0, "the gripper did not move: a weak check"
    assert (out / "episodes.csv").read_text().splitlines()[0].startswith("seed,handle_type,preset,strategy")
    # trained on two train-split knobs, the policy meets test-split handles far outside its training states
    assert all(isinstance(r["stats_sd"], float) and r["stats_dim"].startswith("observation.") for r in rows)
    far = [r for r in rows if r["stats_sd"] > 5.0]
    assert far, [r["stats_sd"] for r in rows]
    warning = next(line for line in r.out.splitlines() if line.startswith("warning: "))
    assert f"in {len(far)} of 4 episodes the states fell more than 5 standard deviations outside the range" in warning


def test_an_older_policy_folder_runs_through_the_fallback_with_a_note(loop: dict[str, Path], rik, tmp_path: Path,
                                                                      monkeypatch: pytest.MonkeyPatch,
                                                                      caplog: pytest.LogCaptureFixture) -> None:
    """A policy saved before rik wrote its contract (no rik_policy_io.json, its training data gone): rik eval and
    --env.*=auto guess its action frame and handle shape from its widths and statistics, and say so in one line."""
    from lerobot_env_rik import RikEnvConfig

    old = tmp_path / "old"
    shutil.copytree(loop["policy"], old)
    (old / "rik_policy_io.json").unlink()
    (old / "train_config.json").unlink()
    out = tmp_path / "eval"
    r = rik("eval", str(old), "--split", "test", *DRAW, "-n", "1", "--episode-length", "5", "--workers", "1",
            "--videos", "0", "--out", str(out), "--variants", str(loop["variants"]))
    assert r.code == 0, r.err
    note = next(line for line in r.out.splitlines() if line.startswith("note: "))
    assert "no rik_policy_io.json beside the policy or its training data" in " ".join(r.out.split())
    assert note.startswith(f"note: {old}")
    needs = json.loads((out / "eval_info.json").read_text())["rik"]["spec"]["needs"]
    assert needs == {"policy_type": "act", "cameras": [], "streams": [], "image_size": [96, 128]}  # world, none
    monkeypatch.setattr("sys.argv", ["lerobot-eval", f"--policy.path={old}", "--env.type=rik"])
    config = RikEnvConfig()  # what lerobot-eval --policy.path=OLD --env.type=rik resolves
    assert (config.action_frame, config.handle_shape, config.cameras) == ("world", "none", "")
    assert any("guessed from its input widths" in rec.getMessage() for rec in caplog.records)


def _frames(path: Path) -> np.ndarray:
    import av

    with av.open(str(path)) as container:
        return np.stack([f.to_ndarray(format="rgb24") for f in container.decode(video=0)])


def _handle_of(variant: str) -> str:
    from rik.registry.ids import parse_variant_id

    return parse_variant_id(CAT, variant).handle


def test_bad_policies_get_one_line(loop: dict[str, Path], rik, tmp_path: Path) -> None:
    policy = loop["policy"]
    empty = tmp_path / "empty"
    empty.mkdir()
    r = rik("eval", str(empty), "--out", str(tmp_path / "o1"))
    assert r.code == 2 and r.err.strip() == (f"rik: error: {empty}: no config.json: not a saved LeRobot policy "
                                             "(lerobot-train saves one in <output_dir>/checkpoints/<step>/"
                                             "pretrained_model)")

    def edited(name: str, change) -> Path:
        copy = tmp_path / name
        shutil.copytree(policy, copy)
        config = json.loads((copy / "config.json").read_text())
        change(config["input_features"])
        (copy / "config.json").write_text(json.dumps(config))
        return copy

    rerendered = edited("rerendered", lambda f: f.__setitem__(
        "observation.images.front_rerendered", {"type": "VISUAL", "shape": [3, 96, 128]}))
    r = rik("eval", str(rerendered), "--out", str(tmp_path / "o2"))
    assert r.code == 2 and r.err.strip() == (
        f"rik: error: {rerendered / 'config.json'}: input 'observation.images.front_rerendered' is a Mitsuba "
        "re-render, which the environment is not asked to render; pass --rerendered (slow without a GPU) or train "
        "without the _rerendered keys (--policy.input_features)")
    old = edited("old", lambda f: f["observation.state"].__setitem__("shape", [14]))
    r = rik("eval", str(old), "--out", str(tmp_path / "o3"))
    assert r.code == 2 and r.err.strip() == (
        f"rik: error: {old / 'config.json'}: input 'observation.state' has 14 numbers: the policy was trained on an "
        "export made before rik split the robot's and the front's state; re-export the episodes (rik "
        "export-lerobot) and train again")
    top = edited("top", lambda f: f.__setitem__("observation.images.top", {"type": "VISUAL", "shape": [3, 96, 128]}))
    r = rik("eval", str(top), "--out", str(tmp_path / "o4"))
    assert r.code == 2 and "input 'observation.images.top' is not something rik's environment supplies" in r.err
    r = rik("eval", str(policy), "--split", "nope", "--out", str(tmp_path / "o5"))
    assert r.code == 2 and r.err.strip() == "rik: error: unknown split 'nope' (splits: train, val, test)"
    assert not any((tmp_path / f"o{i}").exists() for i in range(1, 6))


def test_eval_rejects_unknown_split_preset_and_strategy(rik, tmp_path: Path) -> None:
    r = rik("eval", "strategy:contact_rich", "--split", "tset", "--out", str(tmp_path / "o"))
    assert r.code == 2 and r.err.strip() == ("rik: error: unknown split 'tset' (splits: train, val, test); did you "
                                             "mean 'test'?")
    r = rik("eval", "strategy:contact_rich", "--presets", "smooth,hard", "--out", str(tmp_path / "o"))
    assert r.code == 2 and r.err.strip().startswith("rik: error: unknown preset 'hard' (presets: ")
    r = rik("eval", "strategy:pull_hard", "--out", str(tmp_path / "o"))
    assert r.code == 2 and r.err.strip().startswith("rik: error: unknown strategy 'pull_hard' (strategies: ")
    assert not (tmp_path / "o").exists()


def test_scripted_eval_is_rik_record_on_the_drawn_variant(rik, tmp_path: Path) -> None:
    """``rik eval strategy:S`` runs the episode ``rik record --seed`` records on the drawn variant: the same start
    and the same states up to the step the front reaches 90 % (where the environment ends the episode)."""
    from rik.episodes.draw import Draw
    from rik.episodes.episode import find_episodes, read_episode
    from rik.episodes.record import record

    variants = tmp_path / "variants"
    r = rik("eval", "strategy:contact_rich", "--split", "test", *DRAW, "-n", "1", "--seed", "7", "--videos", "0",
            "--workers", "1", "--out", str(tmp_path / "eval"), "--variants", str(variants))
    assert r.code == 0, r.err
    (row,) = json.loads((tmp_path / "eval" / "eval_info.json").read_text())["rik"]["per_episode"]
    drawn = Draw("test", ("knob",), ("smooth",)).episode(CAT, 7)
    assert (row["variant"], row["front"]) == (drawn.variant, drawn.front)
    meta = record(CAT, drawn.variant, "contact_rich", seed=7, front=drawn.front, out=tmp_path / "rec",
                  variants=variants)[0]
    (episode,) = find_episodes([tmp_path / "rec"])
    opening = np.asarray(read_episode(episode)[1].column("opening").to_pylist())
    reached = np.flatnonzero(opening >= 0.9)
    if reached.size:  # the environment ends the episode at the first step at 90 %
        assert row["outcome"] == "S" and row["steps"] == int(reached[0])
        assert row["final_opening"] == pytest.approx(opening[reached[0]], abs=1e-4)
    else:
        assert row["outcome"] == meta.outcome and row["final_opening"] == pytest.approx(meta.final_opening, abs=1e-4)


def test_env_in_absolute_mode_replays_a_recording_exactly(tmp_path: Path) -> None:
    """The dataset's actions are absolute targets: stepping the environment with a recording's actions from the
    same seed reproduces its states bit for bit."""
    import gymnasium as gym

    import rik.envs.open_front  # noqa: F401
    from rik.episodes.episode import read_episode, states
    from rik.episodes.record import record

    variant = "drawer-bedside-45__knob-mushroom-30__normal"
    variants = tmp_path / "variants"
    meta = record(CAT, variant, "contact_rich", seed=5, out=tmp_path, variants=variants, max_seconds=2.0)[0]
    table = read_episode(tmp_path / meta.id)[1]
    recorded, actions = states(table), np.asarray(table.column("action").to_pylist())
    env = gym.make("rik/OpenFront-v0", variant=variant, variants_dir=str(variants), action_mode="absolute").unwrapped
    env.reset(seed=5)
    assert np.array_equal(env.scene.state(), recorded[0])
    for k in range(len(recorded) - 1):
        env.step(actions[k])
        assert np.array_equal(env.scene.state(), recorded[k + 1]), f"step {k}"
    env.close()


def test_plugin_maps_env_keys_to_the_export_features(tmp_path: Path) -> None:
    """lerobot finds the plugin by its distribution name; ``preprocess_observation`` turns the environment's
    observation into exactly the feature names (and shapes) of ``rik export-lerobot``."""
    from lerobot.envs.configs import EnvConfig
    from lerobot.envs.utils import preprocess_observation
    from lerobot.utils.import_utils import register_third_party_plugins

    from rik.lerobot.policy_io import PolicyIO

    register_third_party_plugins()
    cfg = EnvConfig.get_choice_class("rik")(cameras="front,wrist", observation_height=24, observation_width=32,
                                            split="val", handle_types="knob", presets="smooth", episode_length=5,
                                            variants_dir=str(tmp_path / "variants"))
    assert cfg.gym_kwargs["max_episode_steps"] == 5
    exported = PolicyIO(cameras=("front", "wrist"), streams=("sim",), image_size=(24, 32)).features()
    assert cfg.io == PolicyIO(cameras=("front", "wrist"), streams=("sim",), image_size=(24, 32))
    assert set(cfg.features_map.values()) == set(exported)
    vec = cfg.create_envs(n_envs=1)["rik"][0]
    obs, info = vec.reset(seed=[3])
    batch = preprocess_observation(obs)
    assert set(batch) == set(exported) - {"action"}
    for key, tensor in batch.items():
        shape = tuple(exported[key]["shape"])
        want = (1, shape[2], shape[0], shape[1]) if len(shape) == 3 else (1, *shape)
        assert tuple(tensor.shape) == want, key
    assert vec.call("task_description")[0].startswith("open the drawer by its ")
    _, _, _, _, info = vec.step(np.asarray([vec.envs[0].unwrapped.scene.pose().tolist() + [0.0]], np.float32))
    assert {"is_success", "outcome", "opening", "variant", "preset", "handle_type"} <= set(info)
    vec.close()


def test_draw_gives_n_episodes_per_cell_from_the_split() -> None:
    from rik.episodes.draw import Draw
    from rik.registry.splits import split_handles

    draw = Draw("test", ("knob", "two_point"), ("smooth", "high"))
    episodes = [draw.episode(CAT, s) for s in range(1000, 1000 + 4 * 3)]
    cells = [(e.handle_type, e.preset) for e in episodes]
    assert all(cells.count(c) == 3 for c in draw.cells)
    test = set(split_handles(CAT, "test"))
    assert all(_handle_of(e.variant) in test for e in episodes)
    assert [draw.episode(CAT, s) for s in range(1000, 1012)] == episodes


def test_env_renders_the_rerendered_stream_for_policies_trained_on_it(tmp_path: Path) -> None:
    """A policy trained on ``observation.images.front_rerendered`` can be evaluated: the environment renders Mitsuba's
    stream of the same state (slow without a GPU: a low sample count here)."""
    import gymnasium as gym

    import rik.envs.open_front  # noqa: F401

    env = gym.make("rik/OpenFront-v0", variant="drawer-bedside-45__knob-mushroom-30__normal", streams=("sim",
                   "rerendered"), cameras=("front",), image_size=(24, 32), spp=2,
                   variants_dir=str(tmp_path / "variants")).unwrapped
    obs, _ = env.reset(seed=0)
    assert set(obs["pixels"]) == {"front", "front_rerendered"}
    sim, mitsuba = obs["pixels"]["front"], obs["pixels"]["front_rerendered"]
    assert sim.shape == mitsuba.shape == (24, 32, 3) and mitsuba.dtype == np.uint8
    assert mitsuba.std() > 5 and not np.array_equal(sim, mitsuba)  # an image, and not MuJoCo's
    env.close()


def test_eval_tables_several_operators_side_by_side_and_reuses_finished_runs(rik, tmp_path: Path) -> None:
    args = ("strategy:contact_rich", "strategy:grasp_vertical", "--split", "test", *DRAW, "-n", "1", "--videos", "0",
            "--workers", "1", "--out", str(tmp_path / "both"), "--variants", str(tmp_path / "variants"))
    r = rik("eval", *args)
    assert r.code == 0, r.err
    table = (tmp_path / "both" / "table.md").read_text()
    assert "| contact_rich |" in table and "| grasp_vertical |" in table
    assert (tmp_path / "both" / "success.png").stat().st_size > 10_000
    assert (tmp_path / "both" / "contact_rich" / "eval_info.json").is_file()
    before = (tmp_path / "both" / "contact_rich" / "eval_info.json").read_bytes()
    r = rik("eval", *args)
    assert r.code == 0 and "contact_rich: already evaluated on these episodes" in " ".join(r.out.split())
    assert (tmp_path / "both" / "contact_rich" / "eval_info.json").read_bytes() == before
    r = rik("eval", *args, "--label", "mine")
    assert r.code == 2 and r.err.strip() == ("rik: error: --label given 1 time for 2 policies: once per policy, in "
                                             "their order, or not at all (each named by its type and training run)")


def test_eval_writes_each_policy_into_its_own_folder_in_one_process(rik, tmp_path: Path) -> None:
    """Several --out (and --label), one per policy: each policy's evaluation alone in its folder, the same episodes
    and rows as one evaluation at a time (what scripts/policy_experiment.sh runs, many policies per process)."""
    common = ("--split", "test", *DRAW, "-n", "1", "--videos", "0", "--workers", "1",
              "--variants", str(tmp_path / "variants"))
    r = rik("eval", "strategy:contact_rich", "strategy:grasp_vertical", "--label", "cr", "--out", str(tmp_path / "a"),
            "--label", "gv", "--out", str(tmp_path / "b"), *common)
    assert r.code == 0, r.err
    assert not (tmp_path / "a" / "cr").exists() and not (tmp_path / "table.md").exists()
    r = rik("eval", "strategy:grasp_vertical", "--label", "gv", "--out", str(tmp_path / "alone"), *common)
    assert r.code == 0, r.err

    def rows(folder: str) -> list[dict[str, object]]:
        info = json.loads((tmp_path / folder / "eval_info.json").read_text())["rik"]
        return [{k: v for k, v in row.items() if k != "seconds"} for row in info["per_episode"]]

    assert rows("b") == rows("alone") and [r["strategy"] for r in rows("a")] == ["cr"]
    for extra, message in (
            (("--out", str(tmp_path / "a"), "--out", str(tmp_path / "a")),
             "two policies have the same --out: give each its own folder"),
            (("--out", "x", "--out", "y", "--out", "z"),
             "--out given 3 times for 2 policies: once (their folders in it), or once per policy, in their order")):
        r = rik("eval", "strategy:contact_rich", "strategy:grasp_vertical", *extra, *common)
        assert r.code == 2 and r.err.strip() == f"rik: error: {message}"


def test_out_of_stats_distance_counts_from_the_training_range() -> None:
    """A nearly constant dimension with outliers (the gripper's yaw: 0.012 rad of deviation, starts up to 0.08 rad)
    is no extrapolation inside its training range, however many deviations from its mean; beyond the range it is
    measured from the range's end, in deviations; statistics without a range count from the mean."""
    import torch

    from rik.evaluation.evaluate import _worst_state

    mean, std = np.array([0.0002, 0.5]), np.array([0.0115, 0.1])
    low, high = np.array([-0.0799, 0.3]), np.array([0.0786, 0.7])
    ranged = {"observation.state": (mean, std, low, high, ("yaw", "x"))}
    states = torch.tensor([[[0.075, 0.5], [0.0, 0.6]]])  # yaw at 6.5 deviations from its mean, inside its range
    assert _worst_state({"observation.state": states}, ranged, 1) == (0.0, "")
    beyond = torch.tensor([[[0.0, 0.5], [0.0, 1.2]]])  # x 0.5 past its maximum: 5 deviations
    worst, where = _worst_state({"observation.state": beyond}, ranged, 1)
    assert where == "observation.state.x" and worst == pytest.approx(5.0)
    no_range = {"observation.state": (mean, std, mean, mean, ("yaw", "x"))}
    worst, where = _worst_state({"observation.state": states}, no_range, 1)
    assert where == "observation.state.yaw" and worst == pytest.approx((0.075 - 0.0002) / 0.0115, rel=1e-5)
    assert _worst_state({"observation.state": beyond}, ranged, 0) == (0.0, "")  # only up to the episode's last step
