"""DART-style demonstrations (``rik record --action-noise``): the robot runs the strategy's target plus correlated
noise, the episode records the strategy's own action as the label and what was executed beside it, and replays
bit for bit from the executed one."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest
from shared import BOW

from rik.episodes.episode import EXECUTED, read_episode
from rik.episodes.record import record
from rik.episodes.replay import verify_episode
from rik.errors import RikError
from rik.registry import load_catalog

SECONDS = 2.5
"""Long enough for the approach, the close and the start of the pull."""


def _vectors(table, name: str) -> np.ndarray:
    return np.stack(table.column(name).to_numpy(zero_copy_only=False))


@pytest.fixture(scope="module")
def episodes(bow_variants: Path, tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    cat = load_catalog()
    out = tmp_path_factory.mktemp("noise")
    [plain] = record(cat, BOW, "planned", seed=4, out=out / "plain", variants=bow_variants, max_seconds=SECONDS)
    [noisy] = record(cat, BOW, "planned", seed=4, out=out / "noisy", variants=bow_variants, max_seconds=SECONDS,
                     params={"action_noise": 0.01})
    return {"plain": out / "plain" / plain.id, "noisy": out / "noisy" / noisy.id}


def test_the_noise_moves_the_robot_but_not_the_recorded_actions(episodes: dict[str, Path]) -> None:
    _, plain = read_episode(episodes["plain"])
    meta, noisy = read_episode(episodes["noisy"])
    assert meta.action_noise == 0.01 and EXECUTED in noisy.column_names
    label, executed = _vectors(noisy, "action"), _vectors(noisy, EXECUTED)
    offset = executed - label
    assert 0.003 < float(np.std(offset[:, :3])) < 0.03  # metres: the robot was sent the disturbed target
    assert np.all(offset[:, 6] == 0.0)  # the gripper command is never disturbed
    # the approach runs on the strategy's own commanded path, so until the gripper closes, the recorded action is
    # exactly the undisturbed episode's: none of the noise leaks into the labels
    closing = int(np.argmax(label[:, 6] > 0.5))
    assert closing > 10
    np.testing.assert_array_equal(label[:closing], _vectors(plain, "action")[:closing])
    # while the states differ: the noise did move the gripper
    assert float(np.max(np.abs(_vectors(noisy, "tcp")[:closing] - _vectors(plain, "tcp")[:closing]))) > 0.002


def test_a_noisy_episode_replays_exactly_from_what_was_executed(episodes: dict[str, Path],
                                                                 bow_variants: Path) -> None:
    check = verify_episode(load_catalog(), episodes["noisy"], bow_variants)
    assert check.exact and check.rows > 40


def test_an_episode_without_noise_keeps_its_old_layout(episodes: dict[str, Path]) -> None:
    meta = json.loads((episodes["plain"] / "meta.json").read_text(encoding="utf-8"))
    assert "action_noise" not in meta
    assert EXECUTED not in pq.read_schema(episodes["plain"] / "states.parquet").names


def test_an_unknown_strategy_parameter_is_one_line(bow_variants: Path, tmp_path: Path) -> None:
    with pytest.raises(RikError, match=r"^strategy planned: unknown parameter 'noise' \(parameters: jitter, "
                                       r"regrasps, action_noise\)$"):
        record(load_catalog(), BOW, "planned", out=tmp_path / "e", variants=bow_variants, params={"noise": 0.01})


def test_a_spec_operator_with_noise_hashes_apart_and_old_specs_keep_their_hash(tmp_path: Path) -> None:
    from rik.dataset.spec import load_spec, spec_hash

    example = Path(__file__).parents[1] / "examples" / "dataset-drawers.yaml"
    # the hash rik gave this spec before operators had action_noise (main at f47b46e): its datasets stay current
    assert spec_hash(load_spec(example)) == "ac4fc7fcddaee1f45a48277a3404af7e7f41d87865c923f00b8247ccd32d0509"
    noisy = tmp_path / "noisy.yaml"
    noisy.write_text(example.read_text(encoding="utf-8").replace("  - strategy: contact_rich\n",
                                                                 "  - strategy: contact_rich\n    action_noise: 0.01\n"))
    assert load_spec(noisy).operators[0].params == {"action_noise": 0.01}
    assert spec_hash(load_spec(noisy)) != spec_hash(load_spec(example))
