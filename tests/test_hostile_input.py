"""Hostile and damaged input (issue 16): ids that would lead outside the output folder, catalog ids that collide
once written into variant ids, damaged episodes, out-of-range seeds, concurrent exports, a full disk. Each gets one
line and a non-zero exit, writes nothing outside its output folder and leaves no temporary file behind."""

from __future__ import annotations

import hashlib
import json
import os
import resource
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import pytest
import yaml
from conftest import read_line
from shared import builtin_catalog

from rik.episodes.episode import EpisodeError, meta_digest, read_episode, read_meta
from rik.errors import RikError
from rik.paths import inside

CAT = builtin_catalog()
KNOB = "drawer-bedside-45__knob-mushroom-30__normal"
EXPORT = ["--repo-id", "local/hostile", "--res", "16", "--streams", "sim", "--codec", "h264"]


@pytest.fixture
def episode(knob_recording: Path, tmp_path: Path) -> Path:
    """A private copy of the recorded episode, to damage."""
    src = next((knob_recording / "episodes").iterdir())
    dst = tmp_path / "episodes" / src.name
    shutil.copytree(src, dst)
    return dst


def one_line(result) -> str:
    assert result.code != 0 and "Traceback" not in result.err, result.err
    lines = result.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("rik: error: "), lines
    return lines[0].removeprefix("rik: error: ")


def reseal(episode: Path, **changes) -> None:
    """Change fields of an episode's meta.json and seal it again (as someone who knows how the seal is made would),
    so that what is checked is the fields themselves."""
    data = json.loads((episode / "meta.json").read_text())
    data.update(changes)
    data["states_sha256"] = hashlib.sha256((episode / "states.parquet").read_bytes()).hexdigest()
    data["meta_sha256"] = meta_digest(data)
    (episode / "meta.json").write_text(json.dumps(data))


def tree(root: Path) -> list[str]:
    return sorted(str(p.relative_to(root)) for p in root.rglob("*"))


# ---- 1. ids that would lead outside the output folder ---------------------------------------------------------
def test_inside_refuses_every_way_out(tmp_path: Path) -> None:
    root = tmp_path / "out"
    root.mkdir()
    (root / "link").symlink_to(tmp_path)
    assert inside(root, "a", "b") == root / "a" / "b"
    for parts in (("..", "x"), ("../../x",), ("/abs/x",), ("a/b",), ("link", "x"), ("",), (".",)):
        with pytest.raises(RikError, match="would lead outside"):
            inside(root, *parts)


@pytest.mark.parametrize("bad_id", ["../../escaped", "/tmp/rik-escaped-abs", ".hidden", "a/b"])
def test_episode_id_that_is_not_a_folder_name_is_refused(rik, episode: Path, knob_recording: Path, tmp_path: Path,
                                                          bad_id: str) -> None:
    reseal(episode, id=bad_id)
    before = tree(tmp_path)
    with pytest.raises(EpisodeError, match=r"meta.json: field 'id': Value error, .* is not a safe folder name"):
        read_meta(episode)
    renders = tmp_path / "deep" / "renders"
    msg = one_line(rik("render", str(episode), "--res", "16", "--out", str(renders), "--variants",
                       str(knob_recording / "variants")))
    assert msg.startswith(f"{episode / 'meta.json'}: field 'id': Value error, {bad_id!r} is not a safe folder name")
    out = tmp_path / "deep" / "ds"
    msg = one_line(rik("export-lerobot", str(episode), "--out", str(out), "--renders", str(renders), "--variants",
                       str(knob_recording / "variants"), *EXPORT))
    assert "field 'id'" in msg and "is not a safe folder name" in msg
    assert tree(tmp_path) == before  # nothing written anywhere, not even the output's parents
    assert not Path("/tmp/rik-escaped-abs").exists()


def test_edited_meta_is_refused_by_its_seal(episode: Path) -> None:
    data = json.loads((episode / "meta.json").read_text())
    data["outcome"], data["final_opening"] = "S", 0.99  # valid values, but not what was recorded
    (episode / "meta.json").write_text(json.dumps(data))
    with pytest.raises(EpisodeError, match=r"meta.json: edited or corrupt \(its fields no longer match their "
                                           r"meta_sha256\)"):
        read_episode(episode)


