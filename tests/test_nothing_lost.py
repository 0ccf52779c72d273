"""Nothing lost (issue 29): rik replaces or removes only folders it made, and bad measured data is one line, exit 2,
no traceback and nothing written.

Folders: a report, simulated trials, the demo's folders, an image stream, a variant and an episode are replaced only
when rik recognises them as its own (:class:`rik.paths.MadeFolder`: the file rik writes into each, and nothing else
there but the names rik writes); anything else is refused before any work, and the user's files stay as they were.

Measured data: files that are not UTF-8, time in the wrong unit or with a jump (which made resampling allocate
terabytes), files too large, LeRobot datasets with malformed ``info.json`` or columns, a ``summary.json`` of the
wrong shape and settings that are not numbers.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from rik.errors import RikError
from rik.registry import load_catalog

KNOB = "drawer-bedside-45__knob-mushroom-30__normal"


def tree(root: Path) -> dict[str, bytes | None]:
    """Every entry under ``root`` (hidden ones too) with a file's bytes: what must stay as it was."""
    return {p.relative_to(root).as_posix(): (p.read_bytes() if p.is_file() else None)
            for p in sorted(root.rglob("*"))}


def one_line(err: str) -> str:
    """The single ``rik: error:`` line of ``err`` (and that there is nothing else: no traceback)."""
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("rik: error: "), err
    return lines[0]


@pytest.fixture(scope="module")
def trials():
    """Three simulated trials of a drawer with a self-closing spring (what ``rik sysid simulate`` writes)."""
    from rik.sysid.synthetic.generate import random_truth, simulate_trials

    truth = random_truth("self_close", "slide", np.random.default_rng(3))
    return simulate_trials(truth, n_trials=3, seed=3), truth


def measured(folder: Path, trials) -> list[str]:
    """The trials as a user's measured CSV files in ``folder`` (with a notes file beside them)."""
    from rik.sysid.trials import write_csv_trials

    made, truth = trials
    paths = write_csv_trials(made, folder, truth.joint)
    (folder / "notes.txt").write_text("measured on the bench, 2024-05-02\n")
    return [str(p) for p in paths]


# ---------------------------------------------------------------------------------------- folders rik replaces

def test_fit_report_into_the_data_folder_keeps_the_data(rik, trials, tmp_path: Path) -> None:
    data = tmp_path / "data"
    files = measured(data, trials)
    before = tree(tmp_path)
    res = rik("sysid", "fit", *files, "--report", str(data))
    assert res.code == 2
    line = one_line(res.err)
    assert f"{data}: exists and is not a report of rik sysid fit (it holds notes.txt, trial_1.csv" in line
    assert "choose another --report, or move or remove it yourself" in line
    assert tree(tmp_path) == before  # the data, and no staging folder beside it


def test_fit_report_onto_a_data_file_keeps_it(rik, trials, tmp_path: Path) -> None:
    files = measured(tmp_path / "data", trials)
    before = tree(tmp_path)
    res = rik("sysid", "fit", *files, "--report", files[0])
    assert res.code == 2 and f"{files[0]}: is a file, not a report of rik sysid fit" in one_line(res.err)
    assert tree(tmp_path) == before


def test_a_report_is_replaced_but_not_once_it_holds_a_file_of_the_user(rik, trials, tmp_path: Path) -> None:
    files = measured(tmp_path / "data", trials)
    report = tmp_path / "report"
    assert rik("sysid", "fit", *files, "--report", str(report)).code == 0
    assert rik("sysid", "fit", *files, "--report", str(report)).code == 0  # rik's own report: replaced
    (report / "my-notes.md").write_text("the spring is the runner's\n")
    before = tree(tmp_path)
    res = rik("sysid", "fit", *files, "--report", str(report))
    assert res.code == 2 and "(it holds breakaway.png, my-notes.md, report.md and 5 more)" in one_line(res.err)
    assert tree(tmp_path) == before


