"""Reading a dataset spec, and its hash."""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from typing import Any

from rik.errors import RikError
from rik.lerobot.policy_io import FIELD_TYPES, PolicyIO
from rik.paths import json_sha256
from rik.schemas.dataset import DatasetSpec

DEFAULT_ROBOT = "hand-e"
SPEC_FIELDS = {"image_size": "resolution"}
"""A field of the contract -> the spec's field that says it, where the names differ."""


MAX_SPEC_BYTES = 4_000_000
"""Largest spec file read, bytes (a spec that lists every variant of the catalog by id is ~200 kB)."""
MAX_SPEC_DEPTH = 16
"""Deepest nesting of lists and mappings in a spec (a valid one nests 3 deep); libyaml's composer recurses in C,
and a deeper document crashes the process (a segmentation fault at ~10^5 levels)."""
MAX_SPEC_NODES = 1_000_000
"""Most nodes a spec may hold with its aliases expanded: an alias bomb ("billion laughs") is refused unread."""


def load_spec(path: Path) -> DatasetSpec:
    """The spec in the YAML file ``path``; bad input raises one line naming the file, line and field. The file is
    bounded before it is parsed (:data:`MAX_SPEC_BYTES`, :data:`MAX_SPEC_DEPTH`, :data:`MAX_SPEC_NODES`)."""
    from rik.registry.entries import read_yaml_model

    check_spec_shape(Path(path))
    return read_yaml_model(Path(path), DatasetSpec, "dataset spec")


def check_spec_shape(path: Path) -> None:
    """Refuse, with one line naming the file (and line), a spec larger than :data:`MAX_SPEC_BYTES`, nested deeper
    than :data:`MAX_SPEC_DEPTH` or whose aliases expand past :data:`MAX_SPEC_NODES` values
    (:func:`rik.registry.sources.check_yaml_shape`). What cannot be read or decoded is left to the reader, which
    names it."""
    from rik.registry.sources import check_yaml_shape, display_path

    shown = display_path(path)
    try:
        with open(path, "rb") as f:
            raw = f.read(MAX_SPEC_BYTES + 1)
    except OSError:
        return
    if len(raw) > MAX_SPEC_BYTES:
        raise RikError(f"{shown}: the dataset spec is larger than {MAX_SPEC_BYTES:,} bytes; a spec lists variants, "
                       "operators and settings, not data")
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        return
    check_yaml_shape(text, shown, "dataset spec", MAX_SPEC_DEPTH, MAX_SPEC_NODES)


def spec_data(spec: DatasetSpec) -> dict[str, Any]:
    """The spec as JSON data, every default filled in (what its hash covers), but ``robot`` where it is the
    Hand-E, an operator's ``action_noise`` where it has none, ``outcomes`` where all are exported,
    ``action_frame`` where it is the world, ``handle_shape`` where it is none, ``environment_state`` where it is
    true and the variants' ``joints`` where
    they are the paper's: specs written
    before those existed keep their
    hash, and the datasets built from them stay current."""
    data = spec.model_dump(mode="json")
    if data.get("robot") == DEFAULT_ROBOT:
        del data["robot"]
    for operator in data["operators"]:
        if operator.get("action_noise") is None:
            operator.pop("action_noise", None)
    if data.get("outcomes") == ["F", "P", "S"]:
        del data["outcomes"]
    if data.get("action_frame") == "world":
        del data["action_frame"]
    if data["variants"].get("joints") == "paper":
        del data["variants"]["joints"]
    if data.get("handle_shape") == "none":
        del data["handle_shape"]
    if data.get("environment_state") is True:  # specs from before the option keep their hash
        del data["environment_state"]
    if data["variants"].get("draw") is None:
        data["variants"].pop("draw", None)
    return data


def policy_io(spec: DatasetSpec) -> PolicyIO:
    """The contract of the dataset ``spec`` builds with the policies trained on it: the spec's fields named as the
    contract's (:data:`SPEC_FIELDS`: the resolution is the image size, height first), unchecked
    (:func:`rik.dataset.plan.check_contract` checks it)."""
    width, height = spec.size
    names = {SPEC_FIELDS.get(name, name): name for name in FIELD_TYPES}
    options = {name: getattr(spec, field) for field, name in names.items() if field in DatasetSpec.model_fields}
    return PolicyIO().with_options({**options, "image_size": (height, width)})


def spec_hash(spec: DatasetSpec) -> str:
    """sha256 of the spec with its defaults filled in: two files that say the same thing hash the same."""

    return json_sha256(spec_data(spec))


def library_versions(*names: str) -> dict[str, str]:
    """Installed versions of rik and the distributions ``names`` (without importing them)."""
    out = {}
    for name in ("rik", *names):
        try:
            out[name] = version(name)
        except PackageNotFoundError:
            out[name] = "absent"
    return out
