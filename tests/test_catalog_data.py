"""The built-in catalog: counts, realistic dimensions, presets from the paper, and that every pairing fits."""

from __future__ import annotations

import math

import pytest

from rik.registry import load_catalog
from rik.registry.fit import fitting_rotations
from rik.schemas import HandleType, JointType


@pytest.fixture(scope="module")
def catalog():
    return load_catalog([])


def test_counts_match_the_paper(catalog) -> None:
    assert len(catalog.handles) == 83
    assert len(catalog.designs) == 47
    assert len(catalog.base_units) == 13
    assert len(catalog.presets) >= 3


@pytest.mark.parametrize("handle_type", list(HandleType))
def test_each_type_has_enough_handles_and_designs(catalog, handle_type) -> None:
    handles = [h for h in catalog.handles.values() if catalog.handle_type(h) is handle_type]
    designs = [d for d in catalog.designs.values() if d.type is handle_type]
    assert len(handles) >= 15 and len(designs) >= 10


def test_every_pairing_fits_every_front(catalog) -> None:
    misfits = [(b.id, f.id, h.id) for b in catalog.base_units.values() for f in b.fronts
               for h in catalog.handles.values() if not fitting_rotations(h, f)]
    assert len(catalog.base_units) * len(catalog.handles) == 1079
    assert misfits == []


def test_two_point_hole_spacings_follow_the_32mm_system(catalog) -> None:
    standard = {0.064, 0.096, 0.128, 0.160, 0.192, 0.224, 0.256, 0.320}
    for h in catalog.handles.values():
        if catalog.handle_type(h) is HandleType.two_point:
            assert round(h.geometry.hole_spacing, 3) in standard, h.id
            assert h.id.endswith(f"-{round(h.geometry.hole_spacing * 1000)}"), h.id


def test_dimensions_are_those_of_real_hardware(catalog) -> None:
    for h in catalog.handles.values():
        g, kind = h.geometry, catalog.handle_type(h)
        if kind is HandleType.knob:
            assert 0.015 <= max(g.length, g.width) <= 0.065, h.id  # head size; grip may be a ring wire
            assert 0.015 <= g.projection <= 0.04, h.id
        if kind is HandleType.two_point:
            assert 0.025 <= g.projection <= 0.04, h.id
            assert 0.004 <= g.grip_diameter <= 0.03, h.id
            assert g.clearance.depth >= 0.015, f"{h.id}: no room for a finger behind the bar"
        assert 0.003 <= h.mass <= 0.5, h.id


def test_base_units_cover_the_joint_mechanisms(catalog) -> None:
    kinds = [(f.kind, f.joint.type, tuple(round(a) for a in f.joint.axis))
             for b in catalog.base_units.values() for f in b.fronts]
    assert ("door", JointType.hinge, (0, 0, 1)) in kinds  # hinged right (axis at -x)
    assert ("door", JointType.hinge, (0, 0, -1)) in kinds  # hinged left (axis at +x)
    assert ("flap", JointType.hinge, (1, 0, 0)) in kinds  # lift-up: axis at the top
    assert ("flap", JointType.hinge, (-1, 0, 0)) in kinds  # drop-down: axis at the bottom
    drawer_heights = {f.size[1] for b in catalog.base_units.values() for f in b.fronts if f.kind == "drawer"}
    assert len(drawer_heights) >= 3


def test_slide_presets_are_the_papers(catalog) -> None:
    paper = {"smooth": (2, 5), "normal": (5, 15), "high": (10, 30)}
    for preset_id, (damping, friction) in paper.items():
        slide = catalog.preset(preset_id).slide
        assert (slide.damping, slide.frictionloss, slide.provenance.value) == (damping, friction, "paper")


def test_door_presets_follow_their_written_derivation(catalog) -> None:
    lever = 0.40  # m, stated in presets.yaml
    paper = [p for p in catalog.presets.values() if p.source is not None and p.source.kind.value == "paper"]
    assert [p.id for p in paper] == ["smooth", "normal", "high"] == catalog.default_presets
    for preset in paper:
        assert preset.source is not None and preset.source.lever_arm_m == lever
        assert math.isclose(preset.hinge.frictionloss, preset.slide.frictionloss * lever)
        assert math.isclose(preset.hinge.damping, preset.slide.damping * lever**2)
        assert "0.40" in preset.hinge.notes


def test_every_entry_has_a_licence_and_provenance(catalog) -> None:
    assert all(h.licence not in ("", "Unknown") for h in catalog.handles.values())
    assert all(d.provenance.reference for d in catalog.designs.values())


def test_left_and_right_in_names_are_as_a_person_facing_the_front_sees_them(catalog):
    """+x is on the left of a person facing the front (x = y cross z with y towards them): a door 'hinged left'
    turns about an axis at +x, and of two fronts side by side the one named left is at +x."""
    for base in catalog.base_units.values():
        for front in base.fronts:
            sides = [s for s in ("left", "right") if base.id.endswith(f"-{s}") or front.id.endswith(f"-{s}")]
            for side in sides:
                x = front.joint.anchor[0] if front.joint.type.value == "hinge" and base.id.endswith(side) \
                    else front.center[0]
                assert (x > 0) == (side == "left"), (base.id, front.id, x)
