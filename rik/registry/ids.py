"""Variant ids: ``<base unit>__<handle>__<preset>`` with each catalog id's ``/`` written as ``-``.

For example base unit ``drawer/chest-60``, handle ``two_point/bow-128`` and preset ``normal`` make
``drawer-chest-60__two_point-bow-128__normal``. Ids are stable (they depend on the three catalog ids only) and
safe as directory names.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from rik.errors import RikError, UnknownIdError
from rik.registry.splits import split_handles

if TYPE_CHECKING:
    from collections.abc import Iterable

    from rik.registry.catalog import Catalog

SEPARATOR = "__"


def slug(catalog_id: str) -> str:
    """A catalog id as one path component (``drawer/chest-60`` -> ``drawer-chest-60``)."""
    return catalog_id.replace("/", "-")


@dataclass(frozen=True, order=True)
class VariantKey:
    """The three catalog ids a variant is made of."""

    base: str
    handle: str
    preset: str

    @property
    def id(self) -> str:
        return SEPARATOR.join((slug(self.base), slug(self.handle), self.preset))


def variant_id(base: str, handle: str, preset: str) -> str:
    return VariantKey(base, handle, preset).id


def parse_variant_id(catalog: Catalog, text: str) -> VariantKey:
    """The catalog ids behind a variant id; a malformed id or an unknown part raises with close matches."""
    parts = text.strip().strip("/").split("/")[-1].split(SEPARATOR)
    if len(parts) != 3:
        raise RikError(f"variant id '{text}' must be <base unit>{SEPARATOR}<handle>{SEPARATOR}<preset>, "
                       "for example drawer-chest-60__two_point-bow-128__normal")
    base_slug, handle_slug, preset = parts
    bases = {slug(b): b for b in catalog.base_units}
    handles = {slug(h): h for h in catalog.handles}
    if base_slug not in bases:
        raise UnknownIdError("base unit", base_slug, bases)
    if handle_slug not in handles:
        raise UnknownIdError("handle", handle_slug, handles)
    catalog.preset(preset)
    return VariantKey(bases[base_slug], handles[handle_slug], preset)


def select_variants(catalog: Catalog, *, bases: Iterable[str] = (), handle_types: Iterable[str] = (),
                    handles: Iterable[str] = (), presets: Iterable[str] = (),
                    split: str | None = None) -> list[VariantKey]:
    """Every base unit x handle x preset pairing, filtered; empty filters mean all (for presets: the default set).
    Unknown ids raise.

    ``split`` (train, val or test) keeps the handles of that split (:mod:`rik.registry.splits`); base units and
    presets are not split. An unknown split name raises.

    Order: base units and handles in catalog order, presets in the order asked for (default: the catalog's
    default presets, :attr:`~rik.registry.catalog.Catalog.default_presets`, in catalog order: measured presets are
    built only when named).
    """
    base_ids = [catalog.base_unit(b).id for b in bases] or list(catalog.base_units)
    handle_ids = [catalog.handle(h).id for h in handles] or list(catalog.handles)
    types = set(handle_types)
    if types:
        handle_ids = [h for h in handle_ids if catalog.handle_type(catalog.handles[h]).value in types]
    if split is not None:
        in_split = set(split_handles(catalog, split))
        handle_ids = [h for h in handle_ids if h in in_split]
    preset_ids = [catalog.preset(p).id for p in presets] or catalog.default_presets
    return [VariantKey(b, h, p) for b in base_ids for h in handle_ids for p in preset_ids]
