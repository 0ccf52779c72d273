"""Named, versioned splits of the catalog: every handle design is in exactly one of train, val and test.

Whole designs are held out (all handles of a design share its split) and every split holds all three handle
types. Base units and the paper's presets are not split: every split spans all of them. The **measured presets**
(real doors' hinges, :attr:`rik.schemas.joints.ResistancePreset.in_default_set` false) are split too, whole doors
held out as designs are, each mechanism class (:func:`rik.schemas.joints.JointResistance.mechanism`) in every
split: the ``presets`` mapping of the same ``splits`` key. The assignment is committed data,
``rik/registry/data/splits.yaml`` (a catalog file whose top-level ``splits`` key holds ``version``, a list of
design ids per split and ``presets``, a list of measured preset ids per split). A user overlay may add a
``splits`` mapping of its own that places its own designs and measured presets; overlay designs and measured
presets it does not place are in :data:`OVERLAY_DEFAULT` (train), so the held-out sets only grow when a user says
so. Changing which built-in design or preset is in which split means a new :data:`SPLITS_VERSION`.
"""

from __future__ import annotations

import difflib
from collections.abc import Callable, Mapping, Sequence
from typing import TYPE_CHECKING

from rik.errors import CatalogError, RikError, UnknownIdError
from rik.registry.sources import BUILTIN_DIR, SPLITS_KEY, RawEntry, display_path, line_of

if TYPE_CHECKING:
    from rik.registry.catalog import Catalog

#: The split names, in the order they are listed.
SPLITS = ("train", "val", "test")
#: Version of the built-in assignment; datasets and evaluations record it ("splits v1").
SPLITS_VERSION = 1
#: The key of a ``splits`` mapping that places measured presets (a mapping of split -> preset ids).
PRESETS_KEY = "presets"
#: The split of an overlay design or measured preset that no ``splits`` mapping places.
OVERLAY_DEFAULT = "train"
#: Where the built-in assignment lives.
BUILTIN_SPLITS_FILE = BUILTIN_DIR / "splits.yaml"


def check_split(name: str) -> str:
    """``name`` if it is a split; otherwise a one-line :class:`RikError` (with a close match when there is one)."""
    if name in SPLITS:
        return name
    close = difflib.get_close_matches(name, SPLITS, n=1, cutoff=0.6)
    hint = f"; did you mean '{close[0]}'?" if close else ""
    raise RikError(f"unknown split '{name}' (splits: {', '.join(SPLITS)}){hint}")


def split_designs(catalog: Catalog, name: str) -> tuple[str, ...]:
    """Design ids of split ``name``, in catalog order."""
    check_split(name)
    return tuple(d for d in catalog.designs if catalog.splits[d] == name)


def split_handles(catalog: Catalog, name: str) -> tuple[str, ...]:
    """Handle ids of split ``name``, in catalog order."""
    check_split(name)
    return tuple(h.id for h in catalog.handles.values() if catalog.splits[h.design] == name)


def split_presets(catalog: Catalog, name: str) -> tuple[str, ...]:
    """Ids of the measured presets of split ``name`` (real doors held out whole), in catalog order."""
    check_split(name)
    return tuple(p for p in catalog.presets if catalog.preset_splits.get(p) == name)


def split_of(catalog: Catalog, handle_id: str) -> str:
    """The split a handle is in (that of its design); an unknown handle raises with close ids."""
    return catalog.splits[catalog.handle(handle_id).design]


def splits_version(catalog: Catalog) -> int:
    """The version of the catalog's split assignment (:data:`SPLITS_VERSION`)."""
    return catalog.splits_version


