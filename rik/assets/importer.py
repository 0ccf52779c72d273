"""Import a real handle mesh (paper appendix A.1): read, clean, normalise units and frame, measure its grasp
geometry, and register it as a design + handle in a user overlay catalog, with the mesh file beside the YAML.

The overlay is then used like any catalog (``--catalog DIR`` or ``RIK_CATALOG``): ``rik assets build`` decomposes
the imported mesh with CoACD, ``rik assets fidelity`` measures it, and the combinator pairs it with base units.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rik.errors import RikError
from rik.registry.sources import display_path

if TYPE_CHECKING:
    import trimesh

SUFFIXES = (".stl", ".obj", ".ply", ".off", ".glb", ".gltf")
"""Mesh files rik reads (through trimesh)."""
UNIT_SCALES = {"m": 1.0, "cm": 0.01, "mm": 0.001, "in": 0.0254}
MAX_EXTENT = {"knob": 0.15, "two_point": 1.2, "finger_pull": 1.2}
"""Largest plausible extent of a handle of each type, m (a knob of 15 cm, a wardrobe bar of 1.2 m)."""
MIN_EXTENT = 0.008
"""Smallest plausible extent of any handle, m."""
AXES = {"+x": (1, 0, 0), "-x": (-1, 0, 0), "+y": (0, 1, 0), "-y": (0, -1, 0), "+z": (0, 0, 1), "-z": (0, 0, -1)}
DEFAULT_DENSITY = 6600.0
"""Zinc die-cast, kg/m^3: the usual material of furniture hardware (assumed when no mass is given)."""


@dataclass(frozen=True)
class ImportedHandle:
    handle_id: str
    yaml_path: Path
    mesh_path: Path
    geometry: dict[str, Any]


def mesh_sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def read_mesh(path: Path) -> trimesh.Trimesh:
    """Read a mesh file as one triangle mesh (scenes are flattened); clear errors for every way it can fail."""
    import trimesh

    shown = display_path(path)
    if path.suffix.lower() not in SUFFIXES:
        raise RikError(f"{shown}: unknown mesh file type '{path.suffix or '(none)'}'; rik reads "
                       + ", ".join(SUFFIXES))
    if not path.is_file():
        raise RikError(f"{shown}: no such file")
    try:
        loaded = trimesh.load(path, force="mesh", process=False)
    except Exception as exc:  # trimesh raises many types for a damaged file
        raise RikError(f"{shown}: cannot read the mesh ({exc.__class__.__name__}: {exc})") from None
    if not isinstance(loaded, trimesh.Trimesh) or len(loaded.faces) == 0:
        raise RikError(f"{shown}: the mesh is empty (no triangles)")
    return loaded


def read_user_mesh(path: Path, sha256: str) -> trimesh.Trimesh:
    """An imported design's mesh, after checking it is the file that was registered."""
    if not path.is_file():
        raise RikError(f"{display_path(path)}: the imported mesh is missing")
    if mesh_sha256(path) != sha256:
        raise RikError(f"{display_path(path)}: the mesh file changed since it was imported (sha256 differs from "
                       "generator.sha256); import it again")
    return read_mesh(path)


def clean(mesh: trimesh.Trimesh, shown: str) -> trimesh.Trimesh:
    """Merge duplicate vertices, drop degenerate and duplicate faces, fill small holes, make winding consistent
    and outward. A mesh that is still open or non-manifold after that is refused."""
    import trimesh

    mesh = mesh.copy()
    mesh.merge_vertices()
    mesh.update_faces(mesh.nondegenerate_faces())
    mesh.update_faces(mesh.unique_faces())
    mesh.remove_unreferenced_vertices()
    trimesh.repair.fill_holes(mesh)
    trimesh.repair.fix_normals(mesh)
    if not mesh.is_watertight:
        open_edges = len(trimesh.grouping.group_rows(mesh.edges_sorted, require_count=1))
        raise RikError(f"{shown}: the mesh is not a closed solid after cleaning ({open_edges} open edges, "
                       f"{len(mesh.faces)} faces): rik needs a watertight, manifold mesh; close it in a mesh editor")
    if mesh.volume < 0:
        mesh.invert()
    return mesh


