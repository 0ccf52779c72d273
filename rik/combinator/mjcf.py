"""Materialise a variant as a ``mujoco.MjSpec``: the base unit's bodies and joints, the handle on every front.

Layout of a model (MuJoCo Menagerie's conventions):

- default classes ``visual`` (group 2, no contacts) and ``collision`` (group 3), and one joint class per joint
  type holding the preset's resistance (:mod:`rik.joints.mjcf`);
- a static body ``base_unit`` at the unit's install height with the carcass; one body per front, named by the
  front's id, sitting at the base unit's origin and moving on a joint of the same name;
- in each front a body ``<front>/handle`` at the handle's mount frame, with the visual mesh, the CoACD hulls and
  the sites ``<front>/handle`` (mount frame) and ``<front>/grasp`` (centre of the handle's bounding box: the
  middle of a loop); each front also carries ``<front>/mount`` (its allowed mount rectangle, a box site);
- a passive actuator ``<front>/effect/<kind>`` per native joint effect of the preset (self-closing zone springs,
  a slide's tilt, direction-dependent friction; :mod:`rik.joints.mjcf`);
- a text element ``rik.variant`` with the variant's ids, collision mode and fronts as JSON, so tools can read a
  model alone; a front whose preset has effects MuJoCo lacks lists them as ``runtime_effects``
  (``effect.model_dump()``), which rik's simulator applies each step (:class:`rik.joints.runtime.RuntimeEffects`).

The handle's collision is its CoACD hulls (collision mode ``coacd``, the default) or its single convex hull
(mode ``hull``: the baseline of the fidelity ablation); base-unit parts are the same in both modes. The fronts'
joint friction holds (mode ``held``, the default) or creeps as MuJoCo's defaults let it (``creeping``: the other
side of that ablation; :data:`rik.joints.mjcf.JOINT_FRICTION_MODES`).

Boards are box geoms (exact). Handle meshes are written as STL files under ``meshes/`` and referenced by
relative paths. Masses and inertias are explicit: boards from their volume and a density per finish kind,
handles from their catalogued mass spread over the visual mesh.
"""

from __future__ import annotations

import functools
import json
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from rik.assets.base_units import Panel
from rik.combinator.placement import HandlePlacement, front_motion, place_handle
from rik.joints.mjcf import (
    DEFAULT_JOINT_FRICTION,
    add_effect_actuators,
    add_front_joint,
    add_joint_classes,
    joint_model,
)
from rik.registry.geometry import vec3
from rik.registry.ids import VariantKey

if TYPE_CHECKING:
    from collections.abc import Sequence

    import mujoco
    import numpy as np

    from rik.assets.base_units import PartPlan
    from rik.assets.build import Asset
    from rik.registry.catalog import Catalog
    from rik.schemas import BaseUnit, Front

BOARD_DENSITY = {"wood": 650.0, "lacquer": 750.0}
"""kg/m³ of furniture board by finish kind: veneered particle board (600-700) and lacquered MDF (700-800)."""
DEFAULT_BOARD_DENSITY = 700.0
TIMESTEP = 0.002
"""s; with the implicit-in-velocity integrator, stable for the presets' damping."""
MESHDIR = "meshes"
SITE_GROUP = 4
"""Sites are in group 4, hidden by default in MuJoCo's viewer."""
COLLISION_MODES = ("coacd", "hull")
"""How a handle collides: ``coacd`` (its CoACD decomposition, the default) or ``hull`` (its one convex hull)."""
DEFAULT_COLLISION = "coacd"


@dataclass
class FrontLayout:
    """One front of a built variant: names in the model and where its handle went."""

    id: str
    kind: str
    motion: str
    placement: HandlePlacement
    joint_range: tuple[float, float]
    runtime_effects: tuple[dict[str, Any], ...] = ()
    """The preset's effects on this front's joint that the simulator applies per step."""


