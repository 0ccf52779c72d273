"""Finger-pull generators (edge_profile, tab_pull, cup_pull, recess_lip) on the real built-in catalog: solid,
sized, clear of the finger pocket and of the front, repeatable, and buildable over every design option."""

from __future__ import annotations

import time

import numpy as np
import pytest
from meshcheck import CATALOG, inside, mesh_of, parts

from rik.assets.handles import finger_pulls, generate_handle
from rik.assets.meshkit import require_solid
from rik.schemas.generators import CupPull, EdgeProfile, RecessLip, TabPull
from rik.schemas.handles import Handle

GENERATORS = set(finger_pulls.GENERATORS)
PULLS = [hid for hid, h in CATALOG.handles.items() if CATALOG.designs[h.design].generator.name in GENERATORS]
TOL = 0.5e-3  # m, the contract's tolerance on extents
THINNEST_FRONT = 0.016  # m, how far an edge clip may wrap over the edge


def _grid(lo, hi, n: int = 7, inset: float = 0.1e-3) -> np.ndarray:
    """Points filling the box ``lo..hi`` (m), ``inset`` inside each face."""
    axes = [np.linspace(lo[i] + inset, hi[i] - inset, n) for i in range(3)]
    return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)


def _check_extents(mesh, geometry) -> None:
    ext = mesh.extents
    assert abs(ext[0] - geometry.length) <= TOL, (ext[0], geometry.length)
    assert abs(ext[1] - geometry.width) <= TOL, (ext[1], geometry.width)
    assert abs(mesh.bounds[1, 2] - geometry.projection) <= TOL, (mesh.bounds[1, 2], geometry.projection)


def _check_front_untouched(mesh, spec, geometry, mount) -> None:
    """No material inside the front: z < 0 only where the mount kind allows it."""
    v = mesh.vertices
    if mount.kind == "edge_clip":
        assert v[:, 2].min() >= -THINNEST_FRONT - 1e-6
        assert not np.any((v[:, 2] < -1e-6) & (v[:, 1] > 1e-6))
        front = _grid((-0.5 * geometry.length, 0.0, -THINNEST_FRONT), (0.5 * geometry.length, geometry.width, 0.0),
                      n=7, inset=0.2e-3)
        assert not inside(mesh, front).any()
    elif mount.kind == "two_screw":
        assert v[:, 2].min() >= -1e-6
    else:  # inset: below the face only inside the routed footprint, and no deeper than the recess
        from shapely import contains_xy

        footprint, depth = finger_pulls.recess_cutout(geometry)
        below = v[v[:, 2] < -1e-6]
        assert contains_xy(footprint.buffer(1e-6), below[:, 0], below[:, 1]).all()
        assert v[:, 2].min() >= -depth - 1e-6


def _check_clearance(mesh, spec, geometry, mount, exact: bool) -> None:
    """The finger pocket is empty; with ``exact`` its size is the catalogued clearance."""
    lo, hi = finger_pulls.clearance_box(spec, geometry, mount)
    size = np.subtract(hi, lo)
    assert np.all(size > 0)
    if exact:
        depth_axis = 2 if mount.kind == "inset" else 1
        assert size[0] == pytest.approx(geometry.clearance.width, abs=1e-9)
        assert size[depth_axis] == pytest.approx(geometry.clearance.depth, abs=1e-9)
    assert not inside(mesh, _grid(lo, hi)).any()


def test_the_catalog_has_the_finger_pulls() -> None:
    assert len(PULLS) == 19
    assert {CATALOG.designs[CATALOG.handles[h].design].generator.name for h in PULLS} == GENERATORS


@pytest.mark.parametrize("hid", PULLS)
def test_mesh_is_a_closed_solid(hid: str) -> None:
    mesh = mesh_of(hid)
    assert mesh.is_watertight and mesh.is_winding_consistent
    assert mesh.volume > 0
    assert 100 <= len(mesh.faces) <= 40_000


@pytest.mark.parametrize("hid", PULLS)
def test_extents_follow_the_catalog(hid: str) -> None:
    _check_extents(mesh_of(hid), parts(hid)[0].geometry)