def test_variant_and_front_of_an_episode_are_checked(episode: Path) -> None:
    reseal(episode, variant="../variants-elsewhere")
    with pytest.raises(EpisodeError, match="field 'variant': Value error, '../variants-elsewhere' is not a safe"):
        read_meta(episode)
    reseal(episode, variant=KNOB, front="a/b")
    with pytest.raises(EpisodeError, match=r"field 'front': Value error, 'a/b' is not a simple id"):
        read_meta(episode)


# ---- 2. catalog ids that collide once written into variant ids ------------------------------------------------
def _builtin(section: str, entry_id: str) -> dict:
    from rik.registry.sources import BUILTIN_DIR

    for file in sorted(BUILTIN_DIR.rglob("*.yaml")):
        for entry in (yaml.safe_load(file.read_text()) or {}).get(section) or []:
            if entry["id"] == entry_id:
                return entry
    raise AssertionError(entry_id)


def _overlay(rik, tmp_path: Path, section: str, entry: dict):
    path = tmp_path / "mine.yaml"
    path.write_text(yaml.safe_dump({section: [entry]}, sort_keys=False))
    return one_line(rik("catalog", "list", "--catalog", str(path)))


@pytest.mark.parametrize("new_id", ["drawer-chest-80", "drawer/chest/80"])
def test_base_unit_written_like_a_builtin_one_is_refused(rik, tmp_path: Path, new_id: str) -> None:
    msg = _overlay(rik, tmp_path, "base_units", {**_builtin("base_units", "drawer/chest-80"), "id": new_id})
    assert f"entry base_units[0] '{new_id}', field 'id': written 'drawer-chest-80' in variant ids, the same as " \
           "base unit 'drawer/chest-80' (" in msg
    assert "base_units.yaml, base_units[" in msg and msg.endswith("choose another id")


def test_ids_that_cannot_form_variant_ids_are_refused_at_load(rik, tmp_path: Path) -> None:
    unit = _builtin("base_units", "drawer/chest-80")
    msg = _overlay(rik, tmp_path, "base_units", {**unit, "id": "drawer/my__chest"})
    assert "entry base_units[0] 'drawer/my__chest', field 'id': '__' separates the parts of variant and episode " \
           "ids; a base unit id may not contain it" in msg
    front = {**unit["fronts"][0], "id": "a/b"}
    msg = _overlay(rik, tmp_path, "base_units", {**unit, "id": "drawer/mine", "fronts": [front]})
    assert "entry base_units[0] 'drawer/mine', field 'fronts.0.id': front id 'a/b' must be one word without '/' " \
           "or '__'" in msg
    preset = _builtin("presets", "normal")
    msg = _overlay(rik, tmp_path, "presets", {**preset, "id": "mine/soft"})
    assert "entry presets[0] 'mine/soft', field 'id': a preset id is one word (no '/')" in msg


# ---- 5. damaged episodes and out-of-range numbers: one line, never a traceback ---------------------------------
@pytest.mark.parametrize("seed", ["-1", str(2**63), str(2**63 - 1)])
def test_record_seed_out_of_range(rik, tmp_path: Path, seed: str) -> None:
    args = ["record", KNOB, "--strategy", "grasp_vertical", "--seed", seed, "--out", str(tmp_path / "ep"),
            "--variants", str(tmp_path / "v")]
    if seed == str(2**63 - 1):
        args += ["--episodes", "2"]  # the first fits, the second would not
    msg = one_line(rik(*args))
    assert msg.startswith(f"--seed {seed}: seeds must lie in 0 .. {2**63 - 1} (2^63 - 1)")
    assert not (tmp_path / "ep").exists() and not (tmp_path / "v").exists()


def test_bench_seed_out_of_range(rik, tmp_path: Path) -> None:
    msg = one_line(rik("bench", "--seed", "-1", "--out", str(tmp_path / "b")))
    assert msg.startswith("--seed -1: the benchmark's seed must lie in 0 .. ")


def _export(rik, episode: Path, knob_recording: Path, out: Path):
    return rik("export-lerobot", str(episode.parent), "--out", str(out), "--renders", str(out.parent / "renders"),
               "--variants", str(knob_recording / "variants"), *EXPORT)