def test_quasi_static_report_into_the_data_folder_keeps_the_data(rik, tmp_path: Path) -> None:
    data = tmp_path / "data"
    data.mkdir()
    rows = "".join(f"{trial},{q},{2 + 0.01 * q + 0.1 * trial}\n" for trial in range(4) for q in range(0, 90, 2))
    (data / "door.csv").write_text("trial,position [deg],torque [N·m]\n" + rows)
    before = tree(tmp_path)
    res = rik("sysid", "fit", str(data / "door.csv"), "--joint", "hinge", "--report", str(data))
    assert res.code == 2 and "is not a report of rik sysid fit (it holds door.csv)" in one_line(res.err)
    assert tree(tmp_path) == before


def test_report_into_the_current_folder_is_one_line(rik, trials, tmp_path: Path, monkeypatch) -> None:
    files = measured(tmp_path / "data", trials)
    here = tmp_path / "empty"
    here.mkdir()
    monkeypatch.chdir(here)
    res = rik("sysid", "fit", *files, "--report", ".")
    assert res.code == 2 and ".: is the current folder or holds it" in one_line(res.err)
    assert not any(tmp_path.rglob(".*partial"))


def test_simulate_into_a_folder_of_measurements_keeps_them(rik, trials, tmp_path: Path) -> None:
    data = tmp_path / "data"
    measured(data, trials)
    before = tree(tmp_path)
    res = rik("sysid", "simulate", "--out", str(data), "--trials", "2", "--duration", "2")
    assert res.code == 2
    assert f"{data}: exists and is not a folder of trials rik sysid simulate wrote" in one_line(res.err)
    assert tree(tmp_path) == before


def test_simulate_replaces_its_own_folder_whole(rik, tmp_path: Path) -> None:
    out = tmp_path / "sim"
    assert rik("sysid", "simulate", "--out", str(out), "--trials", "3", "--duration", "2").code == 0
    res = rik("sysid", "simulate", "--out", str(out), "--trials", "2", "--duration", "2", "--seed", "1")
    assert res.code == 0, res.err
    assert sorted(p.name for p in out.iterdir()) == ["trial_1.csv", "trial_2.csv", "truth.json"]  # no stale trial_3
    assert sorted(p.name for p in tmp_path.iterdir()) == ["sim"]


def test_demo_sysid_keeps_folders_it_did_not_make(tmp_path: Path, monkeypatch) -> None:
    from rik.cli.sysid import DEMO_CATALOG, DEMO_DATA, print_demo_sysid

    monkeypatch.chdir(tmp_path)
    for folder in (DEMO_DATA, DEMO_CATALOG):
        (tmp_path / folder).mkdir()
        (tmp_path / folder / "mine.yaml").write_text("presets: []\n")
        before = tree(tmp_path)
        with pytest.raises(RikError, match=rf"^{folder}: exists and is not .* \(it holds mine.yaml\); rik replaces "
                                            r"only folders it made, so nothing was written: run the demo in"):
            print_demo_sysid([])
        assert tree(tmp_path) == before
        (tmp_path / folder / "mine.yaml").unlink()
        (tmp_path / folder).rmdir()


@pytest.mark.slow
def test_demo_sysid_twice_replaces_its_own_folders(tmp_path: Path, monkeypatch, capsys) -> None:
    from rik.cli.sysid import DEMO_CATALOG, DEMO_DATA, DEMO_REPORT, print_demo_sysid

    monkeypatch.chdir(tmp_path)
    print_demo_sysid([])
    first = {f: tree(tmp_path / f) for f in (DEMO_DATA, DEMO_REPORT, DEMO_CATALOG)}
    out = capsys.readouterr().out
    print_demo_sysid([])
    assert capsys.readouterr().out == out
    assert {f: tree(tmp_path / f) for f in (DEMO_DATA, DEMO_REPORT, DEMO_CATALOG)} == first
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(str(f) for f in (DEMO_DATA, DEMO_REPORT, DEMO_CATALOG))


@pytest.mark.parametrize("name", ["datasets/rik-demo", "datasets/rik-demo.partial"])
def test_demo_export_keeps_a_dataset_folder_of_the_user(tmp_path: Path, monkeypatch, name: str) -> None:
    from rik.cli.export import DEMO_DATASET, print_demo_export

    monkeypatch.chdir(tmp_path)
    (tmp_path / name / "meta").mkdir(parents=True)
    (tmp_path / name / "meta" / "info.json").write_text('{"fps": 30}\n')  # a LeRobot dataset, not rik's
    before = tree(tmp_path)
    with pytest.raises(RikError, match=rf"^{name}: exists and is not .*run the demo in another folder"):
        print_demo_export([], [], out=DEMO_DATASET)
    assert tree(tmp_path) == before


