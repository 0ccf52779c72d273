"""The combinator: ids, placement rules, the joint mapping, building, checks, files, resume and the CLI."""

from __future__ import annotations

import hashlib
import json
import math
import os
from pathlib import Path

import mujoco
import pytest
from shared import BOW, builtin_catalog

from rik.combinator.build import build_variant, check_variant, is_current
from rik.combinator.placement import EDGE_INSET, place_handle
from rik.errors import RikError, UnknownIdError
from rik.registry import load_catalog
from rik.registry.ids import VariantKey, parse_variant_id, select_variants, variant_id

CAT = builtin_catalog()


def test_ids_are_readable_and_round_trip() -> None:
    key = VariantKey("drawer/chest-80", "two_point/bow-128", "normal")
    assert key.id == variant_id(*["drawer/chest-80", "two_point/bow-128", "normal"]) == BOW
    assert parse_variant_id(CAT, BOW) == key
    assert parse_variant_id(CAT, f"variants/{BOW}/") == key  # a directory path works too
    assert len(select_variants(CAT, presets=["normal"])) == 1079
    assert len(select_variants(CAT, bases=["drawer/chest-80"], handle_types=["knob"])) == 30 * 3


@pytest.mark.parametrize(("text", "message"), [
    ("drawer-chest-80__two_point-bow-128__nromal", "no preset 'nromal' in the catalog; did you mean 'normal'?"),
    ("drawer-chest-80__two_point-bow-12__normal", "no handle 'two_point-bow-12'"),
    ("drawer-chest-80__normal", "must be <base unit>__<handle>__<preset>"),
])
def test_bad_variant_ids(text: str, message: str) -> None:
    with pytest.raises((RikError, UnknownIdError), match=message.replace("?", r"\?")):
        parse_variant_id(CAT, text)


def _place(base: str, handle: str, front: int = 0):
    unit, h = CAT.base_units[base], CAT.handles[handle]
    return place_handle(unit, unit.fronts[front], h, CAT.handle_type(h))


def test_placement_rules() -> None:
    drawer = _place("drawer/chest-80", "two_point/bow-128")
    assert (drawer.u, drawer.v, drawer.rotation) == (0.0, 0.0, 0)  # centred, horizontal
    door = _place("door/base-40-right", "two_point/bow-128")  # hinge at -x: opening edge at +x
    unit = CAT.base_units["door/base-40-right"]
    assert door.rotation == 90 and door.u > 0
    half_width = unit.fronts[0].mount.size[0] / 2
    assert door.u + CAT.handles["two_point/bow-128"].geometry.width / 2 == pytest.approx(half_width - EDGE_INSET)
    assert door.pos[2] > 0.6  # a base cabinet: near the top, as close to 1 m as the door allows
    wall = _place("door/wall-60-left", "knob/mushroom-30")  # hinge at +x: opening edge at -x; hung at 1.4 m
    assert wall.u < 0 and wall.pos[2] < 0.2 and wall.rotation == 0
    lift = _place("flap/lift-up-60", "two_point/bow-128")  # hinged at the top: handle near the bottom
    assert lift.rotation == 0 and lift.u == 0.0 and lift.pos[2] < 0.1
    edge = _place("drawer/chest-80", "finger_pull/edge-lip-100", front=1)
    assert edge.edge == "top" and edge.rotation == 0
    assert edge.pos[2] == pytest.approx(0.4 + 0.125)  # on the top edge of the middle drawer
    side = _place("door/base-60-left", "finger_pull/side-edge-150")
    assert side.edge == "opening side" and side.rotation in (90, 270)


def test_placement_override_from_the_catalog(tmp_path: Path) -> None:
    overlay = tmp_path / "mine.yaml"
    unit = CAT.base_units["drawer/bedside-45"].model_dump(mode="json")
    unit["id"] = "drawer/bedside-test"
    unit["fronts"][0]["placements"] = [{"at": [0.1, -0.02], "rotation": 90, "handle_types": ["two_point"]}]
    overlay.write_text(json.dumps({"base_units": [unit]}))
    cat = load_catalog([overlay])
    front = cat.base_units["drawer/bedside-test"].fronts[0]
    bow, knob = cat.handles["two_point/bow-128"], cat.handles["knob/mushroom-30"]
    p = place_handle(cat.base_units["drawer/bedside-test"], front, bow, cat.handle_type(bow))
    assert (p.u, p.v, p.rotation, p.rule) == (0.1, -0.02, 90, "catalog placement")
    q = place_handle(cat.base_units["drawer/bedside-test"], front, knob, cat.handle_type(knob))
    assert (q.u, q.v) == (0.0, 0.0)  # the override is for two-point handles only


