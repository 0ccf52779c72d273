"""Import a real handle mesh (paper appendix A.1): read, clean, normalise units and frame, measure its grasp
geometry, and register it as a design + handle in a user overlay catalog, with the mesh file beside the YAML.

The overlay is then used like any catalog (``--catalog DIR`` or ``RIK_CATALOG``): ``rik assets build`` decomposes
the imported mesh with CoACD, ``rik assets fidelity`` measures it, and the combinator pairs it with base units.
"""

from __future__ import annotations

import hashlib
import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rik.errors import RikError
from rik.outputs import NEW, make_stage, move_new, remove_stage, write_text
from rik.registry.sources import display_path

if TYPE_CHECKING:
    import numpy as np
    import trimesh

    from rik.schemas.imports import BaseUnitMapping

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
MAX_FACES = 500_000
"""Most triangles an imported file may have (``--max-faces`` raises it): over 100 times the catalog's own
handles (172 to about 4,000) and well above a scan decimated for simulation (tens of thousands). Cleaning, ray
casts and CoACD grow with the count: a 5.2-million-triangle STL ran for minutes, then the process died without
a message (issue 16), so larger files are refused at once, before any work."""
BYTES_PER_FACE = 512
"""Largest file, per triangle of ``--max-faces``, that rik reads (:func:`check_file_size`): a binary STL takes 50
bytes a triangle, an ASCII STL about 250, an OBJ or PLY written without shared corners (each triangle its own three
vertices, normals and texture coordinates) about 400, a GLB about 120."""
BYTES_ALLOWANCE = 64 * 2**20
"""Added to the bound for headers, materials and textures (a GLB's pictures)."""
GLTF_SIZES = {5120: 1, 5121: 1, 5122: 2, 5123: 2, 5125: 4, 5126: 4}
GLTF_WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}


@dataclass(frozen=True)
class ImportedHandle:
    handle_id: str
    yaml_path: Path
    mesh_path: Path
    geometry: dict[str, Any]


def mesh_sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def largest_file(max_faces: int) -> int:
    """Bytes of the largest mesh file read for ``--max-faces max_faces`` (:data:`BYTES_PER_FACE`)."""
    return BYTES_PER_FACE * max_faces + BYTES_ALLOWANCE


def check_file_size(path: Path, max_faces: int) -> None:
    """Refuse, before trimesh reads it, a mesh file larger than :func:`largest_file`, or a glTF/GLB whose JSON
    declares more data (buffers, accessors) than that: trimesh allocates what they declare (a 16-byte sparse
    accessor of 10^10 points asks for 112 GiB)."""
    shown = display_path(path)
    most = largest_file(max_faces)
    size = path.stat().st_size
    how = (f"--max-faces {max_faces:,} allows {most / 2**20:,.0f} MiB ({BYTES_PER_FACE} bytes a triangle, plus "
           f"{BYTES_ALLOWANCE // 2**20} MiB for headers and textures)")
    if size > most:
        raise RikError(f"{shown}: {size / 2**20:,.0f} MiB, larger than {how}; nothing was read: simplify the mesh, "
                       "or raise --max-faces")
    if path.suffix.lower() in (".glb", ".gltf"):
        declared = _gltf_declared_bytes(path, size)
        if declared > most:
            raise RikError(f"{shown}: its glTF JSON declares {declared / 2**20:,.0f} MiB of buffers and accessors, "
                           f"more than {how}; nothing was loaded: export the file again, or raise --max-faces")


