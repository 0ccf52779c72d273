"""The teleop station's view model (rik.teleop.view_model): an arm's visual meshes decimated to a triangle budget for
the station's cameras only, cached content-addressed, deterministic; the physics model, the recorded episode and
its replay unchanged; what the station draws close to the full model."""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pytest
from shared import BOW, builtin_catalog

from rik.sim.build import build_scene
from rik.teleop.view_model import TRIANGLE_BUDGET, ViewModel, decimate, mesh_key, visible_faces

CAT = builtin_catalog()


@pytest.fixture(scope="module")
def variants(bow_variants: Path) -> Path:
    return bow_variants  # the demo variant, built once per test process (conftest)


def _sphere_corners() -> tuple[np.ndarray, np.ndarray]:
    """A unit icosphere of 5,120 faces stored as a flat-shaded OBJ stores it: each face's corners apart."""
    import trimesh

    s = trimesh.creation.icosphere(4)
    vert = s.vertices[s.faces].reshape(-1, 3)
    return vert, np.arange(len(vert)).reshape(-1, 3)


def _entry(cache: Path) -> Path:
    (path,) = cache.rglob("*.npy")
    return path


def test_a_mesh_is_decimated_to_its_target_the_same_bytes_twice_and_made_once(tmp_path: Path) -> None:
    """5,120 faces to at most 500: the surface stays on the sphere within 1 %; two caches hold the same bytes; a
    second call reads the cache (a different mesh put in the entry comes back); a damaged entry is made again."""
    vert, face = _sphere_corners()
    v, f = decimate(vert, face, 500, tmp_path / "a")
    assert 400 < len(f) <= 500 and f.min() >= 0 and f.max() == len(v) - 1
    radius = np.linalg.norm(v, axis=1)
    assert radius.min() > 0.99 and radius.max() < 1.01
    v2, f2 = decimate(vert, face, 500, tmp_path / "b")
    assert np.array_equal(v, v2) and np.array_equal(f, f2)
    a, b = _entry(tmp_path / "a"), _entry(tmp_path / "b")
    assert a.name == f"{mesh_key(vert, face, 500)}.npy" and a.read_bytes() == b.read_bytes()

    other = (np.eye(3), np.array([[0, 1, 2]], np.int32))  # a hit returns what the entry holds
    with a.open("wb") as fh:
        np.save(fh, other[0])
        np.save(fh, other[1])
    hit = decimate(vert, face, 500, tmp_path / "a")
    assert np.array_equal(hit[0], other[0]) and np.array_equal(hit[1], other[1])

    a.write_bytes(b"not a mesh")  # damaged: made again, and stored again
    again = decimate(vert, face, 500, tmp_path / "a")
    assert np.array_equal(again[1], f) and a.read_bytes() == b.read_bytes()


def test_disjoint_triangles_the_collapse_cannot_merge_still_meet_the_target(tmp_path: Path) -> None:
    """2,000 separate small triangles (nothing to collapse along): brought to at most 300 faces all the same."""
    corners = np.random.default_rng(0).uniform(0.0, 1.0, (2000, 3))
    vert = np.stack([corners, corners + [0.01, 0, 0], corners + [0, 0.01, 0]], axis=1).reshape(-1, 3)
    v, f = decimate(vert, np.arange(len(vert)).reshape(-1, 3), 300, tmp_path)
    assert 0 < len(f) <= 300 and f.max() < len(v)


def test_the_hand_e_scene_is_drawn_as_it_is(variants: Path) -> None:
    """Within budget (about 6,000 visible mesh faces): the view model is the physics model itself."""
    scene = build_scene(variants / BOW)
    view = ViewModel.of(scene)
    assert visible_faces(scene.model) < TRIANGLE_BUDGET and view.model is scene.model and not view.decimated
    assert view.sync(scene.data) is scene.data


def test_a_scene_whose_spec_does_not_match_is_drawn_in_full(variants: Path) -> None:
    """A view model that cannot be made (here: the SO-100's scene given another scene's spec) falls back to the full
    model: the station draws it, slower, rather than stopping."""
    scene = build_scene(variants / BOW, robot=CAT.robot("so100"))
    scene.spec = build_scene(variants / BOW).spec
    view = ViewModel.of(scene)
    assert view.model is scene.model and not view.decimated


