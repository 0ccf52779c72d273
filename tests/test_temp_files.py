"""rik leaves nothing in the machine's temporary folder: LeRobot 0.6.1's ``PreTrainedConfig.from_pretrained`` copies
a policy's ``config.json`` into a named temporary file and never removes it, so every ``rik eval`` of a policy (each
of its worker processes) left a ``/tmp/tmpXXXXXXXX.json``; rik now reads the config it has checked
(:func:`rik.lerobot.policy_files.check_policy_folder`) instead."""

from __future__ import annotations

import dataclasses
import tempfile
from pathlib import Path

import pytest


@pytest.fixture(scope="module")
def policy(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from shared import tiny_act

    return tiny_act(tmp_path_factory.mktemp("tiny") / "policy")


@pytest.fixture
def temp_folder(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """An empty folder that this process's ``tempfile`` uses as the machine's temporary folder."""
    folder = tmp_path / "machine-tmp"
    folder.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(folder))
    return folder


def test_the_config_rik_checks_is_the_one_lerobot_loads(policy: Path, temp_folder: Path) -> None:
    """The config rik evaluates with equals LeRobot's own load of the folder, field for field; and LeRobot's load
    leaves its copy of the file behind (the reason rik does not call it)."""
    from lerobot.configs.policies import PreTrainedConfig

    from rik.lerobot.policy_files import check_policy_folder

    ours = check_policy_folder(policy)
    assert list(temp_folder.iterdir()) == []
    theirs = PreTrainedConfig.from_pretrained(policy)
    assert type(ours) is type(theirs) and dataclasses.asdict(ours) == dataclasses.asdict(theirs)
    assert [p.suffix for p in temp_folder.iterdir()] == [".json"]


def test_rik_eval_of_a_policy_leaves_nothing_in_the_temporary_folder(rik, policy: Path, temp_folder: Path,
                                                                     tmp_path: Path) -> None:
    r = rik("eval", str(policy), "--types", "knob", "--presets", "smooth", "-n", "1", "--videos", "0", "--workers",
            "1", "--episode-length", "5", "--out", str(tmp_path / "out"), "--variants", str(tmp_path / "variants"))
    assert r.code == 0, r.err[-3000:]
    assert (tmp_path / "out" / "table.md").is_file()
    assert list(temp_folder.iterdir()) == []
