"""Surface finishes: the appearance data that the MuJoCo and Mitsuba renderers both read."""

from __future__ import annotations

from typing import Literal

from rik.schemas.common import CatalogId, Frozen, Unit


class Finish(Frozen):
    """A physically based surface description (metallic-roughness model)."""

    id: CatalogId
    """Catalog id, for example ``metal/brushed-steel``."""
    name: str
    """Human-readable name."""
    kind: Literal["metal", "lacquer", "plastic", "wood", "rubber", "leather", "ceramic"]
    """Material family; the renderers pick a BSDF by it."""
    base_color: tuple[Unit, Unit, Unit]
    """Base colour as sRGB components in [0, 1]."""
    metallic: Unit
    """0 for dielectrics, 1 for bare metal."""
    roughness: Unit
    """Perceptual roughness in [0, 1] (0 = mirror)."""
    pattern: Literal["plain", "brushed", "wood_grain"] = "plain"
    """Procedural surface pattern: brushed metal (anisotropic along the part's x axis) or wood grain."""
