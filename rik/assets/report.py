"""Per-handle reports: collision fidelity (with heatmap and thumbnail pictures) and mesh statistics, as rows.

Fidelity results are stored beside the asset in the cache (keyed by the asset key, sample count and seed), so a
second report costs only the pictures that are missing.
"""

from __future__ import annotations

import csv
import functools
import io
from collections.abc import Callable, Sequence
from dataclasses import asdict
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rik.assets import figures
from rik.assets.build import DEFAULT_SEED, build_asset
from rik.assets.cache import AssetCache, source_digest
from rik.assets.fidelity import DEFAULT_POINTS, Deviation, Fidelity, check_points, measure
from rik.assets.stats import MeshStats
from rik.errors import RikError
from rik.outputs import Replaces, write_text
from rik.workers import map_ids

if TYPE_CHECKING:
    from rik.registry.catalog import Catalog

Row = dict[str, Any]

FIDELITY_COLUMNS = ["id", "type", "hulls", "collision_vertices",
                    "eqp_mean_mm", "eqp_p95_mm", "eqp_max_mm", "epq_mean_mm", "epq_p95_mm", "epq_max_mm",
                    "hull_eqp_mean_mm", "hull_eqp_p95_mm", "hull_eqp_max_mm", "hull_epq_mean_mm",
                    "hull_epq_p95_mm", "hull_epq_max_mm", "hull_over_coacd"]
STATS_COLUMNS = ["id", "type", "vertices", "faces", "mean_edge_mm", "mean_face_area_mm2", "watertight", "hulls",
                 "collision_vertices"]


def picture_dir(out: Path, handle_id: str) -> Path:
    """Where a handle's pictures go: ``<out>/<id with / as __>/``."""
    return out / handle_id.replace("/", "__")


def handle_ids(catalog: Catalog, ids: Sequence[str], everything: bool) -> list[str]:
    """Handle ids to report on (all with ``everything``); base units are refused with the reason."""
    if everything:
        return list(catalog.handles)
    if not ids:
        raise RikError("name at least one handle id, or pass --all")
    for hid in ids:
        if hid in catalog.base_units:
            raise RikError(f"{hid} is a base unit: its collision is its own panels (exact, zero deviation); "
                           "fidelity is measured on handles")
        catalog.handle(hid)
    return list(dict.fromkeys(ids))


def _fidelity_from_json(data: dict[str, Any]) -> Fidelity | None:
    """The stored figures; ``None`` when they do not have the current shape (measure again)."""
    try:
        return Fidelity(**{k: Deviation(**v) for k, v in data.items()})
    except TypeError:
        return None


def fidelity_row(catalog: Catalog, handle_id: str, *, out: Path | None = None, points: int = DEFAULT_POINTS,
                 seed: int = DEFAULT_SEED, cache: AssetCache | None = None) -> Row:
    """Fidelity of one handle's collision (CoACD and convex-hull baseline); with ``out``, also write its
    ``thumbnail.png`` and ``fidelity.png`` there."""
    check_points(points)
    cache = cache or AssetCache()
    asset, _ = build_asset(catalog, handle_id, seed, cache)
    part = asset.part("handle")
    name = f"fidelity-{points}-{seed}.json"
    stored = cache.read_extra(asset.key, name)  # verified against its sha256
    fid = _fidelity_from_json(stored) if stored is not None else None
    samples = None
    if fid is None:
        fid, samples = measure(part.visual, part.hulls, part.baseline, points, seed)
        cache.write_extra(asset.key, name, asdict(fid))
    if out is not None:
        pictures = picture_dir(out, handle_id)
        stamp = pictures / "asset.key"  # the asset and drawing code the pictures show: redraw when either changes
        drawn = f"{asset.key} {source_digest([Path(figures.__file__)])[:16]}"
        current = stamp.is_file() and stamp.read_text().strip() == drawn
        if not current or not (pictures / "fidelity.png").is_file():
            if samples is None:
                fid, samples = measure(part.visual, part.hulls, part.baseline, points, seed)
            figures.heatmap(samples, fid, f"{handle_id}: collision deviation", pictures / "fidelity.png", seed)
        if not current or not (pictures / "thumbnail.png").is_file():
            finish = catalog.finish(part.finish)
            figures.thumbnail(part.visual, finish.base_color, finish.metallic, pictures / "thumbnail.png")
        if not current:
            write_text(stamp, drawn + "\n", figures.PICTURE)
    return {"id": handle_id, "type": asset.category, "hulls": len(part.hulls),
            "collision_vertices": sum(len(v) for v, _ in part.hulls),
            **_deviation_cells("eqp", fid.q_to_p), **_deviation_cells("epq", fid.p_to_q),
            **_deviation_cells("hull_eqp", fid.baseline_q_to_p), **_deviation_cells("hull_epq", fid.baseline_p_to_q),
            "hull_over_coacd": round(fid.baseline_q_to_p.mean / max(fid.q_to_p.mean, 1e-9), 2)}