def to_mount_frame(mesh: trimesh.Trimesh, out_axis: str, long_axis: str, shown: str) -> trimesh.Trimesh:
    """Rotate so ``out_axis`` (the file's axis pointing out of the front) becomes +z and ``long_axis`` becomes
    +x; then put the back face on z = 0 and centre x and y on the bounding box."""
    import numpy as np

    z, x = np.array(AXES[out_axis], float), np.array(AXES[long_axis], float)
    if abs(z @ x) > 0.5:
        raise RikError(f"{shown}: --out {out_axis} and --long {long_axis} must be different axes")
    rotation = np.eye(4)
    rotation[:3, :3] = np.vstack([x, np.cross(z, x), z])
    out = mesh.copy()
    out.apply_transform(rotation)
    lo, hi = out.bounds
    out.apply_translation([-(lo[0] + hi[0]) / 2, -(lo[1] + hi[1]) / 2, -lo[2]])
    return out


def scale_to_metres(mesh: trimesh.Trimesh, units: str, handle_type: str, shown: str) -> trimesh.Trimesh:
    """Scale by ``units``; with ``auto`` the file must already be in metres, and a size 1000x too large for the
    handle type is refused with the likely unit."""
    extent = float(mesh.extents.max())
    if units == "auto":
        if extent > MAX_EXTENT[handle_type]:
            guess = "millimetres" if extent / 1000 <= MAX_EXTENT[handle_type] else "an unknown unit"
            raise RikError(f"{shown}: the mesh is {extent:g} units long, more than a {handle_type} handle can be "
                           f"({MAX_EXTENT[handle_type]} m); it looks like {guess}: pass --units mm (or cm, in)")
        scale = 1.0
    else:
        scale = UNIT_SCALES[units]
    out = mesh.copy()
    out.apply_scale(scale)
    size = float(out.extents.max())
    if not MIN_EXTENT <= size <= MAX_EXTENT[handle_type]:
        raise RikError(f"{shown}: in {units if units != 'auto' else 'm'} the mesh is {size:g} m long; a "
                       f"{handle_type} handle is {MIN_EXTENT} to {MAX_EXTENT[handle_type]} m: check --units")
    return out


def _first_hit(mesh: trimesh.Trimesh, origin: tuple[float, float, float], direction: tuple[float, float, float],
               ) -> float | None:
    import numpy as np

    hits, _, _ = mesh.ray.intersects_location([origin], [direction])
    if len(hits) == 0:
        return None
    return float(np.min(np.linalg.norm(hits - np.asarray(origin), axis=1)))


def measure_geometry(mesh: trimesh.Trimesh, handle_type: str, shown: str, hole_spacing: float | None,
                     clearance: tuple[float, float] | None, grip_diameter: float | None) -> dict[str, Any]:
    """The handle's catalog geometry measured on the mesh (mount frame). For two-point handles the loop's
    clearance is found by casting rays from the mount centre: up to the grip (depth), then sideways to the legs
    (width)."""
    length, width, projection = (float(v) for v in mesh.extents)
    geometry: dict[str, Any] = {"length": round(length, 5), "width": round(width, 5),
                                "projection": round(projection, 5)}
    if handle_type == "two_point":
        if hole_spacing is None:
            raise RikError(f"{shown}: a two-point handle needs --hole-spacing (centre-to-centre of its screws, m)")
        depth = _first_hit(mesh, (0.0, 0.0, 1e-5), (0.0, 0.0, 1.0))
        if depth is None:
            raise RikError(f"{shown}: nothing above the mount centre: is --out the axis pointing out of the front?")
        top = _first_hit(mesh, (0.0, 0.0, projection + 0.01), (0.0, 0.0, -1.0))
        sides = [_first_hit(mesh, (0.0, 0.0, depth / 2), (s, 0.0, 0.0)) for s in (1.0, -1.0)]
        if None in sides:
            raise RikError(f"{shown}: no legs found on both sides of the loop: is --long the handle's long axis?")
        geometry |= {"grip_diameter": round(grip_diameter or (projection + 0.01 - top - depth), 5),
                     "hole_spacing": hole_spacing,
                     "clearance": {"depth": round(depth, 5), "width": round(sum(sides), 5)}}  # type: ignore[arg-type]
    elif handle_type == "knob":
        geometry |= {"grip_diameter": round(grip_diameter or max(length, width), 5)}
    else:
        if clearance is None:
            raise RikError(f"{shown}: a finger-pull needs --clearance DEPTH WIDTH (m): how deep fingertips go "
                           "under its lip or hood, and how wide")
        geometry |= {"grip_diameter": grip_diameter or 0.003, "clearance": {"depth": clearance[0],
                                                                           "width": clearance[1]}}
    return geometry


