"""The handle's shape in the front's state: ``rik export-lerobot --handle-shape full`` (a spec's ``handle_shape:
full``) ends ``observation.environment_state`` with the handle's type, mount and catalog grasp dimensions, ``kind``
with its type and mount alone; the environment appends the same numbers (``handle_shape=``), and ``rik eval`` /
``--env.handle_shape=auto`` read which it was trained with from its contract (tests/test_policy_io.py) or, for an
older policy, from its input width."""

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
    for handle in ("two_point/bow-128", "knob/mushroom-30"):  # kind: the type and mount flags alone
        full = handle_shape_state(catalog, handle)
        np.testing.assert_array_equal(handle_shape_state(catalog, handle, "kind"), full[:5])
    assert handle_shape_state(catalog, "knob/mushroom-30", "none").shape == (0,)


def test_an_export_with_the_handle_shape_appends_it_to_the_fronts_state(rik, knob_recording: Path,
                                                                       tmp_path: Path) -> None:
    from rik.lerobot.features import env_state_names
    from rik.lerobot.policy_io import PolicyIO
    from rik.sim.observation import ENV_STATE_NAMES, handle_shape_state

    episodes, variants = knob_recording / "episodes", knob_recording / "variants"
    states = {}
    for shape in ("none", "kind", "full"):
        r = rik("export-lerobot", str(episodes), "--out", str(tmp_path / shape), "--repo-id", f"local/{shape}",
                "--streams", "none", "--variants", str(variants), "--handle-shape", shape)
        assert r.code == 0, r
        states[shape] = _env_states(tmp_path / shape)
        info = json.loads((tmp_path / shape / "meta" / "info.json").read_text())
        assert info["features"]["observation.environment_state"]["names"] == list(env_state_names(shape))
        contract = PolicyIO.from_dataset(tmp_path / shape)  # its meta/rik_policy_io.json: tests/test_policy_io.py
        assert contract == PolicyIO(handle_shape=shape) and (tmp_path / shape / "meta" / "rik_policy_io.json").is_file()
        for key, feature in contract.features().items():  # the contract's features are the dataset's
            assert (info["features"][key]["names"], tuple(info["features"][key]["shape"])) == (
                feature["names"], feature["shape"]), key
    plain = states["none"]
    assert plain.shape[1] == len(ENV_STATE_NAMES) and states["full"].shape == (len(plain), 24)
    assert states["kind"].shape == (len(plain), 18)
    [episode] = list(episodes.iterdir())
    handle = json.loads((episode / "meta.json").read_text())["handle"]
    for shape in ("kind", "full"):
        np.testing.assert_array_equal(states[shape][:, :len(ENV_STATE_NAMES)], plain)  # the front's state unchanged
        expected = handle_shape_state(builtin_catalog(), handle, shape)
        np.testing.assert_allclose(states[shape][:, len(ENV_STATE_NAMES):], np.tile(expected, (len(plain), 1)),
                                   atol=1e-6)
        assert expected[0] == 1.0  # the episode's knob
    assert "**The handle's shape** (`--handle-shape full`" in (tmp_path / "full" / "README.md").read_text()
    assert "handle's shape" not in (tmp_path / "none" / "README.md").read_text()
    r = rik("export-lerobot", str(episodes), "--out", str(tmp_path / "bad"), "--repo-id", "local/bad", "--streams",
            "none", "--variants", str(variants), "--handle-shape", "yes")
    assert r.code == 2 and r.err.strip() == "rik: error: --handle-shape yes: use one of none, kind, full"
    assert not (tmp_path / "bad").exists() and not (tmp_path / "bad.partial").exists()


