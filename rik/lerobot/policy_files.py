"""A saved policy's folder checked before LeRobot reads any of it: a folder from elsewhere is data, never code.

LeRobot 0.6.1 trusts the folder. ``DataProcessorPipeline.from_pretrained`` resolves each step of
``policy_preprocessor.json`` / ``policy_postprocessor.json`` by its ``"registry_name"`` (a look-up in
``ProcessorStepRegistry``) or its ``"class"`` (``importlib.import_module`` of the module part, ``getattr`` of the
last part) and calls the result with the step's ``"config"`` before anything checks it is a processor step, so
``{"class": "subprocess.Popen", "config": {"args": [...]}}`` runs a command. Being registered, or living inside
``lerobot``, is not enough either: the registered ``action_tokenizer_processor`` loads a tokenizer named in its
config with ``trust_remote_code=True`` (its default), ``reward_classifier_processor`` builds a model named in its
config whose encoder loads with ``trust_remote_code=True``; and several policy types (``pi0_fast``, ``groot``,
``gaussian_actor``, ``wall_x``, ...) load models or code named in ``config.json`` when they are built.

So rik accepts only what it has read:

- policy types :data:`POLICY_TYPES` (``act``, ``diffusion``, ``tdmpc``, ``vqbet``): their models are built from
  ``config.json``'s numbers alone (an image backbone is one of torchvision's registered model builders);
- processor steps :data:`STEPS`, the five steps LeRobot's ``make_default_pre_post_processors`` writes for those
  types, named by ``registry_name`` or by their exact class path; nothing a folder names is ever imported;
- every file read (the JSON files, the steps' ``state_file``, ``model.safetensors``) is a regular file inside the
  folder (no ``..``, no absolute path, no symbolic link out of it); the JSON files are at most
  :data:`MAX_JSON_BYTES`, checked before they are read; ``config.json``'s fields have the types LeRobot's config
  class declares (draccus's own complaints are turned into one line naming the field), and every number of it that
  sizes something LeRobot allocates (:data:`SIZES`; a feature's shape, :data:`MAX_FEATURE_NUMBERS`) is within a
  bound, checked before anything is built (a diffusion policy's ``num_train_timesteps`` sizes the arrays its noise
  scheduler makes at once; ACT's ``chunk_size`` a table of Python floats);
- every field of a processor step's config has the type and a value the step can run with (:data:`STEP_CHECKS`:
  a normaliser's ``eps`` a small positive number, its features those of ``config.json``; a device one rik can
  use), checked before LeRobot builds the steps;
- weights are safetensors, read through their header only (no pickle anywhere): ``model.safetensors`` has
  exactly the tensors, with the shapes, of the model ``config.json`` describes (built on PyTorch's ``meta`` device,
  which allocates nothing; at most :data:`MAX_PARAMETERS` of them), and a normaliser's state file has every
  statistic its features need, of their shapes (LeRobot's normaliser silently skips a feature whose statistics are
  missing).

Anything else is a one-line :class:`rik.errors.RikError` naming the file, the step and the field.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path, PurePosixPath
from typing import TYPE_CHECKING, Any

from rik.errors import RikError

if TYPE_CHECKING:
    import torch

CONFIG = "config.json"
WEIGHTS = "model.safetensors"
PROCESSORS = ("policy_preprocessor.json", "policy_postprocessor.json")
MAX_JSON_BYTES = 16 * 2**20
"""Largest JSON file of a policy folder rik reads (LeRobot's are a few kB)."""
POLICY_TYPES = ("act", "diffusion", "tdmpc", "vqbet")
"""Policy types whose models are built from ``config.json``'s numbers alone, loading nothing by name."""
STEPS = ("rename_observations_processor", "to_batch_processor", "device_processor", "normalizer_processor",
         "unnormalizer_processor")
"""Processor steps a policy folder may name: those LeRobot writes for :data:`POLICY_TYPES`."""
STEP_FIELDS = ("registry_name", "class", "config", "state_file")
NORMALISERS = ("normalizer_processor", "unnormalizer_processor")
STATISTICS = {"MEAN_STD": ("mean", "std"), "MIN_MAX": ("min", "max"), "QUANTILES": ("q01", "q99"),
              "QUANTILE10": ("q10", "q90"), "IDENTITY": ()}
"""The statistics each normalisation mode reads (LeRobot's ``_NormalizationMixin._apply_transform``)."""
FEATURE_TYPES = ("STATE", "VISUAL", "ENV", "ACTION", "REWARD", "LANGUAGE")
MAX_FEATURE_NUMBERS = 2**22
"""Most numbers in one feature (its shape's product): a 3 x 1080 x 1280 image fits. Images are rendered at the
size a policy's feature gives, and its state vectors size its layers."""
MAX_FEATURE_DIMS = 3
"""Most dimensions of a feature's shape (an image's channels, height and width)."""
MAX_PARAMETERS = 2**30
"""Most parameters (and buffers) of a model rik eval builds: 4 GiB of float32; LeRobot's largest default of these
types, diffusion's, has about 263 million."""

Bound = tuple[int, int | tuple[str, ...]]
"""(least, most) of an integer field, or of each integer of a list field; most is a number or the fields of the
same config whose sum bounds it."""
SIZES: dict[str, dict[str, Bound]] = {
    "act": {
        "n_obs_steps": (1, 64), "chunk_size": (1, 1024), "n_action_steps": (1, 1024),
        "replace_final_stride_with_dilation": (0, 1), "dim_model": (1, 4096), "n_heads": (1, 128),
        "dim_feedforward": (1, 16384), "n_encoder_layers": (0, 64), "n_decoder_layers": (0, 64),
        "latent_dim": (1, 4096), "n_vae_encoder_layers": (0, 64),
    },
    "diffusion": {
        "n_obs_steps": (1, 64), "horizon": (1, 1024), "n_action_steps": (1, ("horizon",)),
        "resize_shape": (1, 2048), "crop_shape": (1, 2048), "spatial_softmax_num_keypoints": (1, 1024),
        "down_dims": (1, 8192), "kernel_size": (1, 64), "n_groups": (1, 1024), "diffusion_step_embed_dim": (1, 8192),
        "num_train_timesteps": (1, 10_000), "num_inference_steps": (1, ("num_train_timesteps",)),
    },
    "tdmpc": {
        "n_obs_steps": (1, 64), "n_action_repeats": (1, 64), "horizon": (1, 256), "n_action_steps": (1, ("horizon",)),
        "image_encoder_hidden_dim": (1, 4096), "state_encoder_hidden_dim": (1, 16384), "latent_dim": (1, 4096),
        "q_ensemble_size": (1, 64), "mlp_dim": (1, 16384), "cem_iterations": (1, 256),
        "n_gaussian_samples": (1, 8192), "n_pi_samples": (0, 8192),
        "n_elites": (1, ("n_gaussian_samples", "n_pi_samples")),
    },
    "vqbet": {
        "n_obs_steps": (1, 64), "n_action_pred_token": (1, 64), "action_chunk_size": (1, 256),
        "crop_shape": (1, 2048), "spatial_softmax_num_keypoints": (1, 1024), "vqvae_n_embed": (1, 4096),
        "vqvae_embedding_dim": (1, 4096), "vqvae_enc_hidden_dim": (1, 8192), "gpt_block_size": (1, 4096),
        "gpt_input_dim": (1, 8192), "gpt_output_dim": (1, 8192), "gpt_n_layer": (1, 64), "gpt_n_head": (1, 128),
        "gpt_hidden_dim": (1, 8192),
    },
}
"""Every integer field of a policy type's config that sizes what LeRobot builds or allocates when it runs the
policy (layers, buffers, the noise scheduler's tables, the planner's samples, the images it crops), with its bounds:
10 to 100 times LeRobot's defaults, so that no folder makes rik eval allocate more than a few GB. A field of a list
(``down_dims``, ``crop_shape``) bounds each of its numbers."""
TRAINING_ONLY = ("drop_n_last_frames", "scheduler_warmup_steps", "n_vqvae_training_steps")
"""Integer fields read by ``lerobot-train`` only (they size nothing rik eval runs)."""
MAX_LIST = 16
"""Most numbers of a list field of :data:`SIZES` (``down_dims`` has 3, a crop shape 2)."""
_QUOTE = 60


def _short(value: Any) -> str:
    """A value as JSON writes it, cut short."""
    text = json.dumps(value, default=str) if not isinstance(value, str) else repr(value)
    return text if len(text) <= _QUOTE else text[:_QUOTE] + "..."


def _clip(text: str) -> str:
    """The first line of ``text``, at most 300 characters."""
    lines = text.strip().splitlines()
    line = lines[0] if lines else ""
    return line if len(line) <= 300 else line[:300] + "..."


def _first_line(error: BaseException) -> str:
    return _clip(str(error)) or type(error).__name__


def member(root: Path, name: str, where: str) -> Path:
    """``root / name``: a regular file inside the folder ``root`` (no ``..``, no absolute path, no symbolic link
    out of it). ``where`` starts the message otherwise: the file itself, or the file, step and field naming it."""
    rel = PurePosixPath(name)
    if not name or "\x00" in name or "\\" in name or rel.is_absolute() or ".." in rel.parts:
        raise RikError(f"{where}: {_short(name)} is not a file name inside the policy folder (no '..', no "
                       "absolute path)")
    path = Path(root) / name
    label = "" if where == str(path) else f"{path} "
    try:
        real = path.resolve()
    except (OSError, RuntimeError) as e:  # a symbolic link loop
        raise RikError(f"{where}: {label}cannot be resolved ({e})") from None
    if not real.is_relative_to(Path(root).resolve()):
        raise RikError(f"{where}: {label}leads to {real}, outside the policy folder (a symbolic link out of it); "
                       "copy the file into the folder")
    if not real.is_file():
        raise RikError(f"{where}: {label}is missing or not a regular file")
    return path


def read_json(root: Path, name: str) -> Any:
    """The JSON file ``root / name`` (see :func:`member`), refused unread when larger than
    :data:`MAX_JSON_BYTES`."""
    from rik import paths

    file = member(root, name, f"{Path(root) / name}")
    try:
        if file.stat().st_size > MAX_JSON_BYTES:
            raise RikError(f"{file}: larger than {MAX_JSON_BYTES // 2**20} MiB; a policy's JSON files are a few kB")
        return paths.read_json(file, MAX_JSON_BYTES)
    except OSError as e:
        raise RikError(f"{file}: not readable ({e})") from None
    except ValueError as e:  # not UTF-8, not JSON, nested too deeply (or grown past the bound since the stat)
        raise RikError(f"{file}: not readable JSON ({_first_line(e)})") from None


# ---- config.json ---------------------------------------------------------------------------------------------
def config_class(file: Path, data: dict[str, Any]) -> type:
    """LeRobot's config class of the policy type ``data["type"]``, which must be one of :data:`POLICY_TYPES`."""
    import lerobot.policies  # noqa: F401  (registers the policy types)
    from lerobot.configs.policies import PreTrainedConfig

    kind = data.get("type")
    if not isinstance(kind, str):
        raise RikError(f"{file}: field 'type' (the policy type, e.g. act) is missing")
    known = PreTrainedConfig.get_known_choices()
    if kind not in known:
        raise RikError(f"{file}: field 'type': {_short(kind)} is not a LeRobot policy type (rik eval runs "
                       f"{', '.join(POLICY_TYPES)})")
    if kind not in POLICY_TYPES:
        raise RikError(f"{file}: field 'type': rik eval runs {', '.join(POLICY_TYPES)} policies; '{kind}' policies "
                       "load models or code named in config.json when they are built, which rik does not do for a "
                       "folder it did not make (lerobot-eval runs them)")
    return PreTrainedConfig.get_choice_class(kind)


def _plain_kind(hint: Any) -> tuple[type | None, bool]:
    """(int, float, bool or str, whether None is allowed) of a simple field's type; (None, _) for others."""
    import types
    import typing

    optional = False
    if typing.get_origin(hint) in (typing.Union, types.UnionType):
        args = [a for a in typing.get_args(hint) if a is not type(None)]
        optional = len(args) < len(typing.get_args(hint))
        if len(args) != 1:
            return None, optional
        hint = args[0]
    return (hint if hint in (int, float, bool, str) else None), optional


def _wrong_type(value: Any, kind: type) -> bool:
    """Whether a JSON value is not of a simple field's type (an int field takes true and false as Python does:
    LeRobot's own ``replace_final_stride_with_dilation: int = False`` is written so)."""
    if kind is bool:
        return not isinstance(value, bool)
    if kind is int:
        return not isinstance(value, int)
    if kind is float:
        return isinstance(value, bool) or not isinstance(value, (int, float))
    return not isinstance(value, str)


_NAMES = {int: "an integer", float: "a number", bool: "true or false", str: "a string"}


def _check_features(where: str, field: str, value: Any) -> None:
    """An object of LeRobot features (``{"type": "STATE", "shape": [11]}``); ``where`` starts the message, whose
    field is ``field.<key>``."""
    if not isinstance(value, dict):
        raise RikError(f"{where} field '{field}': {_short(value)} is not an object of features")
    for key, feature in value.items():
        name = f"{where} field '{field}.{key}"
        if not isinstance(feature, dict) or set(feature) != {"type", "shape"}:
            raise RikError(f"{name}': a feature is an object with 'type' and 'shape' (got {_short(feature)})")
        if feature["type"] not in FEATURE_TYPES:
            raise RikError(f"{name}.type': {_short(feature['type'])} is not one of {', '.join(FEATURE_TYPES)}")
        shape = feature["shape"]
        if (not isinstance(shape, list) or not shape
                or any(isinstance(n, bool) or not isinstance(n, int) or n < 1 for n in shape)):
            raise RikError(f"{name}.shape': {_short(shape)} is not a list of positive integers")
        if len(shape) > MAX_FEATURE_DIMS or math.prod(shape) > MAX_FEATURE_NUMBERS:
            raise RikError(f"{name}.shape': {_short(shape)} is more than rik eval runs: at most {MAX_FEATURE_DIMS} "
                           f"dimensions of at most {MAX_FEATURE_NUMBERS} numbers in all (a 3 x 1080 x 1280 image)")


def _size_defaults(cls: type, kind: str) -> dict[str, Any]:
    """The defaults of the fields of :data:`SIZES` of the config class ``cls`` of policy type ``kind``."""
    import dataclasses

    out: dict[str, Any] = {}
    for field in dataclasses.fields(cls):
        if field.name in SIZES[kind]:
            factory = field.default_factory
            out[field.name] = field.default if factory is dataclasses.MISSING else factory()
    return out


def _most(values: dict[str, Any], most: int | tuple[str, ...]) -> tuple[int, str]:
    """The largest value a bound allows, given the config's ``values``, and the fields it comes from."""
    if isinstance(most, int):
        return most, ""
    return sum(values[f] for f in most), f" (its {' + '.join(most)})"


def check_sizes(file: Path, cls: type, data: dict[str, Any]) -> None:
    """Every field of :data:`SIZES` of ``config.json``'s ``data`` (a policy type's, of class ``cls``; LeRobot's
    default where the file has none) within its bounds: read before LeRobot parses, builds or allocates anything."""
    import typing

    kind = data["type"]
    hints = typing.get_type_hints(cls)
    values = {**_size_defaults(cls, kind), **{k: v for k, v in data.items() if k in SIZES[kind]}}
    for name, (least, most) in SIZES[kind].items():
        value = values[name]
        if value is None:
            continue
        top, source = _most(values, most)
        listed = "tuple[" in str(hints[name])  # down_dims, crop_shape, resize_shape
        numbers = value if listed and isinstance(value, (list, tuple)) else [value]
        if (listed and not (isinstance(value, (list, tuple)) and 0 < len(value) <= MAX_LIST)) or any(
                not isinstance(n, int) or not least <= n <= top for n in numbers):  # true, false: 1, 0 (_wrong_type)
            what = f"a list of 1 to {MAX_LIST} integers, each" if listed else "an integer"
            raise RikError(f"{file}: field '{name}': {_short(value)} is not {what} from {least} to {top}{source}; "
                           "it sizes what LeRobot builds for the policy")


def parsed_config(policy_dir: Path, data: dict[str, Any]) -> Any:
    """``config.json``'s fields checked against LeRobot's config class of its type, and the config parsed as
    LeRobot parses it (draccus), without a traceback."""
    import dataclasses
    import typing

    import draccus
    from draccus.utils import DecodingError, ParsingError

    file = Path(policy_dir) / CONFIG
    cls = config_class(file, data)
    fields = {f.name: f for f in dataclasses.fields(cls) if f.init}
    hints = typing.get_type_hints(cls)
    for key, value in data.items():
        if key == "type":
            continue
        if key not in fields:
            raise RikError(f"{file}: field '{key}': not a field of LeRobot's {data['type']} config")
        if key in ("input_features", "output_features"):
            _check_features(f"{file}:", key, value)
            continue
        kind, optional = _plain_kind(hints.get(key))
        if kind is not None and not (value is None and optional) and _wrong_type(value, kind):
            raise RikError(f"{file}: field '{key}': {_short(value)} is not {_NAMES[kind]}"
                           f"{' or null' if optional else ''}")
    if data.get("use_peft"):
        raise RikError(f"{file}: field 'use_peft': rik eval runs policies whose whole weights are in {WEIGHTS}, "
                       "not PEFT adapters")
    backbone = data.get("vision_backbone")
    if backbone is not None:
        import torchvision

        if backbone not in torchvision.models.list_models(module=torchvision.models):
            raise RikError(f"{file}: field 'vision_backbone': {_short(backbone)} is not one of torchvision's "
                           "image models (e.g. resnet18)")
    check_sizes(file, cls, data)
    body = {k: v for k, v in data.items() if k != "type"}
    try:
        config = draccus.decode(cls, body)
    except DecodingError as e:
        field = ".".join(map(str, e.key_path))
        where = f"field '{field}'" if field else "its fields"
        raise RikError(f"{file}: {where}: {_clip(e.message)}") from None
    except (ParsingError, ValueError, TypeError, KeyError) as e:
        cause = e.__cause__ or e
        raise RikError(f"{file}: LeRobot's {data['type']} config refuses it: {_first_line(cause)}") from None
    problem = _device_problem(config.device, available=True)
    if problem:
        raise RikError(f"{file}: field 'device': {_short(config.device)} {problem}")
    return config


# ---- safetensors -------------------------------------------------------------------------------------------
def tensor_shapes(file: Path, where: str) -> dict[str, tuple[int, ...]]:
    """Names and shapes of the tensors of a safetensors file, read from its header only (a file that is not
    safetensors, or is truncated, is one line naming ``where``)."""
    from safetensors import SafetensorError, safe_open

    try:
        with safe_open(str(file), framework="pt", device="cpu") as f:
            return {k: tuple(f.get_slice(k).get_shape()) for k in f.keys()}  # noqa: SIM118 (not a dict)
    except (SafetensorError, OSError, ValueError) as e:
        raise RikError(f"{where}: not a safetensors file, or truncated ({_first_line(e)})") from None


def _list(names: list[str], n: int = 3) -> str:
    return ", ".join(sorted(names)[:n]) + (f" and {len(names) - n} more" if len(names) > n else "")


def _expected_tensors(policy_dir: Path, config: Any) -> tuple[dict[str, tuple[int, ...]], list[set[str]]]:
    """The tensors (name: shape) of the model ``config`` describes, built on the ``meta`` device (nothing
    allocated, no pretrained backbone fetched), and the groups of names that share one tensor (tied weights:
    safetensors keeps one of each)."""
    import copy

    import torch
    from lerobot.policies.factory import get_policy_class

    config = copy.deepcopy(config)
    if getattr(config, "pretrained_backbone_weights", None) is not None:
        config.pretrained_backbone_weights = None  # the same architecture; its weights come from model.safetensors
    try:
        with torch.device("meta"):
            model = get_policy_class(config.type)(config)
    except Exception as e:  # noqa: BLE001 (LeRobot's own code building the model config.json describes)
        raise RikError(f"{Path(policy_dir) / CONFIG}: LeRobot cannot build a {config.type} policy from it "
                       f"({type(e).__name__}: {_first_line(e)})") from None
    state: dict[str, torch.Tensor] = model.state_dict(keep_vars=True)
    groups: dict[int, set[str]] = {}
    for name, tensor in state.items():
        groups.setdefault(id(tensor), set()).add(name)
    numbers = sum(state[min(g)].numel() for g in groups.values())
    if numbers > MAX_PARAMETERS:
        raise RikError(f"{Path(policy_dir) / CONFIG}: describes a {config.type} policy of {numbers:,} parameters; rik "
                       f"eval builds policies of at most {MAX_PARAMETERS:,} (4 GiB of float32)")
    return {k: tuple(v.shape) for k, v in state.items()}, list(groups.values())


def check_weights(policy_dir: Path, config: Any) -> None:
    """``model.safetensors`` holds exactly the tensors of the model ``config`` describes, of their shapes."""
    file = member(Path(policy_dir), WEIGHTS, str(Path(policy_dir) / WEIGHTS))
    found = tensor_shapes(file, str(file))
    expected, groups = _expected_tensors(policy_dir, config)
    missing = [min(g) for g in groups if not g & found.keys()]
    if missing:
        raise RikError(f"{file}: lacks {len(missing)} of the model's tensors ({_list(missing)}); it is not the "
                       f"weights of the {config.type} policy config.json describes")
    unexpected = [k for k in found if k not in expected]
    if unexpected:
        raise RikError(f"{file}: holds {len(unexpected)} tensors the model does not have ({_list(unexpected)}); it "
                       f"is not the weights of the {config.type} policy config.json describes")
    for key, shape in found.items():
        if shape != expected[key]:
            raise RikError(f"{file}: tensor '{key}' has shape {list(shape)}; the {config.type} policy config.json "
                           f"describes has {list(expected[key])}")


# ---- the processors -----------------------------------------------------------------------------------------
def allowed_steps() -> dict[str, tuple[str, type]]:
    """The steps a folder may name, by registry name and by class path: name -> (registry name, class)."""
    import lerobot.processor  # noqa: F401  (registers LeRobot's own steps)
    from lerobot.processor.pipeline import ProcessorStepRegistry

    allowed: dict[str, tuple[str, type]] = {}
    for name in STEPS:
        cls = ProcessorStepRegistry.get(name)
        allowed[name] = allowed[f"{cls.__module__}.{cls.__name__}"] = (name, cls)
    return allowed


def _step_class(file: Path, i: int, step: Any, allowed: dict[str, tuple[str, type]]) -> tuple[str, type]:
    """The (registry name, class) a step names, checked to be one of :data:`STEPS`; nothing is imported."""
    where = f"{file}: step {i}"
    if not isinstance(step, dict):
        raise RikError(f"{where}: {_short(step)} is not an object")
    extra = [k for k in step if k not in STEP_FIELDS]
    if extra:
        raise RikError(f"{where} field '{extra[0]}': unknown field (a step has {', '.join(STEP_FIELDS)})")
    if ("registry_name" in step) == ("class" in step):
        raise RikError(f"{where}: names its step by 'registry_name' or by 'class' (one of them)")
    field = "registry_name" if "registry_name" in step else "class"
    name = step[field]
    if not isinstance(name, str) or name not in allowed or (field == "class") != ("." in name):
        raise RikError(f"{where} field '{field}': {_short(name)} is not one of the LeRobot processor steps rik runs "
                       f"({', '.join(STEPS)}); rik never imports or calls a class a policy folder names")
    return allowed[name]


def _check_step_config(file: Path, i: int, step: dict[str, Any], cls: type) -> dict[str, Any]:
    import inspect

    config = step.get("config", {})
    where = f"{file}: step {i} field 'config'"
    if not isinstance(config, dict):
        raise RikError(f"{where}: {_short(config)} is not an object")
    try:
        inspect.signature(cls).bind(**config)
    except TypeError as e:
        raise RikError(f"{where}: {cls.__name__} {_first_line(e)}") from None
    return config


_DEVICE_NAMES = "cpu, cuda, cuda:N, mps or xpu"


def _device_count(family: str) -> int:
    """How many devices of ``family`` (cuda, mps, xpu) this machine has."""
    import torch

    if family == "cuda":
        return torch.cuda.device_count() if torch.cuda.is_available() else 0
    if family == "mps":
        return int(torch.backends.mps.is_available())
    xpu = getattr(torch, "xpu", None)
    return xpu.device_count() if xpu is not None and xpu.is_available() else 0


def _device_problem(value: Any, available: bool) -> str | None:
    """Why ``value`` is not a device rik can run on (None when it is): one of :data:`_DEVICE_NAMES`, and, where
    ``available``, one this machine has."""
    import re

    if not isinstance(value, str) or not re.fullmatch(r"cpu|mps|xpu|cuda(:[0-9]{1,3})?", value):
        return f"is not a device ({_DEVICE_NAMES})"
    family, _, index = value.partition(":")
    if not available or family == "cpu":
        return None
    count = _device_count(family)
    if int(index or 0) >= count:
        return f"is not a device this machine has ({count} {family} device{'s' * (count != 1)}; cpu always works)"
    return None


@dataclass(frozen=True)
class _Step:
    """A processor step whose config is checked, and what its fields are checked against."""

    where: str
    """``<file>: step <i>``: the start of its messages."""
    name: str
    """Its registry name (:data:`STEPS`)."""
    postprocessor: bool
    config: dict[str, Any]
    policy: dict[str, Any]
    """``config.json``'s input and output features by key (empty where not known)."""
    inputs: tuple[str, ...]
    """``config.json``'s input features: what rik's environment supplies."""

    def refuse(self, field: str, text: str) -> RikError:
        return RikError(f"{self.where} field 'config.{field}': {text}")


def _check_device(step: _Step, field: str, value: Any) -> None:
    """A device name; one this machine has, except the preprocessor's device step (rik sets it to the policy's
    device); a normaliser's may be null (its statistics go where the data is)."""
    if value is None and step.name in NORMALISERS:
        return
    problem = _device_problem(value, available=step.name != "device_processor" or step.postprocessor)
    if problem:
        raise step.refuse(field, f"{_short(value)} {problem}")


def _check_float_dtype(step: _Step, field: str, value: Any) -> None:
    if value not in (None, "float32", "float"):
        raise step.refuse(field, f"{_short(value)} is not null or float32: rik runs policies in float32, and inputs "
                                 "or actions of another dtype stop the evaluation")


def _check_null(step: _Step, field: str, value: Any) -> None:
    if value is not None:
        raise step.refuse(field, f"{_short(value)} is not null (LeRobot writes none; the statistics are float32)")


def _check_eps(step: _Step, field: str, value: Any) -> None:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0 < value <= 1:
        raise step.refuse(field, f"{_short(value)} is not a number above 0 and at most 1 (LeRobot writes 1e-08)")


def _check_stats(step: _Step, field: str, value: Any) -> None:
    raise step.refuse(field, "LeRobot keeps a normaliser's statistics in its state file; statistics in the config "
                             "would replace them unchecked")


def _check_step_features(step: _Step, field: str, value: Any) -> None:
    """LeRobot features; those ``config.json`` has too of the same type and shape (the statistics are shaped by
    these, the data by ``config.json``'s)."""
    _check_features(step.where, f"config.{field}", value)
    for key, feature in value.items():
        theirs = step.policy.get(key)
        if theirs is not None and (feature["type"], feature["shape"]) != (theirs["type"], theirs["shape"]):
            raise step.refuse(f"{field}.{key}", f"{_short(feature)} is not the feature {CONFIG} gives it, "
                                                f"{_short(theirs)}")


def _check_norm_map(step: _Step, field: str, value: Any) -> None:
    if not isinstance(value, dict):
        raise step.refuse(field, f"{_short(value)} is not an object of feature types and normalisation modes")
    for kind, mode in value.items():
        if kind not in FEATURE_TYPES:
            raise step.refuse(field, f"{_short(kind)} is not one of {', '.join(FEATURE_TYPES)}")
        if not isinstance(mode, str) or mode not in STATISTICS:
            raise step.refuse(f"{field}.{kind}", f"{_short(mode)} is not one of {', '.join(STATISTICS)}")


def _check_observation_keys(step: _Step, field: str, value: Any) -> None:
    """Null, or names of the step's own features."""
    if value is None:
        return
    if not isinstance(value, list) or not all(isinstance(k, str) for k in value):
        raise step.refuse(field, f"{_short(value)} is not null or a list of feature names")
    features = step.config.get("features") or {}
    for key in value:
        if key not in features:
            raise step.refuse(field, f"{_short(key)} is not one of the step's features ({_list(list(features))})")


def _check_rename_map(step: _Step, field: str, value: Any) -> None:
    """Names to names, renaming none of the policy's inputs away (the policy would never get it)."""
    if not isinstance(value, dict) or not all(isinstance(v, str) for v in value.values()):
        raise step.refuse(field, f"{_short(value)} is not an object of names to names")
    for key, new in value.items():
        if key in step.inputs and new != key:
            raise step.refuse(f"{field}.{key}", f"{_short(new)}: renames the policy's input {key!r} away, so the "
                                                "policy would never get it")


StepCheck = Callable[[_Step, str, Any], None]
_NORMALISER_CHECKS: dict[str, StepCheck] = {
    "features": _check_step_features, "norm_map": _check_norm_map, "eps": _check_eps, "device": _check_device,
    "dtype": _check_null, "normalize_observation_keys": _check_observation_keys, "stats": _check_stats}
STEP_CHECKS: dict[str, dict[str, StepCheck]] = {
    "rename_observations_processor": {"rename_map": _check_rename_map},
    "to_batch_processor": {},
    "device_processor": {"device": _check_device, "float_dtype": _check_float_dtype},
    "normalizer_processor": _NORMALISER_CHECKS,
    "unnormalizer_processor": _NORMALISER_CHECKS,
}
"""Each field a step's config may have (those LeRobot 0.6.1's step classes take from a file), with its check of
type and value: a field of a step that is not here is refused (``to_batch_processor``'s are steps, which a file
cannot give)."""


def _check_step_fields(step: _Step) -> None:
    """Every field of the step's config, by :data:`STEP_CHECKS`."""
    checks = STEP_CHECKS[step.name]
    for field, value in step.config.items():
        if field not in checks:
            raise step.refuse(field, f"not a setting rik reads for {step.name} (it reads "
                                     f"{', '.join(checks) or 'none'})")
        checks[field](step, field, value)


def _check_statistics(file: Path, i: int, config: dict[str, Any], state: Path | None) -> None:
    """A normaliser's state file holds every statistic its features' modes read, of the features' shapes (its
    config checked by :func:`_check_step_fields`)."""
    features, norm_map = config.get("features") or {}, config.get("norm_map") or {}
    needed: dict[str, tuple[int, ...]] = {}
    for key, feature in features.items():
        for stat in STATISTICS[norm_map.get(feature["type"], "IDENTITY")]:
            needed[f"{key}.{stat}"] = tuple(feature["shape"])
    if not needed:
        return
    if state is None:
        raise RikError(f"{file}: step {i}: no 'state_file': the statistics of {_list(list(needed))} are missing")
    found = tensor_shapes(state, str(state))
    for name, shape in needed.items():
        if name not in found:
            raise RikError(f"{state}: lacks the statistic '{name}' (step {i} of {file.name} normalises with it)")
        visual = len(shape) == 3
        ok = {shape, (shape[0], 1, 1), (shape[0],)} if visual else {shape}
        if found[name] not in ok:
            raise RikError(f"{state}: statistic '{name}' has shape {list(found[name])}; the feature has "
                           f"{list(shape)}")


def check_processors(policy_dir: Path, policy: dict[str, Any] | None = None) -> None:
    """Both processor files: objects of LeRobot's shape whose steps are :data:`STEPS`, their configs' fields of
    :data:`STEP_CHECKS` (checked against ``policy``, ``config.json``'s data, where given), with their state files
    inside the folder; then LeRobot loads them (nothing it could import or call is left)."""
    from lerobot.processor.pipeline import DataProcessorPipeline

    allowed = allowed_steps()
    root = Path(policy_dir)
    inputs = dict((policy or {}).get("input_features") or {})
    features = {**inputs, **dict((policy or {}).get("output_features") or {})}
    for name in PROCESSORS:
        file = root / name
        if not file.exists() and not file.is_symlink():
            raise RikError(f"{file}: missing: a policy saved by LeRobot 0.4 or later has its processors beside "
                           f"{CONFIG} (older ones are converted by LeRobot's migrate_policy_normalization script)")
        data = read_json(root, name)
        if not isinstance(data, dict) or not isinstance(data.get("steps"), list):
            raise RikError(f"{file}: not a LeRobot processor file (an object with a list 'steps')")
        extra = [k for k in data if k not in ("name", "steps")]
        if extra:
            raise RikError(f"{file}: field '{extra[0]}': unknown field (a processor file has name and steps)")
        if not isinstance(data.get("name", ""), str):
            raise RikError(f"{file}: field 'name': {_short(data['name'])} is not a string")
        for i, step in enumerate(data["steps"]):
            registry_name, cls = _step_class(file, i, step, allowed)
            config = _check_step_config(file, i, step, cls)
            _check_step_fields(_Step(f"{file}: step {i}", registry_name, name == PROCESSORS[1], config, features,
                                     tuple(inputs)))
            state = None
            if "state_file" in step:
                if not isinstance(step["state_file"], str):
                    raise RikError(f"{file}: step {i} field 'state_file': {_short(step['state_file'])} is not a "
                                   "file name")
                state = member(root, step["state_file"], f"{file}: step {i} field 'state_file'")
                tensor_shapes(state, str(state))
            if registry_name in NORMALISERS:
                _check_statistics(file, i, config, state)
        overrides = {"device_processor": {"device": "cpu"}} if name == PROCESSORS[0] else {}
        try:  # what is left to LeRobot: the steps' own checks of their config values
            DataProcessorPipeline.from_pretrained(str(root), config_filename=name, overrides=overrides)
        except (ValueError, TypeError, KeyError, ImportError, OSError, RuntimeError) as e:
            raise RikError(f"{file}: LeRobot cannot load it ({type(e).__name__}: {_first_line(e)})") from None


def check_policy_folder(policy_dir: Path) -> Any:
    """The whole folder, as the module docstring says: ``config.json``, both processor files with their state
    files, and ``model.safetensors``. Call before handing the folder to LeRobot. Returns the policy's config as
    LeRobot's ``PreTrainedConfig.from_pretrained`` parses it, to use instead of that: LeRobot 0.6.1 copies the
    config into a named temporary file for draccus there and never removes it (one file in ``/tmp`` per load)."""
    root = Path(policy_dir)
    data = read_json(root, CONFIG)
    if not isinstance(data, dict):
        raise RikError(f"{root / CONFIG}: not a JSON object (a LeRobot policy config)")
    config = parsed_config(root, data)
    check_processors(root, data)
    check_weights(root, config)
    return config
