"""Two-point generators (bar_pull, bow_pull) on the real built-in catalog: solid, sized, clear, repeatable."""

from __future__ import annotations

import math
import time

import numpy as np
import pytest
from meshcheck import CATALOG, assert_catalogued_extents, assert_one_closed_body, inside, mesh_of, parts

from rik.assets.handles import generate_handle, two_point
from rik.assets.meshkit import require_solid

GENERATORS = {"bar_pull", "bow_pull"}
HANDLES = [hid for hid, h in CATALOG.handles.items() if CATALOG.designs[h.design].generator.name in GENERATORS]
DESIGNS = sorted({CATALOG.handles[hid].design for hid in HANDLES})
TOL = 0.5e-3  # m, the contract's tolerance on extents
MARGIN = 0.05e-3  # m, how far test points stay from the clearance's boundary


def _clearance_grid(hid: str, nx: int = 25, ny: int = 5, nz: int = 8) -> np.ndarray:
    """Points filling the loop |x| < clearance.width/2, 0 <= z <= clearance.depth, across (and beyond) the width;
    the grid always holds the box's corners (less MARGIN), where a loop's inner corners come closest."""
    g = CATALOG.handles[hid].geometry
    c = g.clearance
    xs = np.linspace(-c.width / 2 + MARGIN, c.width / 2 - MARGIN, nx)
    ys = np.linspace(-g.width / 2 - 1e-3, g.width / 2 + 1e-3, ny)
    zs = np.linspace(MARGIN, c.depth - MARGIN, nz)
    return np.array(np.meshgrid(xs, ys, zs, indexing="ij")).reshape(3, -1).T


def test_the_catalog_has_the_two_point_handles() -> None:
    assert len(HANDLES) == 34
    assert len(DESIGNS) == 17
    assert set(two_point.GENERATORS) == GENERATORS


@pytest.mark.parametrize("hid", HANDLES)
def test_handle_is_a_single_closed_solid(hid: str) -> None:
    mesh = mesh_of(hid)
    assert_one_closed_body(mesh, min_faces=500)


@pytest.mark.parametrize("hid", HANDLES)
def test_handle_extents_match_the_catalog(hid: str) -> None:
    mesh = mesh_of(hid)
    g = CATALOG.handles[hid].geometry
    (x0, y0, z0), (x1, y1, z1) = mesh.bounds
    assert_catalogued_extents(mesh, g, TOL)
    assert z0 == pytest.approx(0.0, abs=1e-6)
    assert (mesh.vertices[:, 2] >= -1e-6).all(), "material inside the front"
    assert abs(x0 + x1) < 5e-6 and abs(y0 + y1) < 5e-6  # symmetric about the screws' midpoint


@pytest.mark.parametrize("hid", HANDLES)
def test_the_loop_is_empty(hid: str) -> None:
    mesh = mesh_of(hid)
    assert not mesh.contains(_clearance_grid(hid)).any()  # dense, by ray casting
    assert not inside(mesh, _clearance_grid(hid, 9, 3, 4)).any()  # sparser, exact


@pytest.mark.parametrize("hid", HANDLES)
def test_a_finger_passes_through_the_loop(hid: str) -> None:
    """A 10 mm finger capsule along y, 2 cm longer than the handle is wide, fits anywhere along the loop."""
    mesh = mesh_of(hid)
    g = CATALOG.handles[hid].geometry
    r = 5e-3 - MARGIN
    half = g.width / 2 + 10e-3
    ring = [(r * math.cos(a), r * math.sin(a)) for a in np.linspace(0, 2 * math.pi, 12, endpoint=False)]
    pts = []
    for cx in np.linspace(-g.clearance.width / 2 + 5e-3, g.clearance.width / 2 - 5e-3, 5):
        cz = g.clearance.depth - 5e-3
        pts += [(cx + dx, y, cz + dz) for dx, dz in ring for y in np.linspace(-half, half, 5)]
        pts += [(cx, sy * (half + r), cz) for sy in (-1, 1)]
    assert not mesh.contains(np.array(pts)).any()


@pytest.mark.parametrize("hid", HANDLES)
def test_the_screws_are_under_material(hid: str) -> None:
    """Legs and feet stand on the screws: just above the front at each screw is solid."""
    mesh = mesh_of(hid)
    g = CATALOG.handles[hid].geometry
    pts = np.array([(sx * g.hole_spacing / 2, 0.0, 0.3e-3) for sx in (-1, 1)])
    assert inside(mesh, pts).all()


def test_same_handle_twice_is_byte_identical() -> None:
    for hid in ("two_point/bar-hex-128", "two_point/trapezoid-128", "two_point/strap-96"):
        start = time.perf_counter()
        a = generate_handle(*parts(hid))
        assert time.perf_counter() - start < 1.0
        b = generate_handle(*parts(hid))
        assert a.vertices.tobytes() == b.vertices.tobytes()
        assert a.faces.tobytes() == b.faces.tobytes()


@pytest.mark.parametrize("design_id", DESIGNS)
def test_every_design_builds_at_its_smallest_size(design_id: str) -> None:
    handles = [CATALOG.handles[hid] for hid in HANDLES if CATALOG.handles[hid].design == design_id]
    smallest = min(handles, key=lambda h: (h.geometry.hole_spacing, h.geometry.length))
    design = CATALOG.designs[design_id]
    mesh = two_point.GENERATORS[design.generator.name](design.generator, smallest.geometry, smallest.mount)
    mesh = require_solid(mesh, smallest.id)
    assert mesh.volume > 0


@pytest.mark.parametrize(
    ("hid", "field"),
    [
        ("two_point/bar-round-128", "leg_ratio"),
        ("two_point/bar-flat-128", "leg_ratio"),
        ("two_point/bow-slim-96", "foot_ratio"),
        ("two_point/frame-160", "foot_ratio"),
    ],
)
def test_oversized_legs_and_feet_are_clamped_clear_of_the_loop(hid: str, field: str) -> None:
    handle, design = parts(hid)
    spec = design.generator.model_copy(update={field: 4.0})
    mesh = require_solid(two_point.GENERATORS[spec.name](spec, handle.geometry, handle.mount), hid)
    g = handle.geometry
    (x0, y0, _), (x1, y1, z1) = mesh.bounds
    assert x1 - x0 == pytest.approx(g.length, abs=TOL)
    assert y1 - y0 <= g.width + TOL
    assert z1 == pytest.approx(g.projection, abs=TOL)
    assert not mesh.contains(_clearance_grid(hid)).any()
    assert not inside(mesh, _clearance_grid(hid, 9, 3, 4)).any()
