"""The Hand-E's action in the handle and the gripper frames: ``rik export-lerobot --action-frame handle`` writes the
target position less the same step's grasp point, ``--action-frame gripper`` less the same step's gripper base
position (and the grasp point from the gripper in the environment state), the environment's ``action_mode="handle"``
and ``"gripper"`` add them back, ``rik eval`` and ``--env.action_frame=auto`` read a policy's frame from its contract
(``rik_policy_io.json``, tests/test_policy_io.py) and, for an older policy, tell it from its inputs and the training
statistics in its own folder, and an arm's joint action has no such frame (one line)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest
from shared import BOW, act_config_folder

from rik.errors import RikError


def _columns(root: Path) -> dict[str, np.ndarray]:
    import pyarrow.parquet as pq

    table = pq.read_table(sorted((root / "data").rglob("*.parquet"))[0])
    return {k: np.stack(table.column(k).to_numpy(zero_copy_only=False)).astype(np.float64)
            for k in ("action", "observation.environment_state")}


def test_a_handle_frame_export_is_the_recorded_action_less_the_grasp_point(rik, knob_recording: Path,
                                                                         tmp_path: Path) -> None:
    import pyarrow.parquet as pq

    from rik.sim.robots.layout import HANDLE_ACTION_NAMES

    episodes, variants = knob_recording / "episodes", knob_recording / "variants"
    r = rik("export-lerobot", str(episodes), "--out", str(tmp_path / "handle"), "--repo-id", "local/handle",
            "--streams", "none", "--variants", str(variants), "--action-frame", "handle")
    assert r.code == 0, r
    handle = _columns(tmp_path / "handle")
    [episode] = list(episodes.iterdir())
    recorded = np.stack(pq.read_table(episode / "states.parquet").column("action").to_numpy(zero_copy_only=False))
    assert recorded.shape == handle["action"].shape  # the Hand-E's world-frame export is the recorded action
    grasp = handle["observation.environment_state"][:, 3:6]
    assert np.abs(grasp).max() > 0.1  # the grasp point is far from the origin: the test can tell the frames apart
    np.testing.assert_allclose(handle["action"][:, :3] + grasp, recorded[:, :3], atol=1e-6)
    np.testing.assert_allclose(handle["action"][:, 3:], recorded[:, 3:], atol=1e-6)
    info = json.loads((tmp_path / "handle" / "meta" / "info.json").read_text())
    assert info["features"]["action"]["names"] == list(HANDLE_ACTION_NAMES)
    assert "in the handle frame, `--action-frame handle`" in (tmp_path / "handle" / "README.md").read_text()
    r = rik("export-lerobot", str(episodes), "--out", str(tmp_path / "up"), "--repo-id", "local/up", "--streams",
            "none", "--variants", str(variants), "--action-frame", "up")
    assert r.code == 2 and r.err.strip() == "rik: error: --action-frame up: use one of world, handle, gripper"
    assert not (tmp_path / "up").exists() and not (tmp_path / "up.partial").exists()


def test_a_gripper_frame_export_is_the_recorded_action_less_the_gripper_and_adds_the_grasp_point_from_it(
        rik, knob_recording: Path, tmp_path: Path) -> None:
    import pyarrow.parquet as pq

    from rik.lerobot.policy_io import PolicyIO
    from rik.sim.observation import ENV_STATE_NAMES, GRIPPER_GRASP_NAMES
    from rik.sim.robots.layout import GRIPPER_ACTION_NAMES

    episodes, variants = knob_recording / "episodes", knob_recording / "variants"
    r = rik("export-lerobot", str(episodes), "--out", str(tmp_path / "gripper"), "--repo-id", "local/gripper",
            "--streams", "none", "--variants", str(variants), "--action-frame", "gripper", "--handle-shape", "kind")
    assert r.code == 0, r
    table = pq.read_table(sorted((tmp_path / "gripper" / "data").rglob("*.parquet"))[0])
    columns = {k: np.stack(table.column(k).to_numpy(zero_copy_only=False)).astype(np.float64)
               for k in ("action", "observation.state", "observation.environment_state")}
    [episode] = list(episodes.iterdir())
    recorded = np.stack(pq.read_table(episode / "states.parquet").column("action").to_numpy(zero_copy_only=False))
    base, env = columns["observation.state"][:, :3], columns["observation.environment_state"]
    assert np.abs(base).max() > 0.1  # the gripper is far from the origin: the test can tell the frames apart
    np.testing.assert_allclose(columns["action"][:, :3] + base, recorded[:, :3], atol=1e-6)
    np.testing.assert_allclose(columns["action"][:, 3:], recorded[:, 3:], atol=1e-6)
    front = len(ENV_STATE_NAMES)
    assert env.shape[1] == front + 3 + 5  # the front, the grasp point from the gripper, then the handle's kind
    np.testing.assert_allclose(env[:, front:front + 3], env[:, 3:6] - base, atol=1e-6)
    info = json.loads((tmp_path / "gripper" / "meta" / "info.json").read_text())
    assert info["features"]["action"]["names"] == list(GRIPPER_ACTION_NAMES)
    assert PolicyIO.from_dataset(tmp_path / "gripper") == PolicyIO(action_frame="gripper", handle_shape="kind")
    names = info["features"]["observation.environment_state"]["names"]
    assert names[front:front + 3] == list(GRIPPER_GRASP_NAMES) and names[front + 3] == "handle_knob"
    card = (tmp_path / "gripper" / "README.md").read_text()
    assert "in the gripper frame, `--action-frame gripper`" in card
    assert "**The grasp point from the gripper** (`--action-frame gripper`: 3 more numbers after" in card


def test_the_handle_and_gripper_action_modes_drive_the_gripper_as_the_absolute_one(bow_variants: Path) -> None:
    import gymnasium as gym

    import rik.envs.open_front  # noqa: F401

    envs = {mode: gym.make("rik/OpenFront-v0", variant=BOW, variants_dir=str(bow_variants), action_mode=mode,
                           disable_env_checker=True).unwrapped for mode in ("absolute", "handle", "gripper")}
    obs = {mode: env.reset(seed=5)[0] for mode, env in envs.items()}
    start = obs["absolute"]["agent_pos"][:6].astype(np.float64)
    for k in range(12):  # towards the handle's grasp point, then closing
        for mode, env in envs.items():
            grasp = obs[mode]["environment_state"][3:6].astype(np.float64)
            target = start.copy()
            target[:3] += (env.scene.grasp_point() + [0, 0.08, 0] - start[:3]) * min(1.0, k / 8)
            action = np.concatenate([target, [1.0 if k > 9 else 0.0]])
            if mode == "handle":
                action[:3] -= env.scene.grasp_point()  # as the policy sees it: float32 in the observation
                assert np.abs(env.scene.grasp_point() - grasp).max() < 1e-6
            if mode == "gripper":
                base = env.scene.pose()[:3]
                action[:3] -= base
                assert np.abs(obs[mode]["agent_pos"][:3] - base).max() < 1e-6
                assert np.abs(obs[mode]["environment_state"][13:16] - (grasp - base)).max() < 1e-6
            obs[mode] = env.step(action)[0]
    assert [obs[m]["environment_state"].shape for m in envs] == [(13,), (13,), (16,)]
    np.testing.assert_allclose(envs["handle"].scene.pose(), envs["absolute"].scene.pose(), atol=1e-9)
    np.testing.assert_allclose(envs["gripper"].scene.pose(), envs["absolute"].scene.pose(), atol=1e-9)
    moved = np.abs(envs["handle"].scene.pose()[:3] - start[:3]).max()
    assert moved > 0.02, moved
    for env in envs.values():
        env.close()


def _policy_stats(folder: Path, action: dict[str, list[float]], env: dict[str, list[float]]) -> Path:
    """A policy folder's postprocessor and its unnormaliser's statistics (as lerobot-train saves them), nothing
    else: what :func:`rik.lerobot.policy_folder.trained_action_frame` reads."""
    from safetensors.numpy import save_file

    folder.mkdir()
    state = "policy_postprocessor_step_0_unnormalizer_processor.safetensors"
    (folder / "policy_postprocessor.json").write_text(json.dumps(
        {"name": "policy_postprocessor", "steps": [{"registry_name": "unnormalizer_processor", "config": {},
                                                     "state_file": state}]}))
    tensors = {f"action.{k}": np.asarray(v, np.float32) for k, v in action.items()}
    tensors |= {f"observation.environment_state.{k}": np.asarray(v, np.float32) for k, v in env.items()}
    save_file(tensors, str(folder / state))
    return folder


def test_a_policys_action_frame_comes_from_its_training_statistics(tmp_path: Path) -> None:
    from rik.lerobot.policy_folder import trained_action_frame

    grasp = [0.0, 0.0, 0.0, 0.0, 0.2, 0.42, 1, 0, 0, 0, 0, -1, 0]  # env state: grasp point at (0, 0.2, 0.42) m
    world = [0.0, 0.27, 0.45, 0.1, 0.0, 1.3, 0.7]  # the gripper's targets hover in front of the handle
    handle = [0.0, 0.07, 0.03, 0.1, 0.0, 1.3, 0.7]  # the same, less the grasp point
    assert trained_action_frame(_policy_stats(tmp_path / "w", {"mean": world}, {"mean": grasp})) == "world"
    assert trained_action_frame(_policy_stats(tmp_path / "h", {"mean": handle}, {"mean": grasp})) == "handle"
    # min-max statistics only (diffusion's mapping): their centre
    span = {"min": [x - 0.1 for x in handle], "max": [x + 0.1 for x in handle]}
    assert trained_action_frame(_policy_stats(tmp_path / "m", span, {"min": grasp, "max": grasp})) == "handle"
    # no environment state in the statistics, or no postprocessor at all: the world, as before the handle frame
    assert trained_action_frame(_policy_stats(tmp_path / "n", {"mean": handle}, {})) == "world"
    (tmp_path / "bare").mkdir()
    assert trained_action_frame(tmp_path / "bare") == "world"
    bad = _policy_stats(tmp_path / "bad", {"mean": handle}, {"mean": grasp})
    state = bad / "policy_postprocessor_step_0_unnormalizer_processor.safetensors"
    state.write_bytes(b"not safetensors")
    with pytest.raises(RikError, match=rf"^{state}: not readable statistics \("):
        trained_action_frame(bad)
    outside = _policy_stats(tmp_path / "out", {"mean": handle}, {"mean": grasp})
    (outside / "policy_postprocessor.json").write_text(json.dumps(
        {"steps": [{"registry_name": "unnormalizer_processor", "state_file": "../h/x.safetensors"}]}))
    with pytest.raises(RikError, match=r"field 'state_file': '\.\./h/x\.safetensors' is not a file name inside the "
                                       r"policy folder"):
        trained_action_frame(outside)


def test_a_policy_reading_the_grasp_point_from_the_gripper_acts_in_the_gripper_frame(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from lerobot_env_rik import RikEnvConfig, env_kwargs

    from rik.lerobot.policy_io import read_policy

    gripper, shaped = (act_config_folder(tmp_path / name, env_width=width)
                       for name, width in (("gripper", 16), ("shaped", 27)))
    assert (read_policy(gripper).io.action_frame, read_policy(gripper).io.handle_shape) == ("gripper", "none")
    assert (read_policy(shaped).io.action_frame, read_policy(shaped).io.handle_shape) == ("gripper", "full")
    assert RikEnvConfig(action_frame="gripper").features["environment_state"].shape == (16,)
    monkeypatch.setattr("sys.argv", ["lerobot-eval", f"--policy.path={shaped}", "--env.type=rik"])
    config = RikEnvConfig()  # auto: as the command line's (older, contract-less) policy reads it
    assert config.features["environment_state"].shape == (27,)
    assert (env_kwargs(config)["action_mode"], env_kwargs(config)["io"].handle_shape) == ("gripper", "full")


def test_an_arm_has_no_handle_frame(rik, bow_variants: Path, tmp_path: Path) -> None:
    from lerobot_env_rik import RikEnvConfig

    spec = tmp_path / "so100.yaml"
    spec.write_text(f"repo_id: local/so\nrobot: so100\naction_frame: handle\nvariants:\n  ids: [{BOW}]\n"
                    "operators:\n  - strategy: planned\nstreams: []\n")
    variants = tmp_path / "variants"
    shutil.copytree(bow_variants, variants)
    r = rik("dataset", "build", str(spec), "--out", str(tmp_path / "ds"), "--variants", str(variants))
    assert r.code == 2 and r.err.strip() == (
        f"rik: error: {spec}, field 'action_frame': action frame 'handle': robot so100 acts with joint targets, "
        "which have no handle frame (it is the Hand-E's pose action's)")
    assert not (tmp_path / "ds").exists()
    with pytest.raises(ValueError, match=r"^--env\.action_frame=up: use one of world, handle, gripper$"):
        RikEnvConfig(action_frame="up")
    assert RikEnvConfig().action_frame == "world"  # auto, without a policy on the command line
    with pytest.raises(ValueError, match=r"^--env\.action_frame=handle: robot so100 acts with joint targets"):
        RikEnvConfig(robot="so100", action_frame="handle")
