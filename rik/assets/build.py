"""Build assets: visual mesh and collision of every rigid part of a handle or a base unit, cached by content.

A handle is one rigid part (``handle``) decomposed with CoACD; a base unit has one part per rigid body
(``carcass`` and each front) whose collision is its panels (see :mod:`rik.assets.base_units`). Every part also
keeps the single convex hull that prior data sets use, as the baseline of the fidelity metric.
"""

from __future__ import annotations

import functools
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rik.assets.base_units import base_unit_plan, part_mesh
from rik.assets.cache import AssetCache, CorruptEntry, content_key, library_versions, source_digest
from rik.assets.decompose import Hulls, coacd_params, convex_hull_baseline, decompose
from rik.assets.handles import generate_handle
from rik.assets.importer import read_user_mesh
from rik.errors import RikError, UnknownIdError
from rik.outputs import remove_cache_entry
from rik.workers import map_ids

if TYPE_CHECKING:
    import numpy as np
    import trimesh

    from rik.registry.catalog import Catalog

DEFAULT_SEED = 0
ASSETS_DIR = Path(__file__).parent


@dataclass
class RigidPart:
    """One rigid body's geometry: visual mesh, convex collision parts and the single-hull baseline (m)."""

    name: str
    role: str
    """``handle``, ``carcass`` or the front's kind (``drawer``, ``door``, ``flap``)."""
    finish: str
    method: str
    """How the collision was made: ``coacd`` or ``exact`` (the part is a union of convex panels)."""
    visual: trimesh.Trimesh
    hulls: Hulls
    baseline: Hulls


@dataclass
class Asset:
    """A built handle or base unit."""

    id: str
    kind: str
    """``handle`` or ``base_unit``."""
    category: str
    """Handle type (``knob``, ``two_point``, ``finger_pull``) or ``base_unit``."""
    key: str
    parts: list[RigidPart]
    meta: dict[str, Any] = field(default_factory=dict)

    def part(self, name: str) -> RigidPart:
        return next(p for p in self.parts if p.name == name)


@dataclass(frozen=True)
class BuildResult:
    """What one build did (small, picklable: sent back from worker processes)."""

    id: str
    kind: str
    key: str
    status: str
    """``cached``, ``built`` or ``rebuilt`` (the cached entry failed its hash check)."""
    seconds: float
    hulls: int
    collision_vertices: int
    note: str = ""


# ---- identities ---------------------------------------------------------------------------------------------------
@functools.cache
def _code_and_versions() -> tuple[str, dict[str, str]]:
    """Digest of the generator code and the library versions: the same for every asset of a run, so read once."""
    sources = [ASSETS_DIR / "meshkit.py", ASSETS_DIR / "base_units.py", *sorted((ASSETS_DIR / "handles").glob("*.py"))]
    return source_digest(sources), library_versions()


def _beside_definition(catalog: Catalog, section: str, entry_id: str, relative: str) -> Path:
    """A file named in a catalog entry, relative to the YAML file that defines the entry."""
    return Path(catalog.origins[(section, entry_id)].file).parent / relative


def asset_kind(catalog: Catalog, asset_id: str) -> str:
    """``handle`` or ``base_unit``; unknown ids raise with close matches from both sections."""
    if asset_id in catalog.handles:
        return "handle"
    if asset_id in catalog.base_units:
        return "base_unit"
    raise UnknownIdError("handle or base unit", asset_id, [*catalog.handles, *catalog.base_units])


def asset_identity(catalog: Catalog, asset_id: str, seed: int = DEFAULT_SEED) -> dict[str, object]:
    """Everything that decides an asset's files: the catalog entry, generator code, CoACD parameters, seed and
    library versions. Its :func:`content_key` addresses the cache."""
    kind = asset_kind(catalog, asset_id)
    code, versions = _code_and_versions()
    ident: dict[str, Any] = {"kind": kind, "seed": seed, "versions": versions, "code": code}
    if kind == "handle":
        handle = catalog.handles[asset_id]
        design = catalog.designs[handle.design]
        ident |= {"entry": handle.model_dump(mode="json", exclude={"licence", "mass"}),
                  "design": design.generator.model_dump(mode="json"),  # an imported mesh: its sha256
                  "coacd": coacd_params(design.type.value, seed).__dict__}
    else:
        unit = catalog.base_units[asset_id]
        ident |= {"entry": unit.model_dump(mode="json", include={"carcass", "fronts", "meshes"})}
        if unit.meshes is not None:
            ident["coacd"] = coacd_params("base_part", seed).__dict__
    return ident