@pytest.mark.parametrize("case", ["huge seed", "fps 0", "random parquet", "narrow state", "text state"])
def test_damaged_episode_is_one_line_and_leaves_nothing(rik, episode: Path, knob_recording: Path, tmp_path: Path,
                                                        case: str) -> None:
    import numpy as np
    import pyarrow as pa
    import pyarrow.parquet as pq

    states = episode / "states.parquet"
    if case == "huge seed":
        reseal(episode, seed=2**63 + 5)
        expected = "meta.json: field 'seed': Input should be less than or equal to 9223372036854775807"
    elif case == "fps 0":
        reseal(episode, fps=0)
        expected = "meta.json: field 'fps': Input should be greater than or equal to 1"
    elif case == "random parquet":
        states.write_bytes(np.random.default_rng(0).bytes(4096))
        reseal(episode)
        expected = "states.parquet: not a readable Parquet file (ArrowInvalid: "
    else:
        table = pq.read_table(states)
        column = table.column("state").to_pylist()
        if case == "narrow state":
            new = pa.array([row[:-1] for row in column], pa.list_(pa.float64()))
            expected = "states.parquet: column 'state' has"
        else:
            new = pa.array([str(row[0]) for row in column])
            expected = "states.parquet: column 'state' holds string, expected lists of floats"
        pq.write_table(table.set_column(table.schema.get_field_index("state"), "state", new), states)
        reseal(episode)
    with pytest.raises(EpisodeError) as err:
        read_episode(episode)
    assert expected in str(err.value)
    out = tmp_path / "ds"
    msg = one_line(_export(rik, episode, knob_recording, out))
    assert expected in msg
    assert not out.exists() and not out.with_name("ds.partial").exists() and not out.with_name("ds.lock").exists()


def test_narrow_state_names_the_row_and_the_meta(episode: Path) -> None:
    import pyarrow as pa
    import pyarrow.parquet as pq

    states = episode / "states.parquet"
    table = pq.read_table(states)
    rows = table.column("state").to_pylist()
    rows[2] = rows[2][:5]
    pq.write_table(table.set_column(table.schema.get_field_index("state"), "state",
                                    pa.array(rows, pa.list_(pa.float64()))), states)
    reseal(episode)
    meta = read_meta(episode)
    with pytest.raises(EpisodeError, match=rf"column 'state' has 5 numbers in row 2, expected {meta.state_size} "
                                           r"\(meta.json's state_size\)"):
        read_episode(episode)


# ---- 7. one export at a time per --out -------------------------------------------------------------------------
def test_second_export_into_the_same_out_is_refused(rik, episode: Path, knob_recording: Path, tmp_path: Path) -> None:
    from rik.locks import exclusive

    out = tmp_path / "ds"
    holder = subprocess.Popen([sys.executable, "-c", (
        "import sys, time; from pathlib import Path; from rik.locks import exclusive\n"
        "with exclusive(Path(sys.argv[1]), 'rik export-lerobot'):\n"
        "    print('held', flush=True); time.sleep(60)\n"), str(out)], stdout=subprocess.PIPE, text=True)
    try:
        assert read_line(holder.stdout).strip() == "held"
        msg = one_line(_export(rik, episode, knob_recording, out))
        assert msg == (f"{out}: another rik export-lerobot (pid {holder.pid}) is writing it now; wait for it to "
                       "finish, or choose another --out")
        assert not out.exists() and not out.with_name("ds.partial").exists()
    finally:
        holder.send_signal(signal.SIGKILL)
        holder.wait()
    with exclusive(out, "rik export-lerobot"):  # a killed holder's lock is free again
        pass
    assert not out.with_name("ds.lock").exists()


def test_out_made_by_someone_else_during_the_export(rik, episode: Path, knob_recording: Path, tmp_path: Path,
                                                    monkeypatch: pytest.MonkeyPatch) -> None:
    """The export finishes, finds --out taken and says so; the finished dataset is kept and --resume publishes
    it once --out is moved away."""
    from rik.exporters import lerobot_card

    out = tmp_path / "ds"
    real = lerobot_card.write_card

    def card_then_someone_makes_out(*args, **kwargs):  # the real card, then another program creates --out
        real(*args, **kwargs)
        (out / "theirs").mkdir(parents=True)

    monkeypatch.setattr(lerobot_card, "write_card", card_then_someone_makes_out)
    msg = one_line(_export(rik, episode, knob_recording, out))
    assert msg == (f"{out}: was created by something else while the export ran, so the finished dataset was not moved "
                   f"there (it is kept in {out.with_name('ds.partial') / 'merged'}); move {out} away and run again "
                   "with --resume")
    assert (out / "theirs").is_dir()
    monkeypatch.setattr(lerobot_card, "write_card", real)
    shutil.move(out, tmp_path / "theirs")
    result = rik("export-lerobot", str(episode.parent), "--out", str(out), "--renders", str(tmp_path / "renders"),
                 "--variants", str(knob_recording / "variants"), *EXPORT, "--resume")
    assert result.code == 0, result.err
    assert (out / "meta" / "info.json").is_file() and not out.with_name("ds.partial").exists()


