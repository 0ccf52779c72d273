"""Loading the catalog: rik's built-in data plus optional user overlays, validated into typed models.

:func:`load_catalog` reads and validates the files (once per process for the same file contents). The fast path
for listing is :mod:`rik.registry.index`, a plain-data view cached by content hash.
"""

from __future__ import annotations

import hashlib
import threading
from collections import OrderedDict
from collections.abc import Iterable, Sequence
from pathlib import Path

from rik.registry import checks
from rik.registry.catalog import Catalog, Origin
from rik.registry.entries import SECTION_MODELS, CatalogModel, parse_entry
from rik.registry.sources import MAX_CATALOG_BYTES, NOUNS, SPLITS_KEY, RawEntry, catalog_sources, read_file
from rik.registry.splits import assign_splits
from rik.schemas import BaseUnit, Finish, Handle, HandleDesign, ResistancePreset
from rik.schemas.robots import Robot


def load_catalog(overlays: Iterable[Path] | None = None) -> Catalog:
    """The built-in catalog plus ``overlays`` (YAML files or directories; ``None``: those of ``RIK_CATALOG``).

    Raises :class:`rik.errors.CatalogError` naming the file, entry and field of the first problem found.
    """
    files = catalog_sources(overlays)
    key = _contents_key(files)
    with _LOADED_LOCK:
        if key is not None and key in _LOADED:
            _LOADED.move_to_end(key)
            return _LOADED[key]
    catalog = build_catalog([e for path, builtin in files for e in read_file(path, builtin)])
    if key is not None:
        with _LOADED_LOCK:
            _LOADED[key] = catalog
            while len(_LOADED) > _LOADED_MAX:
                _LOADED.popitem(last=False)
    return catalog


_LOADED: OrderedDict[tuple[tuple[str, bool, bytes], ...], Catalog] = OrderedDict()
"""Catalogs this process loaded, by the paths and contents of their files: a command that loads the catalog again
(rik eval reads it for the policy's layout, the environment's config and the episodes; a test process hundreds of
times) gets the same :class:`Catalog` (frozen: its models are immutable) in 0.2 ms instead of reading and
validating ~100 kB of YAML again (60 ms). A file that changed, by a byte, is another key."""
_LOADED_MAX = 8
_LOADED_LOCK = threading.Lock()


def _contents_key(files: Sequence[tuple[Path, bool]]) -> tuple[tuple[str, bool, bytes], ...] | None:
    """(path, builtin, sha256 of the bytes) of each file; ``None`` where one cannot be read or is too large (then
    :func:`read_file` says why)."""
    key = []
    for path, builtin in files:
        try:
            with open(path, "rb") as handle:
                raw = handle.read(MAX_CATALOG_BYTES + 1)
        except OSError:
            return None
        if len(raw) > MAX_CATALOG_BYTES:
            return None
        key.append((str(path), builtin, hashlib.sha256(raw).digest()))
    return tuple(key)


def build_catalog(entries: Sequence[RawEntry]) -> Catalog:
    """Validate raw entries (each against its schema, then the cross-entry checks, then the split assignment)
    into a :class:`Catalog`."""
    parsed: dict[str, list[tuple[RawEntry, CatalogModel]]] = {s: [] for s in SECTION_MODELS}
    split_entries = [e for e in entries if e.section == SPLITS_KEY]
    for entry in (e for e in entries if e.section != SPLITS_KEY):
        parsed[entry.section].append((entry, parse_entry(entry)))
    for section, items in parsed.items():
        checks.check_unique_ids(items, NOUNS[section])
    for section in checks.IN_VARIANT_IDS:
        checks.check_variant_id_parts(parsed[section], section, NOUNS[section])
    finishes = dict(_items(parsed, "finishes", Finish))
    presets = dict(_items(parsed, "presets", ResistancePreset))
    designs = dict(_items(parsed, "designs", HandleDesign))
    handles = dict(_items(parsed, "handles", Handle))
    base_units = dict(_items(parsed, "base_units", BaseUnit))
    robots = dict(_items(parsed, "robots", Robot))
    for entry, handle in _entries(parsed, "handles", Handle):
        checks.check_handle(entry, handle, designs, finishes)
    used = [h.design for h in handles.values()]
    for entry, design in _entries(parsed, "designs", HandleDesign):
        checks.check_design(entry, design, used.count(design.id))
    for entry, base in _entries(parsed, "base_units", BaseUnit):
        checks.check_base_unit(entry, base, finishes, presets)
    for entry, preset in _entries(parsed, "presets", ResistancePreset):
        checks.check_preset_breakable(entry, preset, robots)
    origins = {(s, m.id): Origin(str(e.file), e.builtin) for s, items in parsed.items() for e, m in items}
    splits, version, preset_splits = assign_splits(
        split_entries, {m.id: e.builtin for e, m in _entries(parsed, "designs", HandleDesign)},
        {m.id: e.builtin for e, m in _entries(parsed, "presets", ResistancePreset) if not m.in_default_set})
    return Catalog(designs=designs, handles=handles, base_units=base_units, presets=presets, finishes=finishes,
                   origins=origins, splits=splits, splits_version=version, robots=robots,
                   preset_splits=preset_splits)


def _entries[M: CatalogModel](parsed: dict[str, list[tuple[RawEntry, CatalogModel]]], section: str,
                              kind: type[M]) -> list[tuple[RawEntry, M]]:
    """The (entry, model) pairs of ``section``, whose models are all ``kind`` (:data:`SECTION_MODELS`)."""
    return [(e, m) for e, m in parsed[section] if isinstance(m, kind)]


def _items[M: CatalogModel](parsed: dict[str, list[tuple[RawEntry, CatalogModel]]], section: str,
                            kind: type[M]) -> list[tuple[str, M]]:
    """(id, model) of every entry of ``section``, in definition order."""
    return [(m.id, m) for _, m in _entries(parsed, section, kind)]