def test_stream_folder_of_the_user_is_not_replaced(tmp_path: Path) -> None:
    from rik.render.streams import StreamSpec, StreamWriter, stream_dir

    final = stream_dir(tmp_path, "ep", StreamSpec("sim", 8, 8))
    final.mkdir(parents=True)
    (final / "front").mkdir()
    (final / "front" / "holiday.png").write_bytes(b"\x89PNG not rik's")
    before = tree(tmp_path)
    with pytest.raises(RikError, match=r"is not an image stream rik rendered \(it holds front\)"):
        writer = StreamWriter(final, StreamSpec("sim", 8, 8), ["front"], 1, "0" * 64)
        writer.write(0, "front", np.zeros((8, 8, 3), np.uint8))
        writer.publish({})
    assert tree(tmp_path) == before


def test_variant_folder_of_the_user_is_not_replaced(tmp_path: Path) -> None:
    from rik.combinator.build import build_variant
    from rik.registry.ids import parse_variant_id

    cat = load_catalog()
    (tmp_path / KNOB).mkdir()
    (tmp_path / KNOB / "model.xml").write_text("<mujoco model='mine'/>\n")
    before = tree(tmp_path)
    with pytest.raises(RikError, match=rf"{KNOB}: exists and is not a variant rik built \(it holds model.xml\)"):
        build_variant(cat, parse_variant_id(cat, KNOB), tmp_path)
    assert tree(tmp_path) == before


def test_manifest_of_the_user_in_variants_out_is_not_overwritten(rik, tmp_path: Path) -> None:
    out = tmp_path / "work"
    out.mkdir()
    (out / "manifest.json").write_text('{"files": ["a.step"]}\n')
    before = tree(tmp_path)
    res = rik("variants", "build", KNOB, "--out", str(out), "--collision", "hull")
    assert res.code == 2
    assert f"{out / 'manifest.json'}: exists and is not the manifest of rik variants build" in one_line(res.err)
    assert tree(tmp_path) == before


def test_episode_folder_of_the_user_is_not_replaced(tmp_path: Path) -> None:
    from rik.combinator.build import ensure_variant
    from rik.episodes.episode import episode_id
    from rik.episodes.record import record

    cat = load_catalog()
    variants = tmp_path / "variants"
    variants.mkdir()
    (variants / "collision.json").write_text('{"collision": "hull"}\n')  # quick to build
    ensure_variant(cat, KNOB, variants)
    out = tmp_path / "episodes"
    mine = out / episode_id(KNOB, "drawer", "grasp_vertical", 0)
    mine.mkdir(parents=True)
    (mine / "meta.json").write_text('{"mine": true}\n')
    (mine / "video.mp4").write_bytes(b"not rik's")
    before = tree(out)
    with pytest.raises(RikError, match=r"is not an episode rik recorded \(it holds meta.json, video.mp4\)"):
        record(cat, KNOB, "grasp_vertical", out=out, variants=variants, max_seconds=0.2)
    assert tree(out) == before


def test_bench_keeps_a_table_of_the_user(rik, tmp_path: Path) -> None:
    out = tmp_path / "paper"
    out.mkdir()
    (out / "table.md").write_text("| handle | F | P | S |\n|---|---:|---:|---:|\n| knob | 0.1 | 0.2 | 0.7 |\n")
    before = tree(tmp_path)
    res = rik("bench", "--types", "knob", "--presets", "smooth", "--strategies", "grasp_vertical", "-n", "1",
              "--workers", "1", "--variants", str(tmp_path / "variants"), "--out", str(out))
    assert res.code == 2
    assert one_line(res.err) == (f"rik: error: {out / 'table.md'}: exists and was not written by rik bench (no "
                                 "results.csv of its own beside it), so nothing was run: choose another --out, or "
                                 "move it away yourself")
    assert tree(tmp_path) == before


# ------------------------------------------------------------------------------------------- bad measured data

def write_columns(path: Path, header: str, rows: np.ndarray) -> str:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(header + "\n" + "".join(",".join(repr(float(v)) for v in row) + "\n" for row in rows))
    return str(path)