def asset_key(catalog: Catalog, asset_id: str, seed: int = DEFAULT_SEED) -> str:
    return content_key(asset_identity(catalog, asset_id, seed))


# ---- generation -----------------------------------------------------------------------------------------------
def generate_parts(catalog: Catalog, asset_id: str, seed: int = DEFAULT_SEED) -> tuple[str, list[RigidPart]]:
    """Generate and decompose every rigid part (no cache). Returns (category, parts)."""
    if asset_kind(catalog, asset_id) == "handle":
        handle = catalog.handles[asset_id]
        design = catalog.designs[handle.design]
        category = design.type.value
        if design.generator.name == "user_mesh":
            mesh = read_user_mesh(_beside_definition(catalog, "designs", design.id, design.generator.file),
                                  design.generator.sha256)
        else:
            mesh = generate_handle(handle, design)
        hulls = decompose(mesh, coacd_params(category, seed))  # imports are cleaned to closed solids too
        return category, [RigidPart("handle", "handle", handle.finish, "coacd", mesh, hulls,
                                    convex_hull_baseline(mesh))]
    unit = catalog.base_units[asset_id]
    if unit.meshes is not None:
        return "base_unit", _imported_base_parts(catalog, asset_id, seed)
    parts = []
    for plan in base_unit_plan(unit):
        mesh = part_mesh(plan)
        hulls = [_box_hull(p.mesh()) for p in plan.panels]
        parts.append(RigidPart(plan.name, plan.role, plan.finish, "exact", mesh, hulls,
                               convex_hull_baseline(mesh)))
    return "base_unit", parts


def _imported_base_parts(catalog: Catalog, asset_id: str, seed: int) -> list[RigidPart]:
    """The parts of an imported base unit: its mesh files, each decomposed with CoACD on its own."""
    unit = catalog.base_units[asset_id]
    assert unit.meshes is not None
    roles = [("carcass", "carcass", unit.carcass.finish), *((f.id, f.kind, f.finish) for f in unit.fronts)]
    parts = []
    for name, role, finish in roles:
        ref = unit.meshes[name]
        mesh = read_user_mesh(_beside_definition(catalog, "base_units", asset_id, ref.file), ref.sha256)
        parts.append(RigidPart(name, role, finish, "coacd", mesh, decompose(mesh, coacd_params("base_part", seed)),
                               convex_hull_baseline(mesh)))
    return parts


def _box_hull(mesh: trimesh.Trimesh) -> tuple[np.ndarray, np.ndarray]:
    import numpy as np

    return np.asarray(mesh.vertices, dtype=np.float64), np.asarray(mesh.faces, dtype=np.int64)


# ---- (de)serialisation -------------------------------------------------------------------------------------------
def _arrays(parts: Sequence[RigidPart]) -> dict[str, object]:
    import numpy as np

    out: dict[str, Any] = {}
    for i, part in enumerate(parts):
        out[f"p{i}_visual_v"] = np.asarray(part.visual.vertices, dtype=np.float64)
        out[f"p{i}_visual_f"] = np.asarray(part.visual.faces, dtype=np.int64)
        for j, (v, f) in enumerate(part.hulls):
            out[f"p{i}_hull{j}_v"], out[f"p{i}_hull{j}_f"] = v, f
        (bv, bf), = part.baseline
        out[f"p{i}_base_v"], out[f"p{i}_base_f"] = bv, bf
    return out


def load_asset(cache: AssetCache, key: str) -> Asset | None:
    """The asset stored under ``key``, or ``None`` if absent (raises CorruptEntry if damaged)."""
    import numpy as np
    import trimesh

    entry = cache.get(key)
    if entry is None:
        return None
    try:
        with np.load(entry.payload) as data:
            parts = []
            for i, p in enumerate(entry.meta["parts"]):
                visual = trimesh.Trimesh(data[f"p{i}_visual_v"], data[f"p{i}_visual_f"], process=False)
                hulls = [(data[f"p{i}_hull{j}_v"], data[f"p{i}_hull{j}_f"]) for j in range(p["hulls"])]
                baseline = [(data[f"p{i}_base_v"], data[f"p{i}_base_f"])]
                parts.append(RigidPart(p["name"], p["role"], p["finish"], p["method"], visual, hulls, baseline))
    except (KeyError, ValueError, OSError) as exc:

        remove_cache_entry(entry.path)
        raise CorruptEntry(f"cache entry {entry.path} is unreadable ({exc}); it was removed") from None
    m = entry.meta
    return Asset(m["id"], m["kind"], m["category"], key, parts, m)


