"""One bounded reader for episodes' states (rik.episodes.states): a ``states.parquet`` that declares more than its
meta can need (2,000,000 repeated rows in 350 kB, its sha256 and the meta's seal made to match), a meta whose steps
are no episode, a column wider than the meta says or a footer of megabytes are refused in one line before anything
is decoded, by ``rik replay``, ``rik render``, ``rik export-lerobot`` and the station's replay, with nothing
written; an ordinary episode reads the same arrays as before."""

from __future__ import annotations

import hashlib
import json
import shutil
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from shared import builtin_catalog

from rik.episodes.episode import EpisodeError, meta_digest, read_episode, read_meta, states

CRAFTED_ROWS = 2_000_000
EXPORT = ["--repo-id", "local/bounded", "--res", "16", "--streams", "sim", "--codec", "h264"]
MAX_PEAK_RSS = 512 * 2**20
"""Peak resident memory allowed to a ``rik replay`` that refuses the crafted file, bytes (about 50 MiB measured;
a replay of an ordinary episode, scene built, about 250 MiB; the crafted file decodes to about 1.8 GiB)."""


PEAK = """import atexit, sys
def peak(file=sys.argv[1]):
    status = open("/proc/self/status").read().split("VmHWM:")[1].split()[0]
    open(file, "w").write(status)
atexit.register(peak)
sys.argv = ["rik", *sys.argv[2:]]
from rik.cli.app import main
main()
"""
"""``python -c PEAK FILE ARGS...``: ``rik ARGS...``, writing into FILE its peak resident memory (kB, VmHWM: this
program's own from its start, where ru_maxrss would count the parent's pages its fork copied)."""


def reseal(episode: Path, **changes: Any) -> None:
    """Change fields of an episode's meta.json and seal it again, its states' sha256 included (as someone who knows
    how the seal is made would)."""
    data = json.loads((episode / "meta.json").read_text())
    data.update(changes)
    data["states_sha256"] = hashlib.sha256((episode / "states.parquet").read_bytes()).hexdigest()
    data["meta_sha256"] = meta_digest(data)
    (episode / "meta.json").write_text(json.dumps(data))


def recorded(knob_recording: Path) -> Path:
    return next((knob_recording / "episodes").iterdir())


def copy_episode(knob_recording: Path, to: Path) -> Path:
    """A private copy of the recorded episode in ``to/episodes``."""
    src = recorded(knob_recording)
    return Path(shutil.copytree(src, to / "episodes" / src.name))


@pytest.fixture(scope="module")
def crafted(knob_recording: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A ``states.parquet`` of :data:`CRAFTED_ROWS` rows, the recorded episode's rows over and over (dictionary
    encoded and zstd compressed: a few hundred kB), written once per module in row groups of 100,000 rows."""
    import pyarrow.parquet as pq

    table = pq.read_table(recorded(knob_recording) / "states.parquet")
    block = table.take(np.arange(100_000) % table.num_rows)
    out = tmp_path_factory.mktemp("crafted") / "states.parquet"
    with pq.ParquetWriter(out, table.schema, compression="zstd") as writer:
        for _ in range(CRAFTED_ROWS // block.num_rows):
            writer.write_table(block)
    return out


@pytest.fixture
def hostile(knob_recording: Path, crafted: Path, tmp_path: Path) -> Path:
    """A copy of the recorded episode whose states are :func:`crafted`'s, its meta sealed to match (steps kept)."""
    episode = copy_episode(knob_recording, tmp_path)
    shutil.copyfile(crafted, episode / "states.parquet")
    reseal(episode)
    return episode


def one_line(result: Any) -> str:
    assert result.code == 2 and "Traceback" not in result.err, result.err
    lines = result.err.strip().splitlines()
    assert len(lines) == 1, result.err
    return lines[0]


ROWS_REFUSED = f"states.parquet: its footer declares {CRAFTED_ROWS:,} rows, but meta.json's steps (6) make 7"


@pytest.mark.parametrize("command", ["replay", "render", "export-lerobot"])
def test_crafted_states_are_refused_from_the_footer_by_every_command(rik, hostile: Path, knob_recording: Path,
                                                                     tmp_path: Path, command: str) -> None:
    """Each command refuses the 2,000,000-row file in one line, read from its footer, and writes nothing."""
    before = sorted(tmp_path.rglob("*"))
    variants = ["--variants", str(knob_recording / "variants")]
    out = tmp_path / "out"
    args = {"replay": [str(hostile), *variants],
            "render": [str(hostile), "--res", "16", "--out", str(out), *variants],
            "export-lerobot": [str(hostile.parent), "--out", str(out), "--renders", str(tmp_path / "renders"),
                               *variants, *EXPORT]}[command]
    msg = one_line(rik(command, *args))
    assert msg.startswith(f"rik: error: {hostile}/") and ROWS_REFUSED in msg and "refused before decoding" in msg
    assert sorted(tmp_path.rglob("*")) == before  # no --out, no out.partial, no lock, no renders


