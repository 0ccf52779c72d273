"""What the catalog pages show: handles, base units and presets as JSON-ready rows, the pairings that fit, and
where each entry's pictures are.

Built once per app from the validated catalog through the registry's own views: the plain-data index
(:func:`rik.registry.index.build_index`), the CLI's formatted columns (:func:`rik.registry.views.table`), the
fit test of :mod:`rik.registry.fit`, and the per-handle numbers and pictures of ``docs/catalog`` that CATALOG.md
uses (:mod:`rik.registry.doc`). Lengths are in m (SI) with a ``_mm`` copy for display.
"""

from __future__ import annotations

from dataclasses import dataclass
from html import escape
from pathlib import Path
from typing import TYPE_CHECKING, Any

import rik
from rik.registry.doc import PICTURES_DIR, csv_rows, picture_dir
from rik.registry.ids import variant_id
from rik.registry.index import CatalogIndex, build_index
from rik.registry.views import srgb_hex, table

if TYPE_CHECKING:
    from rik.registry.catalog import Catalog

Row = dict[str, Any]

REPO_ROOT = Path(rik.__file__).resolve().parent.parent
"""Where CATALOG.md and ``docs/catalog`` live (a source checkout; an installed package may have neither)."""
PICTURES = ("thumbnail", "fidelity")
"""Per-handle pictures in ``docs/catalog/<id with / as __>/``: a shaded thumbnail and the collision heatmaps."""
FIDELITY_FIELDS = ("eqp_mean_mm", "eqp_p95_mm", "eqp_max_mm", "epq_mean_mm", "epq_p95_mm", "epq_max_mm")
"""Collision-to-visual (E_Q->P) and visual-to-collision (E_P->Q) distances, mm; ``hull_`` + these for the hull."""
MESH_FIELDS = ("vertices", "faces", "mean_edge_mm", "mean_face_area_mm2", "watertight", "hulls", "collision_vertices")


@dataclass(frozen=True)
class CatalogView:
    """The catalog as the pages show it."""

    index: CatalogIndex
    handles: dict[str, Row]
    bases: dict[str, Row]
    presets: list[Row]
    fits: dict[str, list[str]]
    """Handle id -> ids of the base units it fits (every front, :func:`rik.registry.fit.fits_base_unit`)."""
    root: Path

    def picture(self, entry_id: str, name: str) -> Path | None:
        """The picture file ``name`` (thumbnail or fidelity) of a handle, or None when there is none."""
        path = self.root / picture_dir(entry_id) / f"{name}.png"
        return path if path.is_file() else None

    def pairings_of_handle(self, handle_id: str) -> list[Row]:
        """The base units a handle fits, each with the variant id per preset of the default set (the base unit's
        default preset first; measured presets are built when named)."""
        return [self._pairing(b, handle_id, self.bases[b]) for b in self.fits[handle_id]]

    def pairings_of_base(self, base_id: str) -> list[Row]:
        """The handles that fit a base unit, each with the variant id per preset of the default set (the base unit's
        default preset first)."""
        return [self._pairing(base_id, h, self.handles[h]) for h, fit in self.fits.items() if base_id in fit]

    def _pairing(self, base_id: str, handle_id: str, other: Row) -> Row:
        default = self.bases[base_id]["default_preset"]
        presets = [default, *(p["id"] for p in self.presets if p["id"] != default and p["in_default_set"])]
        return {"id": other["id"], "label": other.get("name") or other.get("design_name") or other["id"],
                "type": other.get("type"),
                "variants": {p: variant_id(base_id, handle_id, p) for p in presets}}


def build_view(catalog: Catalog, root: Path = REPO_ROOT) -> CatalogView:
    """The view of ``catalog``; ``root`` is the directory holding ``docs/catalog`` (pictures and numbers)."""
    from rik.registry.fit import fits_base_unit

    index = build_index(catalog)
    designs = {d["id"]: d for d in index.entries("designs")}
    finishes = {f["id"]: f for f in index.entries("finishes")}
    fidelity = csv_rows(root / PICTURES_DIR / "fidelity.csv")
    mesh = csv_rows(root / PICTURES_DIR / "mesh_stats.csv")
    fits = {h.id: [b.id for b in catalog.base_units.values() if fits_base_unit(h, b)]
            for h in catalog.handles.values()}
    view = CatalogView(index, {}, {}, index.entries("presets"), fits, root)
    for entry in index.entries("handles"):
        view.handles[entry["id"]] = handle_row(entry, designs, finishes, fidelity.get(entry["id"]),
                                               mesh.get(entry["id"]), view)
    for entry in index.entries("base_units"):
        view.bases[entry["id"]] = base_row(entry, sum(entry["id"] in f for f in fits.values()))
    return view