@pytest.fixture(scope="module")
def built(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("variants")
    for vid in (BOW, "door-double-80__knob-mushroom-30__high", "flap-drop-down-60__finger_pull-recess-lip-120__smooth",
                "drawer-chest-80__finger_pull-edge-lip-100__normal"):
        result = build_variant(CAT, parse_variant_id(CAT, vid), out)
        assert result.status == "built", result.reason
    return out


def test_built_variants_load_with_plain_mujoco(built: Path) -> None:
    for directory in sorted(p for p in built.iterdir() if (p / "model.xml").exists()):
        model = mujoco.MjModel.from_xml_path(str(directory / "model.xml"))
        scene = mujoco.MjModel.from_xml_path(str(directory / "scene.xml"))
        assert scene.ngeom > model.ngeom and model.nmesh > 0
        text = (directory / "model.xml").read_text()
        assert 'meshdir="meshes"' in text and "/" not in text.split('file="')[1].split('"')[0]
        report = json.loads((directory / "report.json").read_text())
        assert report["status"] == "valid" and all(c["passed"] for c in report["checks"])
        assert {c["name"] for c in report["checks"]} >= {"mount_fit", "sweep_clear", "opens_under_pull",
                                                         "rest_stable", "closed_contact_free", "inertia_valid"}
        assert report["hulls"] > 0 and report["collision_vertices"] > 0 and report["compile_seconds"] > 0
        assert len(report["spec_hash"]) == 64 and is_current(directory, report["spec_hash"])


def test_model_follows_menagerie_conventions_and_carries_the_preset(built: Path) -> None:
    model = mujoco.MjModel.from_xml_path(str(built / BOW / "model.xml"))
    text = (built / BOW / "model.xml").read_text()
    assert '<default class="visual">' in text and '<default class="collision">' in text
    assert 'class="normal_slide"' in text
    normal = CAT.presets["normal"].slide
    for front in ("drawer-1", "drawer-2", "drawer-3"):
        jid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, front)
        dof = model.jnt_dofadr[jid]
        assert model.dof_damping[dof] == normal.damping and model.dof_frictionloss[dof] == normal.frictionloss
        assert mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, f"{front}/mount") >= 0
        assert mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, f"{front}/grasp") >= 0
    visual = [g for g in range(model.ngeom) if model.geom_group[g] == 2]
    assert visual and all(model.geom_contype[g] == 0 and model.geom_conaffinity[g] == 0 for g in visual)
    high = mujoco.MjModel.from_xml_path(str(built / "door-double-80__knob-mushroom-30__high" / "model.xml"))
    assert high.dof_frictionloss[0] == CAT.presets["high"].hinge.frictionloss


def test_edge_pulls_get_their_gap_and_inset_grips_their_recess(built: Path) -> None:
    report = json.loads((built / "drawer-chest-80__finger_pull-edge-lip-100__normal" / "report.json").read_text())
    rules = [f["placement"]["rule"] for f in report["fronts"]]
    assert "cut back" not in rules[0] and all("cut back 1.0 mm" in r for r in rules[1:])  # a 3 mm cap, 3 mm gaps
    model = mujoco.MjModel.from_xml_path(
        str(built / "flap-drop-down-60__finger_pull-recess-lip-120__smooth" / "model.xml"))
    names = {mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, g) for g in range(model.ngeom)}
    assert {"flap/panel_0", "flap/panel_4"} <= names and "flap/panel" not in names  # the panel routed around it


