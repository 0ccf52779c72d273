"""The assets stage's own machinery: base-unit parts, the content-addressed cache, the fidelity metric against
closed-form answers, and the finger probe, on meshes the tests build themselves."""

from __future__ import annotations

import itertools
import json

import numpy as np
import pytest
import trimesh

from rik.assets.base_units import base_unit_plan
from rik.assets.build import build_asset, build_assets
from rik.assets.cache import AssetCache
from rik.assets.decompose import coacd_params, convex_hull_baseline, decompose
from rik.assets.fidelity import measure, sample_shell
from rik.assets.finger import FINGER_RADIUS, finger_test
from rik.registry.load import load_catalog
from rik.schemas.handles import HandleGeometry


@pytest.fixture(scope="module")
def catalog():
    return load_catalog()


def _box(lo, hi) -> tuple[np.ndarray, np.ndarray]:
    b = trimesh.creation.box(bounds=[lo, hi])
    return np.asarray(b.vertices, float), np.asarray(b.faces, np.int64)


# ---- base units ------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("base_id", [
    "drawer/bedside-45", "drawer/chest-80", "drawer/kitchen-60", "drawer/kitchen-80", "drawer/bench-120",
    "door/base-40-right", "door/base-60-left", "door/wall-40-right", "door/wall-60-left", "door/tall-60-right",
    "door/double-80", "flap/lift-up-60", "flap/drop-down-60"])
def test_base_unit_parts_are_solid_and_do_not_interpenetrate(catalog, base_id):
    unit = catalog.base_units[base_id]
    plans = base_unit_plan(unit)
    assert [p.name for p in plans] == ["carcass", *[f.id for f in unit.fronts]]
    boxes = {}
    for plan in plans:
        for panel in plan.panels:
            c, e = np.array(panel.center), np.array(panel.extents)
            assert (e > 0).all(), (plan.name, panel.name)
            boxes[(plan.name, panel.name)] = (c - e / 2, c + e / 2)
    # no two rigid parts overlap with the fronts closed (touching faces are fine)
    for (a, (alo, ahi)), (b, (blo, bhi)) in itertools.combinations(boxes.items(), 2):
        if a[0] == b[0]:
            continue
        overlap = np.minimum(ahi, bhi) - np.maximum(alo, blo)
        assert (overlap <= 1e-9).any(), f"{a} overlaps {b} by {overlap}"


def test_base_unit_asset_has_exact_collision(catalog):
    asset, result = build_asset(catalog, "drawer/chest-80")
    assert result.status in ("built", "cached")
    assert [p.name for p in asset.parts] == ["carcass", "drawer-1", "drawer-2", "drawer-3"]
    drawer = asset.part("drawer-1")
    assert drawer.method == "exact" and len(drawer.hulls) == 6  # front panel + 5 boards of the box
    assert drawer.visual.is_watertight
    assert result.hulls == sum(len(p.hulls) for p in asset.parts)


# ---- cache -----------------------------------------------------------------------------------------------------
def test_second_build_is_a_cache_hit_and_a_corrupt_entry_is_rebuilt(catalog, tmp_path):
    cache = AssetCache(tmp_path / "assets")
    first = build_assets(catalog, ["door/base-40-right", "flap/lift-up-60"], cache=cache)
    assert [r.status for r in first] == ["built", "built"]
    second = build_assets(catalog, ["door/base-40-right", "flap/lift-up-60"], cache=cache)
    assert [r.status for r in second] == ["cached", "cached"]
    assert [r.key for r in first] == [r.key for r in second]
    payload = cache.path(first[0].key) / "asset.npz"
    payload.write_bytes(payload.read_bytes()[:-20] + b"\0" * 20)
    third = build_assets(catalog, ["door/base-40-right"], cache=cache)
    assert third[0].status == "rebuilt"
    assert "failed its sha256 check" in third[0].note and str(cache.path(first[0].key)) in third[0].note
    assert build_assets(catalog, ["door/base-40-right"], cache=cache)[0].status == "cached"


