"""Loading the catalog: rik's built-in data plus optional user overlays, validated into typed models.

:func:`load_catalog` always reads and validates the files. The fast path for listing is
:mod:`rik.registry.index`, a plain-data view cached by content hash.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from pathlib import Path

from rik.registry import checks
from rik.registry.catalog import Catalog, Origin
from rik.registry.entries import SECTION_MODELS, CatalogModel, parse_entry
from rik.registry.sources import NOUNS, SPLITS_KEY, RawEntry, catalog_sources, read_file
from rik.registry.splits import assign_splits
from rik.schemas import BaseUnit, Finish, Handle, HandleDesign, ResistancePreset
from rik.schemas.robots import Robot


def load_catalog(overlays: Iterable[Path] | None = None) -> Catalog:
    """The built-in catalog plus ``overlays`` (YAML files or directories; ``None``: those of ``RIK_CATALOG``).

    Raises :class:`rik.errors.CatalogError` naming the file, entry and field of the first problem found.
    """
    files = catalog_sources(overlays)
    return build_catalog([e for path, builtin in files for e in read_file(path, builtin)])


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
    splits, version = assign_splits(split_entries, {m.id: e.builtin for e, m in _entries(parsed, "designs",
                                                                                           HandleDesign)})
    return Catalog(designs=designs, handles=handles, base_units=base_units, presets=presets, finishes=finishes,
                   origins=origins, splits=splits, splits_version=version, robots=robots)


def _entries[M: CatalogModel](parsed: dict[str, list[tuple[RawEntry, CatalogModel]]], section: str,
                              kind: type[M]) -> list[tuple[RawEntry, M]]:
    """The (entry, model) pairs of ``section``, whose models are all ``kind`` (:data:`SECTION_MODELS`)."""
    return [(e, m) for e, m in parsed[section] if isinstance(m, kind)]


def _items[M: CatalogModel](parsed: dict[str, list[tuple[RawEntry, CatalogModel]]], section: str,
                            kind: type[M]) -> list[tuple[str, M]]:
    """(id, model) of every entry of ``section``, in definition order."""
    return [(m.id, m) for _, m in _entries(parsed, section, kind)]