@pytest.mark.slow
def test_the_panda_is_drawn_within_budget_where_it_is_and_its_physics_and_episode_do_not_change(
        variants: Path, tmp_path: Path) -> None:
    """The Panda with the 2F-85 (about 204,000 visible mesh faces) drawn with at most the budget; the physics model
    keeps every face; after steps of a held input, the view's bodies, sites, cameras and every geom that is not a
    decimated mesh are where the physics puts them, and each decimated geom's world bounding box is within 1.5 cm of
    the full mesh's; the follow view's picture differs from the full model's by under 2 grey levels on average. An
    episode recorded while the station's frames render between steps holds the same states as one recorded without
    rendering, and replays exactly. A second view model is made from the cache (no new entry)."""
    import mujoco

    from rik.episodes.replay import verify_episode
    from rik.teleop.frames import StationFrames
    from rik.teleop.session import TeleopSession

    scene = build_scene(variants / BOW, robot=CAT.robot("panda-2f85"))
    full = visible_faces(scene.model)
    view = ViewModel.of(scene, cache=tmp_path / "cache")
    assert view.decimated and full > 150_000 and visible_faces(view.model) <= TRIANGLE_BUDGET
    assert visible_faces(scene.model) == full
    entries = sorted((tmp_path / "cache").rglob("*.npy"))
    again = ViewModel.of(scene, cache=tmp_path / "cache")
    assert sorted((tmp_path / "cache").rglob("*.npy")) == entries
    assert np.array_equal(again.model.mesh_vert, view.model.mesh_vert)

    def record(render: bool) -> tuple[TeleopSession, list[np.ndarray]]:
        session = TeleopSession(scene, tmp_path / ("rendered" if render else "plain"))
        frames = StationFrames(scene) if render else None
        session.set_input([0.3, -0.5, 0.2, 0.0, 0.4, 0.6])
        for _ in range(25):
            assert session.tick()
            if frames is not None:
                for cam in ("front", "wrist"):
                    frames.render(scene.data, cam, (320, 240))
        if frames is not None:
            frames.close()
        return session, [s.copy() for s in session.recorder.rows["state"]]

    plain, plain_states = record(False)
    rendered, states = record(True)
    assert len(states) == 25 and all(np.array_equal(a, b) for a, b in zip(states, plain_states, strict=True))
    before = scene.state()
    d = view.sync(scene.data)
    assert np.array_equal(scene.state(), before)  # the physics state is only read
    m = scene.model
    ref = copy.copy(scene.data)  # the physics model's kinematics at the same positions (mj_step leaves them one
    mujoco.mj_forward(m, ref)  # physics step behind, computed before it integrates)
    assert np.allclose(d.xpos, ref.xpos) and np.allclose(d.site_xpos, ref.site_xpos)
    assert np.allclose(d.cam_xpos, ref.cam_xpos) and np.allclose(d.cam_xmat, ref.cam_xmat)
    meshes = m.geom_type == mujoco.mjtGeom.mjGEOM_MESH
    changed = meshes & (m.mesh_facenum[m.geom_dataid] != view.model.mesh_facenum[view.model.geom_dataid])
    assert changed.sum() > 20
    assert np.allclose(d.geom_xpos[~changed], ref.geom_xpos[~changed])

    def box(model: mujoco.MjModel, data: mujoco.MjData, g: int) -> np.ndarray:
        mesh = int(model.geom_dataid[g])
        v = model.mesh_vert[model.mesh_vertadr[mesh]:model.mesh_vertadr[mesh] + model.mesh_vertnum[mesh]]
        world = data.geom_xpos[g] + v @ data.geom_xmat[g].reshape(3, 3).T
        return np.concatenate([world.min(axis=0), world.max(axis=0)])

    worst = max(float(np.abs(box(m, ref, g) - box(view.model, d, g)).max()) for g in np.flatnonzero(changed))
    assert worst < 0.015, worst
    detailed, decimated = StationFrames(scene, budget=10**9), StationFrames(scene)
    a, b = (f.render(scene.data, "front", (320, 240)) for f in (detailed, decimated))
    detailed.close()
    decimated.close()
    assert not detailed.view.decimated and np.abs(a.astype(int) - b).mean() < 2.0

    saved = rendered.save()
    assert saved is not None
    assert verify_episode(CAT, saved.path, variants).exact
    print(f"\nPanda: {full:,} visible mesh faces drawn as {visible_faces(view.model):,}; worst bounding box "
          f"{1e3 * worst:.1f} mm; picture {np.abs(a.astype(int) - b).mean():.2f} grey levels apart")


def test_anti_aliasing_is_kept_where_renders_are_fast_and_a_station_without_it_changes_only_its_own_copy(
        variants: Path) -> None:
    """The decision from the trial renders' median (an outlier, such as the first render, does not decide it); a
    station's frames without anti-aliasing render from a copy whose offscreen buffer has no multisampling, the
    scene's model keeps its 4 samples, and the picture differs only at edges."""
    from rik.teleop.frames import ANTIALIAS_BUDGET, StationFrames, keep_antialiasing

    assert keep_antialiasing([ANTIALIAS_BUDGET / 2] * 11 + [1.0] * 9)
    assert not keep_antialiasing([ANTIALIAS_BUDGET * 2] * 20)
    scene = build_scene(variants / BOW)
    plain, smooth = StationFrames(scene, antialias=False), StationFrames(scene, antialias=True)
    a, b = (f.render(scene.data, "front", (320, 240)) for f in (plain, smooth))
    assert plain.renderer((320, 240)).model.vis.quality.offsamples == 0
    assert smooth.renderer((320, 240)).model is scene.model and scene.model.vis.quality.offsamples == 4
    plain.close()
    smooth.close()
    assert a.std() > 10 and 0 < np.abs(a.astype(int) - b).mean() < 3
