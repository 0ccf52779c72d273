"""Follow-ups of the hostile-input probes (issue 29): an image size the default codec cannot encode, an --out inside
the episodes it reads, files read whole with no bound (an episode's meta.json, a catalog YAML file, a mesh, a GLB
that declares more than it holds), a --catalog walk over a whole file system, rik eval and rik assets import writing
over a user's files, and --workers 0. Each is one line, exit 2, with nothing written or overwritten."""

from __future__ import annotations

import json
import os
import shutil
import struct
from pathlib import Path

import pytest
from test_hostile_input import one_line, tree

from rik.registry import load_catalog

CAT = load_catalog()
KNOB = "drawer-bedside-45__knob-mushroom-30__normal"


@pytest.fixture
def episode(knob_recording: Path, tmp_path: Path) -> Path:
    """A copy of the recorded episode in ``tmp_path/episodes``: what a test may find written into it stays there."""
    source = next((knob_recording / "episodes").iterdir())
    return Path(shutil.copytree(source, tmp_path / "episodes" / source.name))


def contents(root: Path) -> dict[str, bytes | None]:
    return {p.relative_to(root).as_posix(): (p.read_bytes() if p.is_file() else None) for p in sorted(root.rglob("*"))}


def refused(result) -> str:
    assert result.code == 2, result.err
    return one_line(result)


# ---- 1. a size the codec cannot encode -------------------------------------------------------------------------
def test_av1_frames_narrower_than_25_pixels_are_refused_first(rik, knob_recording: Path, episode: Path, tmp_path: Path) -> None:
    """libsvtav1 dies of SIGFPE on frames under 25 px wide (any height); 64x8 encodes."""
    before = tree(tmp_path)
    for res, shown in (("16", "16x16"), ("24x64", "24x64")):
        msg = refused(rik("export-lerobot", str(episode), "--out", str(tmp_path / "ds"), "--repo-id", "local/av1",
                          "--res", res, "--streams", "sim", "--renders", str(tmp_path / "renders"), "--variants",
                          str(knob_recording / "variants")))
        assert msg == (f"--res {shown}: --codec libsvtav1 encodes frames at least 25 pixels wide (narrower ones "
                       "crash its encoder); give a width of 25 or more, or --codec h264")
    assert tree(tmp_path) == before
    from rik.errors import RikError
    from rik.exporters.spec import ExportSpec, check_codec_size

    check_codec_size(ExportSpec("local/x", width=25, height=8))
    check_codec_size(ExportSpec("local/x", width=64, height=8))
    check_codec_size(ExportSpec("local/x", width=16, height=16, codec="h264"))
    check_codec_size(ExportSpec("local/x", streams=(), width=16, height=16))  # state only: nothing encoded
    with pytest.raises(RikError, match="at least 25 pixels wide"):
        check_codec_size(ExportSpec("local/x", width=24, height=4096))


# ---- 2. an --out inside the episodes ---------------------------------------------------------------------------
def test_render_out_inside_an_episode_is_refused(rik, knob_recording: Path, episode: Path, tmp_path: Path) -> None:
    before = contents(tmp_path)
    for out in (episode, episode / "renders", episode.parent):  # the last: renders/<id> is the episode itself
        msg = refused(rik("render", str(episode), "--res", "16", "--out", str(out), "--variants",
                          str(knob_recording / "variants")))
        assert msg == (f"--out {out}: would write the streams inside episode folder {episode}; rik never writes into "
                       "an episode: give --out outside the episodes, e.g. renders")
    assert contents(tmp_path) == before


# ---- 3. files read whole ---------------------------------------------------------------------------------------
def test_a_huge_meta_json_is_refused_unread(rik, knob_recording: Path, episode: Path, tmp_path: Path) -> None:
    meta = episode / "meta.json"
    os.truncate(meta, 8 * 2**20)  # sparse: the JSON, then zeros
    before = contents(tmp_path)
    msg = refused(rik("render", str(episode), "--res", "16", "--out", str(tmp_path / "renders"), "--variants",
                      str(knob_recording / "variants")))
    assert msg == (f"{meta}: larger than 1 MiB, not an episode's meta.json (rik writes a few kB); record the episode "
                   "again, or restore the file")
    assert contents(tmp_path) == before


def test_a_huge_catalog_file_is_refused_unread(rik, tmp_path: Path) -> None:
    overlay = tmp_path / "cat" / "big.yaml"
    overlay.parent.mkdir()
    overlay.write_text("schema: 1\n")
    os.truncate(overlay, 17 * 2**20)
    msg = refused(rik("catalog", "list", "--catalog", str(tmp_path / "cat")))
    assert msg == (f"{overlay}: 17 MiB, larger than the 16 MiB a catalog file may have; nothing was read")
    msg = refused(rik("catalog", "list", "--catalog", str(overlay)))
    assert msg.startswith(f"{overlay}: 17 MiB, larger than")
    assert tree(tmp_path) == ["cat", "cat/big.yaml"]


