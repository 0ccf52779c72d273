"""The local registry of built datasets: ``<cache>/datasets.json`` (:func:`rik.paths.cache_dir`), one entry per
dataset folder, written by ``rik dataset build`` and read by ``rik dataset list``. It only points at datasets; the
datasets themselves hold their full record (``meta/rik_dataset.json``)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from rik.paths import cache_dir, write_atomic

REGISTRY = "datasets.json"


def registry_file() -> Path:
    return cache_dir() / REGISTRY


def _read() -> list[dict[str, Any]]:
    try:
        data = json.loads(registry_file().read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return []
    return [e for e in data if isinstance(e, dict) and isinstance(e.get("path"), str)] if isinstance(data, list) else []


def folder_size(root: Path) -> int:
    """Bytes of the files below ``root`` (0 when it does not exist)."""
    return sum(p.stat().st_size for p in Path(root).rglob("*") if p.is_file())


def describe_dataset(root: Path) -> dict[str, Any]:
    """What ``rik dataset list/show`` says of the dataset at ``root`` (read from its metadata; ``present`` is
    False when it is gone or no longer a built dataset)."""
    from rik.dataset.build import BUILD_META, read_dataset_meta

    root = Path(root).absolute()
    meta = read_dataset_meta(root)
    if meta is None:
        return {"path": str(root), "present": False}
    try:
        build = json.loads((root / "meta" / BUILD_META).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        build = {}
    counts = meta.get("counts", {})
    spec = meta.get("spec", {})
    return {"path": str(root), "present": True, "repo_id": spec.get("repo_id"), "spec_hash": meta.get("spec_hash"),
            "source": meta.get("source"), "episodes": counts.get("episodes"), "frames": counts.get("frames"),
            "variants": counts.get("variants"), "streams": spec.get("streams"), "outcomes": meta.get("outcomes", {}),
            "bytes": folder_size(root), "rik": meta.get("versions", {}).get("rik"), "build": build}


def register_dataset(root: Path) -> None:
    """Add (or refresh) the dataset at ``root`` in the registry; a registry that cannot be written is skipped
    (the dataset is complete without it)."""
    from rik.locks import exclusive

    root = Path(root).absolute()
    path = registry_file()
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with exclusive(path, "rik dataset build", wait=True):
            entries = [e for e in _read() if e["path"] != str(root)]
            info = describe_dataset(root)
            entries.append({k: info.get(k) for k in ("path", "repo_id", "spec_hash")})
            write_atomic(path, json.dumps(entries, indent=1) + "\n")
    except OSError:
        pass


def list_datasets() -> list[dict[str, Any]]:
    """Every registered dataset, described as it is now on disk (in registration order)."""
    return [describe_dataset(Path(e["path"])) for e in _read()]
