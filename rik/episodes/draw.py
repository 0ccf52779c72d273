"""Which variant and front an episode opens, drawn from its seed: the same draw for the gym environment,
``rik record --split``, ``rik eval`` and ``lerobot-eval``, so an episode seed names one episode everywhere.

Episodes of a draw cycle through the *cells* of the paper's Table 3 (handle type x resistance preset): seed ``s``
falls in cell ``s mod (types x presets)``, so any run of ``cells x N`` consecutive seeds has exactly ``N``
episodes per cell. Within its cell the seed picks a base unit of the wanted kinds and a handle of the split (and
a front of the base unit) that fit together. The draw uses its own random stream (seeded by ``(seed,
DRAW_STREAM)``), so the start pose of the episode, drawn from ``default_rng(seed)`` as ``rik record --seed``
does, is the same as a recording of that variant with that seed.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from rik.errors import RikError
from rik.registry.ids import SEPARATOR

if TYPE_CHECKING:
    from rik.registry.catalog import Catalog

DEFAULT_TYPES = ("knob", "finger_pull", "two_point")
DEFAULT_PRESETS = ("smooth", "normal", "high")
DEFAULT_KINDS = ("drawer",)
"""The paper's case study opens drawers."""
JOINTS = ("paper", "measured")
"""What the hinges of a draw's doors are: the cell's preset (``paper``, as the paper's Table 3), or a real door's
fitted preset of the draw's split (``measured``: :func:`rik.registry.splits.split_presets`). Drawers and flaps keep
the cell's preset either way: no real drawer or flap was measured, and a vertical door's hinge does not carry a
flap's weight (a drop-down flap with a fridge door's hinge falls open: the variant's rest check refuses it)."""
MEASURED_KINDS = ("door",)
"""The front kinds whose hinges ``measured`` joints replace: those of the real mechanisms."""
ALL_SPLIT = "all"
"""The split name that means every handle of the catalog (``split=None``)."""
DRAW_STREAM = 0x5EED_D4A1
"""Second word of the draw's seed sequence, keeping it apart from the episode's own ``default_rng(seed)``."""


@dataclass(frozen=True)
class EpisodeDraw:
    """One episode's cell and the variant and front it opens."""

    seed: int
    handle_type: str
    preset: str
    """The preset of the variant: the cell's, or with ``measured`` joints a door's real door."""
    variant: str
    front: str


def choose_variant(catalog: Catalog, handle_type: str, preset: str, rng: np.random.Generator, kinds: Sequence[str],
                   compatible: set[str], handles: Sequence[str] | None = None,
                   door_presets: Sequence[str] = ()) -> tuple[str, str]:
    """A (variant id, front id) of ``handle_type`` on a base unit of ``kinds`` with ``preset``, among the
    ``compatible`` variant ids (and the ``handles`` given, default every handle of the type). With
    ``door_presets`` a door (:data:`MEASURED_KINDS`) takes one of them instead of ``preset`` (drawn last from ``rng``,
    so the base unit, handle and front are those of the same draw without them)."""
    from rik.registry.ids import variant_id

    base, handle, front = _choose(catalog, handle_type, preset, rng, kinds, compatible, handles)
    kind = next(f for f in catalog.base_units[base].fronts if f.id == front).kind
    if door_presets and kind in MEASURED_KINDS:
        preset = door_presets[int(rng.integers(len(door_presets)))]
    return variant_id(base, handle, preset), front


def _choose(catalog: Catalog, handle_type: str, preset: str, rng: np.random.Generator, kinds: Sequence[str],
            compatible: set[str], handles: Sequence[str] | None) -> tuple[str, str, str]:
    """(base unit id, handle id, front id) of :func:`choose_variant`'s draw with ``preset``."""
    from rik.registry.ids import variant_id

    bases = sorted(b for b, u in catalog.base_units.items() if u.fronts[0].kind in kinds)
    pool = sorted(h for h, v in catalog.handles.items() if catalog.handle_type(v).value == handle_type
                  and (handles is None or h in handles))
    for _ in range(100):
        if not bases or not pool:
            break
        base = bases[int(rng.integers(len(bases)))]
        handle = pool[int(rng.integers(len(pool)))]
        if variant_id(base, handle, preset) in compatible:
            fronts = catalog.base_units[base].fronts
            return base, handle, fronts[int(rng.integers(len(fronts)))].id
    raise RikError(f"no valid {handle_type} variant on a {'/'.join(kinds)} base unit with preset {preset}")


