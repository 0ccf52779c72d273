"""The handle's shape in the front's state: ``rik export-lerobot --handle-shape`` (a spec's ``handle_shape: true``)
ends ``observation.environment_state`` with the handle's type, mount and catalog grasp dimensions, the environment
appends the same numbers with ``handle_shape=True``, and ``rik eval`` / ``--env.handle_shape=auto`` read from a
policy's input width whether it was trained with them."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from shared import BOW, act_config_folder, builtin_catalog

from rik.errors import RikError


def _env_states(root: Path) -> np.ndarray:
    import pyarrow.parquet as pq

    table = pq.read_table(sorted((root / "data").rglob("*.parquet"))[0])
    return np.stack(table.column("observation.environment_state").to_numpy(zero_copy_only=False)).astype(np.float64)


def test_the_handle_shape_follows_the_catalog() -> None:
    from rik.sim.observation import HANDLE_SHAPE_NAMES, handle_shape_state

    catalog = builtin_catalog()
    bow = dict(zip(HANDLE_SHAPE_NAMES, handle_shape_state(catalog, "two_point/bow-128"), strict=True))
    geometry = catalog.handles["two_point/bow-128"].geometry
    assert (bow["handle_knob"], bow["handle_two_point"], bow["handle_finger_pull"]) == (0.0, 1.0, 0.0)
    assert (bow["handle_edge_clip"], bow["handle_inset"]) == (0.0, 0.0)
    assert bow["handle_length"] == pytest.approx(geometry.length) and bow["handle_length"] > 0.1  # m, not mm
    assert geometry.clearance is not None and bow["handle_clearance_width"] == pytest.approx(geometry.clearance.width)
    kinds = {catalog.handle_type(h).value: handle_shape_state(catalog, h.id)[:3] for h in catalog.handles.values()}
    assert {k: v.tolist() for k, v in kinds.items()} == {"knob": [1, 0, 0], "two_point": [0, 1, 0],
                                                         "finger_pull": [0, 0, 1]}
    mounts = {h.mount.kind: handle_shape_state(catalog, h.id)[3:5].tolist() for h in catalog.handles.values()}
    assert mounts["edge_clip"] == [1, 0] and mounts["inset"] == [0, 1] and mounts["single_screw"] == [0, 0]


def test_an_export_with_the_handle_shape_appends_it_to_the_fronts_state(rik, knob_recording: Path,
                                                                       tmp_path: Path) -> None:
    from rik.sim.observation import ENV_STATE_NAMES, SHAPED_ENV_STATE_NAMES, handle_shape_state

    episodes, variants = knob_recording / "episodes", knob_recording / "variants"
    for name, flags in (("plain", ()), ("shaped", ("--handle-shape",))):
        r = rik("export-lerobot", str(episodes), "--out", str(tmp_path / name), "--repo-id", f"local/{name}",
                "--streams", "none", "--variants", str(variants), *flags)
        assert r.code == 0, r
    plain, shaped = _env_states(tmp_path / "plain"), _env_states(tmp_path / "shaped")
    assert plain.shape[1] == len(ENV_STATE_NAMES) and shaped.shape == (len(plain), len(SHAPED_ENV_STATE_NAMES))
    np.testing.assert_array_equal(shaped[:, :len(ENV_STATE_NAMES)], plain)  # the front's state unchanged
    [episode] = list(episodes.iterdir())
    handle = json.loads((episode / "meta.json").read_text())["handle"]
    expected = handle_shape_state(builtin_catalog(), handle)
    np.testing.assert_allclose(shaped[:, len(ENV_STATE_NAMES):], np.tile(expected, (len(shaped), 1)), atol=1e-6)
    assert expected[0] == 1.0  # the episode's knob
    info = json.loads((tmp_path / "shaped" / "meta" / "info.json").read_text())
    assert info["features"]["observation.environment_state"]["names"] == list(SHAPED_ENV_STATE_NAMES)
    assert "**The handle's shape** (`--handle-shape`" in (tmp_path / "shaped" / "README.md").read_text()
    assert "handle's shape" not in (tmp_path / "plain" / "README.md").read_text()


def test_a_spec_without_the_handle_shape_keeps_its_hash() -> None:
    from rik.dataset.spec import spec_hash
    from rik.schemas.dataset import DatasetSpec

    base = {"repo_id": "local/x", "variants": {"ids": [BOW]}, "operators": [{"strategy": "planned"}]}
    assert spec_hash(DatasetSpec.model_validate(base)) == spec_hash(
        DatasetSpec.model_validate({**base, "handle_shape": False}))
    assert spec_hash(DatasetSpec.model_validate(base)) != spec_hash(
        DatasetSpec.model_validate({**base, "handle_shape": True}))


def test_the_environment_appends_the_drawn_handles_shape(bow_variants: Path) -> None:
    import gymnasium as gym

    import rik.envs.open_front  # noqa: F401
    from rik.sim.observation import ENV_STATE_NAMES, SHAPED_ENV_STATE_NAMES, handle_shape_state

    envs = {shape: gym.make("rik/OpenFront-v0", variant=BOW, variants_dir=str(bow_variants), handle_shape=shape,
                            disable_env_checker=True).unwrapped for shape in (False, True)}
    obs = {shape: env.reset(seed=5)[0]["environment_state"] for shape, env in envs.items()}
    assert envs[True].observation_space["environment_state"].shape == (len(SHAPED_ENV_STATE_NAMES),)
    assert obs[False].shape == (len(ENV_STATE_NAMES),) and obs[True].shape == (len(SHAPED_ENV_STATE_NAMES),)
    np.testing.assert_array_equal(obs[True][:len(ENV_STATE_NAMES)], obs[False])
    np.testing.assert_allclose(obs[True][len(ENV_STATE_NAMES):],
                               handle_shape_state(builtin_catalog(), "two_point/bow-128"), atol=1e-6)
    stepped = envs[True].step(np.concatenate([envs[True].scene.pose(), [0.0]]))[0]["environment_state"]
    np.testing.assert_array_equal(stepped[len(ENV_STATE_NAMES):], obs[True][len(ENV_STATE_NAMES):])
    for env in envs.values():
        env.close()


def test_a_policys_input_width_says_whether_it_reads_the_handle_shape(tmp_path: Path,
                                                                      monkeypatch: pytest.MonkeyPatch) -> None:
    from lerobot_env_rik import RikEnvConfig, env_kwargs

    from rik.evaluation.evaluate import EvalSpec, env_config
    from rik.evaluation.load import policy_needs

    plain, shaped, odd = (act_config_folder(tmp_path / name, env_width=width)
                          for name, width in (("plain", 13), ("shaped", 24), ("odd", 20)))
    assert policy_needs(plain).handle_shape is False and policy_needs(shaped).handle_shape is True
    with pytest.raises(RikError, match=r"^.*odd/config\.json: input 'observation\.environment_state' has shape \[20\]; "
                                       r"rik's environment supplies \[13\] \(or \[24\] with the handle's shape\)$"):
        policy_needs(odd)
    assert RikEnvConfig().features["environment_state"].shape == (13,)  # auto, no policy: without
    assert RikEnvConfig(handle_shape="true").features["environment_state"].shape == (24,)
    with pytest.raises(ValueError, match=r"^--env\.handle_shape='yes': use one of auto, true, false$"):
        RikEnvConfig(handle_shape="yes")
    monkeypatch.setattr("sys.argv", ["lerobot-eval", f"--policy.path={shaped}", "--env.type=rik"])
    config = RikEnvConfig()  # auto: as the command line's policy reads it
    assert config.handle_shape == "true" and env_kwargs(config)["handle_shape"] is True
    spec = EvalSpec(operator=str(shaped), needs={"cameras": (), "streams": ("sim",), "image_size": (96, 128),
                                                 "handle_shape": True})
    assert env_kwargs(env_config(spec))["handle_shape"] is True