def test_a_spec_without_the_handle_shape_keeps_its_hash_and_a_bad_one_is_one_line(rik, tmp_path: Path) -> None:
    from rik.dataset.spec import spec_hash
    from rik.schemas.dataset import DatasetSpec

    base = {"repo_id": "local/x", "variants": {"ids": [BOW]}, "operators": [{"strategy": "planned"}]}
    assert spec_hash(DatasetSpec.model_validate(base)) == spec_hash(
        DatasetSpec.model_validate({**base, "handle_shape": "none"}))
    assert spec_hash(DatasetSpec.model_validate(base)) != spec_hash(
        DatasetSpec.model_validate({**base, "handle_shape": "kind"}))
    spec = tmp_path / "spec.yaml"
    spec.write_text(f"repo_id: local/x\nhandle_shape: true\nvariants:\n  ids: [{BOW}]\noperators:\n"
                    "  - strategy: planned\nstreams: []\n")
    r = rik("dataset", "build", str(spec), "--out", str(tmp_path / "ds"))
    assert r.code == 2 and r.err.strip() == (f"rik: error: {spec}:2, field 'handle_shape': input should be a valid "
                                             "string (got True)")
    spec.write_text(spec.read_text().replace("true", "kinds"))  # a string: the contract checks its value
    r = rik("dataset", "build", str(spec), "--out", str(tmp_path / "ds"))
    assert r.code == 2 and r.err.strip() == (f"rik: error: {spec}, field 'handle_shape': handle shape 'kinds': use one "
                                             "of none, kind, full")
    assert not (tmp_path / "ds").exists()


def test_the_environment_appends_the_drawn_handles_shape(bow_variants: Path) -> None:
    import gymnasium as gym

    import rik.envs.open_front  # noqa: F401
    from rik.lerobot.features import env_state_names
    from rik.sim.observation import ENV_STATE_NAMES, handle_shape_state

    envs = {shape: gym.make("rik/OpenFront-v0", variant=BOW, variants_dir=str(bow_variants), handle_shape=shape,
                            disable_env_checker=True).unwrapped for shape in ("none", "kind", "full")}
    obs = {shape: env.reset(seed=5)[0]["environment_state"] for shape, env in envs.items()}
    for shape, env in envs.items():
        width = len(env_state_names(shape))
        assert env.observation_space["environment_state"].shape == (width,) and obs[shape].shape == (width,)
        np.testing.assert_array_equal(obs[shape][:len(ENV_STATE_NAMES)], obs["none"])
        np.testing.assert_allclose(obs[shape][len(ENV_STATE_NAMES):],
                                   handle_shape_state(builtin_catalog(), "two_point/bow-128", shape), atol=1e-6)
    stepped = envs["full"].step(np.concatenate([envs["full"].scene.pose(), [0.0]]))[0]["environment_state"]
    np.testing.assert_array_equal(stepped[len(ENV_STATE_NAMES):], obs["full"][len(ENV_STATE_NAMES):])
    for env in envs.values():
        env.close()
    with pytest.raises(RikError, match=r"^handle_shape yes: use one of none, kind, full$"):
        gym.make("rik/OpenFront-v0", variant=BOW, variants_dir=str(bow_variants), handle_shape="yes")


def test_a_policys_input_width_says_which_handle_shape_it_reads(tmp_path: Path,
                                                                monkeypatch: pytest.MonkeyPatch) -> None:
    from lerobot_env_rik import RikEnvConfig, env_kwargs

    from rik.evaluation.evaluate import EvalSpec, env_config
    from rik.lerobot.policy_io import PolicyIO, read_policy

    plain, kind, full, odd = (act_config_folder(tmp_path / name, env_width=width)
                              for name, width in (("plain", 13), ("kind", 18), ("full", 24), ("odd", 20)))
    assert [read_policy(p).io.handle_shape for p in (plain, kind, full)] == ["none", "kind", "full"]
    with pytest.raises(RikError, match=r"^.*odd/config\.json: input 'observation\.environment_state' has shape \[20\]; "
                                       r"rik's environment supplies \[13\] \(or \[18\] or \[24\] or \[16\] or \[21\] or "
                                       r"\[27\] with the handle's shape or the grasp point from the gripper\)$"):
        read_policy(odd)
    assert RikEnvConfig().features["environment_state"].shape == (13,)  # auto, no policy: none
    assert RikEnvConfig(handle_shape="kind").features["environment_state"].shape == (18,)
    with pytest.raises(ValueError, match=r"^--env\.handle_shape=yes: use one of none, kind, full$"):
        RikEnvConfig(handle_shape="yes")
    monkeypatch.setattr("sys.argv", ["lerobot-eval", f"--policy.path={full}", "--env.type=rik"])
    config = RikEnvConfig()  # auto: as the command line's policy reads it
    assert config.handle_shape == "full" and env_kwargs(config)["io"].handle_shape == "full"
    spec = EvalSpec(operator=str(kind), io=PolicyIO(handle_shape="kind"))
    assert env_kwargs(env_config(spec))["io"].handle_shape == "kind"