def assign_splits(entries: Sequence[RawEntry], builtin_designs: Mapping[str, bool],
                  measured_presets: Mapping[str, bool] | None = None
                  ) -> tuple[dict[str, str], int, dict[str, str]]:
    """Validate the ``splits`` mappings of the catalog files: (design id -> split, version, measured preset id ->
    split).

    ``builtin_designs``: every design id of the catalog, in catalog order, -> whether it is rik's own;
    ``measured_presets`` the same for the measured presets. Every built-in design and measured preset must be in
    exactly one split of rik's own files; an overlay may place only its own. Raises :class:`CatalogError` naming
    the file, the split and the design or preset.
    """
    measured = dict(measured_presets or {})
    placed: dict[str, tuple[str, RawEntry, int]] = {}
    placed_presets: dict[str, tuple[str, RawEntry, int]] = {}
    version: int | None = None
    builtin_file = next((e.file for e in entries if e.builtin), BUILTIN_SPLITS_FILE)
    for entry in entries:
        data = entry.data
        shown = display_path(entry.file)
        if not isinstance(data, dict):
            raise CatalogError(shown, None, SPLITS_KEY, f"must be a mapping of version, {', '.join(SPLITS)}",
                               line_of(entry.file, (SPLITS_KEY,)))
        for key, value in data.items():
            field = f"{SPLITS_KEY}.{key}"
            line = line_of(entry.file, (SPLITS_KEY, key))
            if key == "version":
                if type(value) is not int or value != SPLITS_VERSION:
                    raise CatalogError(shown, None, field, f"must be {SPLITS_VERSION}, the splits version this rik "
                                       f"reads (got {value!r})", line)
                version = value if entry.builtin else version
                continue
            if key == PRESETS_KEY:
                _place_presets(entry, value, measured, placed_presets)
                continue
            if key not in SPLITS:
                raise CatalogError(shown, None, field, "unknown split; valid fields: version, "
                                   f"{', '.join(SPLITS)}, {PRESETS_KEY}", line)
            if value is None:
                continue
            if not isinstance(value, list):
                raise CatalogError(shown, None, field, "must be a list of design ids", line)
            for i, design in enumerate(value):
                _place(entry, (SPLITS_KEY,), key, i, design, builtin_designs, placed, "design",
                       lambda d: str(UnknownIdError("design", d, builtin_designs)), "a design")
        if entry.builtin and "version" not in data:
            raise CatalogError(shown, None, f"{SPLITS_KEY}.version", "required field is missing",
                               line_of(entry.file, (SPLITS_KEY,)))
    for design, builtin in builtin_designs.items():
        if builtin and design not in placed:
            raise CatalogError(display_path(builtin_file), None, SPLITS_KEY, f"design '{design}' is in no split; "
                               f"add it to one of {', '.join(SPLITS)}", line_of(builtin_file, (SPLITS_KEY,)))
    for preset, builtin in measured.items():
        if builtin and preset not in placed_presets:
            raise CatalogError(display_path(builtin_file), None, f"{SPLITS_KEY}.{PRESETS_KEY}",
                               f"measured preset '{preset}' is in no split; add it to one of {', '.join(SPLITS)}",
                               line_of(builtin_file, (SPLITS_KEY,)))
    splits = {d: placed[d][0] if d in placed else OVERLAY_DEFAULT for d in builtin_designs}
    preset_splits = {p: placed_presets[p][0] if p in placed_presets else OVERLAY_DEFAULT for p in measured}
    return splits, SPLITS_VERSION if version is None else version, preset_splits


def _place_presets(entry: RawEntry, value: object, measured: Mapping[str, bool],
                   placed: dict[str, tuple[str, RawEntry, int]]) -> None:
    """Record the measured presets of a ``splits.presets`` mapping in ``placed``, or raise."""
    shown = display_path(entry.file)
    field = f"{SPLITS_KEY}.{PRESETS_KEY}"
    if value is None:
        return
    if not isinstance(value, dict):
        raise CatalogError(shown, None, field, f"must be a mapping of {', '.join(SPLITS)} to measured preset ids",
                           line_of(entry.file, (SPLITS_KEY, PRESETS_KEY)))
    for split, ids in value.items():
        where = f"{field}.{split}"
        line = line_of(entry.file, (SPLITS_KEY, PRESETS_KEY, split))
        if split not in SPLITS:
            raise CatalogError(shown, None, where, f"unknown split; valid fields: {', '.join(SPLITS)}", line)
        if ids is None:
            continue
        if not isinstance(ids, list):
            raise CatalogError(shown, None, where, "must be a list of measured preset ids", line)
        for i, preset in enumerate(ids):
            _place(entry, (SPLITS_KEY, PRESETS_KEY), split, i, preset, measured, placed, "preset",
                   lambda p: f"'{p}' is not a measured preset (only measured presets are split; the paper's are in "
                   "every split)" + ("" if not measured else f"; measured: {', '.join(list(measured)[:4])}, ..."),
                   "a door")


def _place(entry: RawEntry, at: tuple[str, ...], split: str, index: int, item: object, known: Mapping[str, bool],
           placed: dict[str, tuple[str, RawEntry, int]], noun: str, unknown: Callable[[str], str],
           one: str) -> None:
    """Record ``item`` (entry ``index`` of ``split`` under the keys ``at`` of ``entry``'s file) in ``placed``, or
    raise. ``known``: every id of its kind -> whether it is rik's own; ``noun`` names the kind (design, preset),
    ``unknown(item)`` says why an id not in ``known`` cannot be placed, ``one`` what is in exactly one split."""
    shown = display_path(entry.file)
    field = ".".join((*at, split))
    line = line_of(entry.file, (*at, split, index))
    if not isinstance(item, str):
        raise CatalogError(shown, None, field, f"must list {noun} ids (got {item!r})", line)
    if item not in known:
        raise CatalogError(shown, None, field, unknown(item), line)
    if known[item] and not entry.builtin:
        raise CatalogError(shown, None, field, f"{noun} '{item}' is built in and has its split in rik's own "
                           f"splits.yaml; an overlay may place only its own {noun}s", line)
    if not known[item] and entry.builtin:  # pragma: no cover - built-in data never names overlay ids
        raise CatalogError(shown, None, field, f"{noun} '{item}' is not built in", line)
    if item in placed:
        other, other_entry, other_index = placed[item]
        where = display_path(other_entry.file)
        other_line = line_of(other_entry.file, (*at, other, other_index))
        raise CatalogError(shown, None, field, f"{noun} '{item}' is already in split '{other}' "
                           f"({where}:{other_line}); {one} is in exactly one split", line)
    placed[item] = (split, entry, index)