def test_joint_mapping_materialises_a_user_preset_with_a_spring(tmp_path: Path) -> None:
    overlay = tmp_path / "presets.yaml"
    overlay.write_text("presets:\n  - id: closer\n    name: Self-closing\n"
                       "    slide: {damping: 7.0, frictionloss: 4.0, armature: 0.5, spring: {stiffness: 20.0, "
                       "reference: -0.05}, provenance: assumed}\n"
                       "    hinge: {damping: 0.3, frictionloss: 1.0, provenance: assumed}\n")
    cat = load_catalog([overlay])
    checked = check_variant(cat, VariantKey("drawer/bedside-45", "knob/mushroom-30", "closer"))
    assert checked.failed is None, checked.failed
    model = checked.model
    assert (model.dof_damping[0], model.dof_frictionloss[0], model.dof_armature[0]) == (7.0, 4.0, 0.5)
    assert model.jnt_stiffness[0] == 20.0 and model.qpos_spring[0] == -0.05


def test_rebuild_skips_valid_variants_and_repairs_damaged_ones(built: Path) -> None:
    key = parse_variant_id(CAT, BOW)
    before = (built / BOW / "model.xml").read_bytes()
    assert build_variant(CAT, key, built).status == "skipped"
    (built / BOW / "model.xml").write_text("<mujoco/>")
    assert build_variant(CAT, key, built).status == "built"
    assert (built / BOW / "model.xml").read_bytes() == before  # deterministic: byte-identical MJCF
    assert not (built / ".staging").exists() or not any((built / ".staging").iterdir())



def _files_match_report(directory: Path) -> bool:
    report = json.loads((directory / "report.json").read_text())
    return report["status"] == "valid" and all(
        hashlib.sha256((directory / name).read_bytes()).hexdigest() == sha for name, sha in report["files"].items())


@pytest.mark.parametrize("force", [False, True])
def test_a_damaged_shared_mesh_is_rebuilt_in_every_variant(rik, tmp_path: Path, force: bool) -> None:
    from rik.combinator.build import MESH_STORE, build_variants

    keys = [VariantKey(base, "knob/mushroom-30", "normal") for base in ("drawer/bedside-45", "drawer/chest-80")]
    out = tmp_path / "variants"
    assert {r.status for r in build_variants(CAT, keys, out)} == {"built"}
    first, second = (out / k.id for k in keys)
    shared = sorted(n.name for n in (first / "meshes").iterdir() if (second / "meshes" / n.name).exists() and
                    (first / "meshes" / n.name).stat().st_ino == (second / "meshes" / n.name).stat().st_ino)
    assert shared, "the two variants share no mesh file"
    with (first / "meshes" / shared[0]).open("ab") as fh:  # damages the store file and every variant linked to it
        fh.write(b"x")
    assert rik("variants", "validate", str(second)).code == 2
    results = build_variants(CAT, keys, out, force=force)
    assert [r.status for r in results] == ["built", "built"]
    for directory in (first, second):
        assert _files_match_report(directory), f"{directory.name} still holds the damaged mesh"
        checked = rik("variants", "validate", str(directory))
        assert checked.code == 0, checked.err
    for stored in (out / MESH_STORE).iterdir():  # the store holds each mesh under its content's sha256
        assert stored.stem == hashlib.sha256(stored.read_bytes()).hexdigest(), stored.name


# ---- bad input: each rejected by a named check, nothing written ---------------------------------------------------
LONG_BAR = """handles:
  - id: two_point/bar-round-640
    design: two_point/bar-round
    size: "640"
    finish: metal/stainless
    geometry: {length: 0.68, width: 0.012, projection: 0.035, grip_diameter: 0.012, hole_spacing: 0.64,
               clearance: {depth: 0.023, width: 0.628}}
    mount: {kind: two_screw, screw: M4}
    mass: 0.4
    licence: CC-BY-4.0
"""


def _unit_overlay(tmp_path: Path, base: str, new_id: str, edit) -> Path:
    unit = CAT.base_units[base].model_dump(mode="json")
    unit["id"] = new_id
    edit(unit)
    path = tmp_path / "units.yaml"
    path.write_text(json.dumps({"base_units": [unit]}))
    return path


def _small_drawer(unit: dict) -> None:
    front = unit["fronts"][0]
    front["size"][1] = 0.05
    front["mount"]["size"] = [0.4, 0.02]
    front["drawer_box"]["height"] = 0.03


