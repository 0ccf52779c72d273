"""Rules that span entries or fields: unique ids, references, per-type handle rules, base-unit geometry, presets
that some catalog robot can open.

Each check raises :class:`rik.errors.CatalogError` through the offending entry, naming file, entry and field.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

from rik.errors import UnknownIdError
from rik.registry.geometry import cross, dot, site_axes, sub
from rik.registry.ids import SEPARATOR, slug
from rik.registry.sources import RawEntry, display_path
from rik.schemas import BaseUnit, Front, Handle, HandleDesign, HandleType, JointType, ResistancePreset
from rik.schemas.joints import CATALOG_LEVER_ARM, JointResistance

if TYPE_CHECKING:
    from rik.registry.entries import CatalogModel
    from rik.schemas.robots import Robot

TOL = 1e-6
"""Geometric tolerance, m."""

Parsed = Sequence[tuple[RawEntry, "CatalogModel"]]


def check_unique_ids(parsed: Parsed, noun: str) -> None:
    """No id twice in a section; an overlay may not redefine a built-in id."""
    first: dict[str, RawEntry] = {}
    for entry, model in parsed:
        ident = model.id
        if ident in first:
            before = first[ident]
            if before.builtin and not entry.builtin:
                raise entry.error("id", f"redefines the built-in {noun} '{ident}' ({display_path(before.file)}); "
                                        "an overlay may only add new ids: choose another id")
            raise entry.error("id", f"duplicate {noun} id, first defined in {display_path(before.file)} "
                                    f"as {before.label}")
        first[ident] = entry


#: Sections whose ids go into variant ids (``<base unit>__<handle>__<preset>``, each ``/`` written ``-``).
IN_VARIANT_IDS = ("base_units", "handles", "presets")


def check_variant_id_parts(parsed: Parsed, section: str, noun: str) -> None:
    """Ids that go into variant ids must keep them unambiguous: no ``__`` (the separator), no ``/`` in a preset
    id, and no two ids of a section written the same once ``/`` becomes ``-`` (``drawer-chest-80`` and
    ``drawer/chest-80`` would share every variant folder)."""
    first: dict[str, RawEntry] = {}
    for entry, model in parsed:
        ident = model.id
        if SEPARATOR in ident:
            raise entry.error("id", f"'{SEPARATOR}' separates the parts of variant and episode ids; a {noun} id "
                                    "may not contain it")
        if section == "presets" and "/" in ident:
            raise entry.error("id", "a preset id is one word (no '/'): it is the last part of variant ids")
        written = slug(ident)
        if written in first:
            other = first[written]
            raise entry.error("id", f"written '{written}' in variant ids, the same as {noun} "
                                    f"'{other.data.get('id')}' ({display_path(other.file)}, {other.label}); "
                                    "choose another id")
        first[written] = entry


def _ref(entry: RawEntry, field: str, wanted: str, known: Mapping[str, object], noun: str) -> None:
    if wanted not in known:
        raise entry.error(field, str(UnknownIdError(noun, wanted, known)))


def check_design(entry: RawEntry, design: HandleDesign, handle_count: int) -> None:
    if not design.id.startswith(f"{design.type.value}/"):
        raise entry.error("id", f"a {design.type.value} design's id must start with '{design.type.value}/'")
    if handle_count == 0:
        raise entry.error("id", "design has no handles; add a handle that uses it or remove it")
    if design.generator.name == "user_mesh":
        _mesh_file_exists(entry, "generator.file", design.generator.file)


def _mesh_file_exists(entry: RawEntry, field: str, relative: str) -> None:
    mesh_file = entry.file.parent / relative
    if not mesh_file.is_file():
        raise entry.error(field, f"no mesh file {display_path(mesh_file)} (paths are relative to the YAML file)")


def check_handle(entry: RawEntry, handle: Handle, designs: Mapping[str, HandleDesign],
                 finishes: Mapping[str, object]) -> None:
    _ref(entry, "design", handle.design, designs, "design")
    _ref(entry, "finish", handle.finish, finishes, "finish")
    if handle.id != f"{handle.design}-{handle.size}":
        raise entry.error("id", f"a handle's id is '<design>-<size>': expected '{handle.design}-{handle.size}'")
    kind = designs[handle.design].type
    g, mount = handle.geometry, handle.mount
    expected_mount = {HandleType.knob: ("single_screw",), HandleType.two_point: ("two_screw",)}.get(
        kind, ("two_screw", "edge_clip", "inset"))
    if mount.kind not in expected_mount:
        raise entry.error("mount.kind", f"a {kind.value} handle mounts with {' or '.join(expected_mount)}, "
                                        f"got '{mount.kind}'")
    if (mount.edge is None) == (mount.kind == "edge_clip"):
        raise entry.error("mount.edge", "an edge_clip mount needs the edge it is made for (top or side)"
                          if mount.edge is None else "only edge_clip mounts name an edge")
    if mount.kind == "two_screw":
        if g.hole_spacing is None:
            raise entry.error("geometry.hole_spacing", "a two-screw handle needs its hole spacing (m)")
        if g.hole_spacing >= g.length:
            raise entry.error("geometry.hole_spacing", f"hole spacing {g.hole_spacing} m must be less than the "
                                                       f"overall length {g.length} m")
    elif g.hole_spacing is not None:
        raise entry.error("geometry.hole_spacing", f"only two-screw handles have a hole spacing ({mount.kind} mount)")
    if kind is not HandleType.knob and g.clearance is None:
        raise entry.error("geometry.clearance", f"a {kind.value} handle needs its finger clearance (depth, width)")
    if g.clearance is not None:
        if mount.kind != "inset" and g.clearance.depth >= g.projection:
            raise entry.error("geometry.clearance.depth", f"clearance depth {g.clearance.depth} m must be less "
                                                          f"than the projection {g.projection} m")
        if g.clearance.width > g.length + TOL:
            raise entry.error("geometry.clearance.width", f"clearance width {g.clearance.width} m exceeds the "
                                                          f"overall length {g.length} m")
        if g.hole_spacing is not None and g.clearance.width >= g.hole_spacing:
            raise entry.error("geometry.clearance.width", f"the opening between the screws ({g.clearance.width} m)"
                                                          f" must be less than the hole spacing {g.hole_spacing} m")


def check_base_unit(entry: RawEntry, base: BaseUnit, finishes: Mapping[str, object],
                    presets: Mapping[str, object]) -> None:
    _ref(entry, "carcass.finish", base.carcass.finish, finishes, "finish")
    _ref(entry, "default_preset", base.default_preset, presets, "preset")
    seen: set[str] = set()
    for i, front in enumerate(base.fronts):
        where = f"fronts.{i}"
        if "/" in front.id or SEPARATOR in front.id:
            raise entry.error(f"{where}.id", f"front id '{front.id}' must be one word without '/' or '{SEPARATOR}': it "
                                             "is part of episode ids and folder names")
        if front.id in seen:
            raise entry.error(f"{where}.id", f"duplicate front id '{front.id}' in this base unit")
        seen.add(front.id)
        _ref(entry, f"{where}.finish", front.finish, finishes, "finish")
        _check_front(entry, where, base, front)
        for j, other in enumerate(base.fronts[:i]):
            if _overlap(front, other):
                raise entry.error(f"{where}.center", f"front '{front.id}' overlaps front '{other.id}' "
                                                     f"(fronts.{j}) in the front view")
    if base.meshes is not None:
        parts = ["carcass", *(f.id for f in base.fronts)]
        if sorted(base.meshes) != sorted(parts):
            raise entry.error("meshes", f"needs exactly one mesh per rigid part: {', '.join(parts)} "
                                        f"(got {', '.join(base.meshes) or 'none'})")
        for part, mesh in base.meshes.items():
            _mesh_file_exists(entry, f"meshes.{part}.file", mesh.file)


def _check_front(entry: RawEntry, where: str, base: BaseUnit, front: Front) -> None:
    c = base.carcass
    w, h, t = front.size
    cx, cy, cz = front.center
    if abs(cx) + w / 2 > c.width / 2 + TOL or cz - h / 2 < -TOL or cz + h / 2 > c.height + TOL:
        raise entry.error(f"{where}.center", f"front '{front.id}' ({w} x {h} m at x={cx}, z={cz}) reaches outside "
                                             f"the carcass outline ({c.width} x {c.height} m)")
    if cy - t / 2 < -TOL:
        raise entry.error(f"{where}.center", f"front '{front.id}' cuts into the carcass: its back face must be at "
                                             f"y >= 0, got y = {cy - t / 2:.4f}")
    joint = front.joint
    wanted = JointType.slide if front.kind == "drawer" else JointType.hinge
    if joint.type is not wanted:
        raise entry.error(f"{where}.joint.type", f"a {front.kind} moves on a {wanted.value} joint")
    if joint.type is JointType.slide:
        if dot(joint.axis, (0.0, 1.0, 0.0)) < 0.9:
            raise entry.error(f"{where}.joint.axis", f"a drawer slides out of the front (+y); axis {joint.axis} "
                                                     "opens inward or sideways")
        if joint.range[1] > c.depth + TOL:
            raise entry.error(f"{where}.joint.range", f"travel {joint.range[1]} m exceeds the carcass depth "
                                                      f"{c.depth} m")
    else:
        if abs(joint.axis[1]) > 0.1:
            raise entry.error(f"{where}.joint.axis", "a hinge axis must lie in the plane of the front (y ~ 0)")
        upright = abs(joint.axis[2]) > 0.9
        if (front.kind == "door") != upright:
            raise entry.error(f"{where}.joint.axis", "a door hinges about a vertical axis" if front.kind == "door"
                              else "a flap hinges about a horizontal axis")
        swing = cross(joint.axis, sub(front.center, joint.anchor))
        if swing[1] <= TOL:
            raise entry.error(f"{where}.joint.axis", f"opening about axis {joint.axis} swings front "
                                                     f"'{front.id}' into the carcass; reverse the axis")
    if front.drawer_box is not None:
        box = front.drawer_box
        if front.kind != "drawer":
            raise entry.error(f"{where}.drawer_box", "only drawers have a drawer box")
        inner = c.width - 2 * c.panel_thickness
        if box.width > inner + TOL or box.depth > c.depth - c.panel_thickness + TOL:
            raise entry.error(f"{where}.drawer_box", f"the box ({box.width} x {box.depth} m) does not fit inside "
                                                     f"the carcass ({inner} m wide inside, {c.depth} m deep)")
    _check_mount(entry, where, front)


def _check_mount(entry: RawEntry, where: str, front: Front) -> None:
    site = front.mount
    ax, ay, az = site_axes(site.quat)
    if dot(az, (0.0, 1.0, 0.0)) < 0.999:
        raise entry.error(f"{where}.mount.quat", "the mount site's z axis must point out of the front (+y)")
    face_y = front.center[1] + front.size[2] / 2
    if abs(site.pos[1] - face_y) > 1e-4:
        raise entry.error(f"{where}.mount.pos", f"the mount site must lie on the front's outer face y = {face_y:.4f}"
                                                f", got y = {site.pos[1]}")
    w, h, _ = front.size
    sx, sy = site.size
    for u in (-0.5, 0.5):
        for v in (-0.5, 0.5):
            px = site.pos[0] + u * sx * ax[0] + v * sy * ay[0]
            pz = site.pos[2] + u * sx * ax[2] + v * sy * ay[2]
            if abs(px - front.center[0]) > w / 2 + TOL or abs(pz - front.center[2]) > h / 2 + TOL:
                raise entry.error(f"{where}.mount.size", f"the mount rectangle ({sx} x {sy} m) reaches past the "
                                                         f"edge of front '{front.id}' ({w} x {h} m)")


def _overlap(a: Front, b: Front) -> bool:
    """True when two fronts overlap in the front view (x-z) by more than the tolerance."""
    dx = (a.size[0] + b.size[0]) / 2 - abs(a.center[0] - b.center[0])
    dz = (a.size[1] + b.size[1]) / 2 - abs(a.center[2] - b.center[2])
    return dx > TOL and dz > TOL


def strongest_pull(robots: Mapping[str, Robot]) -> tuple[float, Robot] | None:
    """The largest pull any catalog robot can put on a handle, N, and that robot (None without robots): its
    gripper's friction capacity, 2 pads x pad friction x grip force
    (:attr:`rik.schemas.robots.Gripper.pull_capacity`). A grasp that hooks behind a handle could pull more, but
    the scripted strategies and the benchmark count on friction (``rik robot-check``'s grip check)."""
    if not robots:
        return None
    robot = max(robots.values(), key=lambda r: r.gripper.pull_capacity)
    return robot.gripper.pull_capacity, robot


def check_preset_breakable(entry: RawEntry, preset: ResistancePreset, robots: Mapping[str, Robot]) -> None:
    """A preset must let some catalog robot open its fronts: on each side, what holds the front at closed
    (:meth:`rik.schemas.joints.JointResistance.hold_at_closed`: friction plus a catch's pull, a self-closing
    spring's ``stiffness x zone``, ...) must not exceed :func:`strongest_pull`. A hinge torque is felt at the handle
    divided by the catalog's lever arm (:data:`rik.schemas.joints.CATALOG_LEVER_ARM`, 0.40 m). The field named is
    the largest term."""
    strongest = strongest_pull(robots)
    if strongest is None:
        return
    capacity, robot = strongest
    for side in ("slide", "hinge"):
        resistance = preset.slide if side == "slide" else preset.hinge
        hold = resistance.hold_at_closed()
        force = hold if side == "slide" else hold / CATALOG_LEVER_ARM
        if force <= capacity:
            continue
        terms = [(f, v) for f, v in resistance.hold_terms() if v > 0]
        field = max(terms, key=lambda t: t[1])[0]
        unit = "N" if side == "slide" else "N·m"
        parts = " + ".join(f"{_term_name(resistance, f)} {v:.3g}" for f, v in terms)
        felt = "" if side == "slide" else (f", {force:.3g} N at a handle {CATALOG_LEVER_ARM:.2f} m from the axis "
                                           "(the catalog's lever arm)")
        g = robot.gripper
        raise entry.error(f"{side}.{field}", f"holds the front shut with {hold:.3g} {unit} at closed ({parts}){felt}; "
                                             f"no catalog robot can pull more than {capacity:.3g} N ({robot.id}: "
                                             f"2 pads x friction {g.pad_friction.value:g} x grip {g.grip_force.value:g}"
                                             " N), so none could open it")


def _term_name(resistance: JointResistance, field: str) -> str:
    """How a term of :meth:`~rik.schemas.joints.JointResistance.hold_terms` is named in a message."""
    if field.startswith("effects."):
        return str(resistance.effects[int(field.split(".")[1])].kind)
    return field.split(".")[0]
