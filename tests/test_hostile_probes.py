"""Hostile input to the commands that record, render, build and measure (issue 29): sizes that would exhaust the
machine before any check (episodes, workers, samples, resampling rates, bootstrap resamples, decompressed images),
paths that are files where folders belong (or the reverse), names too long for the file system, and the gym
environment's image arguments. Each is refused with one line, exit 2, before anything is written."""

from __future__ import annotations

import math
import struct
import zlib
from pathlib import Path

import pytest
from shared import builtin_catalog
from test_hostile_input import one_line, tree

from rik.errors import RikError

CAT = builtin_catalog()
KNOB = "drawer-bedside-45__knob-mushroom-30__normal"
EXPORT = ["--repo-id", "local/probes", "--res", "16", "--streams", "sim", "--codec", "h264"]


@pytest.fixture
def episode(knob_recording: Path) -> Path:
    return next((knob_recording / "episodes").iterdir())


def test_workers_beyond_the_machine_are_refused_first(rik, knob_recording: Path, episode: Path, tmp_path: Path) -> None:
    renders = tmp_path / "renders"
    msg = one_line(rik("render", str(episode), "--res", "16", "--workers", "100000", "--out", str(renders),
                       "--variants", str(knob_recording / "variants")))
    assert msg.startswith("--workers 100000: give 1 to ") and "per core of this machine's" in msg
    msg = one_line(rik("record", "--split", "train", "-s", "grasp_vertical", "--episodes", "2", "--workers",
                       "100000", "--out", str(tmp_path / "eps"), "--variants", str(knob_recording / "variants")))
    assert msg.startswith("--workers 100000: give 1 to ")
    assert tree(tmp_path) == []


def test_episode_counts_are_bounded_before_anything_is_drawn(rik, knob_recording: Path, tmp_path: Path) -> None:
    msg = one_line(rik("record", "--split", "train", "-s", "grasp_vertical", "--episodes", str(10**12), "--out",
                       str(tmp_path / "eps"), "--variants", str(knob_recording / "variants")))
    assert msg == "--episodes 1000000000000: give 1 to 1,000,000 episodes per command"
    assert tree(tmp_path) == []


def test_bench_refuses_empty_and_enormous_plans(rik, knob_recording: Path, tmp_path: Path) -> None:
    out = tmp_path / "bench"
    msg = one_line(rik("bench", "--presets", ",", "--out", str(out), "--variants", str(knob_recording / "variants")))
    assert msg == "--presets: empty; give at least one"
    msg = one_line(rik("bench", "--episodes-per-cell", str(10**12), "--out", str(out), "--variants",
                       str(knob_recording / "variants")))
    assert msg == ("--episodes-per-cell 1000000000000: 27,000,000,000,000 episodes in all; give 1 or more, and at "
                   "most 1,000,000 episodes in all")
    assert tree(tmp_path) == []


@pytest.mark.parametrize("command", ["record", "render", "replay", "robot-check", "variants build", "bench",
                                     "fidelity", "export"])
def test_a_file_where_a_folder_belongs(rik, knob_recording: Path, episode: Path, tmp_path: Path, command: str) -> None:
    file = tmp_path / "a-file"
    file.write_text("not a folder\n")
    variants = ["--variants", str(knob_recording / "variants")]
    args, option = {
        "record": (["record", KNOB, "-s", "grasp_vertical", "--out", str(file), *variants], "--out"),
        "render": (["render", str(episode), "--res", "16", "--out", str(file), *variants], "--out"),
        "replay": (["replay", str(episode), "--variants", str(file)], "--variants"),
        "robot-check": (["robot-check", KNOB, "--variants", str(file)], "--variants"),
        "variants build": (["variants", "build", KNOB, "--out", str(file)], "--out"),
        "bench": (["bench", "-n", "1", "-t", "knob", "--presets", "normal", "--strategies", "grasp_vertical",
                   "--workers", "1", "--out", str(file), *variants], "--out"),
        "fidelity": (["assets", "fidelity", "knob/mushroom-30", "--out", str(file)], "--out"),
        "export": (["export-lerobot", str(episode), "--out", str(tmp_path / "ds"), "--renders", str(file), *EXPORT,
                    *variants], "--renders"),
    }[command]
    below = file / "sub"  # a folder below a file: the file is named
    assert one_line(rik(*args)) == f"{option} {file}: a file is there, where a folder is expected"
    args = [str(below) if a == str(file) else a for a in args]
    assert one_line(rik(*args)) == (f"{option} {below}: a file is there, where a folder is expected ({file} is not "
                                    "a folder)")
    assert tree(tmp_path) == ["a-file"]


def test_a_folder_where_a_file_belongs(rik, tmp_path: Path) -> None:
    folder = tmp_path / "taken"
    folder.mkdir()
    msg = one_line(rik("variants", "show", KNOB, "--png", str(folder), "--dir", str(tmp_path / "variants")))
    assert msg == f"--png {folder}: a folder is there; give the path of the PNG file to write"
    msg = one_line(rik("assets", "stats", "knob/mushroom-30", "--out", str(folder)))
    assert msg == f"--out {folder}: a folder is there; give the path of the CSV file to write"
    assert tree(tmp_path) == ["taken"]


