"""Content-addressed store of built assets under ``<cache>/assets/<key[:2]>/<key>/``.

An entry holds ``asset.npz`` (visual mesh and convex parts of every rigid part) and ``meta.json`` (what was
built, from what, the sha256 of ``asset.npz``, and the sha256 of the rest of ``meta.json`` itself). The key is
a sha256 over everything that decides the output: the catalog entry, the generator's source code, the CoACD
parameters, the seed and the library versions, so a change to any of them makes a new entry and a warm rebuild
does no work. Entries are written to a temporary
directory and renamed into place; one whose payload or metadata no longer matches its recorded hash is reported
and rebuilt. Derived results stored beside an entry (:meth:`AssetCache.write_extra`) carry their own sha256 and
are measured again when it does not match.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from typing import Any

from rik.outputs import CACHED, NEW, make_stage, publish_cache_entry, remove_cache_entry, write_text, writing
from rik.paths import cache_dir, json_sha256

ASSET_FORMAT = 2
"""Bumped when the layout of an entry changes (2: ``meta.json`` records its own sha256)."""

VERSIONED_PACKAGES = ("coacd", "trimesh", "numpy", "manifold3d", "shapely")


def library_versions() -> dict[str, str]:
    """Versions of the libraries that shape the meshes and their decomposition."""
    out = {}
    for name in VERSIONED_PACKAGES:
        try:
            out[name] = version(name)
        except PackageNotFoundError:
            out[name] = "absent"
    return out


def source_digest(paths: list[Path]) -> str:
    """sha256 over the given source files (generator code is part of every key)."""
    h = hashlib.sha256()
    for path in sorted(paths):
        h.update(path.name.encode())
        h.update(path.read_bytes())
    return h.hexdigest()


def content_key(identity: dict[str, Any]) -> str:
    """sha256 of a JSON-able description of everything that decides an asset."""
    blob = json.dumps({"format": ASSET_FORMAT, **identity}, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(blob.encode()).hexdigest()


def _meta_sha256(meta: dict[str, Any]) -> str:
    return json_sha256(meta, exclude=("meta_sha256",))


def file_sha256(path: Path) -> str:
    h = hashlib.sha256()
    with path.open("rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


@dataclass(frozen=True)
class CacheEntry:
    key: str
    path: Path
    meta: dict[str, Any]

    @property
    def payload(self) -> Path:
        return self.path / "asset.npz"


class CorruptEntry(Exception):
    """An entry whose payload does not match the hash recorded when it was written."""


class AssetCache:
    """The asset store; ``root`` defaults to ``<rik cache>/assets``."""

    def __init__(self, root: Path | None = None) -> None:
        self.root = root if root is not None else cache_dir() / "assets"

    def path(self, key: str) -> Path:
        return self.root / key[:2] / key

    def get(self, key: str) -> CacheEntry | None:
        """The verified entry for ``key``; ``None`` if absent. Raises :class:`CorruptEntry` (after removing the
        entry) when its files are unreadable, or the payload's or the metadata's sha256 differs from the recorded
        one."""
        path = self.path(key)
        if not path.is_dir():
            return None
        try:
            meta = json.loads((path / "meta.json").read_text())
            ok = (meta["meta_sha256"] == _meta_sha256(meta)
                  and file_sha256(path / "asset.npz") == meta["payload_sha256"])
        except (OSError, ValueError, KeyError, TypeError):
            ok = False
        if not ok:
            remove_cache_entry(path)
            raise CorruptEntry(f"cache entry {path} failed its sha256 check; it was removed and will be rebuilt")
        return CacheEntry(key, path, meta)

    def put(self, key: str, arrays: dict[str, Any], meta: dict[str, Any]) -> CacheEntry:
        """Write an entry atomically (temporary directory, then rename) and return it."""
        import numpy as np

        final = self.path(key)
        final.parent.mkdir(parents=True, exist_ok=True)
        tmp = make_stage(final)
        try:
            with writing(tmp / "asset.npz", NEW, keep_suffix=True) as npz:
                np.savez_compressed(npz, **arrays)
            meta = {**meta, "key": key, "format": ASSET_FORMAT, "payload_sha256": file_sha256(tmp / "asset.npz")}
            meta["meta_sha256"] = _meta_sha256(meta)
            write_text(tmp / "meta.json", json.dumps(meta, indent=1, sort_keys=True), NEW)
            publish_cache_entry(tmp, final)  # another worker may have written the same entry first: keep theirs
        except BaseException:
            remove_cache_entry(tmp)
            raise
        return CacheEntry(key, final, json.loads((final / "meta.json").read_text()))

    def write_extra(self, key: str, name: str, data: dict[str, Any]) -> None:
        """Store a derived JSON result (for example fidelity figures) beside an entry, atomically, with the
        sha256 of its canonical JSON (:func:`json_sha256`)."""
        write_text(self.path(key) / name, json.dumps({"sha256": json_sha256(data), "data": data}, indent=1,
                                                       sort_keys=True), CACHED)

    def read_extra(self, key: str, name: str) -> dict[str, Any] | None:
        """A result stored by :meth:`write_extra`; ``None`` (compute it again) when absent, unreadable, or when
        its content no longer matches its sha256."""
        try:
            stored = json.loads((self.path(key) / name).read_text())
            data, sha = stored["data"], stored["sha256"]
        except (OSError, ValueError, KeyError, TypeError):
            return None
        return data if isinstance(data, dict) and sha == json_sha256(data) else None
