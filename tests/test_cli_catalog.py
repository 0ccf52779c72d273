"""`rik catalog` as a user and a script see it."""

from __future__ import annotations

import csv
import io
import json
import subprocess
import sys

import pytest
from conftest import REPO


def test_list_handles_json_lists_83(rik) -> None:
    result = rik("catalog", "list", "--kind", "handles", "--format", "json")
    assert result.code == 0
    handles = json.loads(result.out)
    assert len(handles) == 83
    assert {"id", "design", "type", "geometry", "mount", "mass", "finish"} <= set(handles[0])


def test_list_counts_per_kind(rik) -> None:
    counts = {k: len(json.loads(rik("catalog", "list", "--kind", k, "-f", "json").out))
              for k in ("designs", "bases", "presets", "finishes")}
    assert counts["designs"] == 47 and counts["bases"] == 13 and counts["presets"] >= 3


def test_type_filter_lists_only_knobs(rik) -> None:
    knobs = json.loads(rik("catalog", "list", "--type", "knob", "--format", "json").out)
    assert len(knobs) == 30 and {h["type"] for h in knobs} == {"knob"}
    table = rik("catalog", "list", "--type", "knob").out
    assert "knob/mushroom-30" in table and "two_point/" not in table


def test_length_and_design_filters(rik) -> None:
    rows = json.loads(rik("catalog", "list", "--min-length", "0.3", "-f", "json").out)
    assert rows and all(r["geometry"]["length"] >= 0.3 for r in rows)
    bows = json.loads(rik("catalog", "list", "--design", "two_point/bow", "-f", "json").out)
    assert [r["id"] for r in bows] == ["two_point/bow-64", "two_point/bow-96", "two_point/bow-128"]


def test_joint_filter_on_bases(rik) -> None:
    slides = json.loads(rik("catalog", "list", "--kind", "bases", "--joint", "slide", "-f", "json").out)
    assert slides and all("slide" in b["joint_types"] for b in slides)


def test_csv_has_one_row_per_handle_in_si_units(rik) -> None:
    rows = list(csv.DictReader(io.StringIO(rik("catalog", "list", "--format", "csv").out)))
    assert len(rows) == 83
    bow = next(r for r in rows if r["id"] == "two_point/bow-128")
    assert float(bow["geometry.hole_spacing"]) == 0.128


def test_json_output_is_stable(rik) -> None:
    first = rik("catalog", "list", "--kind", "bases", "-f", "json").out
    assert first == rik("catalog", "list", "--kind", "bases", "-f", "json").out


def test_show_any_kind(rik) -> None:
    for entry_id in ("two_point/bow-128", "two_point/bow", "drawer/chest-80", "normal", "metal/stainless"):
        result = rik("catalog", "show", entry_id)
        assert result.code == 0 and entry_id in result.out
    shown = json.loads(rik("catalog", "show", "two_point/bow-128", "--format", "json").out)
    assert shown["geometry"]["clearance"] == {"depth": 0.02, "width": 0.116}


def test_show_unknown_id_suggests(rik) -> None:
    result = rik("catalog", "show", "two_point/bow-12")
    assert result.code == 2
    assert result.err.strip() == ("rik: error: no entry 'two_point/bow-12' in the catalog; did you mean "
                                  "'two_point/bow-128' or 'two_point/bow' or 'two_point/bow-96'?")


def test_unknown_design_filter_suggests(rik) -> None:
    result = rik("catalog", "list", "--design", "two_point/bo")
    assert result.code == 2 and "did you mean 'two_point/bow'" in result.err


def test_filter_that_does_not_apply_is_an_error(rik) -> None:
    result = rik("catalog", "list", "--kind", "bases", "--type", "knob")
    assert result.code == 2
    assert result.err.strip() == "rik: error: --type filters handles and designs, not bases"


def _entry(data, entry_id):
    """The dict with ``id`` == entry_id anywhere inside parsed JSON (whatever the file's layout)."""
    if isinstance(data, dict):
        if data.get("id") == entry_id and "geometry" in data:
            return data
        data = list(data.values())
    if isinstance(data, list):
        for item in data:
            if (found := _entry(item, entry_id)) is not None:
                return found
    return None


def test_an_edited_index_is_rebuilt_not_served(rik, tmp_path, monkeypatch) -> None:
    monkeypatch.setenv("RIK_CACHE", str(tmp_path / "cache"))
    args = ("catalog", "list", "--design", "two_point/bow", "-f", "json")
    true = {r["id"]: r for r in json.loads(rik(*args).out)}["two_point/bow-128"]["geometry"]["length"]
    [index] = (tmp_path / "cache" / "catalog").glob("*.json")
    written = index.read_bytes()
    data = json.loads(written)
    _entry(data, "two_point/bow-128")["geometry"]["length"] = 9.5  # still valid JSON, one figure changed
    index.write_text(json.dumps(data))
    listed = {r["id"]: r for r in json.loads(rik(*args).out)}
    assert listed["two_point/bow-128"]["geometry"]["length"] == true != 9.5
    assert index.read_bytes() == written  # rebuilt and rewritten