def _gltf_declared_bytes(path: Path, size: int) -> int:
    """Bytes of data a glTF (.gltf) or GLB file declares: its buffers and accessors (the larger sum), and the
    external files its buffers name; a GLB JSON chunk longer than the file is refused."""
    import json
    import struct

    shown = display_path(path)
    try:
        with open(path, "rb") as handle:
            if path.suffix.lower() == ".glb":
                head = handle.read(20)
                if len(head) < 20 or head[:4] != b"glTF":
                    raise RikError(f"{shown}: not a GLB file (no glTF header)")
                length = struct.unpack("<I", head[12:16])[0]
                if length > size - 20:
                    raise RikError(f"{shown}: its JSON chunk declares {length:,} bytes, more than the file holds "
                                   f"({size:,}); the file is damaged: export it again")
                raw = handle.read(length)
            else:
                raw = handle.read()  # size already bounded
        doc = json.loads(raw.decode("utf-8"))
    except RikError:
        raise
    except (OSError, ValueError, RecursionError) as exc:
        raise RikError(f"{shown}: cannot read its glTF JSON ({exc.__class__.__name__}: {exc})") from None
    if not isinstance(doc, dict):
        raise RikError(f"{shown}: its glTF JSON is not an object")

    def items(key: str) -> list[dict[str, Any]]:
        value = doc.get(key)
        return [v for v in value if isinstance(v, dict)] if isinstance(value, list) else []

    def number(value: Any) -> int:
        return value if isinstance(value, int) and value > 0 else 0

    buffers = 0
    for b in items("buffers"):
        buffers += number(b.get("byteLength"))
        uri = b.get("uri")
        if isinstance(uri, str) and not uri.startswith("data:"):
            try:
                buffers += (path.parent / uri).stat().st_size  # trimesh reads the file whole
            except (OSError, ValueError):
                pass  # a missing file: trimesh says so
    accessors = 0
    for a in items("accessors"):
        kind, shape = a.get("componentType"), a.get("type")
        accessors += (number(a.get("count")) * (GLTF_SIZES.get(kind, 4) if isinstance(kind, int) else 4)
                      * (GLTF_WIDTH.get(shape, 16) if isinstance(shape, str) else 16))
    return max(buffers, accessors)


def _load(path: Path, suffixes: tuple[str, ...], force: str, wrong_type: str, max_faces: int | None = MAX_FACES
          ) -> Any:
    """``trimesh.load`` with one-line errors for a wrong file type, a missing file, one too large for
    ``max_faces`` (:func:`check_file_size`) and a damaged one."""
    import trimesh

    shown = display_path(path)
    if path.suffix.lower() not in suffixes:
        raise RikError(f"{shown}: {wrong_type}")
    if not path.is_file():
        raise RikError(f"{shown}: no such file")
    if max_faces is not None:
        check_file_size(path, max_faces)
    try:
        return trimesh.load(path, force=force, process=False)
    except Exception as exc:  # trimesh raises many types for a damaged file
        raise RikError(f"{shown}: cannot read the file ({exc.__class__.__name__}: {exc})") from None


def check_finite(mesh: trimesh.Trimesh, shown: str) -> None:
    """Refuse a mesh with NaN or infinite coordinates (before cleaning, whose numpy casts would warn on them)."""
    import numpy as np

    bad = ~np.isfinite(np.asarray(mesh.vertices, dtype=float)).all(axis=1)
    if bad.any():
        faces = int(bad[np.asarray(mesh.faces)].any(axis=1).sum())
        raise RikError(f"{shown}: {faces} of its {len(mesh.faces)} triangles have corners that are not finite "
                       "numbers (NaN or infinity); the file is damaged: export it again")


def check_size(faces: int, shown: str, max_faces: int) -> None:
    """Refuse a mesh of more than ``max_faces`` triangles (:data:`MAX_FACES` by default)."""
    if faces > max_faces:
        raise RikError(f"{shown}: the mesh has {faces:,} triangles, more than the limit of {max_faces:,}; "
                       f"simplify it, or raise the limit with --max-faces {faces}")


def read_mesh(path: Path, max_faces: int | None = MAX_FACES) -> trimesh.Trimesh:
    """Read a mesh file as one triangle mesh (scenes are flattened); clear errors for every way it can fail. A file
    larger than ``max_faces`` allows (:func:`check_file_size`) is refused unread; None: no bound (a registered
    mesh, checked by its sha256)."""
    import trimesh

    shown = display_path(path)
    loaded = _load(path, SUFFIXES, "mesh", f"unknown mesh file type '{path.suffix or '(none)'}'; rik reads "
                   + ", ".join(SUFFIXES), max_faces)
    if not isinstance(loaded, trimesh.Trimesh) or len(loaded.faces) == 0:
        raise RikError(f"{shown}: the mesh is empty (no triangles)")
    check_finite(loaded, shown)
    return loaded


