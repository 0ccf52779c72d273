"""Counts that summarise a catalog: what ``rik catalog stats`` and the README's demo print."""

from __future__ import annotations

from collections import Counter
from typing import Any

from rik.registry.index import CatalogIndex
from rik.registry.splits import SPLITS

HANDLE_TYPES = ("knob", "two_point", "finger_pull")


def catalog_stats(index: CatalogIndex) -> dict[str, Any]:
    """Counts per handle type, base units per joint type and front kind, presets, finishes, fitting pairings,
    and the robots' ids. ``presets``: the default set, which variants are built with when no preset is named;
    ``named_presets``: the others (measured), built only when named."""
    handles, designs = index.entries("handles"), index.entries("designs")
    bases = index.entries("base_units")
    fronts = [f for b in bases for f in b["fronts"]]
    return {
        "handles": len(handles),
        "designs": len(designs),
        "by_type": {t: {"designs": sum(d["type"] == t for d in designs),
                        "handles": sum(h["type"] == t for h in handles)} for t in HANDLE_TYPES},
        "base_units": len(bases),
        "fronts": len(fronts),
        "fronts_by_kind": dict(Counter(f["kind"] for f in fronts)),
        "base_units_by_joint": {j: sum(j in b["joint_types"] for b in bases) for j in ("slide", "hinge")},
        "presets": [p["id"] for p in index.entries("presets") if p["in_default_set"]],
        "named_presets": [p["id"] for p in index.entries("presets") if not p["in_default_set"]],
        "finishes": len(index.entries("finishes")),
        "pairings": dict(index.pairings),
        "robots": [r["id"] for r in index.entries("robots")],
        "overlay_entries": sum(e["origin"] == "overlay" for s in index.sections.values() for e in s),
    }


def split_stats(index: CatalogIndex) -> dict[str, Any]:
    """The split version and, per split (train, val, test), its designs and handles per handle type and in all."""
    handles, designs = index.entries("handles"), index.entries("designs")
    per_split: dict[str, Any] = {}
    for split in SPLITS:
        split_designs = [d for d in designs if d["split"] == split]
        split_handles = [h for h in handles if h["split"] == split]
        per_split[split] = {
            "designs": len(split_designs),
            "handles": len(split_handles),
            "by_type": {t: {"designs": sum(d["type"] == t for d in split_designs),
                            "handles": sum(h["type"] == t for h in split_handles)} for t in HANDLE_TYPES},
        }
    return {"version": index.splits_version, "splits": per_split}