@dataclass
class VariantModel:
    """A variant ready to compile and write: the spec, the mesh files it references, and its layout."""

    key: VariantKey
    spec: mujoco.MjSpec
    mesh_files: dict[str, bytes]
    """File name under ``meshes/`` -> STL bytes."""
    mesh_vertices: dict[str, int]
    """Mesh name -> its number of vertices."""
    fronts: list[FrontLayout]
    handle_type: str
    handle_bounds: np.ndarray
    """(2, 3) array: the handle's visual mesh bounds in its mount frame, m."""
    unit: BaseUnit
    recess: tuple[float, float, float, float, float] | None = None
    """Inset handles: the recess cut into each front, (x0, y0, x1, y1) in the mount frame and its depth, m."""
    collision: str = DEFAULT_COLLISION
    """The handle's collision mode (:data:`COLLISION_MODES`)."""
    joint_friction: str = DEFAULT_JOINT_FRICTION
    """How the fronts' joint friction holds (:data:`rik.joints.mjcf.JOINT_FRICTION_MODES`)."""

    @property
    def hulls(self) -> int:
        return sum(1 for g in self.spec.geoms if g.classname.name == "collision" and g.meshname)

    def info(self) -> dict[str, Any]:
        return {"id": self.key.id, "base_unit": self.key.base, "handle": self.key.handle,
                "handle_type": self.handle_type, "preset": self.key.preset, "collision": self.collision,
                "joint_friction": self.joint_friction,
                "fronts": [{"id": f.id, "kind": f.kind, "motion": f.motion, "joint": f.id,
                            "handle_body": f"{f.id}/handle", "grasp_site": f"{f.id}/grasp",
                            "placement": f.placement.rule, "edge": f.placement.edge,
                            **({"runtime_effects": list(f.runtime_effects)} if f.runtime_effects else {})}
                           for f in self.fronts]}


# ---- geometry helpers -------------------------------------------------------------------------------------------
def _board_density(catalog: Catalog, finish: str) -> float:
    return BOARD_DENSITY.get(catalog.finishes[finish].kind, DEFAULT_BOARD_DENSITY)


def _box_inertia(boxes: list[Panel], density: float) -> tuple[float, list[float], list[float]]:
    """Mass (kg), centre of mass and full inertia (Ixx Iyy Izz Ixy Ixz Iyz about the centre, kg·m²) of boxes."""
    import numpy as np

    masses = np.array([density * float(np.prod(b.extents)) for b in boxes])
    centers = np.array([b.center for b in boxes])
    mass = float(masses.sum())
    com = (masses[:, None] * centers).sum(axis=0) / mass
    inertia = np.zeros((3, 3))
    for m, b, c in zip(masses, boxes, centers, strict=True):
        ex, ey, ez = b.extents
        inertia += np.diag([m * (ey**2 + ez**2) / 12, m * (ex**2 + ez**2) / 12, m * (ex**2 + ey**2) / 12])
        d = c - com
        inertia += m * (np.dot(d, d) * np.eye(3) - np.outer(d, d))
    return mass, com.tolist(), _full(inertia)


def _full(inertia: np.ndarray) -> list[float]:
    return [float(inertia[0, 0]), float(inertia[1, 1]), float(inertia[2, 2]),
            float(inertia[0, 1]), float(inertia[0, 2]), float(inertia[1, 2])]


def _panel_boxes(plan: PartPlan) -> list[Panel]:
    return list(plan.panels)


def _trimmed(panel: Panel, axis: tuple[float, float, float], trim: float) -> Panel:
    """``panel`` cut back by ``trim`` (m) at its face toward ``axis`` (a base-frame axis direction)."""
    i = max(range(3), key=lambda k: abs(axis[k]))
    sign = 1.0 if axis[i] > 0 else -1.0
    center, extents = list(panel.center), list(panel.extents)
    extents[i] -= trim
    center[i] -= sign * trim / 2
    return Panel(panel.name, vec3(center), vec3(extents))