# ---- 4. meshes read whole --------------------------------------------------------------------------------------
def _glb(document: dict, binary: bytes) -> bytes:
    text = json.dumps(document).encode()
    text += b" " * (-len(text) % 4)
    binary += b"\0" * (-len(binary) % 4)
    body = struct.pack("<II", len(text), 0x4E4F534A) + text + struct.pack("<II", len(binary), 0x004E4942) + binary
    return struct.pack("<III", 0x46546C67, 2, 12 + len(body)) + body


def test_a_mesh_file_too_large_for_max_faces_is_refused_unread(rik, tmp_path: Path, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "huge.stl").write_bytes(b"\0" * 80 + struct.pack("<I", 2_000_000))  # a binary STL's header
    os.truncate(tmp_path / "huge.stl", 84 + 50 * 2_000_000)  # 95 MiB, sparse
    args = ["--type", "knob", "--id", "knob/huge", "--catalog-dir", "cat", "--max-faces", "1000"]
    msg = refused(rik("assets", "import", "huge.stl", *args))
    assert msg == ("huge.stl: 95 MiB, larger than --max-faces 1,000 allows 64 MiB (512 bytes a triangle, plus 64 "
                   "MiB for headers and textures); nothing was read: simplify the mesh, or raise --max-faces")
    # a GLB of 200 bytes whose sparse accessor declares 10^10 points: trimesh would allocate 112 GiB for it
    accessor = {"componentType": 5126, "count": 10**10, "type": "VEC3",
                "sparse": {"count": 1, "indices": {"bufferView": 0, "componentType": 5125}, "values": {"bufferView": 0}}}
    (tmp_path / "bomb.glb").write_bytes(_glb({
        "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}], "buffers": [{"byteLength": 8}],
        "bufferViews": [{"buffer": 0, "byteLength": 8}], "accessors": [accessor]}, b"\0" * 8))
    msg = refused(rik("assets", "import", "bomb.glb", *args[:-1], "500000"))
    assert msg == ("bomb.glb: its glTF JSON declares 114,441 MiB of buffers and accessors, more than --max-faces "
                   "500,000 allows 308 MiB (512 bytes a triangle, plus 64 MiB for headers and textures); nothing was "
                   "loaded: export the file again, or raise --max-faces")
    # a GLB whose JSON chunk declares 4 GiB
    raw = bytearray(_glb({"asset": {"version": "2.0"}}, b""))
    raw[12:16] = struct.pack("<I", 2**32 - 8)
    (tmp_path / "long.glb").write_bytes(bytes(raw))
    msg = refused(rik("assets", "import", "long.glb", *args))
    assert msg.startswith("long.glb: its JSON chunk declares 4,294,967,288 bytes, more than the file holds (")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bomb.glb", "huge.stl", "long.glb"]


# ---- 5. a catalog walk over a whole file system ----------------------------------------------------------------
def test_a_catalog_walk_is_bounded_and_stays_inside(rik, tmp_path: Path) -> None:
    deep = tmp_path / "deep"
    (deep / "/".join("abcdefghi")).mkdir(parents=True)  # 9 levels
    msg = refused(rik("catalog", "list", "--catalog", str(deep)))
    assert msg == (f"{deep}: has folders more than 8 levels deep ({deep / 'a/b/c/d/e/f/g/h/i'}), too deep for a "
                   "catalog; give --catalog the folder (or file) of the catalog itself")
    many = tmp_path / "many"
    many.mkdir()
    for i in range(1001):
        (many / f"{i}.yaml").write_text("")
    msg = refused(rik("catalog", "list", "--catalog", str(many)))
    assert msg == (f"{many}: holds more than 1,000 YAML files, too many for a catalog; give --catalog the folder (or "
                   "file) of the catalog itself")
    outside = tmp_path / "outside"
    outside.mkdir()
    (outside / "bad.yaml").write_text("not: [a catalog\n")
    linked = tmp_path / "linked"
    linked.mkdir()
    (linked / "elsewhere").symlink_to(outside)  # a symbolic link to a folder is not followed
    ok = rik("catalog", "list", "--catalog", str(linked))
    assert ok.code == 0, ok.err