def trial_rows(trials, scale_time: float = 1.0, jump_after: float | None = None) -> np.ndarray:
    """The first trial's rows (time, position, force), its time multiplied by ``scale_time`` and, after
    ``jump_after`` s, shifted by 10⁹ s."""
    t = trials[0][0].t * scale_time
    if jump_after is not None:
        t = np.where(trials[0][0].t > jump_after, t + 1e9, t)
    return np.column_stack([t, trials[0][0].q, trials[0][0].f])


def test_csv_that_is_not_utf8_is_one_line(rik, tmp_path: Path) -> None:
    data = tmp_path / "latin1.csv"
    data.write_bytes("time [s],position [m],force [N]\n0,0.1,1\n0.01,0.1,1 # Kraft in µN\n".encode("latin-1"))
    res = rik("sysid", "fit", str(data), "--report", str(tmp_path / "report"))
    assert res.code == 2
    assert one_line(res.err) == f"rik: error: {data}: not a UTF-8 text file; expected CSV with a header line"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["latin1.csv"]


@pytest.mark.parametrize("scale, unit, advice", [
    (1e9, "ns", "if it is in ns, convert it to s or ms (rik reads time in s or ms)"),
    (1e6, "µs", "if it is in µs, convert it to s or ms"),
    (1e3, "ms", "if it is in ms, write the header as 'time [ms]' or pass --time-unit ms"),
])
def test_time_in_another_unit_names_the_likely_one(rik, trials, tmp_path: Path, scale: float, unit: str,
                                                     advice: str) -> None:
    data = write_columns(tmp_path / f"time_{unit}.csv", "time [s],position [m],force [N]", trial_rows(trials, scale))
    res = rik("sysid", "fit", data, "--report", str(tmp_path / "report"))
    assert res.code == 2
    line = one_line(res.err)
    assert line.startswith(f"rik: error: {data}, trial 'time_{unit}', column 'time [s]': samples are ") and advice in line
    assert not (tmp_path / "report").exists() and not list(tmp_path.glob(".*"))


def test_time_that_jumps_is_refused_before_resampling(rik, trials, tmp_path: Path) -> None:
    data = write_columns(tmp_path / "jump.csv", "time [s],position [m],force [N]", trial_rows(trials, jump_after=5.0))
    res = rik("sysid", "fit", data, "--report", str(tmp_path / "report"))
    assert res.code == 2
    line = one_line(res.err)
    assert f"{data}, trial 'jump', column 'time [s]': the trial spans 1e+09 s" in line
    assert "the time jumps by 1e+09 s after sample" in line and "check the time column's unit" in line
    assert not (tmp_path / "report").exists()


def test_too_large_csv_is_refused_before_reading(rik, tmp_path: Path) -> None:
    data = tmp_path / "huge.csv"
    data.write_text("time [s],position [m],force [N]\n0,0,0\n")
    os.truncate(data, 256 * 2**20 + 1)  # sparse: no disk used
    res = rik("sysid", "fit", str(data), "--report", str(tmp_path / "report"))
    assert res.code == 2
    assert one_line(res.err) == (f"rik: error: {data}: 256 MiB, more than rik reads from one CSV file (256 MiB); "
                                 "split it (by trial) or downsample it")


def test_parquet_with_too_many_rows_is_refused_before_reading(rik, tmp_path: Path) -> None:
    n = 5_000_001
    t = np.arange(n) / 1000
    data = tmp_path / "long.parquet"
    pq.write_table(pa.table({"time [s]": t, "position [m]": np.zeros(n), "force [N]": np.cos(t)}), data)
    res = rik("sysid", "fit", str(data), "--report", str(tmp_path / "report"))
    assert res.code == 2
    assert one_line(res.err) == (f"rik: error: {data}: more than 5,000,000 data rows (5,000,001); split the file "
                                 "(by trial) or downsample it")