def _deviation_cells(prefix: str, d: Deviation) -> Row:
    return {f"{prefix}_mean_mm": round(d.mean, 3), f"{prefix}_p95_mm": round(d.p95, 3),
            f"{prefix}_max_mm": round(d.max, 3)}


def stats_row(catalog: Catalog, handle_id: str, *, seed: int = DEFAULT_SEED, cache: AssetCache | None = None) -> Row:
    """Mesh statistics of one handle's visual mesh and the size of its collision."""
    asset, _ = build_asset(catalog, handle_id, seed, cache)
    part = asset.part("handle")
    s = MeshStats.of(part.visual)
    return {"id": handle_id, "type": asset.category, "vertices": s.vertices, "faces": s.faces,
            "mean_edge_mm": round(s.mean_edge_mm, 3), "mean_face_area_mm2": round(s.mean_face_area_mm2, 4),
            "watertight": s.watertight, "hulls": len(part.hulls),
            "collision_vertices": sum(len(v) for v, _ in part.hulls)}


def summarise_fidelity(rows: Sequence[Row]) -> dict[str, Row]:
    """Mean of the per-handle means, per handle type and over all handles."""
    groups: dict[str, list[Row]] = {"all": list(rows)}
    for row in rows:
        groups.setdefault(row["type"], []).append(row)
    out = {}
    for name, group in groups.items():
        n = len(group)
        eqp = sum(r["eqp_mean_mm"] for r in group) / n
        hull = sum(r["hull_eqp_mean_mm"] for r in group) / n
        out[name] = {"handles": n, "eqp_mean_mm": eqp, "epq_mean_mm": sum(r["epq_mean_mm"] for r in group) / n,
                     "hull_eqp_mean_mm": hull, "hull_epq_mean_mm": sum(r["hull_epq_mean_mm"] for r in group) / n,
                     "hull_over_coacd": hull / max(eqp, 1e-9)}
    return out


def run_rows(fn: Callable[..., Row], catalog: Catalog, ids: Sequence[str], *, workers: int = 1,
             overlays: Sequence[Path] = (), on_row: Callable[[Row], None] | None = None, **kwargs: Any) -> list[Row]:
    """``fn(catalog, id, **kwargs)`` for every id, in ``workers`` processes; rows come back in ``ids`` order."""
    rows: dict[str, Row] = {}
    for handle_id, row in map_ids(functools.partial(fn, **kwargs), catalog, ids, workers=workers,
                                  overlays=overlays):
        rows[handle_id] = row
        if on_row:
            on_row(row)
    return [rows[i] for i in ids]


def csv_table(columns: Sequence[str]) -> Replaces:
    """What a CSV table of ``columns`` may replace: a table with exactly that header (rik's, whose rows
    :func:`merge_csv` keeps), or a file rik recorded writing there."""
    header = ",".join(columns)

    def test(path: Path) -> bool:
        try:
            with open(path, encoding="utf-8") as handle:
                return handle.readline().rstrip("\r\n") == header
        except (OSError, UnicodeDecodeError):
            return False

    return Replaces.when(f"a table of rik's with the columns {header[:60]}...", test)


def write_csv(rows: Sequence[Row], columns: Sequence[str], path: Path) -> None:
    """Write ``rows`` as CSV atomically, over a table of the same columns only (:func:`csv_table`)."""
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=list(columns), lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    path.parent.mkdir(parents=True, exist_ok=True)
    write_text(path, buf.getvalue(), csv_table(columns))


def merge_csv(rows: Sequence[Row], columns: Sequence[str], path: Path) -> list[Row]:
    """Update ``path`` with ``rows`` (replacing rows with the same id, keeping the others) and return all rows."""
    existing: dict[str, Row] = {}
    if path.is_file():
        with path.open() as fh:
            existing = {r["id"]: r for r in csv.DictReader(fh)}
    existing.update({r["id"]: r for r in rows})
    merged = list(existing.values())
    write_csv(merged, columns, path)
    return merged
