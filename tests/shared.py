"""What many test files share: the built-in catalog, loaded once per test process, the ids of the demo's variant,
and a way to run ``rik`` in this process from a module fixture. Session fixtures that build from them live in
``conftest.py``."""

from __future__ import annotations

import functools
import sys
from typing import TYPE_CHECKING, Any

import pytest

if TYPE_CHECKING:
    from pathlib import Path

    from rik.episodes.operators import ScriptedGrasp
    from rik.registry.catalog import Catalog
    from rik.sim.scene import SimScene

BOW = "drawer-chest-80__two_point-bow-128__normal"
"""The demo's first variant: the 80 cm chest of drawers with the 128 mm bow handle, normal resistance."""
BOW_HANDLE, DEMO_BASE = "two_point/bow-128", "drawer/chest-80"


@functools.cache
def builtin_catalog() -> Catalog:
    """The built-in catalog (no overlays), loaded once per process; treat it as read-only."""
    from rik.registry.load import load_catalog

    return load_catalog([])


def grasp_until_pull(scene: SimScene, max_steps: int, strategy: str = "grasp_vertical") -> ScriptedGrasp:
    """Run ``strategy`` (seed 0, start randomised as a recording does) on ``scene`` until its jaws have closed and
    it starts to pull, or for ``max_steps`` control steps; the operator, for the caller to check its phase."""
    import numpy as np

    from rik.episodes.operators import make_operator
    from rik.episodes.record import randomise_start

    rng = np.random.default_rng(0)
    randomise_start(scene, rng)
    op = make_operator(strategy)
    op.reset(scene, rng)
    for _ in range(max_steps):
        if op._phase == "pull":
            break
        scene.step(op.act(scene))
    return op


def act_config_folder(folder: Path, cameras: tuple[str, ...] = (), size: tuple[int, int] = (72, 96),
                      env_width: int = 13) -> Path:
    """A saved ACT config (LeRobot's own writer, no weights) in the new ``folder`` that reads the Hand-E's state, a
    front's state ``env_width`` numbers wide and ``cameras`` at ``size`` (height, width)."""
    from lerobot.configs import FeatureType, PolicyFeature
    from lerobot.policies.act.configuration_act import ACTConfig

    inputs = {"observation.state": PolicyFeature(type=FeatureType.STATE, shape=(11,)),
              "observation.environment_state": PolicyFeature(type=FeatureType.ENV, shape=(env_width,))}
    for camera in cameras:
        inputs[f"observation.images.{camera}"] = PolicyFeature(type=FeatureType.VISUAL, shape=(3, *size))
    config = ACTConfig(input_features=inputs,
                       output_features={"action": PolicyFeature(type=FeatureType.ACTION, shape=(7,))},
                       device="cpu", push_to_hub=False)
    folder.mkdir()
    config._save_pretrained(folder)
    return folder


def save_untrained(policy: Any, folder: Path, contract: str | None = None) -> Path:
    """Save ``policy`` (a LeRobot policy, weights as made) into ``folder`` as LeRobot does, with its processors
    (statistics of zero mean and unit deviation for each of its features) and, where given, rik's contract (the
    JSON of a :class:`~rik.lerobot.policy_io.PolicyIO`)."""
    import torch
    from lerobot.policies.factory import make_pre_post_processors

    from rik.lerobot.policy_io import POLICY_IO_FILE

    config = policy.config
    stats = {}
    for key, feature in {**config.input_features, **config.output_features}.items():
        per_channel = [1, 1] if len(feature.shape) == 3 else []  # an image's: one per channel
        stats[key] = {"mean": torch.zeros(feature.shape[0], *per_channel),
                      "std": torch.ones(feature.shape[0], *per_channel)}
    pre, post = make_pre_post_processors(config, dataset_stats=stats)
    for part in (policy, pre, post):
        part.save_pretrained(folder)
    if contract is not None:
        (folder / POLICY_IO_FILE).write_text(contract)
    return folder


def tiny_act(folder: Path) -> Path:
    """A tiny state-only ACT policy for the Hand-E (11 state numbers, the front's 13, 7 actions; untrained), saved
    by LeRobot into the new ``folder`` with its processors."""
    from lerobot.configs.types import FeatureType, PolicyFeature
    from lerobot.policies.act.configuration_act import ACTConfig
    from lerobot.policies.act.modeling_act import ACTPolicy

    config = ACTConfig(
        device="cpu", push_to_hub=False, pretrained_backbone_weights=None, dim_model=8, dim_feedforward=16,
        n_heads=2, n_encoder_layers=1, n_decoder_layers=1, chunk_size=2, n_action_steps=2, latent_dim=4,
        use_vae=False,
        input_features={"observation.state": PolicyFeature(FeatureType.STATE, (11,)),
                        "observation.environment_state": PolicyFeature(FeatureType.ENV, (13,))},
        output_features={"action": PolicyFeature(FeatureType.ACTION, (7,))})
    return save_untrained(ACTPolicy(config), folder)


def cli(*args: str, cwd: Path | None = None) -> None:
    """Run ``rik ARGS...`` in this process (as the ``rik`` fixture does, for module fixtures; from ``cwd`` where
    given); it must succeed."""
    from rik.cli.app import main

    with pytest.MonkeyPatch.context() as mp:
        if cwd is not None:
            mp.chdir(cwd)
        mp.setattr(sys, "argv", ["rik", *args])
        try:
            main()
        except SystemExit as exc:
            assert exc.code in (0, None), f"rik {' '.join(args)} exited with {exc.code}"
