"""Rendering: the MuJoCo stream and the Mitsuba re-render of recorded episodes (every camera, resumable, the
same on a second run), the geometric alignment of the two, the choice of Mitsuba variant and the messages."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest
from shared import BOW, builtin_catalog

from rik.episodes.episode import read_episode, states, write_meta
from rik.episodes.record import record
from rik.episodes.replay import episode_scene
from rik.errors import RikError
from rik.render.align import iou, mitsuba_silhouette, mujoco_silhouette
from rik.render.backend import available_variants, use_variant
from rik.render.episodes import render_episode
from rik.render.streams import StreamSpec, parse_resolution, read_frame

pytestmark = pytest.mark.slow  # end-to-end runs: out of the everyday tier (-m "not slow")

CAT = builtin_catalog()
CAMERAS = ("front", "wrist")


@pytest.fixture(scope="module")
def variants(bow_variants: Path) -> Path:
    return bow_variants  # the demo variant, built once per test process (conftest)


@pytest.fixture(scope="module")
def episode(variants: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("episodes")
    meta = record(CAT, BOW, "contact_rich", out=out, variants=variants, max_seconds=0.4)[0]
    return out / meta.id


def _frames(directory: Path) -> dict[str, bytes]:
    return {str(p.relative_to(directory)): p.read_bytes() for p in sorted(directory.rglob("*.png"))}


def test_sim_stream_has_every_camera_and_state_and_matches_a_live_render(episode: Path, variants: Path,
                                                                           tmp_path: Path) -> None:
    import mujoco

    spec = StreamSpec("sim", 48, 32)
    result = render_episode(CAT, episode, spec, renders=tmp_path, variants=variants)
    meta, table = read_episode(episode)
    assert result.frames == len(table) and result.rendered == len(table)
    assert set(result.cameras) == set(CAMERAS)
    for cam in CAMERAS:
        assert len(list((result.directory / cam).glob("*.png"))) == len(table)
    manifest = json.loads((result.directory / "stream.json").read_text())
    assert manifest["states_sha256"] == meta.states_sha256 and manifest["width"] == 48
    # the settings it was drawn with, in its key and its manifest: a 512 px shadow map for a 48 px image
    assert manifest["render_settings"] == {"shadow_size": 512, "multisamples": 4}
    assert result.directory.name == manifest["key"] == "sim-48x32-shadow512-msaa4"
    # Frame k is the recorded state k, seen by that camera with those settings.
    scene = episode_scene(CAT, episode, variants, meta)
    assert scene.model.vis.quality.shadowsize == 2048  # the scene's own
    k = len(table) - 1
    scene.restore(states(table)[k])
    scene.model.vis.quality.shadowsize = 512
    with mujoco.Renderer(scene.model, 32, 48) as r:
        r.update_scene(scene.data, camera="wrist")
        live = r.render()
    np.testing.assert_array_equal(read_frame(result.directory, "wrist", k), live)
    again = render_episode(CAT, episode, spec, renders=tmp_path, variants=variants)
    assert again.rendered == 0  # finished streams are not redone


def test_interrupted_render_resumes_to_the_same_frames(episode: Path, variants: Path, tmp_path: Path) -> None:
    spec = StreamSpec("sim", 40, 30)
    whole = render_episode(CAT, episode, spec, renders=tmp_path / "a", variants=variants)

    class Stop(Exception):
        pass

    done = []

    def interrupt(n: int) -> None:
        done.append(n)
        if len(done) == 3:
            raise Stop

    with pytest.raises(Stop):
        render_episode(CAT, episode, spec, renders=tmp_path / "b", variants=variants, progress=interrupt)
    final = tmp_path / "b" / whole.episode / spec.key
    assert not final.exists()  # nothing that looks finished
    resumed = render_episode(CAT, episode, spec, renders=tmp_path / "b", variants=variants)
    assert 0 < resumed.rendered < whole.frames
    assert _frames(final) == _frames(whole.directory)
    assert not list((tmp_path / "b" / whole.episode).glob(".*partial"))


@pytest.mark.parametrize("variant", [v for v in ("llvm_ad_rgb", "scalar_rgb") if v in available_variants()])
def test_rerender_writes_every_camera_denoised(episode: Path, variants: Path, tmp_path: Path, variant: str) -> None:
    spec = StreamSpec("rerendered", 32, 24, spp=2, denoise=True, variant=variant)
    result = render_episode(CAT, episode, spec, renders=tmp_path, variants=variants)
    manifest = json.loads((result.directory / "stream.json").read_text())
    assert manifest["mitsuba_variant"] == variant and manifest["frames"] == result.frames
    for cam in CAMERAS:
        frames = sorted((result.directory / cam).glob("*.png"))
        assert len(frames) == result.frames
        img = read_frame(result.directory, cam, 0)
        assert img.shape == (24, 32, 3) and img.dtype == np.uint8
        assert 10 < img.mean() < 250 and img.std() > 5  # lit, not blank, not saturated


def test_a_second_episode_of_the_variant_reuses_the_renderer_and_renders_the_same_frames(
        episode: Path, variants: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Streams of one variant's episodes share one renderer per process (its traced kernels are replayed, not
    traced again), and the frames are the ones a renderer of its own gives, byte for byte."""
    import rik.render.renderers as renderers

    second = record(CAT, BOW, "contact_rich", seed=1, out=tmp_path / "episodes", variants=variants,
                    max_seconds=0.2)[0]
    second_dir = tmp_path / "episodes" / second.id
    made: list[str] = []
    make = renderers.make_renderer
    monkeypatch.setattr(renderers, "make_renderer", lambda *a: made.append(a[3].kind) or make(*a))
    renderers.drop_renderers()
    spec = StreamSpec("rerendered", 32, 24, spp=2, denoise=True, variant="llvm_ad_rgb")
    render_episode(CAT, episode, spec, renders=tmp_path / "one", variants=variants)
    reused = render_episode(CAT, second_dir, spec, renders=tmp_path / "one", variants=variants)
    assert made == ["rerendered"]
    manifest = json.loads((reused.directory / "stream.json").read_text())
    assert 0 < manifest["render_seconds"] and manifest["frames"] == reused.frames == len(read_episode(second_dir)[1])
    renderers.drop_renderers()
    fresh = render_episode(CAT, second_dir, spec, renders=tmp_path / "two", variants=variants)
    assert made == ["rerendered", "rerendered"]
    assert _frames(fresh.directory) == _frames(reused.directory)
    renderers.drop_renderers()