def _yaml_text(design: dict[str, Any], handle: dict[str, Any]) -> str:
    import yaml

    header = "# Imported with `rik assets import`; lengths in metres. Edit the names freely; the mesh is the data.\n"
    return header + yaml.safe_dump({"designs": [design], "handles": [handle]}, sort_keys=False)


def import_handle(path: Path, *, handle_type: str, design_id: str, size: str, catalog_dir: Path,
                  name: str | None = None, finish: str = "metal/brushed-steel", units: str = "auto",
                  out_axis: str = "+z", long_axis: str = "+x", hole_spacing: float | None = None,
                  clearance: tuple[float, float] | None = None, grip_diameter: float | None = None,
                  mount: str | None = None, edge: str = "top", mass: float | None = None,
                  density: float = DEFAULT_DENSITY, licence: str = "LicenseRef-user") -> ImportedHandle:
    """Read ``path``, normalise it and register it in ``catalog_dir`` (created if needed).

    Nothing is left behind on failure: files are written to a hidden directory inside ``catalog_dir``, the whole
    catalog (built-in + every overlay file already there + the new one) is validated, and only then are the files
    moved into place."""
    import trimesh  # noqa: F401  (the mesh stack; fail early if it is missing)

    from rik.registry.load import load_catalog

    shown = display_path(path)
    if not design_id.startswith(f"{handle_type}/"):
        raise RikError(f"--id {design_id}: a {handle_type} design's id must start with '{handle_type}/'")
    mesh = read_mesh(path)
    mesh = clean(mesh, shown)
    mesh = scale_to_metres(mesh, units, handle_type, shown)
    mesh = to_mount_frame(mesh, out_axis, long_axis, shown)
    geometry = measure_geometry(mesh, handle_type, shown, hole_spacing, clearance, grip_diameter)
    stem = design_id.replace("/", "__")
    mount_kind = mount or {"knob": "single_screw", "two_point": "two_screw"}.get(handle_type, "edge_clip")
    mount_entry: dict[str, Any] = {"kind": mount_kind}
    if mount_kind == "edge_clip":
        mount_entry["edge"] = edge
    catalog_dir.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=".import-", dir=catalog_dir))
    try:
        (tmp / "meshes").mkdir()
        mesh_rel = Path("meshes") / f"{stem}.stl"
        mesh.export(tmp / mesh_rel, file_type="stl")
        generator = {"name": "user_mesh", "file": mesh_rel.as_posix(), "sha256": mesh_sha256(tmp / mesh_rel)}
        design = {"id": design_id, "type": handle_type, "subtype": "imported", "name": name or f"Imported {stem}",
                  "generator": generator,
                  "provenance": {"origin": "user_mesh", "reference": f"imported from {path.name}"}}
        handle = {"id": f"{design_id}-{size}", "design": design_id, "size": size, "finish": finish,
                  "geometry": geometry, "mount": mount_entry,
                  "mass": round(mass if mass is not None else float(mesh.volume) * density, 4), "licence": licence}
        (tmp / f"{stem}.yaml").write_text(_yaml_text(design, handle))
        for target in (catalog_dir / f"{stem}.yaml", catalog_dir / mesh_rel):
            if target.exists():
                raise RikError(f"{display_path(target)} already exists: design {design_id} was imported before; "
                               "choose another --id or delete the files")
        load_catalog([catalog_dir, tmp])  # the catalog with the new entry must validate as a whole
        (catalog_dir / "meshes").mkdir(exist_ok=True)
        os.replace(tmp / mesh_rel, catalog_dir / mesh_rel)
        os.replace(tmp / f"{stem}.yaml", catalog_dir / f"{stem}.yaml")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return ImportedHandle(handle["id"], catalog_dir / f"{stem}.yaml", catalog_dir / mesh_rel, geometry)
