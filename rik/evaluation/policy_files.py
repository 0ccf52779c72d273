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
  class declares (draccus's own complaints are turned into one line naming the field);
- weights are safetensors, read through their header only (no pickle anywhere): ``model.safetensors`` has
  exactly the tensors, with the shapes, of the model ``config.json`` describes (built on PyTorch's ``meta`` device,
  which allocates nothing), and a normaliser's state file has every statistic its features need, of their shapes
  (LeRobot's normaliser silently skips a feature whose statistics are missing).

Anything else is a one-line :class:`rik.errors.RikError` naming the file, the step and the field.
"""

from __future__ import annotations

import json
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
    body = {k: v for k, v in data.items() if k != "type"}
    try:
        return draccus.decode(cls, body)
    except DecodingError as e:
        field = ".".join(map(str, e.key_path))
        where = f"field '{field}'" if field else "its fields"
        raise RikError(f"{file}: {where}: {_clip(e.message)}") from None
    except (ParsingError, ValueError, TypeError, KeyError) as e:
        cause = e.__cause__ or e
        raise RikError(f"{file}: LeRobot's {data['type']} config refuses it: {_first_line(cause)}") from None


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


def _check_statistics(file: Path, i: int, config: dict[str, Any], state: Path | None) -> None:
    """A normaliser's state file holds every statistic its features' modes read, of the features' shapes."""
    where = f"{file}: step {i}"
    features, norm_map = config.get("features") or {}, config.get("norm_map") or {}
    if not isinstance(features, dict) or not isinstance(norm_map, dict):
        raise RikError(f"{where} field 'config': 'features' and 'norm_map' are objects")
    if "stats" in config:
        raise RikError(f"{where} field 'config.stats': LeRobot keeps a normaliser's statistics in its state file; "
                       "statistics in the config would replace them unchecked")
    needed: dict[str, tuple[int, ...]] = {}
    for key, feature in features.items():
        _check_features(where, "config.features", {key: feature})
        mode = norm_map.get(feature["type"], "IDENTITY")
        if not isinstance(mode, str) or mode not in STATISTICS:
            raise RikError(f"{where} field 'config.norm_map.{feature['type']}': {_short(mode)} is not one of "
                           f"{', '.join(STATISTICS)}")
        for stat in STATISTICS[mode]:
            needed[f"{key}.{stat}"] = tuple(feature["shape"])
    if not needed:
        return
    if state is None:
        raise RikError(f"{where}: no 'state_file': the statistics of {_list(list(needed))} are missing")
    found = tensor_shapes(state, str(state))
    for name, shape in needed.items():
        if name not in found:
            raise RikError(f"{state}: lacks the statistic '{name}' (step {i} of {file.name} normalises with it)")
        visual = len(shape) == 3
        ok = {shape, (shape[0], 1, 1), (shape[0],)} if visual else {shape}
        if found[name] not in ok:
            raise RikError(f"{state}: statistic '{name}' has shape {list(found[name])}; the feature has "
                           f"{list(shape)}")


def check_processors(policy_dir: Path) -> None:
    """Both processor files: objects of LeRobot's shape whose steps are :data:`STEPS`, with their state files
    inside the folder; then LeRobot loads them (nothing it could import or call is left)."""
    from lerobot.processor.pipeline import DataProcessorPipeline

    allowed = allowed_steps()
    root = Path(policy_dir)
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


def check_policy_folder(policy_dir: Path) -> None:
    """The whole folder, as the module docstring says: ``config.json``, both processor files with their state
    files, and ``model.safetensors``. Call before handing the folder to LeRobot."""
    root = Path(policy_dir)
    data = read_json(root, CONFIG)
    if not isinstance(data, dict):
        raise RikError(f"{root / CONFIG}: not a JSON object (a LeRobot policy config)")
    config = parsed_config(root, data)
    check_processors(root)
    check_weights(root, config)
