"""Every bad catalog input: one line naming file, entry and field; exit code 2; no traceback."""

from __future__ import annotations

import textwrap

import pytest

GOOD_HANDLE = """\
handles:
  - id: knob/mushroom-40
    design: knob/mushroom
    size: "40"
    finish: metal/brushed-steel
    geometry: {length: 0.04, width: 0.04, projection: 0.032, grip_diameter: 0.04, clearance: {depth: 0.017, width: 0.04}}
    mount: {kind: single_screw, screw: M4}
    mass: 0.07
    licence: CC-BY-4.0
"""


def run_bad(rik, tmp_path, text: str, name: str = "mine.yaml"):
    path = tmp_path / name
    path.write_text(textwrap.dedent(text))
    result = rik("catalog", "list", "--catalog", str(path))
    assert result.code == 2, result
    assert "Traceback" not in result.err and result.out == ""
    lines = result.err.strip().splitlines()
    assert len(lines) == 1, lines
    return lines[0].removeprefix("rik: error: ")


def test_malformed_yaml(rik, tmp_path) -> None:
    msg = run_bad(rik, tmp_path, "handles:\n  - id: knob/x-1\n    design: [unclosed\n")
    assert msg.startswith("mine.yaml:4") or msg.startswith(f"{tmp_path}/mine.yaml:4")
    assert "malformed YAML" in msg


def test_unknown_handle_type(rik, tmp_path) -> None:
    msg = run_bad(rik, tmp_path, """\
        designs:
          - id: lever/bar
            type: lever
            subtype: bar
            name: A lever
            generator: {name: bar_pull, section: round, leg: round}
            provenance: {origin: parametric, reference: test}
        """)
    assert "entry designs[0] 'lever/bar', field 'type'" in msg
    assert "'knob', 'two_point' or 'finger_pull'" in msg and "(got 'lever')" in msg
    assert ":3," in msg  # the line of the field


def test_duplicate_id_in_one_file(rik, tmp_path) -> None:
    text = GOOD_HANDLE + GOOD_HANDLE.removeprefix("handles:\n")
    msg = run_bad(rik, tmp_path, text)
    assert "entry handles[1] 'knob/mushroom-40', field 'id': duplicate handle id" in msg
    assert "as handles[0] 'knob/mushroom-40'" in msg


def test_handle_whose_design_does_not_exist(rik, tmp_path) -> None:
    msg = run_bad(rik, tmp_path, GOOD_HANDLE.replace("design: knob/mushroom", "design: knob/mushrom")
                  .replace("knob/mushroom-40", "knob/mushrom-40"))
    assert "entry handles[0] 'knob/mushrom-40', field 'design': no design 'knob/mushrom' in the catalog; " \
           "did you mean 'knob/mushroom'?" in msg


@pytest.mark.parametrize("value", ["0", "-0.01"])
def test_zero_or_negative_dimension(rik, tmp_path, value) -> None:
    msg = run_bad(rik, tmp_path, GOOD_HANDLE.replace("projection: 0.032", f"projection: {value}"))
    assert f"entry handles[0] 'knob/mushroom-40', field 'geometry.projection': input should be greater than 0 " \
           f"(got {value})" in msg


def test_nan_dimension(rik, tmp_path) -> None:
    msg = run_bad(rik, tmp_path, GOOD_HANDLE.replace("mass: 0.07", "mass: .nan"))
    assert "field 'mass'" in msg and "finite number" in msg


def base_unit_with_range(lower: str, upper: str) -> str:
    return f"""\
        base_units:
          - id: door/test-40
            name: Test door
            install: floor
            carcass: {{width: 0.4, height: 0.8, depth: 0.6, panel_thickness: 0.018, finish: lacquer/white}}
            fronts:
              - id: door
                kind: door
                size: [0.396, 0.796, 0.018]
                center: [0, 0.011, 0.4]
                joint: {{type: hinge, axis: [0, 0, 1], anchor: [-0.198, 0.002, 0.4], range: [{lower}, {upper}]}}
                mount: {{pos: [0.02, 0.02, 0.4], size: [0.326, 0.766]}}
                finish: lacquer/white
        """


def test_base_unit_overlay_is_accepted(rik, tmp_path) -> None:
    path = tmp_path / "door.yaml"
    path.write_text(textwrap.dedent(base_unit_with_range("0", "1.9")))
    assert rik("catalog", "show", "door/test-40", "--catalog", str(path)).code == 0


def test_hinge_range_in_the_wrong_order(rik, tmp_path) -> None:
    msg = run_bad(rik, tmp_path, base_unit_with_range("1.9", "0"))
    assert "entry base_units[0] 'door/test-40', field 'fronts.0.joint.range': must be (lower, upper) with " \
           "lower < upper, got (1.9, 0.0)" in msg


def test_hinge_that_opens_into_the_carcass(rik, tmp_path) -> None:
    msg = run_bad(rik, tmp_path, base_unit_with_range("0", "1.9").replace("axis: [0, 0, 1]", "axis: [0, 0, -1]"))
    assert "field 'fronts.0.joint.axis': opening about axis (0.0, 0.0, -1.0) swings front 'door' into the " \
           "carcass; reverse the axis" in msg


def test_mount_rectangle_past_the_front(rik, tmp_path) -> None:
    msg = run_bad(rik, tmp_path, base_unit_with_range("0", "1.9").replace("size: [0.326, 0.766]", "size: [0.5, 0.766]"))
    assert "field 'fronts.0.mount.size': the mount rectangle (0.5 x 0.766 m) reaches past the edge" in msg