def _cut_recess(panel: Panel, placement: HandlePlacement,
                recess: tuple[float, float, float, float, float]) -> list[Panel]:
    """The front panel with an inset handle's recess routed into its outer face: up to five boxes (the recess's
    rounded corners are cut square). The panel's outer face must be normal to a base-frame axis."""
    import numpy as np

    from rik.registry.geometry import rotate

    x0, y0, x1, y1, depth = recess
    corners = np.array([rotate(placement.quat, (x, y, 0.0)) for x in (x0, x1) for y in (y0, y1)])
    corners += np.asarray(placement.pos)
    normal = np.asarray(rotate(placement.quat, (0.0, 0.0, 1.0)))
    n_axis = int(np.argmax(np.abs(normal)))
    sign = float(np.sign(normal[n_axis]))
    lo = np.asarray(panel.center) - np.asarray(panel.extents) / 2
    hi = np.asarray(panel.center) + np.asarray(panel.extents) / 2
    r_lo, r_hi = corners.min(axis=0), corners.max(axis=0)
    a, b = [i for i in range(3) if i != n_axis]
    pieces: list[tuple[np.ndarray, np.ndarray]] = []

    def slab(lo_: np.ndarray, hi_: np.ndarray) -> None:
        if np.all(hi_ - lo_ > 1e-9):
            pieces.append((lo_.copy(), hi_.copy()))

    for lo_a, hi_a in ((lo[a], r_lo[a]), (r_hi[a], hi[a])):  # full-depth strips on both sides along a
        p_lo, p_hi = lo.copy(), hi.copy()
        p_lo[a], p_hi[a] = lo_a, hi_a
        slab(p_lo, p_hi)
    for lo_b, hi_b in ((lo[b], r_lo[b]), (r_hi[b], hi[b])):  # strips above and below, between the side strips
        p_lo, p_hi = lo.copy(), hi.copy()
        p_lo[a], p_hi[a] = r_lo[a], r_hi[a]
        p_lo[b], p_hi[b] = lo_b, hi_b
        slab(p_lo, p_hi)
    back_lo, back_hi = lo.copy(), hi.copy()  # the floor of the recess
    back_lo[a], back_hi[a], back_lo[b], back_hi[b] = r_lo[a], r_hi[a], r_lo[b], r_hi[b]
    if sign > 0:
        back_hi[n_axis] = hi[n_axis] - depth
    else:
        back_lo[n_axis] = lo[n_axis] + depth
    slab(back_lo, back_hi)
    return [Panel(f"{panel.name}_{i}", vec3(((p + q) / 2).tolist()), vec3((q - p).tolist()))
            for i, (p, q) in enumerate(pieces)]


@functools.lru_cache(maxsize=64)
def _stl(asset_key: str, part: str, index: int, vertices: bytes, faces: bytes) -> bytes:
    """Binary STL of a mesh (cached per process: a handle's files are the same in every variant)."""
    import numpy as np

    v = np.frombuffer(vertices, dtype=np.float64).reshape(-1, 3)
    f = np.frombuffer(faces, dtype=np.int64).reshape(-1, 3)
    tri = v[f].astype(np.float32)
    normals = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    norm = np.linalg.norm(normals, axis=1, keepdims=True)
    normals = np.divide(normals, norm, out=np.zeros_like(normals), where=norm > 0)
    record = np.zeros(len(f), dtype=[("n", "<f4", 3), ("v", "<f4", (3, 3)), ("attr", "<u2")])
    record["n"], record["v"] = normals, tri
    header = f"rik {asset_key[:16]} {part} {index}".encode().ljust(80, b" ")[:80]
    return header + np.uint32(len(f)).tobytes() + record.tobytes()


def stl_bytes(asset_key: str, part: str, index: int, vertices: np.ndarray, faces: np.ndarray) -> bytes:
    import numpy as np

    return _stl(asset_key, part, index, np.ascontiguousarray(vertices, dtype=np.float64).tobytes(),
                np.ascontiguousarray(faces, dtype=np.int64).tobytes())


@functools.lru_cache(maxsize=64)
def _handle_mass_properties(asset_key: str, mass: float, vertices: bytes, faces: bytes) -> tuple[list, list]:
    """Centre of mass (m, mount frame) and full inertia (kg·m²) of a handle of ``mass`` kg, uniform over its
    visual mesh."""
    import numpy as np
    import trimesh

    mesh = trimesh.Trimesh(np.frombuffer(vertices, dtype=np.float64).reshape(-1, 3),
                           np.frombuffer(faces, dtype=np.int64).reshape(-1, 3), process=False)
    props = mesh.mass_properties  # density 1: mass = volume
    inertia = np.asarray(props["inertia"]) * (mass / props["mass"])
    return list(map(float, props["center_mass"])), _full(inertia)


# ---- the spec ---------------------------------------------------------------------------------------------------
def _material(spec: mujoco.MjSpec, catalog: Catalog, finish_id: str, made: set[str]) -> str:
    if finish_id not in made:
        finish = catalog.finishes[finish_id]
        spec.add_material(name=finish_id, rgba=[*finish.base_color, 1.0], specular=0.3 + 0.5 * finish.metallic,
                          shininess=1.0 - finish.roughness, reflectance=0.1 * finish.metallic)
        made.add(finish_id)
    return finish_id


