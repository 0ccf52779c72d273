"""Reading a dataset spec, and its hash."""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from typing import Any

from rik.schemas.dataset import DatasetSpec

DEFAULT_ROBOT = "hand-e"


def load_spec(path: Path) -> DatasetSpec:
    """The spec in the YAML file ``path``; bad input raises one line naming the file, line and field."""
    from rik.registry.entries import read_yaml_model

    return read_yaml_model(Path(path), DatasetSpec, "dataset spec")


def spec_data(spec: DatasetSpec) -> dict[str, Any]:
    """The spec as JSON data, every default filled in (what its hash covers), but ``robot`` where it is the
    Hand-E: specs written before robots existed keep their hash, and the datasets built from them stay current."""
    data = spec.model_dump(mode="json")
    if data.get("robot") == DEFAULT_ROBOT:
        del data["robot"]
    return data


def spec_hash(spec: DatasetSpec) -> str:
    """sha256 of the spec with its defaults filled in: two files that say the same thing hash the same."""
    from rik.paths import json_sha256

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