def test_two_builds_of_one_asset_at_once_decompose_it_once(catalog, tmp_path):
    """A second build of an asset being built waits for the first and loads its entry (a lock per cache key), rather
    than generating and decomposing it again: workers of one build, or two rik runs, on one cache."""
    import threading

    cache, start, results = AssetCache(tmp_path / "assets"), threading.Barrier(2), []

    def build() -> None:
        start.wait()
        results.append(build_asset(catalog, "door/base-40-right", cache=cache)[1])

    threads = [threading.Thread(target=build) for _ in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout=120)
    assert sorted(r.status for r in results) == ["built", "cached"] and results[0].key == results[1].key
    assert sorted(p.name for p in cache.path(results[0].key).parent.iterdir()) == [results[0].key]  # no lock left


def test_an_edited_entry_meta_is_rebuilt(catalog, tmp_path):
    cache = AssetCache(tmp_path / "assets")
    [first] = build_assets(catalog, ["door/base-40-right"], cache=cache)
    meta = cache.path(first.key) / "meta.json"
    data = json.loads(meta.read_text())
    data["parts"][0]["collision_vertices"] += 1000  # valid JSON, payload untouched
    meta.write_text(json.dumps(data))
    [again] = build_assets(catalog, ["door/base-40-right"], cache=cache)
    assert again.status == "rebuilt" and again.collision_vertices == first.collision_vertices
    assert build_assets(catalog, ["door/base-40-right"], cache=cache)[0].status == "cached"


def test_an_edited_fidelity_result_is_measured_again(rik, catalog, tmp_path):
    from rik.assets.build import asset_key

    args = ("assets", "fidelity", "knob/mushroom-30", "--points", "1000", "--workers", "1",
            "--out", str(tmp_path / "fidelity"), "-f", "json")
    first = rik(*args)
    assert first.code == 0, first.err
    true = json.loads(first.out)["handles"][0]["eqp_mean_mm"]
    stored = AssetCache().path(asset_key(catalog, "knob/mushroom-30")) / "fidelity-1000-0.json"
    written = stored.read_bytes()
    data = json.loads(written)
    fid = data.get("data", data)  # the figures, wherever the file keeps them
    fid["q_to_p"]["mean"] = 12.3  # mm: a figure changed, still valid JSON
    stored.write_text(json.dumps(data, indent=1, sort_keys=True))
    shown = json.loads(rik(*args).out)["handles"][0]["eqp_mean_mm"]  # stdout is the JSON alone: the bar is on stderr
    assert shown == true != 12.3
    assert stored.read_bytes() == written  # measured again and rewritten


def test_keys_change_with_the_seed_and_are_stable(catalog):
    from rik.assets.build import asset_key

    a = asset_key(catalog, "knob/mushroom-30")
    assert a == asset_key(catalog, "knob/mushroom-30")
    assert a != asset_key(catalog, "knob/mushroom-30", seed=1)
    assert a != asset_key(catalog, "knob/mushroom-25") if "knob/mushroom-25" in catalog.handles else True


# ---- the fidelity metric on closed-form cases ------------------------------------------------------------------
def test_shell_sampling_drops_points_inside_other_parts():
    hulls = [_box([-1, -1, -1], [1, 1, 1]), _box([0, -0.5, -0.5], [2, 0.5, 0.5])]
    points = sample_shell(hulls, 20_000, seed=0)
    inner = (np.abs(points[:, 0]) < 1 - 1e-6) & (np.abs(points[:, 1]) < 1 - 1e-6) & (np.abs(points[:, 2]) < 1 - 1e-6)
    assert not inner.any()  # no sample of the second box inside the first
    in_second = (points[:, 0] > 1e-6) & (points[:, 0] < 2 - 1e-6) & (np.abs(points[:, 1]) < 0.5 - 1e-6) & (
        np.abs(points[:, 2]) < 0.5 - 1e-6)
    assert not in_second.any()


def test_an_offset_box_deviates_by_its_offset():
    """A collision box 1 mm larger on every side than a 100 mm visual cube: both directions are 1 mm, except
    near edges and corners (sqrt(2) mm, sqrt(3) mm), which are a small share of the surface."""
    visual = trimesh.creation.box(extents=[0.1, 0.1, 0.1])
    grown = [_box([-0.051] * 3, [0.051] * 3)]
    fid, _ = measure(visual, grown, convex_hull_baseline(visual), points=20_000, seed=0)
    # distances are to the nearest of 200k reference samples (0.55 mm apart on this cube): a little above 1 mm
    assert 0.99 < fid.q_to_p.mean < 1.07
    assert 0.99 < fid.p_to_q.mean < 1.07
    assert np.sqrt(3) - 0.05 < fid.q_to_p.max < np.sqrt(3) + 0.3  # a corner, plus the sample spacing
    assert fid.baseline_q_to_p.mean < 0.3  # a cube is its own hull: only the sampling floor (half a spacing)