def test_a_name_too_long_for_the_file_system_is_one_line(rik, tmp_path: Path, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)
    msg = one_line(rik("variants", "validate", "a" * 5000))
    assert msg.startswith("a" * 200 + "...: File name too long (ENAMETOOLONG); give a path that is a folder")


def test_export_sizes_are_bounded_before_anything_is_written(rik, knob_recording: Path, episode: Path, tmp_path: Path) -> None:
    out = tmp_path / "ds"
    common = [str(episode), "--out", str(out), "--repo-id", "local/probes", "--res", "16", "--renders",
              str(tmp_path / "renders"), "--variants", str(knob_recording / "variants")]
    msg = one_line(rik("export-lerobot", *common, "--streams", "rerendered", "--spp", str(10**12)))
    assert msg == "--spp 1000000000000: give 1 to 4096 samples per pixel"
    msg = one_line(rik("export-lerobot", *common, "--streams", "sim", "--codec", "h264", "--fps", str(10**9)))
    assert msg == "--fps 1000000000: give 1 to 240 Hz"
    assert tree(tmp_path) == []


def test_a_render_larger_than_the_scene_framebuffer(rik, knob_recording: Path, episode: Path, tmp_path: Path) -> None:
    """The scenes' offscreen buffer is 1280 x 960; --res allows up to 4096 a side."""
    from PIL import Image

    renders = tmp_path / "renders"
    result = rik("render", str(episode), "--res", "2048x8", "--cameras", "front", "--out", str(renders),
                 "--variants", str(knob_recording / "variants"))
    assert result.code == 0, result.err
    with Image.open(next(renders.rglob("front/000000.png"))) as im:
        assert im.size == (2048, 8)


def test_fidelity_points_are_bounded(rik, tmp_path: Path) -> None:
    msg = one_line(rik("assets", "fidelity", "knob/mushroom-30", "--points", str(10**12), "--out",
                       str(tmp_path / "fid")))
    assert msg == "--points 1000000000000: give 1,000 to 1,000,000 surface samples per shell"
    assert tree(tmp_path) == []


def _png_header(path: Path, width: int, height: int) -> None:
    """A PNG that declares ``width`` x ``height`` pixels and holds almost none: a decompression bomb's header."""
    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    ihdr = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(b"\0" * 64))
                     + chunk(b"IEND", b""))


def test_visual_gap_bounds_its_work(rik, tmp_path: Path) -> None:
    import numpy as np
    from PIL import Image

    for side in ("real", "sim"):
        (tmp_path / side).mkdir()
        for i in range(4):
            Image.fromarray(np.full((16, 16, 3), 40 * i, np.uint8)).save(tmp_path / side / f"{i}.png")
    folders = ["--real", str(tmp_path / "real"), "--sim", str(tmp_path / "sim")]
    msg = one_line(rik("visual-gap", *folders, "--bootstrap", str(10**12)))
    assert msg == "--bootstrap 1000000000000: give 1 to 10,000 resamples"
    bomb = tmp_path / "sim" / "bomb.png"
    _png_header(bomb, 60_000, 60_000)
    msg = one_line(rik("visual-gap", *folders, "--n", "4"))
    assert msg.startswith(f"{bomb}: not a readable image (Image size (3600000000 pixels) exceeds limit")


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"images": True, "image_size": (-5, 10)}, "image_size (-5, 10): give (height, width), 8 to 4096 pixels each"),
    ({"images": True, "image_size": (32.5, 32)}, "image_size (32.5, 32): give (height, width), two whole numbers"),
    ({"streams": ("rerendered",), "spp": 0}, "--spp 0: give 1 to 4096 samples per pixel"),
    ({"streams": ("bogus",)}, "streams: unknown stream 'bogus' (streams: sim, rerendered)"),
    ({"images": True, "cameras": ("nope",)}, "cameras: no camera 'nope' in the scene (cameras: front, wrist)"),
    ({"images": True, "cameras": ()}, "cameras: give at least one camera"),
    ({"episode_length": math.nan}, "episode_length nan: must be a whole number of control steps, at least 1"),
])
def test_gym_env_checks_its_arguments(knob_recording: Path, kwargs: dict, message: str) -> None:
    from rik.envs.open_front import OpenFrontEnv

    with pytest.raises(RikError) as exc:
        OpenFrontEnv(KNOB, variants_dir=knob_recording / "variants", **kwargs)
    assert str(exc.value).startswith(message)


def test_gym_env_variants_dir_that_is_a_file(tmp_path: Path) -> None:
    from rik.envs.open_front import OpenFrontEnv

    file = tmp_path / "variants"
    file.write_text("")
    with pytest.raises(RikError, match="^--variants .*: a file is there, where a folder is expected$"):
        OpenFrontEnv(KNOB, variants_dir=file)
