"""What many test files share: the built-in catalog, loaded once per test process, and the ids of the demo's
variant. Session fixtures that build from them live in ``conftest.py``."""

from __future__ import annotations

import functools
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from rik.registry.catalog import Catalog

BOW = "drawer-chest-80__two_point-bow-128__normal"
"""The demo's first variant: the 80 cm chest of drawers with the 128 mm bow handle, normal resistance."""
BOW_HANDLE, DEMO_BASE = "two_point/bow-128", "drawer/chest-80"


@functools.cache
def builtin_catalog() -> Catalog:
    """The built-in catalog (no overlays), loaded once per process; treat it as read-only."""
    from rik.registry.load import load_catalog

    return load_catalog([])
