"""Quasi-static force profiles (force against position, no time axis): reading, fitting, reports and the CLI.
The data is made here (never the shared real profiles, which CI does not have)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from rik.errors import RikError

BINS = 36
"""Angle bins of an opening, about 1° each (as in the real door profiles)."""


def write_profiles(path: Path, forces: list[np.ndarray], *, group: str | None = None,
                   header: str = "trial,angle bin,force [N]") -> Path:
    """A CSV of openings: one row per (trial, bin), in the layout of the shared door profiles."""
    lines = [header if group is None else "mechanism," + header]
    for k, f in enumerate(forces):
        for b, value in enumerate(f):
            row = f"{k},{b},{value:.6g}"
            lines.append(row if group is None else f"{group},{row}")
    path.write_text("\n".join(lines) + "\n")
    return path


def catch_openings(n: int = 8, *, force: float = 30.0, decay_deg: float = 3.0, level: float = 2.0,
                   noise: float = 0.4, seed: int = 0) -> list[np.ndarray]:
    """Openings of a door with a magnetic catch (or seal): ``level + force / (1 + q/decay)²`` N at the handle."""
    rng = np.random.default_rng(seed)
    q = np.arange(BINS, dtype=float)
    law = level + force / (1.0 + q / decay_deg) ** 2
    return [law + rng.normal(0.0, noise, BINS) for _ in range(n)]


def friction_openings(n: int = 8, level: float = 2.5, noise: float = 0.3, seed: int = 1) -> list[np.ndarray]:
    rng = np.random.default_rng(seed)
    return [level + rng.normal(0.0, noise, BINS) for _ in range(n)]


def _fit(path: Path, **kw):
    from rik.sysid.profile import read_profiles
    from rik.sysid.profile_fit import fit_profile

    data = read_profiles(path, "hinge", position="angle bin", position_unit="bin", force="force [N]", **kw)
    return data, [fit_profile(g, data.joint, data.force_unit) for g in data.groups]


def test_a_catch_and_a_friction_level_are_recovered(tmp_path: Path) -> None:
    data, (fit,) = _fit(write_profiles(tmp_path / "door.csv", catch_openings()))
    assert data.handle_force and data.bins and data.force_unit == "N at the handle"
    assert fit.selection.found
    assert fit.selection.final.kinds == ("magnetic_catch",)
    (catch,) = fit.effects
    assert catch.force == pytest.approx(30.0, rel=0.15)
    assert math.degrees(catch.decay) == pytest.approx(3.0, rel=0.3)
    assert fit.level == pytest.approx(2.0, abs=0.4)
    assert fit.selection.gain > 0.5


def test_pure_friction_gives_no_position_dependent_effect(tmp_path: Path) -> None:
    from rik.sysid.profile_report import verdict

    _, (fit,) = _fit(write_profiles(tmp_path / "flat.csv", friction_openings()))
    assert not fit.selection.found
    assert fit.level == pytest.approx(2.5, abs=0.1)
    assert "no position-dependent effect; friction level (or constant force) 2.48 N" in verdict(fit)


def test_groups_are_fitted_apart(tmp_path: Path) -> None:
    a = write_profiles(tmp_path / "a.csv", catch_openings(), group="fridge")
    b = write_profiles(tmp_path / "b.csv", friction_openings(), group="cabinet")
    from rik.sysid.profile import read_profiles
    from rik.sysid.profile_fit import fit_profile

    data = read_profiles([a, b], "hinge", position="angle bin", position_unit="bin", force="force [N]",
                         group="mechanism")
    assert [g.name for g in data.groups] == ["fridge", "cabinet"]
    found = {g.name: fit_profile(g, data.joint, data.force_unit).selection.found for g in data.groups}
    assert found == {"fridge": True, "cabinet": False}


def test_missing_column_lists_the_columns(tmp_path: Path) -> None:
    from rik.sysid.profile import read_profiles

    path = write_profiles(tmp_path / "door.csv", friction_openings(n=2))
    with pytest.raises(RikError) as exc:
        read_profiles(path, "hinge", position="angle", force="force [N]")
    assert str(exc.value) == (f"{path}, column 'angle': no such column (--position); did you mean 'angle bin'? "
                              "(columns: 'trial', 'angle bin', 'force [N]')")


def test_nan_names_the_row_or_is_dropped_and_counted(tmp_path: Path) -> None:
    from rik.sysid.profile import read_profiles

    openings = catch_openings(n=4)
    openings[1][5] = np.nan
    path = write_profiles(tmp_path / "door.csv", openings)
    kw = dict(position="angle bin", position_unit="bin", force="force [N]")
    with pytest.raises(RikError) as exc:
        read_profiles(path, "hinge", **kw)
    assert str(exc.value) == (f"{path}, column 'force [N]': row 41 (line 43) is NaN; every value must be a finite "
                              "number (or pass --drop-nan to leave such rows out, counted)")
    data = read_profiles(path, "hinge", drop_nan=True, **kw)
    assert data.dropped == 1 and data.dropped_rows == (f"{path} row 41 (line 43)",)
    assert [len(p.q) for p in data.groups[0].profiles] == [BINS, BINS - 1, BINS, BINS]


def test_units_must_fit_the_joint(tmp_path: Path) -> None:
    from rik.sysid.profile import read_profiles

    path = write_profiles(tmp_path / "door.csv", friction_openings(n=2))
    with pytest.raises(RikError) as exc:
        read_profiles(path, "slide", position="angle bin", position_unit="bin", force="force [N]")
    assert str(exc.value) == (f"{path}, column 'angle bin': 'bin' is a hinge's position unit but the joint is a "
                              "slide (pass --joint hinge?); a slide's position is in m, mm, cm")
    with pytest.raises(RikError) as exc:
        read_profiles(path, "hinge", position="angle bin", force="force [N]")
    assert str(exc.value) == (f"{path}, column 'angle bin': no unit; pass --position-unit or write the header as "
                              "'angle bin [unit]': a hinge's position is in rad, deg, bin")


def test_cli_quasi_static_end_to_end(rik, tmp_path: Path) -> None:
    openings = catch_openings(n=6)
    openings[0][3] = np.nan
    path = write_profiles(tmp_path / "door.csv", openings)
    report = tmp_path / "report"
    res = rik("sysid", "fit", str(path), "--quasi-static", "--joint", "hinge", "--position", "angle bin",
              "--position-unit", "bin", "--force", "force [N]", "--drop-nan", "--report", str(report))
    assert res.code == 0, res.err
    assert f"left out 1 rows with an empty or NaN cell (first: {path} row 3 (line 5))" in res.out
    assert "door: magnetic catch: a pull of" in res.out
    assert "forces are at the handle, in N (no lever arm given)" in res.out
    assert sorted(p.name for p in report.iterdir()) == ["profile.png", "report.md", "summary.json"]
    summary = json.loads((report / "summary.json").read_text())
    assert summary["mode"] == "quasi-static" and summary["effects"] == ["magnetic_catch"]
    assert summary["dropped_rows"] == 1 and summary["units"]["force"] == "N at the handle"


def test_cli_detects_a_profile_without_a_time_column_and_groups(rik, tmp_path: Path) -> None:
    path = write_profiles(tmp_path / "flat.csv", friction_openings(), group="cabinet one")
    report = tmp_path / "report"
    res = rik("sysid", "fit", str(path), "--joint", "hinge", "--position", "angle bin", "--position-unit", "bin",
              "--force", "force [N]", "--group", "mechanism", "--report", str(report))
    assert res.code == 0, res.err
    assert "no time column: reading the data as a quasi-static force profile" in res.out
    assert "cabinet one: no position-dependent effect; friction level (or constant force) 2.48 N" in res.out
    assert (report / "report.md").is_file()


def test_report_says_what_was_and_was_not_identifiable(tmp_path: Path) -> None:
    from rik.sysid.profile_report import write_profile_report

    data, fits = _fit(write_profiles(tmp_path / "door.csv", catch_openings()))
    out = write_profile_report(data, fits, tmp_path / "r")
    text = (out / "report.md").read_text()
    assert "Identified (fitted and selected):" in text
    assert "- the friction level (or constant force)" in text
    assert "Not identifiable from a force-against-position profile:" in text
    assert "- damping, inertia and speed effects (stiction, quadratic damping, a soft-close damper)" in text
    assert "friction against a constant force: on opening-only data they are the same thing" in text
    assert "no lever arm is given: forces are at the handle, in N" in text
    assert "Positions: angle bins read as 1 bin = 1 degree" in text
    summary = json.loads((out / "summary.json").read_text())
    assert any(t.startswith("damping, inertia") for t in summary["not_identified"])


def test_cli_bad_profile_is_one_line_error(rik, tmp_path: Path) -> None:
    path = write_profiles(tmp_path / "door.csv", friction_openings(n=2), header="trial,angle bin,pull [N]")
    res = rik("sysid", "fit", str(path), "--joint", "hinge", "--position", "angle bin", "--position-unit", "bin",
              "--report", str(tmp_path / "r"))
    assert res.code == 2
    assert res.err.strip() == (f"rik: error: {path}: no force column (looked for 'force' or 'torque' or 'f'); name "
                               "it with --force COLUMN; the columns are: 'trial', 'angle bin', 'pull [N]'")


def test_parquet_with_a_loggers_column_names(rik, tmp_path: Path) -> None:
    """Any column names, mapped on the command line; a slide in mm; one opening held out by --heldout."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    rng = np.random.default_rng(3)
    q = np.linspace(0.0, 300.0, 60)
    runs, pos, force = [], [], []
    for k in range(4):
        runs += [f"run{k}"] * q.size
        pos += list(q)
        force += list(4.0 + 0.2 * np.maximum(40.0 - q, 0.0) + rng.normal(0.0, 0.2, q.size))
    path = tmp_path / "drawer.parquet"
    pq.write_table(pa.table({"run": runs, "enc_pos": pos, "ft_fx": force}), path)
    res = rik("sysid", "fit", str(path), "--position", "enc_pos", "--position-unit", "mm", "--force", "ft_fx",
              "--force-unit", "N", "--trial", "run", "--heldout", "0", "--report", str(tmp_path / "r"))
    assert res.code == 0, res.err
    assert "drawer: self-closing spring: a pull of 7.96 N at closed, falling linearly to 0 at 40.5 mm" in res.out
    summary = json.loads((tmp_path / "r" / "summary.json").read_text())
    assert summary["trials"]["heldout"] == ["run0"] and summary["units"] == {"position": "m", "force": "N"}
    res = rik("sysid", "fit", str(path), "--position", "enc_pos", "--position-unit", "mm", "--force", "ft_fx",
              "--force-unit", "N", "--trial", "run", "--heldout", "9", "--report", str(tmp_path / "r"))
    assert res.code == 2
    assert res.err.strip() == ("rik: error: drawer: held-out trials must be some but not all of its 4 openings (0 to "
                               "3), got [9]")


def test_too_few_points_to_hold_out(tmp_path: Path) -> None:
    path = write_profiles(tmp_path / "door.csv", friction_openings(n=1))
    with pytest.raises(RikError) as exc:
        _fit(path)
    assert str(exc.value) == ("door: only 9 points in the held-out openings (0), at least 16 needed: measure more "
                              "openings or more points per opening")
