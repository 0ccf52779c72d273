"""A plain-data view of the validated catalog, cached by content hash: what ``rik catalog`` lists and shows.

Building the typed :class:`~rik.registry.catalog.Catalog` means creating the schema classes and validating
every entry, which costs more than the rest of a ``rik catalog list`` call. The index holds the same entries
as JSON-ready dicts in definition order (plus a few derived fields), written only after full validation, under
``<cache>/catalog/<sha256>.json``; the key hashes every source file, the schema and registry code, and the
library versions, so any change to them rebuilds it. The file also records the sha256 of its payload, checked
on every read: an edited or damaged index is rebuilt, never served. Errors are never cached.
"""

from __future__ import annotations

import hashlib
import json
import os
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import rik
from rik.errors import UnknownIdError
from rik.outputs import PRIVATE, write_text
from rik.paths import cache_dir
from rik.registry.fit import fits_base_unit
from rik.registry.sources import NOUNS, SECTIONS, catalog_sources, read_file
from rik.registry.splits import check_split

if TYPE_CHECKING:
    from rik.registry.catalog import Catalog

#: The order in which ``lookup`` searches sections and ``rik catalog`` lists kinds.
LOOKUP_ORDER = ("handles", "designs", "base_units", "presets", "finishes", "robots")


@dataclass(frozen=True)
class CatalogIndex:
    """Catalog entries as plain dicts (SI units, as in the YAML), in definition order, with derived fields:
    handles get ``type``, designs ``handle_count``, handles and designs ``split``, base units ``joint_types``,
    presets ``in_default_set`` (:attr:`rik.schemas.joints.ResistancePreset.in_default_set`);
    every entry gets ``origin`` (``builtin`` or ``overlay``)."""

    fingerprint: str
    sections: dict[str, list[dict[str, Any]]]
    pairings: dict[str, int]
    """``total`` base unit x handle pairings and how many ``fit`` every front of the base unit."""
    splits_version: int = 0
    """Version of the split assignment (:mod:`rik.registry.splits`)."""

    def entries(self, section: str) -> list[dict[str, Any]]:
        return self.sections[section]

    def get(self, section: str, entry_id: str) -> dict[str, object]:
        """One entry by id; :class:`UnknownIdError` with suggestions when absent."""
        for entry in self.sections[section]:
            if entry["id"] == entry_id:
                return entry
        raise UnknownIdError(NOUNS[section], entry_id, [e["id"] for e in self.sections[section]])

    def lookup(self, entry_id: str) -> tuple[str, dict[str, Any]]:
        """Find an id in any section: (section, entry)."""
        for section in LOOKUP_ORDER:
            for entry in self.sections[section]:
                if entry["id"] == entry_id:
                    return section, entry
        raise UnknownIdError("entry", entry_id, [e["id"] for s in LOOKUP_ORDER for e in self.sections[s]])

    def select(self, section: str, *, type: str | None = None, design: str | None = None,
               joint: str | None = None, min_length: float | None = None,
               max_length: float | None = None, split: str | None = None) -> list[dict[str, Any]]:
        """Entries of a section matching every given criterion.

        ``type``: handle type (handles, designs); ``design``: design id (handles); ``joint``: joint type of
        any front (base units); ``min_length``/``max_length``: overall handle length, m, inclusive; ``split``:
        train, val or test (handles, designs).
        """
        if design is not None:
            self.get("designs", design)  # an unknown design is an error with suggestions, not an empty list
        if split is not None:
            check_split(split)
        rows = self.sections[section]
        if type is not None:
            rows = [r for r in rows if r.get("type") == type]
        if split is not None:
            rows = [r for r in rows if r.get("split") == split]
        if design is not None:
            rows = [r for r in rows if r.get("design") == design]
        if joint is not None:
            rows = [r for r in rows if joint in r.get("joint_types", ())]
        if min_length is not None:
            rows = [r for r in rows if r["geometry"]["length"] >= min_length]
        if max_length is not None:
            rows = [r for r in rows if r["geometry"]["length"] <= max_length]
        return rows


def catalog_index(overlays: Iterable[Path] | None = None, use_cache: bool = True) -> CatalogIndex:
    """The index of the built-in catalog plus ``overlays`` (``None``: those of ``RIK_CATALOG``).

    Raises :class:`rik.errors.CatalogError` on the first problem in any file.
    """
    files = catalog_sources(overlays)
    key = fingerprint(files)
    path = cache_dir() / "catalog" / f"{key}.json"
    if use_cache:
        cached = _read(path, key)
        if cached is not None:
            return cached
    from rik.registry.load import build_catalog  # creates the schema classes: only on a cache miss

    catalog = build_catalog([e for p, builtin in files for e in read_file(p, builtin)])
    index = build_index(catalog, key)
    if use_cache:
        _write(path, index)
    return index


