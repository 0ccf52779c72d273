"""Loading the catalog: rik's built-in data plus optional user overlays, validated into typed models.

:func:`load_catalog` always reads and validates the files. The fast path for listing is
:mod:`rik.registry.index`, a plain-data view cached by content hash.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from pathlib import Path

from pydantic import BaseModel

from rik.registry import checks
from rik.registry.catalog import Catalog, Origin
from rik.registry.entries import SECTION_MODELS, parse_entry
from rik.registry.sources import NOUNS, RawEntry, catalog_sources, read_file


def load_catalog(overlays: Iterable[Path] | None = None) -> Catalog:
    """The built-in catalog plus ``overlays`` (YAML files or directories; ``None``: those of ``RIK_CATALOG``).

    Raises :class:`rik.errors.CatalogError` naming the file, entry and field of the first problem found.
    """
    files = catalog_sources(overlays)
    return build_catalog([e for path, builtin in files for e in read_file(path, builtin)])


def build_catalog(entries: Sequence[RawEntry]) -> Catalog:
    """Validate raw entries (each against its schema, then the cross-entry checks) into a :class:`Catalog`."""
    parsed: dict[str, list[tuple[RawEntry, BaseModel]]] = {s: [] for s in SECTION_MODELS}
    for entry in entries:
        parsed[entry.section].append((entry, parse_entry(entry)))
    for section, items in parsed.items():
        checks.check_unique_ids(items, NOUNS[section])
    for section in checks.IN_VARIANT_IDS:
        checks.check_variant_id_parts(parsed[section], section, NOUNS[section])
    by_id = {s: {m.id: m for _, m in items} for s, items in parsed.items()}  # type: ignore[attr-defined]
    designs, finishes, presets = by_id["designs"], by_id["finishes"], by_id["presets"]
    for entry, handle in parsed["handles"]:
        checks.check_handle(entry, handle, designs, finishes)  # type: ignore[arg-type]
    used = [h.design for h in by_id["handles"].values()]  # type: ignore[attr-defined]
    for entry, design in parsed["designs"]:
        checks.check_design(entry, design, used.count(design.id))  # type: ignore[arg-type, attr-defined]
    for entry, base in parsed["base_units"]:
        checks.check_base_unit(entry, base, finishes, presets)  # type: ignore[arg-type]
    origins = {(s, m.id): Origin(str(e.file), e.builtin) for s, items in parsed.items() for e, m in items}  # type: ignore[attr-defined]
    return Catalog(**by_id, origins=origins)  # type: ignore[arg-type]