@pytest.mark.parametrize("cell, what", [("nan", "NaN"), ("inf", "inf"), ("", "empty")])
def test_nan_inf_and_empty_cells_are_one_line(rik, trials, tmp_path: Path, cell: str, what: str) -> None:
    rows = trial_rows(trials).tolist()
    lines = ["time [s],position [m],force [N]"] + [f"{t!r},{q!r},{f!r}" for t, q, f in rows]
    lines[101] = f"{rows[100][0]!r},{cell},{rows[100][2]!r}"
    data = tmp_path / "cells.csv"
    data.write_text("\n".join(lines) + "\n")
    res = rik("sysid", "fit", str(data), "--report", str(tmp_path / "report"))
    assert res.code == 2
    assert one_line(res.err) == (f"rik: error: {data}, trial 'cells', column 'position [m]': row 100 (line 102) is "
                                 f"{what}; every value must be a finite number")


def test_empty_file_is_one_line_without_a_guess(rik, tmp_path: Path) -> None:
    data = tmp_path / "empty.csv"
    data.write_text("")
    res = rik("sysid", "fit", str(data), "--report", str(tmp_path / "report"))
    assert res.code == 2 and res.out == ""  # no "reading the data as a quasi-static profile" first
    assert one_line(res.err) == (f"rik: error: {data}: empty file; the first line must be a header such as "
                                 "'time [s],position [m],force [N]'")


@pytest.mark.parametrize("setting", ["nan", "inf", "1e300"])
def test_delay_that_is_not_a_duration_is_one_line(rik, trials, tmp_path: Path, setting: str) -> None:
    data = write_columns(tmp_path / "d.csv", "time [s],position [m],force [N]", trial_rows(trials))
    res = rik("sysid", "fit", data, "--delay", setting, "--report", str(tmp_path / "report"))
    assert res.code == 2
    expected = ("preprocessing setting delay_s (--delay) must be a number of seconds shorter than the trial"
                if setting == "1e300" else f"--delay: {setting} is not a finite number")  # nan, inf: at the option
    assert expected in one_line(res.err)
    assert not (tmp_path / "report").exists()


def lerobot(root: Path, trials, info: dict | None = None, columns: dict | None = None) -> Path:
    """A LeRobot v3.0 dataset of the first trial (meta/info.json and one data file), with ``info`` and
    ``columns`` replacing its own."""
    trial = trials[0][0]
    n = trial.samples
    (root / "meta").mkdir(parents=True)
    (root / "data" / "chunk-000").mkdir(parents=True)
    base = {"fps": 200, "features": {"observation.state": {"dtype": "float32", "shape": [1]},
                                     "action": {"dtype": "float32", "shape": [1]}}}
    (root / "meta" / "info.json").write_text(json.dumps({**base, **(info or {})}))
    table = {"observation.state": pa.array(trial.q[:, None].tolist(), pa.list_(pa.float32())),
             "action": pa.array(trial.f[:, None].tolist(), pa.list_(pa.float32())),
             "timestamp": pa.array(trial.t, pa.float32()), "frame_index": pa.array(range(n), pa.int64()),
             "episode_index": pa.array([0] * n, pa.int64())}
    table.update(columns or {})
    pq.write_table(pa.table({k: v for k, v in table.items() if v is not None}),
                   root / "data" / "chunk-000" / "file-000.parquet")
    return root


LEROBOT_FAULTS = {
    "fps_text": ({"fps": "fast"}, None, "meta/info.json: field 'fps' must be a positive number of frames per "
                                        "second, got 'fast'"),
    "feature_text": ({"features": {"observation.state": "float", "action": {"shape": [1]}}}, None,
                     "meta/info.json, column 'observation.state[0]': feature 'observation.state' is malformed"),
    "shape_text": ({"features": {"observation.state": {"shape": "1"}, "action": {"shape": [1]}}}, None,
                   "meta/info.json, column 'observation.state[0]': feature 'observation.state' is malformed"),
    "timestamp_text": (None, {"timestamp": lambda n: pa.array([f"{i / 200}" for i in range(n)])},
                       "column 'timestamp': column 'timestamp' holds string values, not numbers"),
    "episode_text": (None, {"episode_index": lambda n: pa.array(["a"] * n)},
                     "column 'episode_index': must be whole numbers in every row, got string"),
    "action_missing": (None, {"action": lambda n: None},
                       "column 'action[0]': no column 'action' in the data file"),
}


