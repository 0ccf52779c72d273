"""Measured data in and preprocessing (``rik.sysid.trials``, ``rik.sysid.preprocess``) on synthetic trials: a
mass-damper-Coulomb drawer simulated with numpy, pushed by an impedance controller between waypoints with holds,
logged at 200 Hz with noise and a known force-to-position delay."""

from __future__ import annotations

import functools
import json
import math

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from rik.errors import RikError
from rik.sysid.preprocess import observed_limits, preprocess, resample, uniform_grid
from rik.sysid.trials import ColumnMap, Trial, TrialError, load_lerobot_trials, load_trials

# ------------------------------------------------------------------------------------------- synthetic truth

M, C, FC = 6.0, 4.0, 3.0  # kg, N·s/m, N
FINE_DT = 1e-3  # s: the simulation step, finer than the 200 Hz log
RATE = 200.0  # Hz
WAYPOINTS = (0.02, 0.30, 0.10, 0.385, 0.05, 0.25, 0.015)  # m; the ends come near the limits (0, 0.4)


def _min_jerk(s: np.ndarray) -> np.ndarray:
    return 10 * s**3 - 15 * s**4 + 6 * s**5


@functools.cache
def simulate() -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(t s, x m, v m/s, f N) on a 1 ms grid: moves of 0.8 s then holds of 0.5 s, where Coulomb friction sticks
    the drawer short of the target while the controller still pushes (stick phases with a force)."""
    move, hold = 0.8, 0.5
    t = np.arange(int((len(WAYPOINTS) - 1) * (move + hold) / FINE_DT)) * FINE_DT
    seg = np.minimum((t // (move + hold)).astype(int), len(WAYPOINTS) - 2)
    s = np.clip((t - seg * (move + hold)) / move, 0, 1)
    w = np.asarray(WAYPOINTS)
    ref = w[seg] + (w[seg + 1] - w[seg]) * _min_jerk(s)
    x, v = WAYPOINTS[0], 0.0
    xs, vs, fs = np.empty_like(t), np.empty_like(t), np.empty_like(t)
    for i in range(len(t)):
        f = 400.0 * (ref[i] - x) - 60.0 * v
        xs[i], vs[i], fs[i] = x, v, f
        if v == 0.0 and abs(f) <= FC:
            continue  # stuck: static friction holds the applied force
        direction = math.copysign(1.0, v) if v != 0.0 else math.copysign(1.0, f)
        new = v + FINE_DT * (f - C * v - FC * direction) / M
        v = 0.0 if v != 0.0 and new * v < 0 else new
        x += v * FINE_DT
    return t, xs, vs, fs


def record(delay: float, q_noise: float = 1e-4, f_noise: float = 0.2, seed: int = 0) -> dict[str, np.ndarray]:
    """The simulation logged at 200 Hz: the position is recorded ``delay`` s later than the force (its sample
    at time t is the state at t − delay). Also returns the true state behind each position sample."""
    t, x, v, f = simulate()
    rng = np.random.default_rng(seed)
    lag = int(round(delay / FINE_DT))
    step = int(round(1 / (RATE * FINE_DT)))
    idx = np.arange(max(lag, 0), len(t) - max(-lag, 0), step)
    return {"t": t[idx], "q": x[idx - lag] + rng.normal(0, q_noise, idx.size),
            "f": f[idx] + rng.normal(0, f_noise, idx.size), "x_true": x[idx - lag], "v_true": v[idx - lag],
            "f_true": f[idx - lag]}


# ------------------------------------------------------------------------------------------------ file helpers

def write_csv(path, columns: dict[str, list | np.ndarray]) -> None:
    names = list(columns)
    rows = zip(*(columns[n] for n in names), strict=True)
    body = "\n".join(",".join(v if isinstance(v, str) else repr(float(v)) for v in row) for row in rows)
    path.write_text(",".join(names) + "\n" + body + "\n", encoding="utf-8")


def write_parquet(path, columns: dict[str, list | np.ndarray]) -> None:
    pq.write_table(pa.table({k: (list(v) if isinstance(v, list) else np.asarray(v)) for k, v in columns.items()}),
                   path)


def clean(n: int = 100) -> dict[str, np.ndarray]:
    """A plain good trial in SI units: 200 Hz, a sine stroke of ±50 mm and a force of ±5 N."""
    t = np.arange(n) / RATE
    return {"time [s]": t, "position [m]": 0.1 + 0.05 * np.sin(2 * np.pi * t),
            "force [N]": 5 * np.sin(2 * np.pi * t + 0.3)}


def message(paths, joint: str = "slide") -> str:
    with pytest.raises(RikError) as info:
        load_trials(paths, joint)
    text = str(info.value)
    assert "\n" not in text and isinstance(info.value, RikError)
    return text


# ------------------------------------------------------------------------------------------------ loading

def test_slide_units_convert_to_si(tmp_path) -> None:
    base = clean()
    path = tmp_path / "drawer.csv"
    write_csv(path, {"T [ms]": base["time [s]"] * 1e3, "Position [mm]": base["position [m]"] * 1e3,
                     "f [kN]": base["force [N]"] / 1e3, "velocity [cm/s]": np.full(100, 12.5)})
    (trial,) = load_trials(path, "slide")
    assert isinstance(trial, Trial) and trial.name == "drawer" and trial.source == str(path)
    np.testing.assert_allclose(trial.t, base["time [s]"], rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(trial.q, base["position [m]"], rtol=1e-12)
    np.testing.assert_allclose(trial.f, base["force [N]"], rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(trial.qd, 0.125, rtol=1e-12)
    meta = trial.meta
    assert (meta.units.time, meta.units.position, meta.units.force, meta.units.velocity) == ("ms", "mm", "kN", "cm/s")
    assert meta.columns.position == "Position [mm]" and meta.joint == "slide"
    assert meta.samples == 100 and meta.duration == pytest.approx(99 / RATE)
    assert not trial.q.flags.writeable


@pytest.mark.parametrize("unit, factor", [("N·mm", 1e-3), ("Nmm", 1e-3), ("N*mm", 1e-3), ("N·m", 1.0),
                                          ("Nm", 1.0), ("N*m", 1.0)])
def test_hinge_units_convert_to_si(tmp_path, unit: str, factor: float) -> None:
    t = np.arange(80) / 100.0
    deg = 40 * np.sin(np.pi * t)
    path = tmp_path / "door.parquet"
    write_parquet(path, {"time [s]": t, "q [deg]": deg, f"torque [{unit}]": 300 * np.cos(np.pi * t),
                         "qd [deg/s]": 40 * np.pi * np.cos(np.pi * t)})
    (trial,) = load_trials(path, "hinge")
    np.testing.assert_allclose(trial.q, np.radians(deg), rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(trial.f, 300 * factor * np.cos(np.pi * t), rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(trial.qd, np.radians(40 * np.pi * np.cos(np.pi * t)), rtol=1e-12, atol=1e-15)
    assert trial.joint == "hinge" and trial.meta.units.force == unit


def test_several_trials_in_one_file_and_several_files(tmp_path) -> None:
    base = clean(60)
    names = ["up"] * 60 + ["down"] * 60 + ["up2"] * 60
    cols = {k: np.concatenate([v, v * 2, v * 3]) for k, v in base.items()}
    cols["time [s]"] = np.concatenate([base["time [s]"]] * 3)
    # "up" continues after "down": rows of one trial need not be contiguous
    order = np.r_[0:30, 60:120, 30:60, 120:180]
    one = tmp_path / "strokes.csv"
    write_csv(one, {"trial": [names[i].replace("up2", "up3") for i in order],
                    **{k: v[order] for k, v in cols.items()}})
    other = tmp_path / "more.csv"
    write_csv(other, clean(70))
    trials = load_trials([one, other], "slide")
    assert [(t.name, t.samples, t.source) for t in trials] == [
        ("up", 60, str(one)), ("down", 60, str(one)), ("up3", 60, str(one)), ("more", 70, str(other))]
    np.testing.assert_array_equal(trials[0].q, base["position [m]"])
    np.testing.assert_array_equal(trials[1].f, base["force [N]"] * 2)
    np.testing.assert_array_equal(trials[2].q, base["position [m]"] * 3)


def test_csv_and_parquet_give_identical_trials(tmp_path) -> None:
    rec = record(0.03)
    cols = {"trial": ["a"] * 400 + ["b"] * (len(rec["t"]) - 400), "time [ms]": rec["t"] * 1e3,
            "position [mm]": rec["q"] * 1e3, "force [N]": rec["f"], "velocity [mm/s]": rec["v_true"] * 1e3}
    write_csv(tmp_path / "log.csv", cols)
    write_parquet(tmp_path / "log.parquet", cols)
    from_csv = load_trials(tmp_path / "log.csv", "slide")
    from_parquet = load_trials(tmp_path / "log.parquet", "slide")
    assert len(from_csv) == len(from_parquet) == 2
    for a, b in zip(from_csv, from_parquet, strict=True):
        for name in ("t", "q", "f", "qd"):
            np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
        assert a.meta.model_dump(exclude={"source"}) == b.meta.model_dump(exclude={"source"})


LOGGER = ColumnMap(time="timestamp_ms", time_unit="ms", position="enc_pos", position_unit="mm", force="ft_fx",
                   force_unit="N", velocity="enc_vel", velocity_unit="mm/s", trial="run")


@pytest.mark.parametrize("suffix", [".csv", ".parquet"])
def test_named_columns_with_declared_units(tmp_path, suffix: str) -> None:
    """A logger's own headers (no units; a counter 't' and a 'trial' column that must not be taken) read through a
    ColumnMap, into SI units."""
    base = clean(120)
    cols = {"t": np.arange(120.0), "trial": ["x"] * 120, "run": ["a"] * 60 + ["b"] * 60,
            "timestamp_ms": 1e3 * base["time [s]"], "enc_pos": 1e3 * base["position [m]"], "ft_fx": base["force [N]"],
            "enc_vel": np.full(120, 25.0)}
    path = tmp_path / f"log{suffix}"
    (write_csv if suffix == ".csv" else write_parquet)(path, cols)
    first, second = load_trials(path, "slide", columns=LOGGER)
    assert (first.name, second.name, first.samples) == ("a", "b", 60)
    np.testing.assert_allclose(np.r_[first.t, second.t], base["time [s]"], rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(np.r_[first.q, second.q], base["position [m]"], rtol=1e-12)
    np.testing.assert_allclose(np.r_[first.f, second.f], base["force [N]"], rtol=1e-12)
    np.testing.assert_allclose(first.qd, 0.025, rtol=1e-12)
    units, columns = first.meta.units, first.meta.columns
    assert (units.time, units.position, units.force, units.velocity) == ("ms", "mm", "N", "mm/s")
    assert (columns.time, columns.position, columns.force, columns.velocity) == ("timestamp_ms", "enc_pos", "ft_fx",
                                                                                "enc_vel")


def test_plain_headers_with_declared_units_and_names_matching_headers_with_units(tmp_path) -> None:
    base = clean()
    write_csv(tmp_path / "plain.csv", {"t": base["time [s]"], "q": 1e2 * base["position [m]"], "f": base["force [N]"]})
    (trial,) = load_trials(tmp_path / "plain.csv", "slide", columns=ColumnMap(time_unit="s", position_unit="cm",
                                                                              force_unit="N"))
    np.testing.assert_allclose(trial.q, base["position [m]"], rtol=1e-12)
    assert trial.meta.units.position == "cm" and trial.meta.columns.time == "t"
    # a name matches a header's name without its unit, case-insensitively; a unit option agreeing with the header's
    # (in any spelling) is fine, and brackets holding no unit of the quantity are just text
    cols = {"Time [ms]": 1e3 * base["time [s]"], "Angle [enc]": np.degrees(base["position [m]"]),
            "torque [Nm]": base["force [N]"]}
    write_csv(tmp_path / "door.csv", cols)
    (door,) = load_trials(tmp_path / "door.csv", "hinge", columns=ColumnMap(time="time", position="angle",
                                                                            position_unit="deg", force_unit="N·m"))
    np.testing.assert_allclose(door.t, base["time [s]"], rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(door.q, base["position [m]"], rtol=1e-12)
    assert (door.meta.units.time, door.meta.units.position, door.meta.units.force) == ("ms", "deg", "N·m")


@pytest.mark.parametrize("headers, columns, expected", [
    (["timestamp_ms", "enc_pos_mm", "ft_fx"], {"time_unit": "ms", "position": "enc_pos", "force_unit": "N"},
     "column 'enc_pos': no such column (--position); did you mean 'enc_pos_mm'? (columns: 'timestamp_ms', 'enc_pos_mm', 'ft_fx')"),
    (["time [s]", "q [m]", "ft_fx"], {"force": "load"},
     "column 'load': no such column (--force) (columns: 'time [s]', 'q [m]', 'ft_fx')"),
    (["time [s]", "q [m]", "f [N]"], {"trial": "run"},
     "column 'run': no such column (--trial) (columns: 'time [s]', 'q [m]', 'f [N]')"),
    (["time [s]", "enc_pos", "f [N]"], {"position": "enc_pos"},
     "column 'enc_pos': no unit in the header; pass --position-unit: a slide's position is in m, mm or cm"),
    (["t", "q", "f"], {"position_unit": "m", "force_unit": "N"},
     "column 't': no unit; write the header as 't [unit]' (e.g. 't [s]') or pass --time-unit: time is in s or ms"),
    (["t", "q", "f"], {"time_unit": "s", "position_unit": "deg", "force_unit": "N"},
     "column 'q': --position-unit: 'deg' is an angle unit but the joint is a slide; a slide's position is in m, mm or cm"),
    (["t", "q", "f"], {"time_unit": "s", "position_unit": "m", "force_unit": "lbf"},
     "column 'f': --force-unit: unknown unit 'lbf'; a slide's force is in N or kN"),
    (["time [s]", "position [mm]", "force [N]"], {"position_unit": "m"},
     "column 'position [mm]': the header says 'mm' but --position-unit says 'm'; drop the option or make them agree"),
    (["time [s]", "Time [ms]", "q [m]", "f [N]"], {"time": "time"},
     "column 'time': --time matches 'time [s]' and 'Time [ms]'; name one exactly"),
    (["time [s]", "q [m]", "f [N]"], {"velocity_unit": "m/s"},
     "--velocity-unit is given but the file has no velocity column; name it with --velocity"),
])
def test_bad_column_names_and_units(tmp_path, headers: list[str], columns: dict, expected: str) -> None:
    path = tmp_path / "c.csv"
    write_csv(path, {h: np.linspace(0, 1, 60) for h in headers})
    with pytest.raises(TrialError) as info:
        load_trials(path, "slide", columns=ColumnMap(**columns))
    sep = ": " if expected.startswith("--") else ", "
    assert str(info.value) == f"{path}{sep}{expected}"


def test_one_column_named_for_two_quantities() -> None:
    with pytest.raises(RikError) as info:
        ColumnMap(position="x", force="x")
    assert str(info.value) == "--position and --force both name column 'x'; each quantity needs its own column"


def lerobot_dataset(root, episodes: dict[int, dict[str, np.ndarray]], fps: int = 50) -> None:
    """A LeRobot v3.0 dataset as lerobot writes it (meta/info.json plus a data Parquet file), without video."""
    (root / "meta").mkdir(parents=True)
    (root / "data" / "chunk-000").mkdir(parents=True)
    info = {"codebase_version": "v3.0", "fps": fps, "robot_type": "test", "features": {
        "observation.state": {"dtype": "float32", "shape": [3], "names": ["tcp_x", "front_qpos", "front_qvel"]},
        "action": {"dtype": "float32", "shape": [2], "names": {"motors": ["push", "grip"]}},
        "timestamp": {"dtype": "float32", "shape": [1], "names": None},
        "frame_index": {"dtype": "int64", "shape": [1], "names": None},
        "episode_index": {"dtype": "int64", "shape": [1], "names": None},
        "index": {"dtype": "int64", "shape": [1], "names": None},
        "task_index": {"dtype": "int64", "shape": [1], "names": None}}}
    (root / "meta" / "info.json").write_text(json.dumps(info))
    state, action, stamp, frame, episode = [], [], [], [], []
    for ep, data in episodes.items():
        n = len(data["q"])
        state += [[0.5, q, qd] for q, qd in zip(data["q"], data["qd"], strict=True)]
        action += [[f, 1.0] for f in data["f"]]
        stamp += list(np.arange(n, dtype=np.float32) / np.float32(fps))
        frame += list(range(n))
        episode += [ep] * n
    rows = len(frame)
    table = pa.table({
        "observation.state": pa.array(state, pa.list_(pa.float32())), "action": pa.array(action, pa.list_(pa.float32())),
        "timestamp": pa.array(stamp, pa.float32()), "frame_index": pa.array(frame, pa.int64()),
        "episode_index": pa.array(episode, pa.int64()), "index": pa.array(range(rows), pa.int64()),
        "task_index": pa.array([0] * rows, pa.int64())})
    pq.write_table(table, root / "data" / "chunk-000" / "file-000.parquet")


def test_lerobot_episodes_become_trials(tmp_path) -> None:
    t = np.arange(100) / 50
    episodes = {0: {"q": 0.1 * np.sin(t), "qd": 0.1 * np.cos(t), "f": 5 * np.cos(t)},
                3: {"q": 20 * np.sin(t), "qd": 20 * np.cos(t), "f": -4 * np.cos(t)}}
    lerobot_dataset(tmp_path / "ds", episodes)
    trials = load_lerobot_trials(tmp_path / "ds", "slide", ColumnMap(
        position="observation.state[front_qpos]", position_unit="m", force="action[0]", force_unit="N",
        velocity="observation.state[2]", velocity_unit="m/s"))
    assert [t.name for t in trials] == ["episode_0", "episode_3"]
    for trial, ep in zip(trials, (0, 3), strict=True):
        np.testing.assert_array_equal(trial.q, episodes[ep]["q"].astype(np.float32))
        np.testing.assert_array_equal(trial.f, episodes[ep]["f"].astype(np.float32))
        np.testing.assert_array_equal(trial.qd, episodes[ep]["qd"].astype(np.float32))
        np.testing.assert_allclose(trial.t, t, atol=1e-6)
        assert trial.meta.columns.position == "observation.state[front_qpos]" and trial.meta.units.time == "s"
    (only,) = load_lerobot_trials(tmp_path / "ds", "hinge", ColumnMap(position="observation.state[1]",
                                  position_unit="deg", force="action[push]", force_unit="N·mm"), episodes=[3])
    np.testing.assert_allclose(only.q, np.radians(episodes[3]["q"].astype(np.float32).astype(np.float64)), rtol=1e-12)
    np.testing.assert_allclose(only.f, 1e-3 * episodes[3]["f"].astype(np.float32).astype(np.float64), rtol=1e-12)


def test_lerobot_time_feature_and_unit(tmp_path) -> None:
    t = np.arange(60) / 50
    lerobot_dataset(tmp_path / "ds", {0: {"q": np.sin(t), "qd": np.cos(t), "f": np.cos(t)}})
    refs = {"position": "observation.state[1]", "position_unit": "m", "force": "action[0]", "force_unit": "N"}
    (ms,) = load_lerobot_trials(tmp_path / "ds", "slide", ColumnMap(**refs, time_unit="ms"))
    np.testing.assert_allclose(ms.t, t / 1e3, atol=1e-9)
    assert (ms.meta.units.time, ms.meta.columns.time) == ("ms", "timestamp")
    (frames,) = load_lerobot_trials(tmp_path / "ds", "slide", ColumnMap(**refs, time="frame_index", time_unit="s"))
    np.testing.assert_array_equal(frames.t, np.arange(60))
    assert frames.meta.columns.time == "frame_index"


@pytest.mark.parametrize("kwargs, expected", [
    ({"position": "observation.stat[1]"},
     "{info}, column 'observation.stat[1]': no feature 'observation.stat' in the dataset; did you mean 'observation.state'?"),
    ({"position": "observation.state[5]"},
     "{info}, column 'observation.state[5]': index 5 is out of range; 'observation.state' holds 3 values (0 to 2)"),
    ({"position": "observation.state"},
     "{info}, column 'observation.state': 'observation.state' holds 3 values; name one as 'observation.state[index]' or 'observation.state[name]'"),
    ({"force": "action[gripper]"},
     "{info}, column 'action[gripper]': 'action' has no value named 'gripper' (names: push, grip)"),
    ({"position_unit": "deg"},
     "{root}, column 'observation.state[1]': --position-unit: 'deg' is an angle unit but the joint is a slide; a slide's position is in m, mm or cm"),
    ({"force_unit": None},
     "{root}, column 'action[0]': no unit (LeRobot records none); pass --force-unit: a slide's force is in N or kN"),
    ({"time": "timestamp"},
     "{root}, column 'timestamp': no unit (LeRobot records none); pass --time-unit: time is in s or ms"),
    ({"force": None}, "{root}: a LeRobot dataset needs --position and --force naming its features"),
    ({"trial": "run"},
     "{root}, column 'run': a LeRobot dataset's trials are its episodes (episode_index); --trial is for CSV and Parquet files"),
    ({"velocity_unit": "m/s"}, "{root}: --velocity-unit is given but no --velocity feature"),
])
def test_lerobot_bad_references(tmp_path, kwargs: dict, expected: str) -> None:
    t = np.arange(60) / 50
    lerobot_dataset(tmp_path / "ds", {0: {"q": np.sin(t), "qd": np.cos(t), "f": np.cos(t)}})
    args = {"position": "observation.state[1]", "position_unit": "m", "force": "action[0]", "force_unit": "N"}
    with pytest.raises(TrialError) as info:
        load_lerobot_trials(tmp_path / "ds", "slide", ColumnMap(**(args | kwargs)))
    assert str(info.value) == expected.format(info=tmp_path / "ds" / "meta" / "info.json", root=tmp_path / "ds")


def test_lerobot_bad_data_names_the_episode(tmp_path) -> None:
    t = np.arange(60) / 50
    q = np.sin(t)
    q[7] = np.nan
    lerobot_dataset(tmp_path / "ds", {0: {"q": np.sin(t), "qd": q, "f": np.cos(t)},
                                      1: {"q": q, "qd": q, "f": np.cos(t)}})
    with pytest.raises(TrialError) as info:
        load_lerobot_trials(tmp_path / "ds", "slide", ColumnMap(position="observation.state[1]", position_unit="m",
                                                               force="action[0]", force_unit="N"))
    file = tmp_path / "ds" / "data" / "chunk-000" / "file-000.parquet"
    assert str(info.value) == (f"{file}, trial 'episode_1', column 'observation.state[1]': row 67 is NaN; "
                               "every value must be a finite number")


# ------------------------------------------------------------------------------------------------ bad input

def test_nan(tmp_path) -> None:
    cols = clean()
    cols["position [m]"][7] = np.nan
    write_csv(tmp_path / "bad.csv", cols)
    assert message(tmp_path / "bad.csv") == (f"{tmp_path / 'bad.csv'}, trial 'bad', column 'position [m]': row 7 "
                                             "(line 9) is NaN; every value must be a finite number")


def test_inf_and_null_in_parquet(tmp_path) -> None:
    cols = clean()
    cols["force [N]"][12] = -np.inf
    write_parquet(tmp_path / "bad.parquet", cols)
    assert message(tmp_path / "bad.parquet") == (f"{tmp_path / 'bad.parquet'}, trial 'bad', column 'force [N]': "
                                                 "row 12 is -inf; every value must be a finite number")
    table = pa.table({"time [s]": clean()["time [s]"], "position [m]": clean()["position [m]"],
                      "force [N]": pa.array([1.0] * 5 + [None] + [2.0] * 94)})
    pq.write_table(table, tmp_path / "null.parquet")
    assert message(tmp_path / "null.parquet") == (f"{tmp_path / 'null.parquet'}, trial 'null', column 'force [N]': "
                                                  "row 5 is empty; every value must be a finite number")


def test_empty_csv_cell_in_a_later_trial(tmp_path) -> None:
    one, two = clean(), clean()
    cols = {"trial": ["first"] * 100 + ["second"] * 100,
            **{k: np.concatenate([one[k], two[k]]).astype(object) for k in one}}
    cols["force [N]"][130] = ""
    write_csv(tmp_path / "two.csv", cols)
    assert message(tmp_path / "two.csv") == (f"{tmp_path / 'two.csv'}, trial 'second', column 'force [N]': row 130 "
                                             "(line 132) is empty; every value must be a finite number")


def test_time_goes_back(tmp_path) -> None:
    cols = clean()
    cols["time [s]"][[40, 41]] = cols["time [s]"][[41, 40]]
    write_csv(tmp_path / "bad.csv", cols)
    assert message(tmp_path / "bad.csv") == (f"{tmp_path / 'bad.csv'}, trial 'bad', column 'time [s]': time goes "
                                             "back at row 41 (line 43): 0.2 s after 0.205 s; time must increase "
                                             "strictly within a trial")


def test_time_repeats(tmp_path) -> None:
    cols = clean()
    cols["time [ms]"] = cols.pop("time [s]") * 1000
    cols["time [ms]"][21] = cols["time [ms]"][20]
    write_parquet(tmp_path / "bad.parquet", cols)
    assert message(tmp_path / "bad.parquet") == (f"{tmp_path / 'bad.parquet'}, trial 'bad', column 'time [ms]': "
                                                 "time repeats at row 21: 100 ms twice; time must increase strictly "
                                                 "within a trial")


def test_too_few_samples(tmp_path) -> None:
    write_csv(tmp_path / "short.csv", clean(20))
    assert message(tmp_path / "short.csv") == (f"{tmp_path / 'short.csv'}, trial 'short': only 20 samples; a trial "
                                               "needs at least 50")


def test_no_motion(tmp_path) -> None:
    cols = clean()
    cols["position [mm]"] = 120 + 0.2 * np.sin(np.arange(100))
    del cols["position [m]"]
    write_csv(tmp_path / "still.csv", cols)
    lo, hi = cols["position [mm]"].min(), cols["position [mm]"].max()
    assert message(tmp_path / "still.csv") == (
        f"{tmp_path / 'still.csv'}, trial 'still', column 'position [mm]': no motion: the position spans "
        f"{hi - lo:.6g} mm (from {lo:.6g} to {hi:.6g} mm); a trial must move at least 1 mm")


def test_constant_force(tmp_path) -> None:
    cols = clean()
    cols["force [N]"] = np.full(100, 4.5)
    write_csv(tmp_path / "flat.csv", cols)
    assert message(tmp_path / "flat.csv") == (
        f"{tmp_path / 'flat.csv'}, trial 'flat', column 'force [N]': constant force: it spans 0 N (from 4.5 to "
        "4.5 N); a trial's force must vary by at least 0.01 N")


def test_constant_torque_threshold_in_declared_unit(tmp_path) -> None:
    cols = {"time [s]": clean()["time [s]"], "q [deg]": np.linspace(0, 30, 100), "torque [N·mm]": np.full(100, 200.0)}
    write_csv(tmp_path / "door.csv", cols)
    assert message(tmp_path / "door.csv", "hinge") == (
        f"{tmp_path / 'door.csv'}, trial 'door', column 'torque [N·mm]': constant torque: it spans 0 N·mm (from 200 "
        "to 200 N·mm); a trial's torque must vary by at least 1 N·mm")


@pytest.mark.parametrize("joint, header, problem", [
    ("hinge", "position [mm]", "'mm' is a length unit but the joint is a hinge; a hinge's position is in rad or deg"),
    ("slide", "torque [N·m]", "'N·m' is a torque unit but the joint is a slide; a slide's force is in N or kN"),
    ("hinge", "force [N]", "'N' is a force unit but the joint is a hinge; a hinge's torque is in N·m, Nm, N*m, N·mm, Nmm or N*mm"),
    ("slide", "velocity [deg/s]", "'deg/s' is an angular velocity unit but the joint is a slide; a slide's velocity is in m/s, mm/s or cm/s"),
    ("slide", "position", "no unit; write the header as 'position [unit]' (e.g. 'position [m]') or pass --position-unit: a slide's position is in m, mm or cm"),
    ("slide", "time []", "no unit; write the header as 'time [unit]' (e.g. 'time [s]') or pass --time-unit: time is in s or ms"),
    ("slide", "position [inch]", "unknown unit 'inch'; a slide's position is in m, mm or cm"),
    ("hinge", "time [h]", "unknown unit 'h'; time is in s or ms"),
])
def test_bad_units(tmp_path, joint: str, header: str, problem: str) -> None:
    good = {"slide": {"time": "time [s]", "position": "position [m]", "force": "force [N]"},
            "hinge": {"time": "time [s]", "position": "position [rad]", "force": "torque [N·m]"}}[joint]
    role = {"torque": "force"}.get(header.split()[0], header.split()[0])
    headers = [h for r, h in good.items() if r != role] + [header]
    write_csv(tmp_path / "u.csv", {h: np.linspace(0, 1, 60) for h in headers})
    assert message(tmp_path / "u.csv", joint) == f"{tmp_path / 'u.csv'}, column '{header}': {problem}"


@pytest.mark.parametrize("joint, headers, expected", [
    ("slide", ["time [s]", "force [N]"],
     "column 'position': missing; the file needs a position column named position or q with its unit, e.g. 'position [m]', or name it with --position (columns: 'time [s]', 'force [N]')"),
    ("hinge", ["t [s]", "q [rad]", "load [N·m]"],
     "column 'torque': missing; the file needs a torque column named torque or f with its unit, e.g. 'torque [N·m]', or name it with --force (columns: 't [s]', 'q [rad]', 'load [N·m]')"),
    ("slide", ["time [s]", "t [ms]", "q [m]", "f [N]"],
     "column 't [ms]': a second time column (besides 'time [s]'); keep one or name one with --time"),
])
def test_missing_or_doubled_columns(tmp_path, joint: str, headers: list[str], expected: str) -> None:
    write_csv(tmp_path / "c.csv", {h: np.linspace(0, 1, 60) for h in headers})
    assert message(tmp_path / "c.csv", joint) == f"{tmp_path / 'c.csv'}, {expected}"


def test_malformed_csv(tmp_path) -> None:
    path = tmp_path / "bad.csv"
    path.write_text("time [s],position [m],force [N]\n0,0,1\n0.01,0.1\n")
    assert message(path) == f"{path}: malformed CSV: line 3 has 2 fields but the header has 3"
    path.write_text("time [s],position [m],force [N]\n0,0,1\n0.01,0.1,lots\n")
    assert message(path) == f"{path}, column 'force [N]': malformed CSV: row 1 (line 3) holds 'lots', not a number"
    path.write_text("\n\n")
    assert message(path) == (f"{path}: empty file; the first line must be a header such as "
                             "'time [s],position [m],force [N]'")
    path.write_text("time [s],position [m],force [N]\n")
    assert message(path) == f"{path}: no data rows below the header"
    path.write_bytes(b"\xff\xfe\x00garbage")
    assert message(path) == f"{path}: not a UTF-8 text file; expected CSV with a header line"


def test_malformed_parquet(tmp_path) -> None:
    path = tmp_path / "bad.parquet"
    path.write_bytes(b"PAR1 this is not parquet")
    text = message(path)
    assert text.startswith(f"{path}: not a readable Parquet file (") and text.endswith(")")
    write_parquet(path, {**clean(), "position [m]": ["x"] * 100})
    assert message(path) == f"{path}, column 'position [m]': holds string values, not numbers"


def test_bad_paths_and_joint(tmp_path) -> None:
    assert message(tmp_path / "x.txt") == f"{tmp_path / 'x.txt'}: unknown file type '.txt'; use .csv, .parquet or .pq"
    assert message(tmp_path / "gone.csv") == f"{tmp_path / 'gone.csv'}: no such file"
    write_csv(tmp_path / "ok.csv", clean())
    assert message(tmp_path / "ok.csv", "prismatic") == "unknown joint type 'prismatic'; use 'slide' or 'hinge'"


# ------------------------------------------------------------------------------------------------ preprocessing

def make_trial(tmp_path, rec: dict[str, np.ndarray], name: str = "sim") -> Trial:
    write_parquet(tmp_path / f"{name}.parquet", {"time [s]": rec["t"], "position [m]": rec["q"], "force [N]": rec["f"]})
    (trial,) = load_trials(tmp_path / f"{name}.parquet", "slide")
    return trial


def test_resampling_preserves_a_sine() -> None:
    rng = np.random.default_rng(1)
    t = np.cumsum(rng.uniform(0.004, 0.006, 1000))  # jittered around 200 Hz
    signal = lambda x: 0.2 * np.sin(2 * np.pi * 2.0 * x + 0.4)  # noqa: E731
    for rate in (200.0, 500.0):
        grid = uniform_grid(t, rate)
        assert grid[0] == t[0] and t[-1] - 1 / rate < grid[-1] <= t[-1] and np.allclose(np.diff(grid), 1 / rate)
        # at or above the source rate values are interpolated: error ≤ A ω² dt² / 8 with dt ≤ 6 ms
        bound = 0.2 * (4 * np.pi) ** 2 * 0.006**2 / 8
        error = np.abs(resample(t, signal(t), grid) - signal(grid)).max()
        assert 0.02 * bound < error < bound
    # downsampling 1 kHz with noise to 100 Hz averages each interval: the sine stays (box filter gain at 2 Hz is
    # sinc(0.02) ≈ 0.9993) and the noise drops by about √10
    fine = np.arange(0, 5, 1e-3)
    noise = rng.normal(0, 0.01, fine.size)
    coarse = uniform_grid(fine, 100.0)
    error = resample(fine, signal(fine) + noise, coarse) - signal(coarse)
    assert np.abs(error[1:-1]).mean() < 0.01 * 0.8 / math.sqrt(10) * 1.5 and abs(error.mean()) < 1e-3


def test_default_rate_is_the_rounded_median(tmp_path) -> None:
    rec = record(0.0)
    jitter = np.random.default_rng(2).uniform(-4e-4, 4e-4, rec["t"].size)
    trial = make_trial(tmp_path, {**rec, "t": rec["t"] + jitter})
    prepared = preprocess(trial, delay_s=0.0)
    assert prepared.settings.rate_hz == 200.0 and np.allclose(np.diff(prepared.t), 1 / 200)
    assert preprocess(trial, 100.0, delay_s=0.0).settings.rate_hz == 100.0


def test_derivatives_of_a_known_function(tmp_path) -> None:
    """Cubic Savitzky–Golay over 0.1 s at 200 Hz on 0.1 sin(3πt) + 0.05 t²: velocity within 0.05 % of its peak
    and acceleration within 2.5 % away from the ends (a window from them), 0.5 % and 5 % at the ends."""
    t = np.arange(800) / RATE
    w = 3 * np.pi
    q = 0.1 * np.sin(w * t) + 0.05 * t**2
    v = 0.1 * w * np.cos(w * t) + 0.1 * t
    a = -0.1 * w**2 * np.sin(w * t) + 0.1
    prepared = preprocess(make_trial(tmp_path, {"t": t, "q": q, "f": np.cos(t)}), delay_s=0.0)
    assert prepared.settings.window_samples == 21
    h = 10
    v_err = np.abs(prepared.qd - v) / np.abs(v).max()
    a_err = np.abs(prepared.qdd - a) / np.abs(a).max()
    assert v_err[h:-h].max() < 5e-4 and a_err[h:-h].max() < 0.025
    assert v_err.max() < 5e-3 and a_err.max() < 0.05
    assert np.abs(prepared.q - q).max() < 1e-4


@pytest.mark.parametrize("delay", [0.03, -0.02])
def test_delay_is_found_and_applied(tmp_path, delay: float) -> None:
    trial = make_trial(tmp_path, record(delay))
    prepared = preprocess(trial)
    assert prepared.settings.delay_estimated
    assert abs(prepared.delay_s - delay) <= 1 / RATE + 1e-12
    assert len(prepared.t) == len(uniform_grid(trial.t, RATE)) - round(abs(prepared.delay_s) * RATE)

    def fit(p) -> tuple[np.ndarray, float]:
        x = np.column_stack([p.qdd, p.qd, np.sign(p.qd)])[p.moving]
        y = p.f_smooth[p.moving]
        coef, *_ = np.linalg.lstsq(x, y, rcond=None)
        return coef, float(np.sqrt(np.mean((y - x @ coef) ** 2)))

    (mass, _, coulomb), aligned = fit(prepared)
    assert mass == pytest.approx(M, rel=0.05) and coulomb == pytest.approx(FC, rel=0.05)
    # the shift goes the right way: none, or the opposite one, explains the force worse
    _, unaligned = fit(preprocess(trial, delay_s=0.0))
    _, reversed_ = fit(preprocess(trial, delay_s=-prepared.delay_s))
    assert aligned < 0.8 * unaligned < 0.8 * reversed_


def test_masks_match_the_motion_phases(tmp_path) -> None:
    rec = record(0.03)
    prepared = preprocess(make_trial(tmp_path, rec), limits=(0.0, 0.4), limit_margin=0.02)
    s = prepared.settings
    assert s.limits == (0.0, 0.4) and not s.limits_observed and s.moving_velocity == 0.01
    truth = {k: np.interp(prepared.t, rec["t"], rec[k]) for k in ("x_true", "v_true", "f_true")}
    v, x = truth["v_true"], truth["x_true"]
    clear = (np.abs(v) > 2 * s.moving_velocity) | (v == 0)  # away from the threshold
    assert np.mean(prepared.moving[clear] == (np.abs(v[clear]) > 0)) > 0.97
    fast_open, fast_close = v > 2 * s.moving_velocity, v < -2 * s.moving_velocity
    assert prepared.opening[fast_open].mean() > 0.99 and prepared.closing[fast_close].mean() > 0.99
    assert not (prepared.opening & prepared.closing).any()
    stuck = (v == 0) & (np.abs(truth["f_true"]) > 2 * s.sticking_force)
    assert stuck.sum() > 0.05 * len(v)  # the holds do stick the drawer under a force
    assert prepared.sticking[stuck].mean() > 0.95
    resting = (v == 0) & (np.abs(truth["f_true"]) < 0.5 * s.sticking_force)
    assert resting.sum() > 0.02 * len(v) and prepared.sticking[resting].mean() < 0.05
    assert not prepared.sticking[np.abs(v) > 2 * s.moving_velocity].any()
    near = (x < 0.02 - 2e-3) | (x > 0.38 + 2e-3)
    far = (x > 0.02 + 2e-3) & (x < 0.38 - 2e-3)
    assert near.any() and prepared.near_limit[near].all() and not prepared.near_limit[far].any()


def test_observed_limits_and_measured_velocity(tmp_path) -> None:
    rec = record(0.0, q_noise=0.0)
    path = tmp_path / "v.csv"
    write_csv(path, {"time [s]": rec["t"], "position [m]": rec["q"], "force [N]": rec["f"],
                     "velocity [m/s]": rec["v_true"]})
    (trial,) = load_trials(path, "slide")
    prepared = preprocess(trial, delay_s=0.0)
    lo, hi = prepared.settings.limits
    assert prepared.settings.limits_observed and lo == pytest.approx(rec["q"].min(), abs=1e-3)
    assert hi == pytest.approx(rec["q"].max(), abs=1e-3)
    assert prepared.near_limit[np.argmin(prepared.q)] and prepared.near_limit[np.argmax(prepared.q)]
    assert observed_limits([trial]) == (rec["q"].min(), rec["q"].max())
    np.testing.assert_allclose(prepared.qd_measured, rec["v_true"][: len(prepared.t)], atol=1e-12)
    assert not prepared.qd.flags.writeable


def test_preprocessing_refuses_a_trial_too_short_for_its_window(tmp_path) -> None:
    write_csv(tmp_path / "brief.csv", clean(60))
    (trial,) = load_trials(tmp_path / "brief.csv", "slide")
    with pytest.raises(TrialError) as info:
        preprocess(trial, window_s=0.5)
    assert str(info.value) == (f"{tmp_path / 'brief.csv'}, trial 'brief': 60 samples at 200 Hz (0.295 s) are too "
                               "few for a 101-sample smoothing window plus a ±20-sample delay; lower window_s or "
                               "max_delay_s")


def test_preprocessing_refuses_a_delay_it_cannot_estimate_and_bad_settings(tmp_path) -> None:
    cols = clean()
    cols["position [m]"] = np.linspace(0.1, 0.102, 100)  # 2 mm in 0.5 s: 4 mm/s, below the 10 mm/s of moving
    write_csv(tmp_path / "creep.csv", cols)
    (trial,) = load_trials(tmp_path / "creep.csv", "slide")
    with pytest.raises(TrialError) as info:
        preprocess(trial)
    assert str(info.value) == (f"{tmp_path / 'creep.csv'}, trial 'creep', column 'position [m]': only 0 moving "
                               "samples (|velocity| ≥ 0.01 m/s) to estimate the delay from, at least 20 needed; "
                               "pass delay_s")
    assert preprocess(trial, delay_s=0.0).moving.sum() == 0
    assert preprocess(trial, delay_s=0.0, moving_velocity=0.002).moving.mean() > 0.9
    with pytest.raises(TrialError, match=r"trial 'creep': preprocessing setting window_s must be a positive number, got -0.1$"):
        preprocess(trial, window_s=-0.1)
    with pytest.raises(TrialError, match=r"polyorder must be 2 to 6 \(got 1\)"):
        preprocess(trial, polyorder=1)