def _bar_pull() -> tuple[trimesh.Trimesh, HandleGeometry]:
    """A 128 mm bar pull built here, independent of rik's generators."""
    r, length, spacing, proj = 0.006, 0.168, 0.128, 0.035
    bar = trimesh.creation.cylinder(radius=r, height=length, sections=64)
    bar.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, [0, 1, 0]))
    bar.apply_translation([0, 0, proj - r])
    legs = []
    for x in (-spacing / 2, spacing / 2):
        leg = trimesh.creation.cylinder(radius=r, height=proj - r, sections=64)
        leg.apply_translation([x, 0, (proj - r) / 2])
        legs.append(leg)
    mesh = trimesh.boolean.union([bar, *legs], engine="manifold")
    geometry = HandleGeometry(length=length, width=2 * r, projection=proj, grip_diameter=2 * r,
                              hole_spacing=spacing, clearance={"depth": proj - 2 * r, "width": spacing - 2 * r})
    return mesh, geometry


@pytest.fixture(scope="module")
def bar():
    mesh, geometry = _bar_pull()
    return mesh, geometry, decompose(mesh, coacd_params("two_point"))


def test_coacd_of_a_bar_pull_keeps_the_loop_and_the_hull_fills_it(bar):
    mesh, geometry, hulls = bar
    fid, _ = measure(mesh, hulls, convex_hull_baseline(mesh), points=10_000, seed=0)
    assert len(hulls) >= 3  # at least the bar and two legs
    assert fid.q_to_p.mean < 1.0
    assert fid.baseline_q_to_p.mean > 5 * fid.q_to_p.mean


def test_decomposition_is_deterministic(bar):
    mesh, _, hulls = bar
    again = decompose(mesh, coacd_params("two_point"))
    assert len(again) == len(hulls)
    for (v1, f1), (v2, f2) in zip(hulls, again, strict=True):
        assert np.array_equal(v1, v2) and np.array_equal(f1, f2)


def test_finger_passes_the_coacd_loop_and_is_blocked_by_the_hull(bar):
    mesh, geometry, hulls = bar
    free = finger_test(hulls, geometry)
    blocked = finger_test(convex_hull_baseline(mesh), geometry)
    assert free.passes and free.min_distance > 0
    assert not blocked.passes
    # the probe sits at half the clearance: its gap to the bar is (depth - 2 r) / 2 where the bar is exact
    assert free.min_distance <= (geometry.clearance.depth - 2 * FINGER_RADIUS) / 2 + 1e-4


def test_worker_processes_build_the_same_assets(catalog, tmp_path):
    ids = ["door/double-80", "flap/drop-down-60"]
    alone = build_assets(catalog, ids, cache=AssetCache(tmp_path / "one"))
    pooled = build_assets(catalog, ids, workers=2, cache=AssetCache(tmp_path / "two"))
    assert [r.status for r in pooled] == ["built", "built"]
    assert [(r.id, r.key, r.hulls, r.collision_vertices) for r in pooled] == \
        [(r.id, r.key, r.hulls, r.collision_vertices) for r in alone]


def test_distances_to_samples_are_the_exact_nearest_ones() -> None:
    """The metric's nearest-sample distances (a k-d tree split at sliding midpoints) are the brute-force minimum,
    also for points far from every sample, for duplicate samples, and for a single sample."""
    from rik.assets.fidelity import distance_to_samples

    rng = np.random.default_rng(7)
    samples = rng.normal(size=(3000, 3)) * [0.02, 0.005, 0.04]
    samples = np.vstack([samples, samples[:50]])  # duplicates
    points = np.vstack([rng.normal(size=(400, 3)) * 0.03, rng.normal(size=(100, 3)) + 5.0])  # near, and far away
    brute = np.sqrt(((points[:, None, :] - samples[None, :, :]) ** 2).sum(axis=2)).min(axis=1)
    np.testing.assert_allclose(distance_to_samples(points, samples), brute, rtol=1e-12, atol=0)
    one = samples[:1]
    np.testing.assert_allclose(distance_to_samples(points, one), np.linalg.norm(points - one, axis=1), rtol=1e-12,
                               atol=0)