def _door_hinged_into_the_carcass(unit: dict) -> None:
    unit["fronts"][0]["joint"]["axis"] = [0, 0, -1]


def _doors_hinged_on_the_same_side(unit: dict) -> None:
    left = unit["fronts"][1]  # at +x; hinge it on its right (the middle), like the other door
    left["joint"] = {"type": "hinge", "axis": [0, 0, 1], "anchor": [0.0015, 0.002, 0.4], "range": [0, 1.91986]}
    left["mount"]["pos"] = [0.21975, 0.02, 0.4]


@pytest.mark.parametrize(("base", "handle", "edit", "check", "words"), [
    ("drawer/bedside-45", "two_point/bar-round-640", None, "mount_fit", "overruns drawer's mount rectangle"),
    ("drawer/bedside-test", "knob/mushroom-30", _small_drawer, "mount_fit", "along its height"),
    # the left door, hinged in the middle, swings its edge into the right door at 14°
    ("door/double-test", "two_point/bow-128", _doors_hinged_on_the_same_side, "sweep_clear",
     "with door-left at 14°: door-right/panel (door-right) and door-left/panel (door-left) overlap by 1.3 mm"),
])
def test_bad_pairings_are_rejected_by_a_named_check(rik, tmp_path, base, handle, edit, check, words) -> None:
    paths = [tmp_path / "bar.yaml"]
    paths[0].write_text(LONG_BAR)
    if edit is not None:
        source = {"drawer/bedside-test": "drawer/bedside-45", "door/base-40-test": "door/base-40-right",
                  "door/double-test": "door/double-80"}[base]
        paths.append(_unit_overlay(tmp_path, source, base, edit))
    vid = variant_id(base, handle, "normal")
    out = tmp_path / "variants"
    result = rik("variants", "build", vid, "--out", str(out), *(a for p in paths for a in ("--catalog", str(p))))
    assert result.code == 2
    line = result.err.strip().splitlines()[-1]
    assert line.startswith(f"rik: error: variant {vid} rejected by check {check}: ") and words in line, line
    assert not (out / vid).exists()
    assert json.loads((out / "manifest.json").read_text())["variants"][vid]["failed_check"] == check


def test_hinge_that_opens_into_the_carcass_is_refused(rik, tmp_path) -> None:
    """The catalog refuses it on load (file, entry, field); the combinator's own check catches a model whose axis
    was flipped after the catalog (here, in the compiled model)."""
    path = _unit_overlay(tmp_path, "door/base-40-right", "door/base-40-test", _door_hinged_into_the_carcass)
    out = tmp_path / "variants"
    result = rik("variants", "build", "door-base-40-test__knob-mushroom-30__normal", "--out", str(out),
                 "--catalog", str(path))
    assert result.code == 2 and not out.exists()
    assert result.err.strip().endswith("entry base_units[0] 'door/base-40-test', field 'fronts.0.joint.axis': opening "
                                       "about axis (0.0, 0.0, -1.0) swings front 'door' into the carcass; reverse "
                                       "the axis")
    from rik.combinator.checks import ModelContext, check_opens_outward

    checked = check_variant(CAT, VariantKey("door/base-40-right", "knob/mushroom-30", "normal"))
    checked.model.jnt_axis[0] *= -1
    ctx = ModelContext(checked.variant, checked.variant.unit, checked.model, mujoco.MjData(checked.model))
    result = check_opens_outward(ctx)
    assert not result.passed and result.reason == ("opening door of door/base-40-right moves its handle into the "
                                                   "carcass (its joint axis points the wrong way: flip the axis)")


def test_unknown_preset_is_refused(rik, tmp_path) -> None:
    result = rik("variants", "build", "--all", "--base", "drawer/chest-80", "--preset", "nomal", "--out",
                 str(tmp_path / "v"))
    assert result.code == 2
    assert result.err.strip() == "rik: error: no preset 'nomal' in the catalog; did you mean 'normal'?"
    assert not (tmp_path / "v").exists()