def handle_row(entry: Row, designs: dict[str, Row], finishes: dict[str, Row], fidelity: dict[str, str] | None,
               mesh: dict[str, str] | None, view: CatalogView) -> Row:
    """One handle for the pages: the index entry plus display cells, mm copies, mesh and fidelity numbers."""
    g = entry["geometry"]
    headers, cells = table("handles", [entry])
    finish = finishes[entry["finish"]]
    return {
        **entry,
        "design_name": designs[entry["design"]]["name"],
        "finish_name": finish["name"],
        "finish_color": srgb_hex(finish["base_color"]),
        "dimensions_mm": {k: _mm(g[k]) for k in ("length", "width", "projection", "grip_diameter", "hole_spacing")}
        | {f"clearance_{k}": _mm((g.get("clearance") or {}).get(k)) for k in ("depth", "width")},
        "display": dict(zip(headers, cells[0], strict=True)),
        "mesh": None if mesh is None else {k: _number(mesh[k]) for k in MESH_FIELDS},
        "fidelity": None if fidelity is None else {
            "hulls": int(fidelity["hulls"]), "hull_over_coacd": float(fidelity["hull_over_coacd"]),
            "coacd": {k: float(fidelity[k]) for k in FIDELITY_FIELDS},
            "hull": {k: float(fidelity[f"hull_{k}"]) for k in FIDELITY_FIELDS}},
        "pictures": {p: view.picture(entry["id"], p) is not None for p in PICTURES},
        "fits": len(view.fits[entry["id"]]),
        "fit_bases": view.fits[entry["id"]],
        "extent_mm": _mm(max(g["length"], g["width"], g["projection"])),
    }


def base_row(entry: Row, fitting_handles: int) -> Row:
    """One base unit for the pages: the index entry plus display cells, mm copies and how many handles fit."""
    headers, cells = table("base_units", [entry])
    return {**entry, "display": dict(zip(headers, cells[0], strict=True)),
            "carcass_mm": {k: _mm(entry["carcass"][k]) for k in ("width", "height", "depth")},
            "fronts_mm": [{"id": f["id"], "kind": f["kind"], "joint": f["joint"]["type"],
                           "size": [_mm(v) for v in f["size"][:2]], "mount": [_mm(v) for v in f["mount"]["size"]]}
                          for f in entry["fronts"]],
            "fits": fitting_handles}


def base_unit_svg(entry: Row) -> str:
    """A front-view drawing of a base unit from its data (carcass outline, fronts by kind, ids), as SVG in mm.

    Base-unit frame: +x to the left of a person facing the front, +z up from the carcass's bottom."""
    width, height = entry["carcass"]["width"] * 1000, entry["carcass"]["height"] * 1000
    pad = 0.06 * max(width, height)
    colours = {"drawer": "#c9a46a", "door": "#9fb8c8", "flap": "#b7c99f"}
    parts = [f'<rect x="0" y="0" width="{width:.1f}" height="{height:.1f}" fill="#f3efe7" stroke="#555" '
             f'stroke-width="{pad / 6:.1f}"/>']
    for front in entry["fronts"]:
        w, h = front["size"][0] * 1000, front["size"][1] * 1000
        cx, cz = front["center"][0] * 1000, front["center"][2] * 1000
        x, y = width / 2 - cx - w / 2, height - cz - h / 2
        parts.append(f'<rect x="{x:.1f}" y="{y:.1f}" width="{w:.1f}" height="{h:.1f}" '
                     f'fill="{colours.get(front["kind"], "#ccc")}" stroke="#333" stroke-width="{pad / 10:.1f}"/>')
        size = min(w, h, width) / 5
        parts.append(f'<text x="{x + w / 2:.1f}" y="{y + h / 2 + size / 3:.1f}" font-size="{size:.1f}" '
                     f'text-anchor="middle" font-family="sans-serif" fill="#222">{escape(front["id"])}</text>')
    box = f"{-pad:.1f} {-pad:.1f} {width + 2 * pad:.1f} {height + 2 * pad:.1f}"
    return (f'<svg xmlns="http://www.w3.org/2000/svg" viewBox="{box}" width="240" '
            f'height="{240 * (height + 2 * pad) / (width + 2 * pad):.0f}">'
            f'<title>{escape(entry["id"])} (front view)</title>{"".join(parts)}</svg>')


def placeholder_svg(entry_id: str, name: str) -> str:
    """The picture shown where an entry has none (a user catalog's handle before ``rik assets fidelity``)."""
    return ('<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 240 160" width="240" height="160">'
            '<rect width="240" height="160" fill="#eee" stroke="#bbb" stroke-dasharray="6 4"/>'
            f'<text x="120" y="72" font-size="14" text-anchor="middle" font-family="sans-serif" fill="#666">'
            f'no {escape(name)} picture</text>'
            f'<text x="120" y="96" font-size="11" text-anchor="middle" font-family="sans-serif" fill="#888">'
            f'{escape(entry_id)}</text></svg>')


def _mm(value: float | None) -> float | None:
    return None if value is None else round(value * 1000, 3)


def _number(text: str) -> int | float | bool:
    if text in ("True", "False"):
        return text == "True"
    try:
        return int(text)
    except ValueError:
        return float(text)