def test_denoising_brings_a_noisy_render_closer_to_a_converged_one(episode: Path, variants: Path) -> None:
    from rik.render.renderers import MitsubaFrames

    meta, table = read_episode(episode)
    scene = episode_scene(CAT, episode, variants, meta)
    scene.restore(states(table)[0])

    def front(spp: int, denoise: bool, seed: int = 1) -> np.ndarray:
        spec = StreamSpec("rerendered", 48, 36, spp=spp, denoise=denoise)
        return MitsubaFrames(scene.model, scene.data, ["front"], spec, CAT.finishes).render_linear(scene.data,
                                                                                                  seed)["front"]

    reference = front(256, False, seed=7)
    noisy, clean = front(4, False), front(4, True)
    err_noisy = float(np.mean((np.clip(noisy, 0, 1) - np.clip(reference, 0, 1)) ** 2))
    err_clean = float(np.mean((np.clip(clean, 0, 1) - np.clip(reference, 0, 1)) ** 2))
    assert err_clean < 0.5 * err_noisy


def test_each_camera_renders_its_own_view(episode: Path, variants: Path) -> None:
    from rik.render.renderers import MitsubaFrames

    meta, table = read_episode(episode)
    scene = episode_scene(CAT, episode, variants, meta)
    scene.restore(states(table)[-1])
    spec = StreamSpec("rerendered", 24, 16, spp=2, denoise=False)
    both = MitsubaFrames(scene.model, scene.data, list(CAMERAS), spec, CAT.finishes).render_linear(scene.data, 3)
    for cam in CAMERAS:
        alone = MitsubaFrames(scene.model, scene.data, [cam], spec, CAT.finishes).render_linear(scene.data, 3)[cam]
        np.testing.assert_array_equal(both[cam], alone)
    assert not np.array_equal(both["front"], both["wrist"])


@pytest.mark.parametrize("variant", [v for v in ("llvm_ad_rgb", "scalar_rgb") if v in available_variants()])
def test_rerender_silhouettes_align_with_mujoco(episode: Path, variants: Path, variant: str) -> None:
    meta, table = read_episode(episode)
    scene = episode_scene(CAT, episode, variants, meta)
    recorded = states(table)
    for k in (0, len(recorded) - 1):
        scene.restore(recorded[k])
        for cam in CAMERAS:
            mj = mujoco_silhouette(scene.model, scene.data, cam, 96, 72)
            mi = mitsuba_silhouette(scene.model, scene.data, cam, 96, 72, CAT.finishes, variant)
            assert 0.05 < mj.mean() < 0.95  # the masks hold an object and some background
            assert iou(mj, mi) >= 0.95, (k, cam)


def test_silhouette_check_detects_a_misaligned_camera(episode: Path, variants: Path) -> None:
    meta, table = read_episode(episode)
    scene = episode_scene(CAT, episode, variants, meta)
    scene.restore(states(table)[0])
    mi = mitsuba_silhouette(scene.model, scene.data, "front", 96, 72, CAT.finishes)
    scene.model.cam_fovy[0] *= 1.15  # MuJoCo's camera zooms out; the re-render's stays
    mj = mujoco_silhouette(scene.model, scene.data, "front", 96, 72)
    assert iou(mj, mi) < 0.95


