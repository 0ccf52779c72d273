"""The catalog's 3D view models as binary glTF (GLB): a handle's visual mesh in its mount frame, and a built
variant's visual geoms posed at ``qpos0``, one node per geom, each with a PBR material from its catalog finish
(sRGB base colour made linear, metallic and roughness as the finish says). Lengths in m, z up (MuJoCo's frame).

Made on request and memoised (a few small GLBs: a handle's is under 150 KB, a variant's under a few MB). Nothing
here builds: a handle's mesh is the generator's (no CoACD), and a variant is read only when it is already built and
current (:func:`built_variant`); otherwise a one-line :class:`rik.errors.RikError` names the command that builds it.
"""

from __future__ import annotations

import threading
from collections import OrderedDict
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from rik.errors import RikError
from rik.paths import inside

if TYPE_CHECKING:
    import trimesh

    from rik.registry.catalog import Catalog
    from rik.schemas.finishes import Finish

GLB_MEDIA_TYPE = "model/gltf-binary"
MEMO_ENTRIES = 32
"""GLBs kept in memory per app (least recently used dropped first)."""
NEUTRAL = (0.7, 0.7, 0.7, 1.0)
"""Linear RGBA of a geom with no catalog finish (a robot's or an unnamed material's), when its own colour is unset."""


class Memo:
    """A small thread-safe least-recently-used map of GLB bytes (web requests run in a thread pool)."""

    def __init__(self, entries: int = MEMO_ENTRIES) -> None:
        self._items: OrderedDict[object, bytes] = OrderedDict()
        self._entries = entries
        self._lock = threading.Lock()

    def get(self, key: object, make: Callable[[], bytes]) -> bytes:
        """The bytes stored under ``key``, made by ``make()`` on a miss (outside the lock: two misses may both make)."""
        with self._lock:
            if key in self._items:
                self._items.move_to_end(key)
                return self._items[key]
        data = make()
        with self._lock:
            self._items[key] = data
            while len(self._items) > self._entries:
                self._items.popitem(last=False)
        return data


def pbr_material(finish: Finish | None, rgba: tuple[float, ...] | np.ndarray = NEUTRAL) -> object:
    """A glTF metallic-roughness material of a catalog finish (its sRGB base colour converted to linear), or a
    dielectric of the linear ``rgba`` where there is none."""
    from trimesh.visual.material import PBRMaterial

    from rik.render.materials import srgb_to_linear

    if finish is None:
        return PBRMaterial(baseColorFactor=[float(c) for c in rgba], metallicFactor=0.0, roughnessFactor=0.6,
                           doubleSided=True)
    colour = [*(float(c) for c in srgb_to_linear(finish.base_color)), 1.0]
    return PBRMaterial(name=finish.id, baseColorFactor=colour, metallicFactor=float(finish.metallic),
                       roughnessFactor=float(finish.roughness), doubleSided=True)


def _textured(mesh: trimesh.Trimesh, material: object) -> trimesh.Trimesh:
    from trimesh.visual import TextureVisuals

    mesh.visual = TextureVisuals(material=material)
    return mesh


def handle_mesh(catalog: Catalog, handle_id: str) -> trimesh.Trimesh:
    """A handle's visual mesh (metres, mount frame): the generator's, or a user mesh read and checked against its
    recorded sha256. No CoACD runs."""
    from rik.assets.build import _beside_definition
    from rik.assets.handles import generate_handle
    from rik.assets.importer import read_user_mesh

    handle = catalog.handles[handle_id]
    design = catalog.designs[handle.design]
    if design.generator.name == "user_mesh":
        return read_user_mesh(_beside_definition(catalog, "designs", design.id, design.generator.file),
                              design.generator.sha256)
    return generate_handle(handle, design)


def handle_glb(catalog: Catalog, handle_id: str) -> bytes:
    """The GLB of one handle: its visual mesh with its finish's material, one node."""
    import trimesh

    mesh = handle_mesh(catalog, handle_id).copy()
    material = pbr_material(catalog.finishes[catalog.handles[handle_id].finish])
    scene = trimesh.Scene()
    scene.add_geometry(_textured(mesh, material), node_name="handle", geom_name="handle")
    return bytes(scene.export(file_type="glb", include_normals=True))


def built_variant(catalog: Catalog, variants: Path, variant: str) -> tuple[str, Path, str]:
    """The canonical id, folder and spec hash of ``variant`` when it is built in ``variants`` and current, else a
    one-line RikError naming what builds it. Reads (and hashes) the variant's files; writes nothing."""
    from rik.combinator.build import folder_spec_hash, is_current
    from rik.registry.ids import parse_variant_id

    key = parse_variant_id(catalog, variant)
    directory = inside(variants, key.id, what="variant id")
    digest = folder_spec_hash(catalog, key, variants)
    if not is_current(directory, digest):
        state = "is not built" if not (directory / "report.json").exists() else "is out of date"
        raise RikError(f"variant {key.id} {state} in {variants}: open its station (/teleop/{key.id}) or run "
                       f"`rik variants build {key.id}`")
    return key.id, directory, digest


def variant_glb(model_xml: Path, finishes: Mapping[str, Finish]) -> bytes:
    """The GLB of a built variant: every geom MuJoCo draws (groups 0-2, not transparent; planes left out), posed
    at ``qpos0`` (the fronts closed), one node per geom, materials from the catalog finishes they are named by."""
    import mujoco
    import trimesh

    from rik.render.geoms import drawn_geoms, geom_triangles, rigid
    from rik.render.materials import srgb_to_linear

    model = mujoco.MjModel.from_xml_path(str(model_xml))
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    scene = trimesh.Scene()
    materials: dict[str, object] = {}
    for g in drawn_geoms(model):
        if int(model.geom_type[g]) == mujoco.mjtGeom.mjGEOM_PLANE:
            continue
        v, f, n, _ = geom_triangles(model, g)
        mesh = trimesh.Trimesh(v, f, vertex_normals=n, process=False)
        mat = int(model.geom_matid[g])
        name = str(mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_MATERIAL, mat)) if mat >= 0 else ""
        rgba = model.mat_rgba[mat] if mat >= 0 else model.geom_rgba[g]
        key = name if name in finishes else repr(np.round(rgba, 4).tolist())
        if key not in materials:
            linear = (*srgb_to_linear(rgba[:3]), float(rgba[3]))
            materials[key] = pbr_material(finishes[name]) if name in finishes else pbr_material(None, linear)
        scene.add_geometry(_textured(mesh, materials[key]), node_name=f"g{g}", geom_name=f"g{g}",
                           transform=rigid(data.geom_xpos[g], data.geom_xmat[g]))
    return bytes(scene.export(file_type="glb", include_normals=True))