def _add_boxes(spec: mujoco.MjSpec, body: mujoco.MjsBody, boxes: list[Panel], prefix: str, material: str,
               classes: dict[str, mujoco.MjsDefault]) -> None:
    import mujoco

    for b in boxes:
        half = [e / 2 for e in b.extents]
        body.add_geom(name=f"{prefix}{b.name}", default=classes["collision"], type=mujoco.mjtGeom.mjGEOM_BOX,
                      pos=list(b.center), size=half)
        body.add_geom(default=classes["visual"], type=mujoco.mjtGeom.mjGEOM_BOX, pos=list(b.center), size=half,
                      material=material)


def _add_mesh_part(spec: mujoco.MjSpec, body: mujoco.MjsBody, asset: Asset, part_name: str, prefix: str,
                   material: str, classes: dict[str, mujoco.MjsDefault], files: dict[str, bytes],
                   vertices: dict[str, int], pos: Sequence[float] | None = None,
                   quat: Sequence[float] | None = None, single_hull: bool = False) -> None:
    """A part from meshes: its visual mesh and its hulls (meshes added once per model, geoms per use);
    ``single_hull`` collides it with its one convex hull (``part.baseline``) instead."""
    import mujoco

    part = asset.part(part_name)
    hulls = part.baseline if single_hull else part.hulls
    stem = f"{asset.id.replace('/', '-')}-{part_name}"
    hull = f"{stem}-convex-hull" if single_hull else f"{stem}-hull"
    frame = {} if pos is None or quat is None else {"pos": list(pos), "quat": list(quat)}
    visual = f"{stem}-visual"
    if f"{visual}.stl" not in files:
        files[f"{visual}.stl"] = stl_bytes(asset.key, part_name, -1, part.visual.vertices, part.visual.faces)
        spec.add_mesh(name=visual, file=f"{visual}.stl")
        vertices[visual] = len(part.visual.vertices)
        for i, (v, f) in enumerate(hulls):
            files[f"{hull}-{i:02d}.stl"] = stl_bytes(asset.key, part_name, i, v, f)
            spec.add_mesh(name=f"{hull}-{i:02d}", file=f"{hull}-{i:02d}.stl")
            vertices[f"{hull}-{i:02d}"] = len(v)
    body.add_geom(name=f"{prefix}visual", default=classes["visual"], type=mujoco.mjtGeom.mjGEOM_MESH,
                  meshname=visual, material=material, **frame)
    for i in range(len(hulls)):
        body.add_geom(name=f"{prefix}hull-{i:02d}", default=classes["collision"], type=mujoco.mjtGeom.mjGEOM_MESH,
                      meshname=f"{hull}-{i:02d}", **frame)


def _set_inertial(body: mujoco.MjsBody, mass: float, com: list[float], full: list[float]) -> None:
    body.explicitinertial = True
    body.mass = mass
    body.ipos = com
    body.fullinertia = full


def _mesh_inertial(catalog: Catalog, asset: Asset, part_name: str, finish: str) -> tuple[float, list, list]:
    import numpy as np

    props = asset.part(part_name).visual.mass_properties
    density = _board_density(catalog, finish)
    return (float(props["mass"] * density), list(map(float, props["center_mass"])),
            _full(np.asarray(props["inertia"]) * density))


