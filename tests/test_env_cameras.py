"""``--env.cameras=auto`` (the default): ``lerobot-eval --env.type=rik --policy.path=<an image policy>`` renders the
cameras the policy reads instead of ending in ``KeyError: 'observation.images.front'`` inside it; cameras given by
hand that leave one out are refused, naming it."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest
from shared import act_config_folder

# lerobot (torch, datasets, pandas: ~6 s) is imported by the tests that use it, not at collection, which every
# xdist worker of every run pays, the everyday tier's included


def _env_config(**fields: object):
    """The plugin's ``RikEnvConfig(**fields)``, as lerobot-eval makes it."""
    from lerobot_env_rik import RikEnvConfig

    return RikEnvConfig(**fields)


def _argv(monkeypatch: pytest.MonkeyPatch, *args: str) -> None:
    monkeypatch.setattr(sys, "argv", ["lerobot-eval", "--env.type=rik", *args])


def test_auto_cameras_follow_the_command_lines_imageact_config_folder(monkeypatch, tmp_path: Path) -> None:
    policy = act_config_folder(tmp_path / "act", ("front", "wrist"))
    _argv(monkeypatch, f"--policy.path={policy}")
    cfg = _env_config()
    assert cfg.cameras == "front,wrist" and cfg.streams == "sim"
    assert (cfg.observation_height, cfg.observation_width) == (72, 96)
    assert cfg.features["pixels/front"].shape == (72, 96, 3)
    assert cfg.features_map["pixels/wrist"] == "observation.images.wrist"


def test_auto_cameras_are_none_for_a_state_policy_or_without_one(monkeypatch, tmp_path: Path) -> None:
    _argv(monkeypatch, f"--policy.path={act_config_folder(tmp_path / 'act', ())}")
    assert _env_config().cameras == ""
    _argv(monkeypatch)
    cfg = _env_config()
    assert cfg.cameras == "" and not any(k.startswith("pixels/") for k in cfg.features)


def test_cameras_that_leave_out_the_policys_image_are_refused(monkeypatch, tmp_path: Path) -> None:
    policy = act_config_folder(tmp_path / "act", ("front",))
    _argv(monkeypatch, f"--policy.path={policy}")
    with pytest.raises(ValueError, match=r"^--env.cameras='' --env.streams='sim': the policy in .*act reads "
                                         r"observation.images.front, which they do not render; leave --env.cameras "
                                         r"out \(it then follows the policy\) or pass --env.cameras=front$"):
        _env_config(cameras="")
    with pytest.raises(ValueError, match=r"reads 72x96 images; pass --env.observation_height=72"):
        _env_config(cameras="front")
    assert _env_config(cameras="front,wrist", observation_height=72, observation_width=96).cameras == "front,wrist"