def test_crafted_states_are_refused_with_little_memory(hostile: Path, knob_recording: Path, tmp_path: Path) -> None:
    """``rik replay`` of the crafted file, in a process of its own: its peak resident memory stays far below what
    the file decodes to."""
    import pyarrow.parquet as pq

    metadata = pq.ParquetFile(hostile / "states.parquet").metadata
    decoded = sum(metadata.row_group(g).column(c).num_values * 8
                  for g in range(metadata.num_row_groups) for c in range(metadata.num_columns))
    assert decoded > 3 * MAX_PEAK_RSS
    peak = tmp_path / "peak"
    child = subprocess.run([sys.executable, "-c", PEAK, str(peak), "replay", str(hostile), "--variants",
                            str(knob_recording / "variants")], capture_output=True, text=True, timeout=600)
    assert int(peak.read_text()) * 1024 < MAX_PEAK_RSS, f"peak {int(peak.read_text()) / 1024:.0f} MiB"
    lines = child.stderr.strip().splitlines()
    assert child.returncode == 2 and len(lines) == 1 and ROWS_REFUSED in lines[0], child.stderr


def test_the_station_refuses_a_crafted_replay_with_a_message(knob_recording: Path, crafted: Path,
                                                             tmp_path: Path) -> None:
    """The station's replay link of the crafted file, its meta saying 1,999,999 steps (so rows, sha256 and seal all
    match): refused by the meta's bound in one line on the page; the station goes on, and replays the ordinary
    episode beside it."""
    from web_fixtures import TOKEN, WAIT_MS, served_app
    from websockets.sync.client import connect

    from rik.web.app import AppConfig, create_app

    ordinary = read_meta(copy_episode(knob_recording, tmp_path))
    episode = tmp_path / "episodes" / "crafted"
    shutil.copytree(recorded(knob_recording), episode)
    shutil.copyfile(crafted, episode / "states.parquet")
    reseal(episode, id="crafted", steps=CRAFTED_ROWS - 1)
    app = create_app(AppConfig(builtin_catalog(), variants=knob_recording / "variants", episodes=episode.parent,
                               token=TOKEN))
    wait = WAIT_MS / 1000
    with served_app(app) as url, connect(url.replace("http://", "ws://") + f"/teleop/{ordinary.variant}/ws?token="
                                         f"{TOKEN}", open_timeout=wait) as ws:
        def status(until: Callable[[dict[str, Any]], bool]) -> dict[str, Any]:
            deadline = time.monotonic() + wait
            while time.monotonic() < deadline:
                message = ws.recv(timeout=wait)
                if isinstance(message, str) and until(st := json.loads(message)):
                    return st
            raise AssertionError("no such status from the station")

        def replay(episode: str) -> dict[str, Any]:
            """The first status that shows the replay of ``episode``, its end or its failure."""
            ws.send(json.dumps({"type": "command", "name": "replay", "episode": episode}))
            return status(lambda s: s.get("replay") is not None or s.get("message") == f"replayed {episode}; back to "
                          "live" or (s.get("message") or "").startswith("replay failed"))

        status(lambda s: s.get("ready") is True)
        st = replay(ordinary.id)
        assert (st["replay"] or {}).get("rows", 7) == 7 and "failed" not in st["message"], st
        status(lambda s: s.get("message") == f"replayed {ordinary.id}; back to live")
        st = replay("crafted")
        assert st["replay"] is None and st["ready"] and st["error"] is None
        assert st["message"] == (f"replay failed: {episode / 'meta.json'}: field 'steps': 1,999,999 steps at 20 "
                                 "Hz last 27.8 h, longer than an episode rik reads (24 h)")


@pytest.mark.parametrize(("changes", "says"), [
    ({"steps": 10**9}, "field 'steps': 1,000,000,000 steps at 20 Hz last 13,888.9 h, longer than an episode rik "
                       "reads (24 h)"),
    ({"steps": 10**8, "fps": 10_000}, "fields 'steps' and 'state_size': 100,000,001 rows of 124 numbers would "
                                      "decode to 92.4 GiB, more than rik reads of one episode (1 GiB)"),
    ({"state_size": 10**9}, "fields 'steps' and 'state_size': 7 rows of 1,000,000,037 numbers would decode to "
                            "52.2 GiB")], ids=["a day", "1 GiB", "state size"])