# ---- CLI ----------------------------------------------------------------------------------------------------------
def test_cli_list_build_validate_show(rik, tmp_path, built: Path) -> None:
    rows = json.loads(rik("variants", "list", "--base", "drawer/chest-80", "--preset", "normal", "-f", "json",
                          "--dir", str(built)).out)
    assert len(rows) == 83 and next(r for r in rows if r["id"] == BOW)["status"] == "valid"
    knobs = json.loads(rik("variants", "list", "-t", "knob", "-p", "high", "-f", "json").out)
    assert len(knobs) == 13 * 30 and {r["preset"] for r in knobs} == {"high"}
    ok = rik("variants", "validate", str(built / BOW))
    assert ok.code == 0 and "checked from files" in ok.out and "FAIL" not in ok.out
    assert "loads with mujoco.MjModel.from_xml_path" in ok.out
    png = tmp_path / "chest.png"
    shown = rik("variants", "show", BOW, "--png", str(png), "--width", "160", "--height", "120",
                "--dir", str(built))
    assert shown.code == 0, shown.err
    import numpy as np
    from PIL import Image

    image = Image.open(png)
    colours = np.unique(np.asarray(image).reshape(-1, 3), axis=0)
    assert image.size == (160, 120) and len(colours) > 50  # a picture, not a blank frame
    none = rik("variants", "build", "--out", str(tmp_path / "x"))
    assert none.code == 2 and "name at least one variant id, or pass --all" in none.err


def test_validate_reports_a_damaged_model_file(rik, tmp_path, built: Path) -> None:
    import shutil

    copy = tmp_path / BOW
    shutil.copytree(built / BOW, copy)
    (copy / "model.xml").write_text("<mujoco><worldbody><geom type='nonsense'/></worldbody></mujoco>")
    result = rik("variants", "validate", str(copy))
    assert result.code == 2 and result.err.startswith(f"rik: error: {copy / 'model.xml'}: MuJoCo cannot load it")


def test_test_pull_is_the_documented_multiple_of_the_force_to_open(built: Path) -> None:
    from rik.combinator.checks import MIN_TEST_PULL, PULL_FACTOR

    report = json.loads((built / "door-double-80__knob-mushroom-30__high" / "report.json").read_text())
    for front in report["fronts"]:
        assert front["test_pull_n"] == pytest.approx(max(MIN_TEST_PULL, PULL_FACTOR * front["force_to_open_n"]),
                                                     abs=1e-3)
        # a hinge: the friction torque over the lever arm (the door has no spring and swings horizontally)
        assert front["force_to_open_n"] == pytest.approx(CAT.presets["high"].hinge.frictionloss
                                                         / front["lever_arm_m"], rel=0.05)
        assert 0 < front["seconds_to_open"] < 5 and math.isfinite(front["lever_arm_m"])


def _build_in_a_process(out: str) -> str:
    return build_variant(CAT, parse_variant_id(CAT, BOW), Path(out)).status


def _ready(flags: str) -> None:
    """A pool worker's initializer: this module (rik, MuJoCo) is imported; say so."""
    (Path(flags) / f"ready-{os.getpid()}").touch()


def test_two_processes_building_one_variant_build_it_once(tmp_path: Path) -> None:
    # evaluations side by side share a variants folder: the second waits for the first's build and reuses it
    # (before, both built, and the second replaced the folder under the first one's compiling model)
    import multiprocessing
    import time

    from rik.locks import exclusive

    flags = tmp_path / "ready"
    flags.mkdir()
    with multiprocessing.get_context("spawn").Pool(2, initializer=_ready, initargs=(str(flags),)) as pool:
        deadline = time.monotonic() + 300
        while len(list(flags.iterdir())) < 2:  # both workers past their imports: the sleep below only covers the
            assert time.monotonic() < deadline, "the pool's workers never started"  # way to the lock
            time.sleep(0.1)
        with exclusive(tmp_path / BOW, "test"):  # both processes reach the build while the lock is held here
            pending = pool.map_async(_build_in_a_process, [str(tmp_path)] * 2)
            time.sleep(3)
        statuses = pending.get(timeout=300)
    assert sorted(statuses) == ["built", "skipped"]
    assert is_current(tmp_path / BOW, json.loads((tmp_path / BOW / "report.json").read_text())["spec_hash"])
    assert mujoco.MjModel.from_xml_path(str(tmp_path / BOW / "scene.xml")).nbody > 1
    assert not list(tmp_path.glob("*.lock"))
