"""The catalog registry: rik's data files, their loading and validation, queries, and CATALOG.md."""

from rik.registry.catalog import Catalog, Origin
from rik.registry.fit import fits, fitting_rotations, footprint
from rik.registry.load import build_catalog, load_catalog

__all__ = ["Catalog", "Origin", "build_catalog", "fits", "fitting_rotations", "footprint", "load_catalog"]