def build_asset(catalog: Catalog, asset_id: str, seed: int = DEFAULT_SEED,
                cache: AssetCache | None = None) -> tuple[Asset, BuildResult]:
    """The asset for ``asset_id`` from the cache, or generated, decomposed and stored."""
    cache = cache or AssetCache()
    t0 = time.perf_counter()
    key = asset_key(catalog, asset_id, seed)
    status, note = "cached", ""
    try:
        asset = load_asset(cache, key)
    except CorruptEntry as exc:
        asset, status, note = None, "rebuilt", str(exc)
    if asset is None:
        from rik.locks import exclusive

        # one process decomposes an asset; another that needs it at the same time (a worker of the same build, a
        # second rik on the same cache) waits for it and loads the entry, rather than running CoACD again
        with exclusive(cache.path(key), "rik assets build", wait=True):
            asset = load_asset(cache, key)
            if asset is None:
                status = "built" if status == "cached" else status
                category, parts = generate_parts(catalog, asset_id, seed)
                meta = {"id": asset_id, "kind": asset_kind(catalog, asset_id), "category": category, "seed": seed,
                        "build_seconds": round(time.perf_counter() - t0, 3),
                        "parts": [{"name": p.name, "role": p.role, "finish": p.finish, "method": p.method,
                                   "hulls": len(p.hulls), "collision_vertices": sum(len(v) for v, _ in p.hulls),
                                   "visual_vertices": len(p.visual.vertices), "visual_faces": len(p.visual.faces)}
                                  for p in parts]}
                cache.put(key, _arrays(parts), meta)
                asset = load_asset(cache, key)
                assert asset is not None
    result = BuildResult(asset_id, asset.kind, key, status, time.perf_counter() - t0,
                         sum(len(p.hulls) for p in asset.parts),
                         sum(len(v) for p in asset.parts for v, _ in p.hulls), note)
    return asset, result


# ---- many at once ------------------------------------------------------------------------------------------------
def resolve_ids(catalog: Catalog, ids: Iterable[str], everything: bool) -> list[str]:
    """The asset ids to build: all handles then all base units with ``everything``, else ``ids`` checked."""
    wanted = list(ids)
    if everything:
        return [*catalog.handles, *catalog.base_units]
    if not wanted:
        raise RikError("name at least one handle or base unit id, or pass --all")
    for asset_id in wanted:
        asset_kind(catalog, asset_id)
    return list(dict.fromkeys(wanted))


def _build_result(catalog: Catalog, asset_id: str, seed: int, cache_root: Path) -> BuildResult:
    return build_asset(catalog, asset_id, seed, AssetCache(cache_root))[1]


def build_assets(catalog: Catalog, ids: Sequence[str], *, overlays: Sequence[Path] = (), seed: int = DEFAULT_SEED,
                 workers: int = 1, cache: AssetCache | None = None,
                 on_result: Callable[[BuildResult], None] | None = None) -> list[BuildResult]:
    """Build every id; cache hits are answered in this process, misses go to ``workers`` processes
    (:func:`rik.workers.map_ids`).

    ``on_result`` is called once per id as it finishes (for progress bars). Results come back in ``ids`` order.
    """
    cache = cache or AssetCache()
    done: dict[str, BuildResult] = {}

    corrupt: dict[str, str] = {}

    def finish(result: BuildResult) -> None:
        if result.id in corrupt:
            from dataclasses import replace

            result = replace(result, status="rebuilt", note=corrupt[result.id])
        done[result.id] = result
        if on_result:
            on_result(result)

    misses = []
    for asset_id in ids:
        t0 = time.perf_counter()
        key = asset_key(catalog, asset_id, seed)
        try:
            entry = cache.get(key)
        except CorruptEntry as exc:
            entry, corrupt[asset_id] = None, str(exc)
        if entry is None:
            misses.append(asset_id)
            continue
        m = entry.meta
        finish(BuildResult(asset_id, m["kind"], key, "cached", time.perf_counter() - t0,
                           sum(p["hulls"] for p in m["parts"]), sum(p["collision_vertices"] for p in m["parts"])))
    build = functools.partial(_build_result, seed=seed, cache_root=cache.root)
    for _, result in map_ids(build, catalog, misses, workers=workers, overlays=overlays):
        finish(result)
    return [done[i] for i in ids]