def build_index(catalog: Catalog, key: str = "") -> CatalogIndex:
    """The plain-data index of a validated catalog."""
    sections: dict[str, list[dict[str, Any]]] = {}
    for section in SECTIONS:
        rows = []
        for entry_id, model in getattr(catalog, section).items():
            row = model.model_dump(mode="json")
            row["origin"] = "builtin" if catalog.origins[(section, entry_id)].builtin else "overlay"
            rows.append(row)
        sections[section] = rows
    for row in sections["handles"]:
        row["type"] = catalog.handle_type(catalog.handles[row["id"]]).value
    for row in sections["handles"]:
        row["split"] = catalog.splits[row["design"]]
    for row in sections["designs"]:
        row["handle_count"] = len(catalog.handles_of(row["id"]))
        row["split"] = catalog.splits[row["id"]]
    for row in sections["presets"]:
        row["in_default_set"] = catalog.presets[row["id"]].in_default_set
    for row in sections["base_units"]:
        row["joint_types"] = [j.value for j in catalog.joint_types(catalog.base_units[row["id"]])]
    fit = sum(fits_base_unit(h, b) for b in catalog.base_units.values() for h in catalog.handles.values())
    pairings = {"total": len(catalog.base_units) * len(catalog.handles), "fit": fit}
    return CatalogIndex(key, sections, pairings, catalog.splits_version)


def fingerprint(files: Sequence[tuple[Path, bool]]) -> str:
    """sha256 of the source files (path, role, bytes), the schema and registry code, and library versions."""
    digest = hashlib.sha256()
    digest.update(f"rik {rik.__version__} schema {rik.CATALOG_SCHEMA}\n".encode())
    digest.update(_pydantic_version())
    package = Path(rik.__file__).parent
    code = sorted((package / "schemas").glob("*.py")) + sorted((package / "registry").glob("*.py"))
    for path, builtin in [(p, True) for p in code] + list(files):
        digest.update(f"{os.path.abspath(path)}\0{builtin}\0".encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()


INDEX_FORMAT = 3
"""Layout of the cached file: a header (format, fingerprint, the sha256 of the payload) then the payload."""


def _header(key: str, sha: str) -> bytes:
    return f'{{"format": {INDEX_FORMAT}, "fingerprint": "{key}", "sha256": "{sha}", "index": '.encode()


def _pydantic_version() -> bytes:
    """What identifies the installed pydantic: the bytes of its ``version.py``, found without importing pydantic
    (that import, ~20 ms, was most of a warm ``rik catalog``'s own start-up); its ``VERSION`` if not found."""
    from importlib.util import find_spec

    spec = find_spec("pydantic")
    if spec is not None and spec.origin:
        try:
            return Path(spec.origin).with_name("version.py").read_bytes()
        except OSError:
            pass
    import pydantic

    return f"pydantic {pydantic.VERSION}".encode()


def _read(path: Path, key: str) -> CatalogIndex | None:
    """The cached index, verified: its payload (the bytes after the header) must hash to the header's sha256;
    anything else (missing, partial, edited, another layout or key) is a miss and gets rebuilt."""
    try:
        raw = path.read_bytes()
    except OSError:
        return None
    start = len(_header(key, "0" * 64))
    head, payload = raw[:start], raw[start:-1]
    sha = hashlib.sha256(payload).hexdigest()
    if head != _header(key, sha) or raw[-1:] != b"}":
        return None
    try:
        data = json.loads(payload)
        return CatalogIndex(key, data["sections"], data["pairings"], data["splits_version"])
    except (ValueError, KeyError, TypeError):
        return None


def _write(path: Path, index: CatalogIndex) -> None:
    """Write atomically, with the sha256 of the payload in the header; a cache that cannot be written (read-only
    home) is not an error."""
    payload = json.dumps({"sections": index.sections, "pairings": index.pairings,
                          "splits_version": index.splits_version})
    sha = hashlib.sha256(payload.encode()).hexdigest()
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        write_text(path, _header(index.fingerprint, sha).decode() + payload + "}", PRIVATE)
    except OSError:
        pass