def read_user_mesh(path: Path, sha256: str) -> trimesh.Trimesh:
    """An imported design's mesh, after checking it is the file that was registered."""
    if not path.is_file():
        raise RikError(f"{display_path(path)}: the imported mesh is missing")
    if mesh_sha256(path) != sha256:
        raise RikError(f"{display_path(path)}: the mesh file changed since it was imported (sha256 differs from "
                       "generator.sha256); import it again")
    return read_mesh(path, None)  # its sha256 matched: the file rik wrote, within the --max-faces it was given


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
                     clearance: tuple[float, float] | None, grip_diameter: float | None) -> dict[str, object]:
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
        # the ignores: `top` is never None here (to_mount_frame put the back face on z = 0, so the ray down from
        # above the top crosses the grip that `depth` hit), and `sides` holds no None after the check above
        geometry |= {"grip_diameter": round(grip_diameter or (projection + 0.01 - top - depth), 5),  # type: ignore[operator]
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


def _yaml_text(document: dict[str, Any], header: str) -> str:
    import yaml

    return f"# {header}\n" + yaml.safe_dump(document, sort_keys=False)


Prepare = Callable[[Path], None]
"""Work that must succeed before an import is registered (decomposition, measurements), given the staging
directory: load the catalog with it as the last overlay. Files it writes there are moved in with the entry."""


def check_extras(catalog_dir: Path, extras: Path | None) -> None:
    """Refuse (one line), before any work, an import whose pictures (``extras``, a folder relative to
    ``catalog_dir``) would go where something already is: rik never writes over a file it did not make there."""
    if extras is None:
        return
    folder = catalog_dir / extras
    if not os.path.lexists(folder):
        return
    try:
        names = sorted(os.listdir(folder)) if folder.is_dir() and not folder.is_symlink() else [folder.name]
    except OSError:
        names = [folder.name]
    if names:
        shown = ", ".join(names[:3]) + (f" and {len(names) - 3} more" if len(names) > 3 else "")
        raise RikError(f"{display_path(folder)}: already holds {shown}, where this import writes its pictures; rik "
                       "writes only new files into the catalog folder: move or remove it, or choose another --id "
                       "(nothing was read or written)")


def _register(catalog_dir: Path, stem: str, meshes: dict[Path, trimesh.Trimesh],
              yaml_text: Callable[[dict[Path, str]], str], what: str, prepare: Prepare | None = None) -> Path:
    """Add ``<stem>.yaml`` and ``meshes`` (paths relative to ``catalog_dir``) to the user catalog. Nothing is left
    behind on failure: the files are staged in a hidden directory inside ``catalog_dir`` (which catalog scans
    skip), existing files are never overwritten, the whole catalog (built-in + every overlay file already
    there + the new one) must validate and ``prepare`` must finish before the files are moved into place, and
    every folder they go to is made first. ``yaml_text`` receives each mesh file's sha256. Returns the YAML's
    path."""
    from rik.registry.load import load_catalog

    catalog_dir.mkdir(parents=True, exist_ok=True)
    yaml_rel = Path(f"{stem}.yaml")
    tmp = make_stage(catalog_dir / "import")
    try:
        sha256 = {}
        for rel, mesh in meshes.items():
            (tmp / rel).parent.mkdir(parents=True, exist_ok=True)
            mesh.export(tmp / rel, file_type="stl")
            sha256[rel] = mesh_sha256(tmp / rel)
        write_text(tmp / yaml_rel, yaml_text(sha256), NEW)
        for rel in (yaml_rel, *meshes):
            if (catalog_dir / rel).exists():
                raise RikError(f"{display_path(catalog_dir / rel)} already exists: {what} was imported before; "
                               "choose another --id or delete the files")
        load_catalog([catalog_dir, tmp])
        if prepare is not None:
            prepare(tmp)
        extras = sorted(p.relative_to(tmp) for p in tmp.rglob("*") if p.is_file() and p.relative_to(tmp) != yaml_rel
                        and p.relative_to(tmp) not in meshes)  # what prepare wrote (pictures)
        for rel in extras:  # never over a file rik did not make (one made meanwhile: check_extras ran first)
            if os.path.lexists(catalog_dir / rel):
                raise RikError(f"{display_path(catalog_dir / rel)}: already exists, and rik writes only new files into "
                               f"the catalog folder; move or remove it, then import again (nothing was registered)")
        order = (*extras, *meshes, yaml_rel)  # the YAML last: it is what makes the entry visible
        for rel in order:
            folder = (catalog_dir / rel).parent
            try:
                folder.mkdir(parents=True, exist_ok=True)
            except OSError as exc:
                raise RikError(f"{display_path(folder)}: cannot create the folder ({exc.strerror}); nothing was "
                               f"registered") from None
        for rel in order:
            move_new(tmp / rel, catalog_dir / rel)
    finally:
        remove_stage(tmp)
    return catalog_dir / yaml_rel


def import_handle(path: Path, *, handle_type: str, design_id: str, size: str, catalog_dir: Path,
                  name: str | None = None, finish: str = "metal/brushed-steel", units: str = "auto",
                  out_axis: str = "+z", long_axis: str = "+x", hole_spacing: float | None = None,
                  clearance: tuple[float, float] | None = None, grip_diameter: float | None = None,
                  mount: str | None = None, edge: str = "top", mass: float | None = None,
                  density: float = DEFAULT_DENSITY, licence: str = "LicenseRef-user", max_faces: int = MAX_FACES,
                  prepare: Prepare | None = None, extras: Path | None = None) -> ImportedHandle:
    """Read ``path``, normalise it and register it in ``catalog_dir`` (created if needed). A file of more than
    ``max_faces`` triangles is refused before any work, and so is an ``extras`` folder (relative to
    ``catalog_dir``: where ``prepare`` writes pictures) that already holds anything.

    Nothing is left behind on failure: files are written to a hidden directory inside ``catalog_dir``, the whole
    catalog (built-in + every overlay file already there + the new one) is validated, ``prepare`` (the
    decomposition) runs, and only then are the files moved into place."""
    import trimesh  # noqa: F401  (the mesh stack; fail early if it is missing)


    shown = display_path(path)
    if not design_id.startswith(f"{handle_type}/"):
        raise RikError(f"--id {design_id}: a {handle_type} design's id must start with '{handle_type}/'")
    yaml_file = catalog_dir / f"{design_id.replace('/', '__')}.yaml"
    if yaml_file.exists():  # as _register says, before any work
        raise RikError(f"{display_path(yaml_file)} already exists: design {design_id} was imported before; choose "
                       "another --id or delete the files")
    check_extras(catalog_dir, extras)
    mesh = read_mesh(path, max_faces)
    check_size(len(mesh.faces), shown, max_faces)
    mesh = clean(mesh, shown)
    mesh = scale_to_metres(mesh, units, handle_type, shown)
    mesh = to_mount_frame(mesh, out_axis, long_axis, shown)
    geometry = measure_geometry(mesh, handle_type, shown, hole_spacing, clearance, grip_diameter)
    stem = design_id.replace("/", "__")
    mount_kind = mount or {"knob": "single_screw", "two_point": "two_screw"}.get(handle_type, "edge_clip")
    mount_entry: dict[str, Any] = {"kind": mount_kind}
    if mount_kind == "edge_clip":
        mount_entry["edge"] = edge
    mesh_rel = Path("meshes") / f"{stem}.stl"
    handle_id = f"{design_id}-{size}"

    def yaml_text(sha256: dict[Path, str]) -> str:
        generator = {"name": "user_mesh", "file": mesh_rel.as_posix(), "sha256": sha256[mesh_rel]}
        design = {"id": design_id, "type": handle_type, "subtype": "imported", "name": name or f"Imported {stem}",
                  "generator": generator,
                  "provenance": {"origin": "user_mesh", "reference": f"imported from {path.name}"}}
        handle = {"id": handle_id, "design": design_id, "size": size, "finish": finish,
                  "geometry": geometry, "mount": mount_entry,
                  "mass": round(mass if mass is not None else float(mesh.volume) * density, 4), "licence": licence}
        return _yaml_text({"designs": [design], "handles": [handle]},
                          "Imported with `rik assets import`; lengths in metres. Edit the names freely; the mesh is "
                          "the data.")

    yaml_path = _register(catalog_dir, stem, {mesh_rel: mesh}, yaml_text, f"design {design_id}", prepare)
    return ImportedHandle(handle_id, yaml_path, catalog_dir / mesh_rel, geometry)


# ---- base units from a GLB with named nodes ---------------------------------------------------------------------
def read_mapping(path: Path) -> BaseUnitMapping:
    """The mapping file of a base-unit import, validated; errors name the file, line and field."""
    from rik.registry.entries import read_yaml_model
    from rik.schemas.imports import BaseUnitMapping

    return read_yaml_model(path, BaseUnitMapping, "mapping file")


def node_meshes(path: Path, nodes: dict[str, str], mapping_file: Path, max_faces: int = MAX_FACES
                ) -> dict[str, trimesh.Trimesh]:
    """For each ``field -> node name``, the node's geometry and its descendants', in the file's world frame."""
    import trimesh

    shown = display_path(path)
    scene = _load(path, (".glb", ".gltf"), "scene", "a base unit is imported from a .glb or .gltf file with named "
                  "nodes", max_faces)
    graph = scene.graph
    parents = graph.transforms.parents
    names = sorted(n for n in graph.nodes if n != graph.base_frame)
    out: dict[str, trimesh.Trimesh] = {}
    for field, node in nodes.items():
        if node not in graph.nodes:
            raise RikError(f"{display_path(mapping_file)}, field '{field}': no node '{node}' in {shown}; its nodes "
                           f"are: {', '.join(names)}")
        pieces = []
        for geom_node in graph.nodes_geometry:
            walk = geom_node
            while walk != node and walk in parents:
                walk = parents[walk]
            if walk != node:
                continue
            transform, geom_name = graph[geom_node]
            mesh = scene.geometry[geom_name].copy()
            mesh.apply_transform(transform)
            pieces.append(mesh)
        if not pieces:
            raise RikError(f"{display_path(mapping_file)}, field '{field}': node '{node}' of {shown} has no mesh")
        out[field] = trimesh.util.concatenate(pieces)  # type: ignore[assignment]  # typed Geometry; of meshes, a Trimesh
        check_finite(out[field], f"{shown} node '{node}'")
    return out


def _frame_rotation(up: str, front: str, shown: str) -> np.ndarray:
    import numpy as np

    u, f = np.array(AXES[up], float), np.array(AXES[front], float)
    if abs(u @ f) > 0.5:
        raise RikError(f"{shown}: 'up' ({up}) and 'front' ({front}) must be different axes")
    rotation = np.eye(4)
    rotation[:3, :3] = np.vstack([np.cross(f, u), f, u])  # rows: rik's x, y (out of the front), z (up)
    return rotation


def _hinge(side: str, lo: np.ndarray, hi: np.ndarray, back: float) -> tuple[list[float], list[float]]:
    """Axis and anchor of a hinge on ``side`` of a front spanning ``lo``..``hi`` whose back face is at ``back``;
    the axis is signed so that positive angles swing the front outward (+y)."""
    cx, cz = float(lo[0] + hi[0]) / 2, float(lo[2] + hi[2]) / 2
    # +x is on the left of a person facing the front (rik.schemas.base_units)
    return {"left": ([0.0, 0.0, -1.0], [float(hi[0]), back, cz]), "right": ([0.0, 0.0, 1.0], [float(lo[0]), back, cz]),
            "top": ([1.0, 0.0, 0.0], [cx, back, float(hi[2])]),
            "bottom": ([-1.0, 0.0, 0.0], [cx, back, float(lo[2])])}[side]


def import_base_unit(path: Path, mapping_path: Path, *, unit_id: str, catalog_dir: Path,
                     licence: str = "LicenseRef-user", max_faces: int = MAX_FACES,
                     prepare: Prepare | None = None) -> tuple[str, Path]:
    """Read a GLB's named nodes as the rigid parts of a base unit (mapping in ``mapping_path``), normalise units
    and frame (origin at the bottom of the carcass's front plane, centred, +y out of the front, +z up), measure the
    carcass and fronts, and register the unit with its part meshes in ``catalog_dir``. A file whose parts have more
    than ``max_faces`` triangles in all is refused before any work. Validated as a whole, and ``prepare`` (the
    decomposition) finished, before anything is moved into place."""
    import numpy as np


    mapping = read_mapping(mapping_path)
    fields = {"carcass.node": mapping.carcass.node,
              **{f"fronts.{i}.node": f.node for i, f in enumerate(mapping.fronts)}}
    raw = node_meshes(path, fields, mapping_path, max_faces)
    check_size(sum(len(m.faces) for m in raw.values()), display_path(path), max_faces)
    rotation = _frame_rotation(mapping.up, mapping.front, display_path(mapping_path))
    parts: dict[str, Any] = {}
    for field, mesh in raw.items():
        name = "carcass" if field == "carcass.node" else mapping.fronts[int(field.split(".")[1])].id
        mesh = clean(mesh, f"{display_path(path)} node '{fields[field]}'")
        mesh.apply_scale(UNIT_SCALES[mapping.units])
        mesh.apply_transform(rotation)
        parts[name] = mesh
    lo, hi = parts["carcass"].bounds
    shift = np.array([-(lo[0] + hi[0]) / 2, -hi[1], -lo[2]])
    for mesh in parts.values():
        mesh.apply_translation(shift)
    lo, hi = parts["carcass"].bounds
    width, depth, height = (float(v) for v in hi - lo)
    if not 0.1 <= max(width, depth, height) <= 4.0:
        raise RikError(f"{display_path(path)}: the carcass is {max(width, depth, height):g} m in size after "
                       f"'units: {mapping.units}' ({display_path(mapping_path)}); furniture is 0.1 to 4 m: check units")
    fronts = []
    for f in mapping.fronts:
        flo, fhi = parts[f.id].bounds
        t = f.panel_thickness
        centre = [float(flo[0] + fhi[0]) / 2, float(fhi[1]) - t / 2, float(flo[2] + fhi[2]) / 2]
        w, h = float(fhi[0] - flo[0]), float(fhi[2] - flo[2])
        if f.joint.type == "slide":
            axis, anchor = [0.0, 1.0, 0.0], centre
        else:
            if f.joint.side is None:
                raise RikError(f"{display_path(mapping_path)}, field 'fronts.{mapping.fronts.index(f)}.joint.side': "
                               "a hinge needs the edge it is on: left, right, top or bottom")
            axis, anchor = _hinge(f.joint.side, flo, fhi, float(fhi[1]) - t)
        m = f.mount_margin
        fronts.append({"id": f.id, "kind": f.kind, "size": [round(w, 5), round(h, 5), t],
                       "center": [round(c, 5) for c in centre],
                       "joint": {"type": f.joint.type, "axis": axis, "anchor": [round(a, 5) for a in anchor],
                                 "range": list(f.joint.range)},
                       "mount": {"pos": [round(centre[0], 5), round(float(fhi[1]), 5), round(centre[2], 5)],
                                 "size": [round(w - 2 * m, 5), round(h - 2 * m, 5)]},
                       "finish": f.finish})
    stem = unit_id.replace("/", "__")
    files = {Path("meshes") / stem / f"{name}.stl": mesh for name, mesh in parts.items()}

    def yaml_text(sha256: dict[Path, str]) -> str:
        meshes = {rel.stem: {"file": rel.as_posix(), "sha256": digest} for rel, digest in sha256.items()}
        entry = {"id": unit_id, "name": mapping.name or f"Imported {stem}",
                 "description": mapping.description or f"Imported from {path.name}", "install": mapping.install,
                 "install_height": mapping.install_height,
                 "carcass": {"width": round(width, 5), "height": round(height, 5), "depth": round(depth, 5),
                             "panel_thickness": mapping.carcass.panel_thickness, "finish": mapping.carcass.finish},
                 "fronts": fronts, "licence": licence, "meshes": meshes}
        return _yaml_text({"base_units": [entry]},
                          "Imported with `rik assets import --base-unit`; lengths in metres, angles in radians.")

    yaml_path = _register(catalog_dir, stem, files, yaml_text, f"base unit {unit_id}", prepare)
    return unit_id, yaml_path