def test_rerender_cli_and_its_messages(rik, episode: Path, variants: Path, tmp_path: Path) -> None:
    ok = rik("rerender", str(episode), "--res", "24x16", "--spp", "1", "--no-denoise", "--cameras", "front",
             "--out", str(tmp_path), "--variants", str(variants))
    assert ok.code == 0, ok.err
    assert "rerendered-24x16-1spp-raw" in ok.out and "front" in ok.out
    assert len(list(tmp_path.rglob("front/*.png"))) > 0 and not list(tmp_path.rglob("wrist"))

    bad = rik("rerender", str(episode), "--variant", "cuda_rgb", "--out", str(tmp_path))
    assert bad.code == 2
    assert bad.err.strip() == ("rik: error: renderer variant 'cuda_rgb' is not supported; use one of: auto, "
                               "cuda_ad_rgb, llvm_ad_rgb, scalar_rgb")
    cam = rik("render", str(episode), "--cameras", "top", "--out", str(tmp_path), "--variants", str(variants))
    assert cam.code == 2
    assert cam.err.strip() == f"rik: error: {episode}: no camera 'top' in the scene (cameras: front, wrist)"
    res = rik("render", str(episode), "--res", "0x5", "--out", str(tmp_path))
    assert res.code == 2
    assert res.err.strip() == "rik: error: --res 0x5: give a size like 256 or 320x240, 8 to 4096 pixels a side"
    missing = rik("render", str(tmp_path / "nope"), "--out", str(tmp_path))
    assert missing.code == 2 and "nope: no such episode or directory" in missing.err
    assert "Traceback" not in bad.err + cam.err + res.err + missing.err


def test_unavailable_llvm_is_a_clear_error(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.setenv("DRJIT_LIBLLVM_PATH", str(tmp_path / "libLLVM-19.so"))
    assert "llvm_ad_rgb" not in available_variants()
    with pytest.raises(RikError, match=r"^renderer variant 'llvm_ad_rgb' is not available here: no libLLVM 16 or "
                                       r"newer found \(install Debian's libllvm19, or set DRJIT_LIBLLVM_PATH\); "
                                       r"available: .*scalar_rgb$"):
        use_variant("llvm_ad_rgb")


def test_episode_whose_variant_files_are_missing_is_rebuilt_first(episode: Path, variants: Path,
                                                                  tmp_path: Path) -> None:
    meta = json.loads((episode / "meta.json").read_text())
    model = variants / meta["variant"] / "model.xml"
    model.unlink()
    result = render_episode(CAT, episode, StreamSpec("sim", 16, 16), renders=tmp_path, variants=variants)
    assert model.is_file() and result.rendered == result.frames


def test_episode_whose_variant_cannot_be_rebuilt(episode: Path, tmp_path: Path) -> None:
    copy = shutil.copytree(episode, tmp_path / "ep")
    meta = json.loads((copy / "meta.json").read_text())
    meta["variant"] = meta["variant"].replace("bow-128", "bow-999")
    write_meta(copy, meta)  # recorded on a variant of a catalog that is no longer there: sealed, but unknown
    with pytest.raises(RikError) as err:
        render_episode(CAT, copy, StreamSpec("sim", 32, 24), renders=tmp_path / "r", variants=tmp_path / "v")
    msg = str(err.value)
    assert msg.startswith(f"{copy / 'meta.json'}: field 'variant': cannot load {meta['variant']} from {tmp_path / 'v'} "
                          "or rebuild it from the catalog: ")
    assert "no handle 'two_point-bow-999' in the catalog" in msg
    assert not (tmp_path / "r").exists() or not list((tmp_path / "r").rglob("*.png"))


@pytest.mark.parametrize(("text", "size"), [("256", (256, 256)), ("320x240", (320, 240)), ("64X48", (64, 48))])
def test_resolution(text: str, size: tuple[int, int]) -> None:
    assert parse_resolution(text) == size


@pytest.mark.parametrize(("size", "shadow"), [((8, 8), 512), ((64, 64), 512), ((128, 96), 512), ((129, 64), 1024),
                                              ((256, 256), 1024), ((320, 240), 2048), ((4096, 4096), 2048)])
def test_sim_settings_scale_the_shadow_map_with_the_image(size: tuple[int, int], shadow: int) -> None:
    """Four shadow-map texels per pixel of the longer side, one of 512, 1024 and 2048 px; a stream's key says it."""
    spec = StreamSpec("sim", *size)
    assert spec.sim.shadow_size == shadow and spec.sim.multisamples == 4
    assert spec.key == f"sim-{size[0]}x{size[1]}-shadow{shadow}-msaa4"


def test_a_sim_renderer_leaves_the_scenes_model_as_it_was(variants: Path) -> None:
    """The shadow map's size and the multisamples are set for the renderer's context only: the model is shared with
    the scene (and the teleop viewer), whose own renders keep rik's 2048 px map."""
    from rik.render.renderers import MujocoFrames
    from rik.sim.build import build_scene

    scene = build_scene(variants / BOW, None)
    quality = scene.model.vis.quality
    before = (quality.shadowsize, quality.offsamples)
    frames = MujocoFrames(scene.model, ["front"], StreamSpec("sim", 16, 16))
    try:
        assert frames.render(scene.data, 0)["front"].shape == (16, 16, 3)
    finally:
        frames.close()
    assert (quality.shadowsize, quality.offsamples) == before == (2048, 4)