# ---- 9. small ones ----------------------------------------------------------------------------------------------
def test_resume_on_a_folder_that_is_not_a_rik_export(rik, episode: Path, knob_recording: Path, tmp_path: Path) -> None:
    out = tmp_path / "photos"
    out.mkdir()
    (out / "cat.jpg").write_bytes(b"\xff\xd8")
    msg = one_line(rik("export-lerobot", str(episode.parent), "--out", str(out), *EXPORT, "--resume"))
    assert msg == (f"{out}: exists and is not a rik export (no meta/info.json and meta/rik_card.json), so there is nothing "
                   "to resume there; choose another --out")
    assert tree(out) == ["cat.jpg"]


def _full_disk(code: str, limit: int = 2000) -> subprocess.CompletedProcess:
    """Run ``code`` in a fresh Python whose files may not grow past ``limit`` bytes (as on a full disk: writes fail
    with EFBIG instead of the process being killed)."""
    def limit_files() -> None:
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))

    return subprocess.run([sys.executable, "-c", code], preexec_fn=limit_files, capture_output=True, text=True,
                          timeout=120)


def test_full_disk_leaves_no_temporary_files(tmp_path: Path) -> None:
    done = _full_disk(
        "import sys; from pathlib import Path; import numpy as np\n"
        "from rik.outputs import NEW, write_png, write_text\n"
        f"d = Path({str(tmp_path)!r})\n"
        "for f in (lambda: write_text(d / 'a.json', 'x' * 100_000, NEW),\n"
        "          lambda: write_png(d / 'b.png', np.random.default_rng(0).integers(0, 255, (200, 200, 3)), NEW)):\n"
        "    try:\n"
        "        f()\n"
        "    except OSError as exc:\n"
        "        print(exc.errno)\n")
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["27", "27"]  # EFBIG, twice
    assert os.listdir(tmp_path) == []


def test_full_disk_in_a_command_is_one_line(tmp_path: Path) -> None:
    """A command whose output cannot be written: one line naming the file, exit 1, nothing half-written."""
    out = tmp_path / "sysid-data"
    done = _full_disk(f"import sys; sys.argv = ['rik', 'sysid', 'simulate', '--effect', 'soft_close', '--out', "
                      f"{str(out)!r}]\nfrom rik.cli.app import main\nmain()", limit=20_000)
    assert done.returncode == 1, done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("rik: error: ") and "File too large (EFBIG)" in lines[0], lines
    assert not [p for p in tmp_path.rglob("*") if p.name.endswith(".tmp")]


@pytest.mark.slow  # a build, recording or render end to end: out of the everyday tier
def test_two_renders_of_one_stream_render_it_once(episode: Path, knob_recording: Path, tmp_path: Path) -> None:
    """While one process renders a stream (holding its lock), another waits, then reuses the finished stream
    instead of rendering beside it into the same folder."""
    from rik.render.episodes import render_episode
    from rik.render.streams import StreamSpec

    renders = tmp_path / "renders"
    holder = subprocess.Popen([sys.executable, "-c", (
        "import sys, time; from pathlib import Path\n"
        "from rik.locks import exclusive; from rik.registry import load_catalog\n"
        "from rik.render.episodes import _render_stream; from rik.render.streams import StreamSpec, stream_dir\n"
        "from rik.episodes.episode import read_meta\n"
        "ep, renders, variants = map(Path, sys.argv[1:])\n"
        "spec = StreamSpec('sim', 16, 16); final = stream_dir(renders, read_meta(ep).id, spec)\n"
        "with exclusive(final, 'rik render'):\n"
        "    print('held', flush=True); time.sleep(2)\n"
        "    _render_stream(load_catalog(), ep, spec, final, variants, None, None)\n"),
        str(episode), str(renders), str(knob_recording / "variants")], stdout=subprocess.PIPE, text=True)
    try:
        assert read_line(holder.stdout).strip() == "held"
        result = render_episode(CAT, episode, StreamSpec("sim", 16, 16), renders=renders, variants=knob_recording / "variants")
        assert holder.wait(timeout=120) == 0
    finally:
        holder.kill()
    assert result.rendered == 0 and result.frames == read_meta(episode).steps + 1
    assert not [p for p in renders.rglob("*") if p.name.endswith((".lock", ".partial", ".tmp"))]
