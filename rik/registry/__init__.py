"""The catalog registry: rik's data files, their loading and validation, queries, and CATALOG.md.

``load_catalog()`` gives typed models; ``catalog_index()`` a cached plain-data view for fast listing.
This package's own import is cheap: the schema classes load with ``load_catalog``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from rik.registry.index import CatalogIndex, catalog_index

if TYPE_CHECKING:
    from rik.registry.catalog import Catalog

__all__ = ["Catalog", "CatalogIndex", "catalog_index", "load_catalog"]


def __getattr__(name: str) -> Any:
    if name in ("load_catalog", "build_catalog"):
        from rik.registry import load

        return getattr(load, name)
    if name == "Catalog":
        from rik.registry.catalog import Catalog

        return Catalog
    raise AttributeError(f"module 'rik.registry' has no attribute {name!r}")