def variant_spec(catalog: Catalog, key: VariantKey, handle_asset: Asset, base_asset: Asset,
                 collision: str = DEFAULT_COLLISION, joint_friction: str = DEFAULT_JOINT_FRICTION) -> VariantModel:
    """The MjSpec of one variant (not compiled), its handles colliding as ``collision`` says
    (:data:`COLLISION_MODES`), its fronts' friction holding as ``joint_friction`` says
    (:data:`rik.joints.mjcf.JOINT_FRICTION_MODES`)."""
    import mujoco
    import numpy as np

    from rik.assets.base_units import base_unit_plan

    unit = catalog.base_units[key.base]
    handle = catalog.handles[key.handle]
    handle_type = catalog.handle_type(handle)
    preset = catalog.presets[key.preset]

    spec = mujoco.MjSpec()
    spec.modelname = key.id
    spec.compiler.degree = False
    spec.compiler.meshdir = MESHDIR
    spec.compiler.inertiafromgeom = mujoco.mjtInertiaFromGeom.mjINERTIAFROMGEOM_FALSE
    spec.option.timestep = TIMESTEP
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    classes = {"visual": spec.add_default("visual", spec.default),
               "collision": spec.add_default("collision", spec.default)}
    classes["visual"].geom.contype = 0
    classes["visual"].geom.conaffinity = 0
    classes["visual"].geom.group = 2
    classes["collision"].geom.group = 3
    joint_classes = add_joint_classes(spec, preset, catalog.joint_types(unit), joint_friction)
    joint_models = {t.value: joint_model(preset.for_joint(t), t) for t in catalog.joint_types(unit)}

    files: dict[str, bytes] = {}
    vertices: dict[str, int] = {}
    materials: set[str] = set()
    root = spec.worldbody.add_body(name="base_unit", pos=[0.0, 0.0, unit.install_height])
    plans = {p.name: p for p in base_unit_plan(unit)} if unit.meshes is None else {}
    carcass_material = _material(spec, catalog, unit.carcass.finish, materials)
    if plans:
        _add_boxes(spec, root, _panel_boxes(plans["carcass"]), "carcass/", carcass_material, classes)
    else:
        _add_mesh_part(spec, root, base_asset, "carcass", "carcass/", carcass_material, classes, files, vertices)

    hpart = handle_asset.part("handle")
    bounds = np.asarray(hpart.visual.bounds)
    recess = None
    if handle.mount.kind == "inset":
        from rik.assets.handles.finger_pulls import recess_cutout

        polygon, depth = recess_cutout(handle.geometry)
        recess = (*polygon.bounds, depth)
    h_com, h_inertia = _handle_mass_properties(handle_asset.key, handle.mass,
                                               np.ascontiguousarray(hpart.visual.vertices, np.float64).tobytes(),
                                               np.ascontiguousarray(hpart.visual.faces, np.int64).tobytes())
    handle_material = _material(spec, catalog, handle.finish, materials)
    fronts = []
    overhang = max(0.0, -float(bounds[0][1])) if handle.mount.kind == "edge_clip" else 0.0
    for front in unit.fronts:
        placement = place_handle(unit, front, handle, handle_type, overhang)
        body = root.add_body(name=front.id)
        add_front_joint(body, front.id, front.joint, joint_classes[front.joint.type.value])
        jmodel = joint_models[front.joint.type.value]
        add_effect_actuators(spec, front.id, jmodel)
        material = _material(spec, catalog, front.finish, materials)
        if plans:
            boxes = _panel_boxes(plans[front.id])
            if placement.trim > 0 and placement.edge_axis is not None:
                boxes = [_trimmed(b, placement.edge_axis, placement.trim) if b.name == "panel" else b for b in boxes]
            if recess is not None:
                panel = next(b for b in boxes if b.name == "panel")
                boxes = [b for b in boxes if b.name != "panel"] + _cut_recess(panel, placement, recess)
            _add_boxes(spec, body, boxes, f"{front.id}/", material, classes)
            _set_inertial(body, *_box_inertia(boxes, _board_density(catalog, front.finish)))
        else:
            _add_mesh_part(spec, body, base_asset, front.id, f"{front.id}/", material, classes, files, vertices)
            _set_inertial(body, *_mesh_inertial(catalog, base_asset, front.id, front.finish))
        _add_mount_site(body, front)
        hbody = body.add_body(name=f"{front.id}/handle", pos=list(placement.pos), quat=list(placement.quat))
        _add_mesh_part(spec, hbody, handle_asset, "handle", f"{front.id}/handle/", handle_material, classes, files,
                       vertices, single_hull=collision == "hull")
        _set_inertial(hbody, handle.mass, h_com, h_inertia)
        hbody.add_site(name=f"{front.id}/handle", group=SITE_GROUP, size=[0.003, 0.003, 0.003])
        hbody.add_site(name=f"{front.id}/grasp", group=SITE_GROUP, pos=((bounds[0] + bounds[1]) / 2).tolist(),
                       size=[0.004, 0.004, 0.004], rgba=[1.0, 0.2, 0.2, 0.6])
        fronts.append(FrontLayout(front.id, front.kind, front_motion(front), placement, front.joint.range,
                                  jmodel.runtime_effects))
    model = VariantModel(key, spec, files, vertices, fronts, handle_type.value, bounds, unit, recess, collision,
                         joint_friction)
    spec.add_text(name="rik.variant", data=json.dumps(model.info(), separators=(",", ":")))
    return model


def _add_mount_site(body: mujoco.MjsBody, front: Front) -> None:
    import mujoco

    sx, sy = front.mount.size
    body.add_site(name=f"{front.id}/mount", type=mujoco.mjtGeom.mjGEOM_BOX, group=SITE_GROUP,
                  pos=list(front.mount.pos), quat=list(front.mount.quat), size=[sx / 2, sy / 2, 0.0005],
                  rgba=[0.2, 0.6, 1.0, 0.25])