@pytest.mark.parametrize("fault", sorted(LEROBOT_FAULTS))
def test_lerobot_dataset_faults_are_one_line(rik, trials, tmp_path: Path, fault: str) -> None:
    info, columns, message = LEROBOT_FAULTS[fault]
    n = trials[0][0].samples
    root = lerobot(tmp_path / "ds", trials, info, {k: f(n) for k, f in (columns or {}).items()})
    res = rik("sysid", "fit", str(root), "--position", "observation.state[0]", "--position-unit", "m",
              "--force", "action[0]", "--force-unit", "N", "--report", str(tmp_path / "report"))
    assert res.code == 2
    line = one_line(res.err)
    assert line.startswith(f"rik: error: {root}/") and message in line
    assert not (tmp_path / "report").exists()


def test_summary_with_a_joint_that_is_no_name_is_one_line(rik, tmp_path: Path) -> None:
    report = tmp_path / "report"
    report.mkdir()
    (report / "summary.json").write_text('{"format": 1, "joint": ["slide"]}\n')
    res = rik("sysid", "apply", str(report), "--as-preset", "mine", "--catalog-dir", str(tmp_path / "cat"))
    assert res.code == 2
    assert one_line(res.err) == f"rik: error: {report / 'summary.json'}: field 'joint' must be slide or hinge, got ['slide']"
    assert not (tmp_path / "cat").exists()


DEEP = "[" * 100_000 + "]" * 100_000
"""JSON nested deeper than Python's parser goes (it raised RecursionError)."""


def test_json_nested_too_deeply_is_one_line(rik, trials, tmp_path: Path) -> None:
    from rik.sysid.synthetic.generate import read_truth

    report = tmp_path / "report"
    report.mkdir()
    (report / "summary.json").write_text(DEEP)
    res = rik("sysid", "apply", str(report), "--as-preset", "mine", "--catalog-dir", str(tmp_path / "cat"))
    assert res.code == 2
    assert one_line(res.err) == f"rik: error: {report / 'summary.json'}: not valid JSON (nested too deeply)"
    root = lerobot(tmp_path / "ds", trials)
    (root / "meta" / "info.json").write_text(DEEP)
    res = rik("sysid", "fit", str(root), "--position", "observation.state[0]", "--position-unit", "m",
              "--force", "action[0]", "--force-unit", "N", "--report", str(tmp_path / "out"))
    assert res.code == 2
    assert one_line(res.err) == f"rik: error: {root / 'meta' / 'info.json'}: not valid JSON (nested too deeply)"
    (report / "truth.json").write_text(DEEP)
    with pytest.raises(RikError, match=r"truth.json: cannot read the ground truth \(nested too deeply\)$"):
        read_truth(report)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ds", "report"]


def test_ground_truth_that_is_not_utf8_names_the_file(tmp_path: Path) -> None:
    from rik.sysid.synthetic.generate import read_truth

    (tmp_path / "truth.json").write_bytes(b'{"joint": "slide", "note": "\xb5"}')
    with pytest.raises(RikError, match=rf"^{tmp_path / 'truth.json'}: cannot read the ground truth \('utf-8' codec"):
        read_truth(tmp_path)
    (tmp_path / "truth.json").write_text('{"joint": "slide"}')
    with pytest.raises(RikError, match=rf"^{tmp_path / 'truth.json'}: ground truth lacks"):
        read_truth(tmp_path)


@pytest.mark.slow
def test_resuming_a_finished_export_says_it_is_complete(rik, tmp_path: Path) -> None:
    """``export-lerobot --resume`` into a finished export: "already complete", not "not a rik export" (rik's card
    fields live in ``meta/``), and the dataset is left as it was."""
    from rik.episodes.record import record

    cat = load_catalog()
    record(cat, KNOB, "grasp_vertical", seed=3, out=tmp_path / "episodes", variants=tmp_path / "variants",
           max_seconds=0.3)
    out = tmp_path / "ds"
    args = ["export-lerobot", str(tmp_path / "episodes"), "--out", str(out), "--repo-id", "local/done", "--streams",
            "none", "--variants", str(tmp_path / "variants"), "--renders", str(tmp_path / "renders")]
    assert rik(*args).code == 0
    before = tree(out)
    res = rik(*args, "--resume")
    assert one_line(res.err) == f"rik: error: {out}: the export is already complete (nothing to resume); choose another --out " \
                                "to export again" and res.code == 2
    assert tree(out) == before