@pytest.mark.parametrize("hid", PULLS)
def test_finger_pocket_is_free(hid: str) -> None:
    handle, design = parts(hid)
    _check_clearance(mesh_of(hid), design.generator, handle.geometry, handle.mount, exact=True)


@pytest.mark.parametrize("hid", PULLS)
def test_nothing_inside_the_front(hid: str) -> None:
    handle, design = parts(hid)
    _check_front_untouched(mesh_of(hid), design.generator, handle.geometry, handle.mount)


@pytest.mark.parametrize("hid", [h for h in PULLS if CATALOG.handles[h].mount.kind == "two_screw"])
def test_cup_screws_go_through_the_flange(hid: str) -> None:
    handle, _ = parts(hid)
    mesh, g = mesh_of(hid), handle.geometry
    half = 0.5 * g.hole_spacing
    t = g.grip_diameter
    holes = np.array([(s * half, 0.0, 0.5 * t) for s in (-1, 1)])
    beside = np.array([(s * (half + 3.0e-3), 0.0, 0.5 * t) for s in (-1, 1)])
    assert not inside(mesh, holes).any()
    assert inside(mesh, beside).all()


def test_same_handle_builds_byte_identical() -> None:
    for hid in ("finger_pull/edge-lip-100", "finger_pull/cup-64", "finger_pull/tab-40", "finger_pull/recess-lip-120"):
        a, b = generate_handle(*parts(hid)), generate_handle(*parts(hid))
        assert a.vertices.tobytes() == b.vertices.tobytes()
        assert a.faces.tobytes() == b.faces.tobytes()


def _smallest(design_id: str) -> Handle:
    return min(CATALOG.handles_of(design_id), key=lambda h: (h.geometry.length, h.id))


@pytest.mark.parametrize("design_id", sorted({CATALOG.handles[h].design for h in PULLS}))
def test_every_design_builds_at_its_smallest_size(design_id: str) -> None:
    handle, design = _smallest(design_id), CATALOG.designs[design_id]
    start = time.perf_counter()
    mesh = generate_handle(handle, design)
    assert time.perf_counter() - start < 1.0
    assert mesh.is_watertight and mesh.volume > 0
    _check_extents(mesh, handle.geometry)


def _variants():
    """Every option of every finger-pull generator, with its ratios at the ends of their valid ranges."""
    for section in ("lip", "j_hook", "l_angle", "rounded_bead", "bevel"):
        for angle, wall in ((0.0, 0.0), (45.0, 1.0), (90.0, 0.15)):
            yield EdgeProfile(name="edge_profile", section=section, lip_angle_deg=angle, wall_ratio=wall)
    for outline in ("rectangle", "rounded", "trapezoid"):
        for overhang in (0.0, 0.5, 1.0):
            yield TabPull(name="tab_pull", outline=outline, overhang_ratio=overhang)
    for hood in ("half_moon", "rectangular", "long_hood"):
        for flange in (0.0, 0.25, 1.0):
            yield CupPull(name="cup_pull", hood=hood, flange_ratio=flange)
    for lip in (0.0, 0.8, 1.0):
        yield RecessLip(name="recess_lip", lip_ratio=lip)


@pytest.mark.parametrize("spec", list(_variants()), ids=lambda s: "-".join(str(v) for v in s.model_dump().values()))
def test_every_option_builds_at_the_smallest_catalogued_size(spec) -> None:
    """Any valid parameter set builds a clean, sized solid that keeps the pocket and the front free (ratios the
    geometry cannot honour are clamped as the generators document, so the pocket may shrink, never fill)."""
    sizes = [CATALOG.handles[h] for h in PULLS if CATALOG.designs[CATALOG.handles[h].design].generator.name == spec.name]
    handle = min(sizes, key=lambda h: (h.geometry.length, h.id))
    mesh = require_solid(finger_pulls.GENERATORS[spec.name](spec, handle.geometry, handle.mount), spec.name)
    assert mesh.is_watertight and mesh.volume > 0
    _check_extents(mesh, handle.geometry)
    _check_front_untouched(mesh, spec, handle.geometry, handle.mount)
    _check_clearance(mesh, spec, handle.geometry, handle.mount, exact=False)