@dataclass(frozen=True)
class Draw:
    """The episodes of a split: handle types x presets on base units of some kinds (see the module docstring)."""

    split: str | None = "test"
    """Catalog split of the handles (``rik catalog splits``), or None for every handle."""
    handle_types: tuple[str, ...] = DEFAULT_TYPES
    presets: tuple[str, ...] = DEFAULT_PRESETS
    kinds: tuple[str, ...] = DEFAULT_KINDS
    joints: str = "paper"
    """:data:`JOINTS`: ``measured`` gives doors the split's real doors' presets."""

    @classmethod
    def parse(cls, split: str, types: str | None = None, presets: str | None = None,
              kinds: str | None = None, joints: str | None = None) -> Draw:
        """A draw from command-line text: a split name (:data:`ALL_SPLIT` for every handle) and comma-separated
        handle types, presets and front kinds (None: the defaults; a list with no name fails :meth:`check`), and
        the joints (:data:`JOINTS`)."""
        def names(text: str | None, default: tuple[str, ...]) -> tuple[str, ...]:
            return default if text is None else tuple(t.strip() for t in text.split(",") if t.strip())

        return cls(None if split == ALL_SPLIT else split, names(types, DEFAULT_TYPES),
                   names(presets, DEFAULT_PRESETS), names(kinds, DEFAULT_KINDS), (joints or "paper").strip())

    def door_presets(self, catalog: Catalog) -> tuple[str, ...]:
        """The presets a door of this draw takes in place of its cell's: none for ``paper`` joints, the
        split's measured presets (every measured preset for :data:`ALL_SPLIT`) for ``measured``."""
        if self.joints != "measured":
            return ()
        if self.split is None:
            return tuple(catalog.preset_splits)
        from rik.registry.splits import split_presets

        return split_presets(catalog, self.split)

    @property
    def cells(self) -> list[tuple[str, str]]:
        """(handle type, preset) of each cell, in seed order."""
        return [(t, p) for t in self.handle_types for p in self.presets]

    def check(self, catalog: Catalog) -> None:
        """Unknown split, handle type, preset or kind: one clear line."""
        if self.split is not None:
            from rik.registry.splits import split_handles

            split_handles(catalog, self.split)
        from rik.schemas.handles import HandleType

        types = {t.value for t in HandleType}
        for t in self.handle_types:
            if t not in types:
                raise RikError(f"unknown handle type '{t}' (types: {', '.join(sorted(types))})")
        for p in self.presets:
            if p not in catalog.presets:
                raise RikError(f"unknown preset '{p}' (presets: {', '.join(catalog.presets)})")
        kinds = sorted({f.kind for u in catalog.base_units.values() for f in u.fronts})
        for k in self.kinds:
            if k not in kinds:
                raise RikError(f"unknown front kind '{k}' (kinds: {', '.join(kinds)})")
        if not (self.handle_types and self.presets and self.kinds):
            raise RikError("a draw needs at least one handle type, preset and front kind")
        if self.joints not in JOINTS:
            raise RikError(f"unknown joints '{self.joints}' (joints: {', '.join(JOINTS)})")
        if self.joints == "measured":
            if not set(self.kinds) & set(MEASURED_KINDS):
                raise RikError(f"joints 'measured': real doors' presets go on doors; the kinds "
                               f"{', '.join(self.kinds)} have none (drawers and flaps keep the paper's presets: no "
                               "real drawer or flap was measured)")
            if not self.door_presets(catalog):
                raise RikError(f"joints 'measured': split '{self.split}' holds no measured preset (rik catalog "
                               "splits lists them)")

    def episode(self, catalog: Catalog, seed: int) -> EpisodeDraw:
        """The episode of ``seed`` (an integer >= 0)."""
        cells = self.cells
        handle_type, preset = cells[seed % len(cells)]
        rng = np.random.default_rng([seed, DRAW_STREAM])
        compatible, handles = _pool(catalog, self)
        variant, front = choose_variant(catalog, handle_type, preset, rng, self.kinds, compatible, handles,
                                        self.door_presets(catalog))
        return EpisodeDraw(seed, handle_type, variant.rsplit(SEPARATOR, 1)[1], variant, front)


_POOLS: dict[tuple[int, Draw], tuple[Catalog, set[str], tuple[str, ...] | None]] = {}


def _pool(catalog: Catalog, draw: Draw) -> tuple[set[str], tuple[str, ...] | None]:
    """(variant ids of the draw, handles of its split or None), computed once per catalog and draw."""
    from rik.registry.ids import select_variants

    hit = _POOLS.get((id(catalog), draw))
    if hit is None or hit[0] is not catalog:
        handles = None
        if draw.split is not None:
            from rik.registry.splits import split_handles

            handles = split_handles(catalog, draw.split)
        ids = {k.id for k in select_variants(catalog, handle_types=draw.handle_types, presets=draw.presets,
                                             handles=handles or ())}
        hit = _POOLS[(id(catalog), draw)] = (catalog, ids, handles)
    return hit[1], hit[2]
