"""The local registry of built datasets: ``<cache>/datasets.json`` (:func:`rik.paths.cache_dir`), one entry per
dataset folder, written by ``rik dataset build`` and read by ``rik dataset list``. It only points at datasets; the
datasets themselves hold their full record (``meta/rik_dataset.json``)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from rik.dataset.meta import BUILD_META, read_dataset_meta, read_meta_file
from rik.errors import RikError
from rik.outputs import PRIVATE, write_text
from rik.paths import cache_dir, read_json

REGISTRY = "datasets.json"


def registry_file() -> Path:
    return cache_dir() / REGISTRY


def _read() -> list[dict[str, Any]]:
    """The registry's entries ([] when there is none yet); a damaged registry raises one line naming it (and the
    entry), never read as empty: a build would then write over the pointers it still holds."""

    path = registry_file()
    fix = "it only points at datasets: move it away, and rebuild (or list) the datasets it named"
    try:
        data = read_json(path)
    except FileNotFoundError:
        return []
    except OSError as exc:
        raise RikError(f"{path}: cannot read the registry of datasets ({exc.strerror})") from None
    except ValueError as exc:
        raise RikError(f"{path}: the registry of datasets is damaged (not JSON: {str(exc).splitlines()[0]}); "
                       f"{fix}") from None
    if not isinstance(data, list):
        raise RikError(f"{path}: the registry of datasets is damaged (a JSON {type(data).__name__}, not a list); "
                       f"{fix}")
    for i, e in enumerate(data):
        if not isinstance(e, dict) or not isinstance(e.get("path"), str):
            raise RikError(f"{path}, entry {i}, field 'path': the registry of datasets is damaged (no folder's "
                           f"path there); {fix}")
    return data


def folder_size(root: Path) -> int:
    """Bytes of the files below ``root`` (0 when it does not exist)."""
    return sum(p.stat().st_size for p in Path(root).rglob("*") if p.is_file())


def describe_dataset(root: Path) -> dict[str, Any]:
    """What ``rik dataset list/show`` says of the dataset at ``root`` (read from its metadata; ``present`` is
    False when it is gone or no longer a built dataset). Damaged metadata raises one line naming the file and the
    field (:func:`rik.dataset.build.read_meta_file`)."""
    from rik.schemas.dataset import BuildRecord

    root = Path(root).absolute()
    meta = read_dataset_meta(root)
    if meta is None:
        return {"path": str(root), "present": False}
    build_file = root / "meta" / BUILD_META
    build = read_meta_file(build_file, BuildRecord) if build_file.exists() else {}
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
            write_text(path, json.dumps(entries, indent=1) + "\n", PRIVATE)
    except (OSError, RikError):  # a damaged registry is left as it is (rik dataset list names it), not replaced
        pass


def list_datasets() -> list[dict[str, Any]]:
    """Every registered dataset, described as it is now on disk (in registration order); one whose metadata is
    damaged is listed with ``damaged``, the line that names the file and field, so the others still show."""

    rows = []
    for e in _read():
        try:
            rows.append(describe_dataset(Path(e["path"])))
        except RikError as exc:
            rows.append({"path": str(Path(e["path"]).absolute()), "present": True, "damaged": str(exc)})
    return rows