@pytest.mark.slow
def test_stats_and_demo(rik, tmp_path, monkeypatch) -> None:
    numbers = json.loads(rik("catalog", "stats", "--format", "json").out)
    assert numbers["pairings"] == {"total": 1079, "fit": 1079}
    assert numbers["by_type"]["two_point"] == {"designs": 17, "handles": 34}
    monkeypatch.chdir(tmp_path)  # the demo writes into the working directory: here, not the repository
    # the README's `rik demo` records 2 episodes and renders them at 128 px: the same code, less work
    demo = rik("demo", "--res", "32", "--episodes", "1")
    assert "observation.images.front (3, 32, 32)" in demo.out and "dataset datasets/rik-demo: 1 episode" in demo.out
    assert demo.code == 0 and "1079 of 1079" in demo.out
    assert {"variants", "episodes", "renders", "datasets", "sysid-data", "sysid-report", "sysid-catalog"} <= {
        p.name for p in tmp_path.iterdir()}


def test_demo_refuses_a_size_its_video_encoder_cannot_take_before_any_work(rik, tmp_path, monkeypatch) -> None:
    """``rik demo --res 16`` once rendered for half a minute and then died in the export (AV1 takes frames 25 px
    wide or more, rik.exporters.spec.MIN_WIDTH): the option now stops it at once, writing nothing."""
    from rik.exporters.spec import MIN_WIDTH

    monkeypatch.chdir(tmp_path)
    r = rik("demo", "--res", str(MIN_WIDTH["libsvtav1"] - 1))
    assert r.code == 2 and "--res" in r.out + r.err and "25<=x<=1024" in r.out + r.err, r.out + r.err
    assert list(tmp_path.iterdir()) == []


def test_catalog_commands_import_nothing_heavy(tmp_path) -> None:
    """`rik catalog` must not import simulators, renderers or learning libraries; warm, not even the schemas
    or pydantic."""
    probe = (
        "import sys, io, json, contextlib\n"
        "from rik.cli.app import main\n"
        "for args in json.loads(sys.argv[1]):\n"
        "    sys.argv = ['rik', *args]\n"
        "    with contextlib.redirect_stdout(io.StringIO()):\n"
        "        try: main()\n"
        "        except SystemExit as exc: assert not exc.code, (args, exc.code)\n"
        "print(' '.join(sorted(sys.modules)))\n"
    )
    env = {"RIK_CACHE": str(tmp_path), "PATH": "/usr/bin:/bin", "HOME": str(tmp_path)}
    commands = [["catalog", "list", "--type", "knob"], ["catalog", "list", "--type", "knob"], ["catalog", "stats"]]
    cold = subprocess.run([sys.executable, "-c", probe, json.dumps(commands)], env=env, capture_output=True,
                          text=True, check=True, cwd=REPO)
    modules = set(cold.stdout.split())
    for heavy in ("mujoco", "coacd", "torch", "lerobot", "mitsuba", "trimesh", "numpy"):
        assert heavy not in modules, f"rik catalog imported {heavy}"
    warm = subprocess.run([sys.executable, "-c", probe, json.dumps(commands[1:])], env=env, capture_output=True,
                          text=True, check=True, cwd=REPO)
    modules = set(warm.stdout.split())
    assert "rik.cli.app" in modules
    assert "rik.schemas" not in modules, "a warm `rik catalog` should read the index, not validate"
    assert "pydantic" not in modules, "a warm `rik catalog` needs no pydantic (its import is ~20 ms)"


def test_a_command_runs_with_the_same_help_as_in_the_full_app(rik) -> None:
    """`main` builds only the group or command named first (start-up); what each prints must not change."""
    from typer.main import get_command_name
    from typer.testing import CliRunner

    from rik.cli.app import app

    names = [g.name for g in app.registered_groups] + [c.name or get_command_name(c.callback.__name__)
                                                       for c in app.registered_commands]
    assert len(names) == 17
    for args in [[n, "--help"] for n in names] + [["catalog", "list", "--help"]]:
        full = CliRunner().invoke(app, args, prog_name="rik", env={"COLUMNS": "100"})
        with pytest.MonkeyPatch.context() as mp:
            mp.setenv("COLUMNS", "100")
            fast = rik(*args)
        assert (fast.code, fast.out + fast.err) == (full.exit_code, full.output), args
    for args, line in ((["catalog", "lst"], "No such command 'lst'. Did you mean 'list'? (see rik catalog --help)"),
                       (["catalgo"], "No such command 'catalgo'. Did you mean 'catalog'? (see rik --help)")):
        fast = rik(*args)  # a usage error: one line, as every bad input (the full app's typer box is not printed)
        assert (fast.code, fast.out, fast.err) == (2, "", f"rik: error: {line}\n"), args


def test_version_prints_without_a_command(rik) -> None:
    from rik import __version__

    result = rik("--version")
    assert (result.code, result.out, result.err) == (0, f"rik {__version__}\n", "")