def test_a_meta_whose_steps_are_no_episode_is_refused_by_its_bound(rik, knob_recording: Path, tmp_path: Path,
                                                                   changes: dict[str, int], says: str) -> None:
    episode = copy_episode(knob_recording, tmp_path)
    reseal(episode, **changes)
    with pytest.raises(EpisodeError) as err:
        read_episode(episode)
    assert str(err.value).startswith(f"{episode / 'meta.json'}: {says}")
    if "fps" in changes:
        msg = one_line(rik("replay", str(episode), "--variants", str(knob_recording / "variants")))
        assert msg.startswith(f"rik: error: {episode / 'meta.json'}: {says}")


def test_a_column_wider_than_its_meta_is_refused_before_decoding(knob_recording: Path, tmp_path: Path) -> None:
    """7 rows whose states hold 1,000,000 numbers each (7 kB on disk, 56 MB decoded): refused by the values its
    pages declare."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    episode = copy_episode(knob_recording, tmp_path)
    table = pq.read_table(episode / "states.parquet")
    wide = pa.ListArray.from_arrays(pa.array(np.arange(8) * 1_000_000, pa.int32()), pa.array(np.zeros(7_000_000)))
    pq.write_table(table.set_column(table.schema.get_field_index("state"), "state", wide), episode / "states.parquet",
                   compression="zstd")
    reseal(episode)
    with pytest.raises(EpisodeError) as err:
        read_episode(episode, ("opening",))
    assert str(err.value) == (f"{episode / 'states.parquet'}: column 'state' declares 7,000,000 numbers, more than 7 "
                              "rows of 87 can hold (132,290 at most); refused before decoding")


def test_a_footer_of_megabytes_is_refused_unread(knob_recording: Path, tmp_path: Path) -> None:
    import pyarrow.parquet as pq

    episode = copy_episode(knob_recording, tmp_path)
    table = pq.read_table(episode / "states.parquet")
    pq.write_table(table.replace_schema_metadata({"pad": "x" * 2**21}), episode / "states.parquet")
    reseal(episode)
    with pytest.raises(EpisodeError, match=r"states.parquet: its Parquet footer declares [\d,]+ bytes, more than an "
                                           r"episode's \(4,194,304 at most; rik writes a few kB\); refused unread$"):
        read_episode(episode)


def test_a_file_larger_than_its_rows_can_take_is_refused_unread(knob_recording: Path, tmp_path: Path) -> None:
    """32 MiB where 7 rows can take about 19 MiB (a column's bound per column, and a footer's)."""
    episode = copy_episode(knob_recording, tmp_path)
    (episode / "states.parquet").write_bytes(bytes(32 * 2**20))
    reseal(episode)
    with pytest.raises(EpisodeError, match=r"states.parquet: more than [\d,]+ bytes, more than 7 rows of this episode "
                                           r"\(its meta.json's steps and state_size\) can take; refused unread$"):
        read_episode(episode)


def test_an_ordinary_episode_reads_the_same_arrays(knob_recording: Path, tmp_path: Path) -> None:
    """The recorded episode read whole, by columns, for a render and for an export gives the arrays pyarrow reads
    from the file; so does one written with other Parquet settings (pages of version 2, small pages, no dictionary,
    several row groups, no compression); and it still replays exactly."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    from rik.episodes.recorded import RecordedEpisode
    from rik.episodes.replay import verify_episode
    from rik.exporters.lerobot_frames import load_episode

    episode = copy_episode(knob_recording, tmp_path)
    file = pq.read_table(episode / "states.parquet")
    meta, table = read_episode(episode)
    assert table.equals(file) and meta == read_meta(episode)
    assert read_episode(episode, ("opening", "state"))[1].column_names == ["opening", "state"]
    assert np.array_equal(states(read_episode(episode, ("state",))[1]), states(file))
    assert np.array_equal(RecordedEpisode(episode).states, states(file))
    loaded = load_episode(builtin_catalog(), episode)
    action = np.asarray(file.column("action").to_pylist())
    assert np.array_equal(loaded.actions, action) and np.array_equal(loaded.recorded.states, states(file))
    assert verify_episode(builtin_catalog(), episode, knob_recording / "variants").exact
    rows = 5000
    rng = np.random.default_rng(0)
    columns = {f.name: (pa.FixedSizeListArray.from_arrays(pa.array(rng.standard_normal(rows * f.type.list_size)),
                                                          f.type.list_size) if pa.types.is_fixed_size_list(f.type)
                        else pa.array(np.arange(rows, dtype=np.int32)) if pa.types.is_integer(f.type)
                        else pa.array(rng.standard_normal(rows)))
               for f in file.schema}
    other = pa.table(columns, schema=file.schema)
    for settings in ({"data_page_version": "2.0", "compression": "snappy", "row_group_size": 1500},
                     {"use_dictionary": False, "data_page_size": 4096, "compression": "none"}):
        pq.write_table(other, episode / "states.parquet", **settings)
        reseal(episode, steps=rows - 1)
        assert read_episode(episode)[1].equals(other), settings
