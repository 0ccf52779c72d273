"""A dataset and a policy without the simulator's state (issue 54): ``rik export-lerobot --no-environment-state``
writes the robot's own state and the cameras only, as a real robot would have them; the dataset loads with
LeRobot's ``LeRobotDataset`` and trains a step of ACT; the contract says so (``environment_state: false``), the
environment then gives no ``environment_state``, and the options that need the front's state are refused in one
line."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from rik.lerobot.features import OBS_ENV_STATE, OBS_STATE
from rik.lerobot.policy_io import POLICY_IO_FILE, PolicyIO

pytestmark = pytest.mark.slow  # an export with rendered streams and a training step


@pytest.fixture(scope="module")
def images_only(knob_recording: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The knob recording exported with the sim stream of both cameras at 32x24 px and no front's state."""
    from shared import cli

    root = tmp_path_factory.mktemp("images-only")
    shutil.copytree(knob_recording / "variants", root / "variants")
    cli("export-lerobot", str(knob_recording / "episodes"), "--out", str(root / "dataset"), "--repo-id",
        "local/images-only", "--streams", "sim", "--res", "32x24", "--no-environment-state", "--variants",
        str(root / "variants"), "--renders", str(root / "renders"))
    return root / "dataset"


def test_the_export_has_no_front_state_and_says_so(images_only: Path) -> None:
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    ds = LeRobotDataset("local/images-only", root=images_only, video_backend="pyav")
    assert OBS_ENV_STATE not in ds.meta.features
    assert {OBS_STATE, "observation.images.front", "observation.images.wrist", "action"} <= set(ds.meta.features)
    item = ds[0]
    assert OBS_ENV_STATE not in item and tuple(item["observation.images.front"].shape) == (3, 24, 32)
    card = " ".join((images_only / "README.md").read_text().split())
    assert "**No `observation.environment_state`** (`--no-environment-state`)" in card
    assert "(the front's state, 13 numbers)" not in card
    contract = json.loads((images_only / "meta" / POLICY_IO_FILE).read_text())
    assert contract["environment_state"] is False
    assert PolicyIO.from_dataset(images_only) == PolicyIO(cameras=("front", "wrist"), streams=("sim",),
                                                         image_size=(24, 32), environment_state=False)


def test_act_trains_a_step_on_the_images_and_the_robots_state(images_only: Path) -> None:
    """LeRobot's own factory makes ACT from the dataset's features (state and two cameras, no front's state) and
    one optimiser step changes its weights with a finite loss."""
    import torch
    from lerobot.datasets.lerobot_dataset import LeRobotDataset
    from lerobot.policies.act.configuration_act import ACTConfig
    from lerobot.policies.factory import make_policy, make_pre_post_processors

    ds = LeRobotDataset("local/images-only", root=images_only, video_backend="pyav",
                        delta_timestamps={"action": [k / 20 for k in range(4)]})  # chunks of 4 actions at 20 Hz
    config = ACTConfig(device="cpu", push_to_hub=False, pretrained_backbone_weights=None, dim_model=16,
                       dim_feedforward=32, n_heads=2, n_encoder_layers=1, n_decoder_layers=1, chunk_size=4,
                       n_action_steps=4, latent_dim=4, n_vae_encoder_layers=1)
    policy = make_policy(config, ds_meta=ds.meta)
    assert OBS_ENV_STATE not in policy.config.input_features
    assert {"observation.images.front", "observation.images.wrist"} <= set(policy.config.input_features)
    pre, _ = make_pre_post_processors(policy.config, dataset_stats=ds.meta.stats)
    batch = pre(next(iter(torch.utils.data.DataLoader(ds, batch_size=2, shuffle=False))))
    before = [p.detach().clone() for p in policy.parameters()]
    optimiser = torch.optim.AdamW(policy.parameters(), lr=1e-3)
    policy.train()
    loss, _ = policy.forward(batch)
    loss.backward()
    optimiser.step()
    assert np.isfinite(float(loss))
    assert any(not torch.equal(a, b) for a, b in zip(before, policy.parameters(), strict=True))


def test_the_environment_gives_no_front_state_to_such_a_policy(knob_recording: Path, tmp_path: Path) -> None:
    import gymnasium as gym

    from rik.lerobot.env_config import RikEnvConfig, env_features

    io = PolicyIO(cameras=("front",), streams=("sim",), image_size=(16, 16), environment_state=False)
    features, features_map = env_features(io)
    assert "environment_state" not in features and "agent_pos" in features
    assert RikEnvConfig.for_contract(io).io == io  # the option carries it to lerobot's config and back
    shutil.copytree(knob_recording / "variants", tmp_path / "variants")
    variant = next(p.name for p in (tmp_path / "variants").iterdir() if p.is_dir())
    env = gym.make("rik/OpenFront-v0", variant=variant, io=io, variants_dir=str(tmp_path / "variants"))
    try:
        obs, _ = env.reset(seed=0)
        assert set(obs) == {"agent_pos", "pixels"} and set(env.observation_space.spaces) == set(obs)
    finally:
        env.close()


@pytest.mark.parametrize(("extra", "message"), [
    (("--streams", "none"), "--no-environment-state: a policy without the front's state reads the robot's state "
                            "and images: give it streams (sim)"),
    (("--streams", "sim", "--handle-shape", "full"), "--no-environment-state: the handle's shape and the gripper "
                                                     "frame's grasp point are part of the front's state: use "
                                                     "handle_shape none and the world or handle frame"),
])
def test_options_that_need_the_front_state_are_refused_in_one_line(rik, knob_recording: Path, tmp_path: Path,
                                                                     extra: tuple[str, ...], message: str) -> None:
    res = rik("export-lerobot", str(knob_recording / "episodes"), "--out", str(tmp_path / "ds"), "--repo-id",
              "local/x", "--no-environment-state", *extra, "--variants", str(knob_recording / "variants"))
    assert res.code == 2 and "Traceback" not in res.err
    assert res.err.strip().splitlines() == [f"rik: error: {message}"], res.err
    assert not (tmp_path / "ds").exists()


def test_a_contract_that_drops_the_front_state_but_a_policy_that_reads_it_is_refused(tmp_path: Path) -> None:
    from shared import act_config_folder

    from rik.errors import RikError
    from rik.lerobot.policy_io import read_policy

    folder = act_config_folder(tmp_path / "policy", cameras=("front",), size=(16, 16))
    file = folder / POLICY_IO_FILE
    file.write_text(PolicyIO(cameras=("front",), streams=("sim",), image_size=(16, 16),
                             environment_state=False).to_json())
    with pytest.raises(RikError, match=rf"^{file}: field 'environment_state' is false, but the policy reads "
                                       r"observation.environment_state: the policy was not trained on that dataset$"):
        read_policy(folder)
    file.write_text(file.read_text().replace("false", '"no"'))
    with pytest.raises(RikError, match=rf"^{file}: field 'environment_state': 'no' is not true or false$"):
        read_policy(folder)
