"""Base-unit generator: the carcass and every moving front as separate rigid parts built from panels.

All meshes are in the base unit's frame with every front closed (origin at the bottom of the carcass's front
plane, +x to the left of a person facing the front, +y out of the front, +z up; metres). Each part is built from
rectangular panels with thickness, and the panels themselves are its exact convex decomposition: a box is convex,
so the collision of a generated base unit needs no CoACD and has zero surface deviation. (Imported base units are
decomposed with CoACD.)
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from rik.assets.meshkit import require_solid, union
from rik.registry.geometry import vec3

if TYPE_CHECKING:
    import trimesh

    from rik.schemas.base_units import BaseUnit, Front

BACK_PANEL_THICKNESS = 0.006
"""Hardboard back panel, m."""


@dataclass(frozen=True)
class Panel:
    """An axis-aligned board: its centre and its extents along x, y, z (m)."""

    name: str
    center: tuple[float, float, float]
    extents: tuple[float, float, float]

    def mesh(self) -> trimesh.Trimesh:
        import trimesh

        box = trimesh.creation.box(extents=self.extents)
        box.apply_translation(self.center)
        return box


@dataclass(frozen=True)
class PartPlan:
    """One rigid part of a base unit: ``carcass`` or a front's id, its finish and its panels."""

    name: str
    role: str
    """``carcass`` (fixed) or the front's kind (``drawer``, ``door``, ``flap``)."""
    finish: str
    panels: tuple[Panel, ...]


def _slab(name: str, lo: tuple[float, float, float], hi: tuple[float, float, float]) -> Panel:
    center = vec3((a + b) / 2 for a, b in zip(lo, hi, strict=True))
    extents = vec3(b - a for a, b in zip(lo, hi, strict=True))
    return Panel(name, center, extents)


def carcass_panels(unit: BaseUnit) -> tuple[Panel, ...]:
    """Sides, top, bottom and back of the carcass, plus a divider between drawers that sit side by side."""
    c = unit.carcass
    w, h, d, t = c.width / 2, c.height, c.depth, c.panel_thickness
    panels = [
        _slab("side_left", (-w, -d, 0), (-w + t, 0, h)),
        _slab("side_right", (w - t, -d, 0), (w, 0, h)),
        _slab("bottom", (-w + t, -d, 0), (w - t, 0, t)),
        _slab("top", (-w + t, -d, h - t), (w - t, 0, h)),
        _slab("back", (-w + t, -d, t), (w - t, -d + BACK_PANEL_THICKNESS, h - t)),
    ]
    panels += _dividers(unit)
    return tuple(panels)


def _dividers(unit: BaseUnit) -> list[Panel]:
    """A vertical divider midway between the boxes of two drawers that share a height band."""
    c = unit.carcass
    t = c.panel_thickness
    drawers = sorted(((f, f.drawer_box) for f in unit.fronts if f.drawer_box is not None),
                     key=lambda fb: fb[0].center[0])
    out = []
    for (left, left_box), (right, right_box) in zip(drawers, drawers[1:], strict=False):
        lz = (left.center[2] - left.size[1] / 2, left.center[2] + left.size[1] / 2)
        rz = (right.center[2] - right.size[1] / 2, right.center[2] + right.size[1] / 2)
        if min(lz[1], rz[1]) <= max(lz[0], rz[0]):
            continue
        gap_lo = left.center[0] + left_box.width / 2
        gap_hi = right.center[0] - right_box.width / 2
        if gap_hi - gap_lo <= t:
            continue
        x = (gap_lo + gap_hi) / 2
        out.append(_slab(f"divider_{left.id}_{right.id}", (x - t / 2, -c.depth + BACK_PANEL_THICKNESS, t),
                         (x + t / 2, 0, c.height - t)))
    return out


def front_panels(front: Front) -> tuple[Panel, ...]:
    """The front panel, and for a drawer its box: front wall, two sides, back and bottom (running clearance is
    the catalog's: the box is narrower than the carcass opening)."""
    fw, fh, ft = front.size
    cx, cy, cz = front.center
    panels = [Panel("panel", (cx, cy, cz), (fw, ft, fh))]
    box = front.drawer_box
    if box is None:
        return tuple(panels)
    y_front = cy - ft / 2  # back face of the front panel
    wt, bw, bh, bd = box.wall_thickness, box.width / 2, box.height, box.depth
    z0 = cz - bh / 2
    x0, x1 = cx - bw, cx + bw
    y0 = y_front - bd
    panels += [
        _slab("box_front", (x0 + wt, y_front - wt, z0 + wt), (x1 - wt, y_front, z0 + bh)),
        _slab("box_side_left", (x0, y0, z0), (x0 + wt, y_front, z0 + bh)),
        _slab("box_side_right", (x1 - wt, y0, z0), (x1, y_front, z0 + bh)),
        _slab("box_back", (x0 + wt, y0, z0 + wt), (x1 - wt, y0 + wt, z0 + bh)),
        _slab("box_bottom", (x0 + wt, y0, z0), (x1 - wt, y_front, z0 + wt)),
    ]
    return tuple(panels)


def base_unit_plan(unit: BaseUnit) -> tuple[PartPlan, ...]:
    """Every rigid part of ``unit``: the carcass first, then the fronts in catalog order."""
    parts = [PartPlan("carcass", "carcass", unit.carcass.finish, carcass_panels(unit))]
    parts += [PartPlan(f.id, f.kind, f.finish, front_panels(f)) for f in unit.fronts]
    return tuple(parts)


def part_mesh(plan: PartPlan) -> trimesh.Trimesh:
    """The visual mesh of a part: the union of its panels (watertight)."""
    return require_solid(union([p.mesh() for p in plan.panels]), f"part {plan.name}")
