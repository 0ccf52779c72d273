"""Knob generators (knob_lathe, knob_prism, knob_ring) on the real built-in catalog: solid, sized, clear, repeatable."""

from __future__ import annotations

import math

import numpy as np
import pytest
from meshcheck import CATALOG, assert_catalogued_extents, assert_one_closed_body, inside, mesh_of, parts

from rik.assets.handles import generate_handle, knobs
from rik.assets.meshkit import require_solid
from rik.schemas.generators import KnobLathe, KnobPrism, KnobRing
from rik.schemas.handles import Handle

GENERATORS = {"knob_lathe", "knob_prism", "knob_ring"}
KNOBS = [hid for hid, h in CATALOG.handles.items() if CATALOG.designs[h.design].generator.name in GENERATORS]
TOL = 0.5e-3  # m, the contract's tolerance on extents


def _annulus(r_in: float, r_out: float, z_lo: float, z_hi: float) -> np.ndarray:
    """Points filling the annulus r_in..r_out, z_lo..z_hi around z (m)."""
    pts = [(r * math.cos(a), r * math.sin(a), z)
           for r in np.linspace(r_in, r_out, 4)
           for a in np.linspace(0, 2 * math.pi, 16, endpoint=False) + 0.1
           for z in np.linspace(z_lo, z_hi, 4)]
    return np.array(pts)


def test_the_catalog_has_the_knobs() -> None:
    assert len(KNOBS) == 30
    assert len({CATALOG.handles[h].design for h in KNOBS}) == 18


@pytest.mark.parametrize("hid", KNOBS)
def test_knob_is_a_single_closed_solid(hid: str) -> None:
    mesh = mesh_of(hid)
    assert_one_closed_body(mesh, min_faces=200)


@pytest.mark.parametrize("hid", KNOBS)
def test_knob_extents_match_the_catalog(hid: str) -> None:
    mesh = mesh_of(hid)
    g = CATALOG.handles[hid].geometry
    (x0, y0, z0), (x1, y1, z1) = mesh.bounds
    assert_catalogued_extents(mesh, g, TOL)
    assert z0 >= -1e-6, "material inside the front"
    assert abs(x0 + x1) < TOL  # centred on the screw along x
    name = parts(hid)[1].generator.name
    if name == "knob_ring":
        assert y1 == pytest.approx(g.width - g.length, abs=TOL)  # boss radius above the screw, ring below
    else:
        assert abs(y0 + y1) < TOL


@pytest.mark.parametrize("hid", [h for h in KNOBS if CATALOG.handles[h].geometry.clearance is not None])
def test_knob_clearance_is_free(hid: str) -> None:
    handle, design = parts(hid)
    spec, g = design.generator, handle.geometry
    mesh = mesh_of(hid)
    m = 0.2e-3  # stay this far from the region's boundary
    if isinstance(spec, KnobRing):
        # behind the ring: inside its outer circle, outside the boss, from the front to the ring's back
        D = g.length
        r_boss = max(0.5 * spec.boss_ratio * D, 1.5 * spec.section_ratio * D)
        xs = np.linspace(-0.5 * D + m, 0.5 * D - m, 13)
        ys = np.linspace(-D + m, -m, 13)
        zs = np.linspace(m, g.clearance.depth - m, 3)
        pts = np.array([(x, y, z) for x in xs for y in ys for z in zs])
        in_ring = np.hypot(pts[:, 0], pts[:, 1] + 0.5 * D) < 0.5 * D - m
        out_boss = np.hypot(pts[:, 0], pts[:, 1]) > r_boss + m
        pts = pts[in_ring & out_boss]
        assert g.clearance.width == pytest.approx(D * (1 - 2 * spec.section_ratio), abs=TOL)
    else:
        head_r = 0.5 * g.clearance.width
        assert head_r == pytest.approx(0.5 * (g.grip_diameter if isinstance(spec, KnobLathe) else g.width))
        r_in = spec.neck_ratio * head_r
        z_lo = knobs.base_zone(spec, g)
        assert z_lo <= 0.25 * g.clearance.depth  # the rose stays a small foot
        pts = _annulus(r_in + m, head_r - m, z_lo + m, g.clearance.depth - m)
    assert len(pts) >= 200
    solid = inside(mesh, pts)
    assert not solid.any(), f"{solid.sum()} clearance points inside the knob, e.g. {pts[solid][0]}"
    # the check would notice material: the head itself is found solid just above the clearance
    probe = np.array([[0.0, 0.0 if not isinstance(spec, KnobRing) else -g.length + 0.5 * g.grip_diameter,
                       g.projection - 0.5 * min(g.projection - g.clearance.depth, g.grip_diameter)]])
    assert inside(mesh, probe).all()