def test_overlay_that_redefines_a_builtin(rik, tmp_path) -> None:
    msg = run_bad(rik, tmp_path, GOOD_HANDLE.replace("knob/mushroom-40", "knob/mushroom-30").replace('"40"', '"30"'))
    assert "entry handles[0] 'knob/mushroom-30', field 'id': redefines the built-in handle 'knob/mushroom-30'" in msg
    assert "an overlay may only add new ids" in msg


def test_unknown_field_lists_valid_ones(rik, tmp_path) -> None:
    msg = run_bad(rik, tmp_path, GOOD_HANDLE.replace("mass: 0.07", "mass: 0.07\n    colour: red"))
    assert "field 'colour': unknown field; valid fields: id, design, size, finish, geometry, mount, mass, licence" in msg


def test_two_point_handle_without_hole_spacing(rik, tmp_path) -> None:
    text = GOOD_HANDLE.replace("knob/mushroom-40", "two_point/bow-999").replace("knob/mushroom", "two_point/bow") \
        .replace('"40"', '"999"').replace("single_screw", "two_screw")
    msg = run_bad(rik, tmp_path, text)
    assert "field 'geometry.hole_spacing': a two-screw handle needs its hole spacing (m)" in msg


def test_unknown_section_and_missing_file(rik, tmp_path) -> None:
    assert "field 'handels': unknown section" in run_bad(rik, tmp_path, "handels: []\n")
    result = rik("catalog", "list", "--catalog", str(tmp_path / "nope.yaml"))
    assert result.code == 2 and result.err.strip().endswith("nope.yaml: no such catalog file or directory")


def test_errors_are_not_cached(rik, tmp_path) -> None:
    run_bad(rik, tmp_path, "handles: 3\n")
    run_bad(rik, tmp_path, "handles: 3\n")  # still reported, not served from a cache



def preset(hinge: str, slide: str = "{damping: 5.0, frictionloss: 15.0, provenance: assumed}", source: str = "") -> str:
    """A user catalog with one preset, ``stuck``, with these sides (flow mappings) and source."""
    return f"presets:\n  - id: stuck\n    name: Stuck\n    slide: {slide}\n    hinge: {hinge}\n" + (
        f"    source: {source}\n" if source else "")


def test_preset_with_negative_friction(rik, tmp_path) -> None:
    msg = run_bad(rik, tmp_path, preset("{damping: 0.8, frictionloss: -1.0, provenance: assumed}"))
    assert msg.endswith("mine.yaml:5, entry presets[0] 'stuck', field 'hinge.frictionloss': input should be greater "
                        "than or equal to 0 (got -1.0)"), msg


def test_preset_whose_catch_no_robot_can_break(rik, tmp_path) -> None:
    """The strongest pull of a catalog robot is the Hand-E's friction capacity, 2 pads x 0.3 x 130 N = 78 N: a hinge
    holding 32 N·m at closed needs 80 N at a handle 0.40 m from its axis."""
    msg = run_bad(rik, tmp_path, preset("{damping: 0.8, frictionloss: 2.0, provenance: assumed, effects: "
                                        "[{kind: magnetic_catch, force: 30.0, decay: 0.05}]}"))
    assert msg.endswith("mine.yaml:5, entry presets[0] 'stuck', field 'hinge.effects.0.force': holds the front shut "
                        "with 32 N·m at closed (frictionloss 2 + magnetic_catch 30), 80 N at a handle 0.40 m from the "
                        "axis (the catalog's lever arm); no catalog robot can pull more than 78 N (hand-e: 2 pads x "
                        "friction 0.3 x grip 130 N), so none could open it"), msg
    ok = preset("{damping: 0.8, frictionloss: 2.0, provenance: assumed, effects: "
                "[{kind: magnetic_catch, force: 29.0, decay: 0.05}]}")  # 31 N·m: 77.5 N at the handle
    (tmp_path / "ok.yaml").write_text(ok)
    assert rik("catalog", "show", "stuck", "--catalog", str(tmp_path / "ok.yaml")).code == 0


def test_preset_whose_self_closing_drawer_no_robot_can_open(rik, tmp_path) -> None:
    msg = run_bad(rik, tmp_path, preset("{damping: 0.8, frictionloss: 6.0, provenance: assumed}",
                                        slide="{damping: 5.0, frictionloss: 15.0, provenance: assumed, effects: "
                                              "[{kind: self_close, zone: 0.05, stiffness: 1400.0}]}"))
    assert msg.endswith("mine.yaml:4, entry presets[0] 'stuck', field 'slide.effects.0.stiffness': holds the front "
                        "shut with 85 N at closed (frictionloss 15 + self_close 70); no catalog robot can pull more "
                        "than 78 N (hand-e: 2 pads x friction 0.3 x grip 130 N), so none could open it"), msg


@pytest.mark.parametrize(("source", "field", "problem"), [
    ("{kind: measured, reference: my drawer}", "source.data", "a measured source names the data file it was "
                                                              "fitted to"),
    ("{kind: paper, reference: Real-IKEA, mechanism: door}", "source.mechanism", "only a measured source names its "
                                                                                "mechanism (this one is paper)"),
    ("{kind: measured, reference: r, data: d.csv, trials_heldout: ['3']}", "source.heldout_rms_n",
     "held-out trials need the preset's RMS error over them, N"),
    ("{kind: guessed, reference: r}", "source.kind", "input should be 'paper', 'literature', 'assumed' or "
                                                     "'measured' (got 'guessed')"),
])
def test_preset_source_that_does_not_hold_together(rik, tmp_path, source, field, problem) -> None:
    msg = run_bad(rik, tmp_path, preset("{damping: 0.8, frictionloss: 6.0, provenance: assumed}", source=source))
    assert msg.endswith(f"entry presets[0] 'stuck', field '{field}': {problem}"), msg