# ---- 6. rik eval over a user's files ---------------------------------------------------------------------------
def test_eval_keeps_a_users_files_in_out(rik, knob_recording: Path, tmp_path: Path) -> None:
    out = tmp_path / "results"
    out.mkdir()
    (out / "table.md").write_text("my notes\n")
    before = contents(tmp_path)
    msg = refused(rik("eval", "strategy:grasp_vertical", "--split", "all", "--types", "knob", "--presets", "normal",
                      "-n", "1", "--episode-length", "3", "--videos", "0", "--workers", "1", "--out", str(out),
                      "--variants", str(knob_recording / "variants")))
    assert msg == (f"{out / 'table.md'}: exists and was not written by rik eval (no eval_info.json of its own beside "
                   "it), so nothing was run: choose another --out, or move it away yourself")
    assert contents(tmp_path) == before
    from rik.evaluation.evaluate import check_eval_out

    (out / "eval_info.json").write_text(json.dumps({"rik": {"spec": {}, "per_episode": []}}))
    check_eval_out(out)  # an earlier rik eval's folder: a rerun writes over it


# ---- 7. rik assets import over a user's pictures ---------------------------------------------------------------
def test_import_keeps_a_users_pictures(rik, tmp_path: Path, monkeypatch) -> None:
    import trimesh

    monkeypatch.chdir(tmp_path)
    trimesh.creation.icosphere(subdivisions=2, radius=0.015).export(tmp_path / "knob.stl")
    mine = tmp_path / "cat" / "pictures" / "knob__mine-imported" / "fidelity.png"
    mine.parent.mkdir(parents=True)
    mine.write_bytes(b"my picture")
    before = contents(tmp_path)
    msg = refused(rik("assets", "import", "knob.stl", "--type", "knob", "--id", "knob/mine", "--catalog-dir", "cat"))
    assert msg == ("cat/pictures/knob__mine-imported: already holds fidelity.png, where this import writes its "
                   "pictures; rik writes only new files into the catalog folder: move or remove it, or choose another "
                   "--id (nothing was read or written)")
    assert contents(tmp_path) == before


# ---- 8. --workers 0 --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("command", [["render", "x"], ["record", KNOB], ["bench"], ["export-lerobot", "x", "--out", "y"],
                                     ["variants", "build", KNOB], ["assets", "build", "--all"],
                                     ["eval", "strategy:grasp_vertical"], ["dataset", "plan", "spec.yaml"]])
@pytest.mark.parametrize("workers", ["0", "-2"])
def test_workers_below_one_is_one_line(rik, tmp_path: Path, monkeypatch, command: list[str], workers: str) -> None:
    monkeypatch.chdir(tmp_path)
    msg = refused(rik(*command, "--workers", workers))
    assert msg.startswith(f"--workers {workers}: give 1 ")
    assert tree(tmp_path) == []


def test_a_catalog_or_mapping_file_nested_too_deeply_or_an_alias_bomb_is_one_line(rik, tmp_path: Path) -> None:
    """A catalog overlay nested 100,000 deep crashed the process (libyaml's composer recursing in C: a segmentation
    fault, exit -11); one whose aliases expand past a million values, and a base unit's mapping file likewise, are
    one line before they are parsed."""
    import subprocess
    import sys

    deep = tmp_path / "deep.yaml"
    deep.write_text("handles:\n  - " + "[" * 100_000 + "]" * 100_000 + "\n", encoding="utf-8")
    run = subprocess.run([sys.executable, "-m", "rik", "catalog", "list", "--catalog", str(deep)],
                         capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert run.returncode == 2, (run.returncode, run.stderr[-500:])
    assert one_line_text(run.stderr) == "deep.yaml:2: the catalog file nests lists and mappings more than 16 deep"
    bomb = tmp_path / "bomb.yaml"
    levels = ['a0: &a0 [x, x, x, x, x, x, x, x, x, x]']
    levels += [f"a{i}: &a{i} [{', '.join([f'*a{i - 1}'] * 10)}]" for i in range(1, 8)]
    bomb.write_text("\n".join(levels) + "\nhandles: []\n", encoding="utf-8")
    msg = one_line(rik("catalog", "list", "--catalog", str(bomb)))
    assert msg.startswith(f"{bomb}:") and "the catalog file expands to more than 1,000,000 values through its " \
                                          "aliases" in msg
    msg = one_line(rik("assets", "import", str(bomb), "--base-unit", "--parts", str(bomb), "--id", "drawer/x",
                       "--catalog-dir", str(tmp_path / "mine")))
    assert "the mapping file expands to more than 1,000,000 values" in msg, msg
    assert not (tmp_path / "mine").exists()


def one_line_text(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("rik: error: "), err[-2000:]
    return lines[0].removeprefix("rik: error: ")