def test_same_handle_twice_gives_identical_bytes() -> None:
    handle, design = parts("knob/fluted-34")
    a, b = generate_handle(handle, design), generate_handle(handle, design)
    assert a.vertices.tobytes() == b.vertices.tobytes()
    assert a.faces.tobytes() == b.faces.tobytes()
    ring = parts("knob/ring-pull-35")
    assert generate_handle(*ring).vertices.tobytes() == generate_handle(*ring).vertices.tobytes()


def _smallest(design_id: str) -> Handle:
    """The design's smallest catalogued handle (by length x width)."""
    return min(CATALOG.handles_of(design_id), key=lambda h: (h.geometry.length * h.geometry.width, h.id))


def _check_valid(mesh, g) -> None:
    """A closed solid, outside the front, within the catalogued projection and length."""
    mesh = require_solid(mesh, "test")
    assert mesh.volume > 0
    (x0, y0, z0), (x1, y1, z1) = mesh.bounds
    assert z0 >= -1e-6
    assert z1 <= g.projection + 1e-6
    assert x1 - x0 <= g.length + 1e-6


@pytest.mark.parametrize("design_id", sorted({CATALOG.handles[h].design for h in KNOBS}))
def test_every_design_builds_at_its_smallest_size(design_id: str) -> None:
    handle = _smallest(design_id)
    _check_valid(generate_handle(handle, CATALOG.designs[design_id]), handle.geometry)


LATHE_EXTREMES = [
    {"neck_ratio": 0.05, "head_ratio": 0.05, "edge_round": 0.0},
    {"neck_ratio": 1.0, "head_ratio": 1.0, "edge_round": 1.0},
    {"neck_ratio": 0.9, "head_ratio": 0.9, "edge_round": 1.0, "flutes": 64},
    {"neck_ratio": 0.3, "head_ratio": 0.5, "edge_round": 0.5, "flutes": 5},
]


@pytest.mark.parametrize("profile", list(KnobLathe.model_fields["profile"].annotation.__args__))
def test_knob_lathe_accepts_extreme_parameters(profile: str) -> None:
    g = _smallest("knob/peg").geometry
    for params in LATHE_EXTREMES:
        spec = KnobLathe(name="knob_lathe", profile=profile, **params)
        _check_valid(knobs.knob_lathe(spec, g, CATALOG.handles["knob/peg-16"].mount), g)


@pytest.mark.parametrize("outline", list(KnobPrism.model_fields["outline"].annotation.__args__))
def test_knob_prism_accepts_extreme_parameters(outline: str) -> None:
    handle = _smallest("knob/t-bar")
    for params in ({"neck_ratio": 0.05, "head_ratio": 0.05, "corner_round": 0.0, "taper": 0.0},
                   {"neck_ratio": 1.0, "head_ratio": 1.0, "corner_round": 1.0, "taper": 1.0}):
        spec = KnobPrism(name="knob_prism", outline=outline, **params)
        _check_valid(knobs.knob_prism(spec, handle.geometry, handle.mount), handle.geometry)


def test_knob_ring_accepts_extreme_parameters() -> None:
    handle = _smallest("knob/ring-pull")
    for section, boss in ((0.01, 0.01), (1.0, 1.0), (0.3, 0.05)):
        spec = KnobRing(name="knob_ring", section_ratio=section, boss_ratio=boss)
        _check_valid(knobs.knob_ring(spec, handle.geometry, handle.mount), handle.geometry)
