"""Collision modes of variant builds: a handle colliding as its CoACD hulls (``coacd``) or as its single convex
hull (``hull``, the fidelity ablation's baseline); folders keep their mode, and episodes say theirs."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
from shared import builtin_catalog

from rik.combinator.build import build_variants, ensure_variant, spec_hash
from rik.errors import RikError
from rik.registry.ids import parse_variant_id

pytestmark = pytest.mark.slow  # end-to-end runs: out of the everyday tier (-m "not slow")

CAT = builtin_catalog()
BOW = "drawer-bedside-45__two_point-bow-128__normal"
"""One front with a bow handle: concave, so CoACD splits it into several hulls."""


@pytest.fixture(scope="module")
def folders(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    root = tmp_path_factory.mktemp("collision")
    key = parse_variant_id(CAT, BOW)
    for mode in ("coacd", "hull"):
        [result] = build_variants(CAT, [key], root / mode, collision=mode)
        assert result.status == "built", result
    return {"coacd": root / "coacd", "hull": root / "hull"}


def _handle_collision_geoms(directory: Path) -> dict[str, int]:
    """Front id -> number of collision geoms on its handle body, from the written model."""
    import mujoco

    model = mujoco.MjModel.from_xml_path(str(directory / "model.xml"))
    counts: dict[str, int] = {}
    for g in range(model.ngeom):
        body = model.body(model.geom_bodyid[g]).name
        if body.endswith("/handle") and model.geom_contype[g]:
            counts[body] = counts.get(body, 0) + 1
    return counts


def test_hull_build_collides_each_handle_as_one_convex_hull(folders: dict[str, Path]) -> None:
    hull, coacd = _handle_collision_geoms(folders["hull"] / BOW), _handle_collision_geoms(folders["coacd"] / BOW)
    assert hull == {"drawer/handle": 1}
    assert coacd["drawer/handle"] > 1  # the bow is concave
    for mode, folder in folders.items():
        report = json.loads((folder / BOW / "report.json").read_text(encoding="utf-8"))
        assert report["collision"] == mode and report["status"] == "valid"
        assert json.loads((folder / "collision.json").read_text(encoding="utf-8")) == {"collision": mode}
        assert f'"collision":"{mode}"' in (folder / BOW / "model.xml").read_text(encoding="utf-8")
    key = parse_variant_id(CAT, BOW)
    assert spec_hash(CAT, key, "hull") != spec_hash(CAT, key, "coacd") == spec_hash(CAT, key)
    digests = {json.loads((f / BOW / "report.json").read_text(encoding="utf-8"))["spec_hash"]
               for f in folders.values()}
    assert len(digests) == 2


def test_a_folder_rebuilds_its_variants_with_its_own_mode(folders: dict[str, Path], tmp_path: Path) -> None:
    folder = tmp_path / "variants-hull"
    shutil.copytree(folders["hull"], folder)
    shutil.rmtree(folder / BOW)  # missing: ensure_variant builds it again, with the folder's mode
    directory = ensure_variant(CAT, BOW, folder)
    assert json.loads((directory / "report.json").read_text(encoding="utf-8"))["collision"] == "hull"
    assert _handle_collision_geoms(directory) == {"drawer/handle": 1}
    (folder / "collision.json").write_text('{"collision": "convex"}', encoding="utf-8")
    with pytest.raises(RikError, match=r"collision.json: field collision 'convex': not a collision mode; valid "
                                       r"modes are coacd, hull$"):
        ensure_variant(CAT, BOW, folder)


def test_record_and_replay_in_a_hull_folder(rik, folders: dict[str, Path], tmp_path: Path) -> None:
    folder = tmp_path / "variants-hull"
    r = rik("variants", "build", BOW, "--collision", "hull", "--out", str(folder))
    assert r.code == 0, r.err
    assert "handle collision: hull" in r.out
    report = (folder / BOW / "report.json").read_text(encoding="utf-8")
    r = rik("record", BOW, "--strategy", "grasp_vertical", "--variants", str(folder), "--out", str(tmp_path / "ep"))
    assert r.code == 0, r.err
    assert (folder / BOW / "report.json").read_text(encoding="utf-8") == report  # used as found, not rebuilt
    [episode] = [d for d in (tmp_path / "ep").iterdir() if (d / "meta.json").is_file()]
    assert json.loads((episode / "meta.json").read_text(encoding="utf-8"))["collision"] == "hull"
    r = rik("replay", str(episode), "--variants", str(folder))
    assert r.code == 0 and "exact" in r.out, r.out + r.err
    r = rik("replay", str(episode), "--variants", str(folders["coacd"]))
    assert r.code == 2 and "field 'collision': hull, but" in r.err and "holds coacd collision variants" in r.err


def test_bad_collision_modes_are_named(rik, folders: dict[str, Path], tmp_path: Path) -> None:
    r = rik("variants", "build", BOW, "--collision", "nope", "--out", str(tmp_path / "v"))
    assert r.code == 2
    assert "rik: error: --collision 'nope': not a collision mode; valid modes are coacd, hull" in r.err
    assert len(r.err.strip().splitlines()) == 1 and not (tmp_path / "v").exists()
    r = rik("variants", "build", BOW, "--collision", "coacd", "--out", str(folders["hull"]))
    assert r.code == 2
    assert f"{folders['hull']}: this folder holds hull collision variants, not coacd (its collision.json); build " \
           "--collision coacd variants into another --out folder" in r.err
    legacy = tmp_path / "variants"  # built before collision modes: variants, no collision.json
    shutil.copytree(folders["coacd"], legacy)
    (legacy / "collision.json").unlink()
    r = rik("variants", "build", BOW, "--collision", "hull", "--out", str(legacy))
    assert r.code == 2 and "this folder holds coacd collision variants, not hull" in r.err


def test_record_split_skips_variants_rejected_in_a_hull_folder(rik, tmp_path: Path) -> None:
    """A finger pull's single convex hull fills the gap behind its lip and sinks into the front: in a hull folder its
    variant fails the seating check, and ``rik record --split`` records the other seeds and lists the skipped ones."""
    hull = tmp_path / "hull"
    res = rik("variants", "build", "drawer-bedside-45__finger_pull-cup-64__smooth", "--collision", "hull", "--out",
              str(hull))
    assert res.code == 0, res.err
    res = rik("record", "--split", "train", "--types", "finger_pull", "--presets", "smooth", "--seed", "0",
              "--episodes", "3", "-s", "contact_rich", "--out", str(tmp_path / "eps"), "--variants", str(hull))
    assert res.code == 0, res.err
    assert "seed 0 skipped: variant drawer-bench-120__finger_pull-side-edge-150__smooth cannot be simulated: check " \
           "handle_seated failed" in " ".join(res.out.split())
    assert "__s0002: " in res.out and "__s0000: " not in res.out
    assert sorted(p.name.rsplit("__", 1)[1] for p in (tmp_path / "eps").iterdir()) == ["s0002"]


def _plans(directory: Path, strategy: str) -> list[tuple[str, tuple[float, ...], tuple[float, ...]]]:
    from rik.episodes.operators import STRATEGIES
    from rik.sim.build import build_scene

    scene = build_scene(directory)
    return [(p.mode, tuple(p.tcp.round(9)), tuple(p.angles.round(9))) for p in STRATEGIES[strategy].make().planner(scene)]


def test_the_planned_strategy_grasps_the_same_under_hull_and_coacd_collision(folders: dict[str, Path]) -> None:
    """The fidelity ablation's demonstrator plans on the catalog's visual mesh: the same grasps, in the same order,
    whichever collision model the simulator has; contact_rich, which ray casts the collision model, does not."""
    planned = {mode: _plans(folders[mode] / BOW, "planned") for mode in ("coacd", "hull")}
    assert planned["coacd"] and planned["coacd"] == planned["hull"]
    assert planned["coacd"][0][0].startswith("hook")  # the loop of the bow is found on the visual mesh
    rich = {mode: _plans(folders[mode] / BOW, "contact_rich") for mode in ("coacd", "hull")}
    assert rich["coacd"] != rich["hull"]


def test_planned_above_hooks_from_above_first_and_is_as_blind_to_collision(folders: dict[str, Path]) -> None:
    """planned_above keeps planned's plans but puts the hooks from above first (planned ranks hooks by bite, so a
    handle is hooked from above in one drawer and from below in another); it plans on the visual mesh too."""
    from rik.sim.build import build_scene
    from rik.sim.grasp import hook_plans

    above = {mode: _plans(folders[mode] / BOW, "planned_above") for mode in ("coacd", "hull")}
    assert above["coacd"] and above["coacd"] == above["hull"]
    hooks = [m for m, _, _ in above["coacd"] if m.startswith("hook")]
    assert hooks and hooks == sorted(hooks, key=lambda m: m != "hook_above")  # every above hook before any below
    scene = build_scene(folders["coacd"] / BOW)
    every = hook_plans(scene, limit=50, geometry="visual")
    preferred = hook_plans(scene, limit=50, geometry="visual", prefer="below")
    assert {p.key for p in every} == {p.key for p in preferred} and {p.mode for p in every} == {"hook_above",
                                                                                                "hook_below"}
    assert [p.key for p in preferred if p.mode == "hook_below"] == [p.key for p in every if p.mode == "hook_below"]
    assert preferred[0].mode == "hook_below"


def test_planned_typed_takes_one_hook_side_per_handle_type(folders: dict[str, Path]) -> None:
    """planned_typed puts the hooks of its type's side first (a two-point handle: from above, as planned_above does),
    and plans on the visual mesh too; knobs keep planned's ranking by bite."""
    from rik.episodes.operators import TYPED_HOOK_SIDES

    assert TYPED_HOOK_SIDES == {"two_point": "above", "finger_pull": "below"}
    typed = {mode: _plans(folders[mode] / BOW, "planned_typed") for mode in ("coacd", "hull")}
    assert typed["coacd"] and typed["coacd"] == typed["hull"]
    planned = [m for m, _, _ in _plans(folders["coacd"] / BOW, "planned") if m.startswith("hook")]
    assert [m for m, _, _ in typed["coacd"] if m.startswith("hook")] == ["hook_above"] * 2 != planned  # planned: a
    # hook from below among its two
    assert typed["coacd"] == _plans(folders["coacd"] / BOW, "planned_above")  # the bow is a two-point handle
