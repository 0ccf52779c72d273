"""``rik sysid simulate | fit | apply`` end to end, and a preset made from measured data building a variant that
re-simulates held-out openings better than the preset it replaces."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from rik.registry import load_catalog
from rik.schemas.joints import JointType
from rik.sysid.discover import discover
from rik.sysid.preset import apply_report
from rik.sysid.report import write_report
from rik.sysid.synthetic.generate import GroundTruth, random_truth, simulate_trials, write_trials

PLOTS = {"residual_time.png", "residual_position.png", "residual_velocity.png", "breakaway.png", "resimulated.png"}


@pytest.fixture(scope="module")
def simulated(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from typer.testing import CliRunner

    from rik.cli.app import app

    out = tmp_path_factory.mktemp("sysid") / "data"
    result = CliRunner().invoke(app, ["sysid", "simulate", "--effect", "self_close", "--out", str(out),
                                      "--seed", "3", "--trials", "3"])
    assert result.exit_code == 0, result.output
    return out


def test_simulate_fit_names_the_effect_with_plots(rik, simulated: Path, tmp_path: Path) -> None:
    files = sorted(str(p) for p in simulated.glob("*.csv"))
    assert len(files) == 3 and (simulated / "truth.json").is_file()
    report = tmp_path / "report"
    res = rik("sysid", "fit", *files, "--joint", "slide", "--report", str(report))
    assert res.code == 0, res.err
    assert "The simulation misses a self-closing spring" in res.out
    assert PLOTS | {"report.md", "summary.json"} == {p.name for p in report.iterdir()}
    for plot in PLOTS:
        assert (report / plot).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    text = (report / "report.md").read_text()
    assert "The simulation misses a self-closing spring" in text and "![residual against position]" in text
    summary = json.loads((report / "summary.json").read_text())
    assert summary["effect"] == "self_close" and summary["verdict"] == "effect"
    assert summary["resistance"]["effects"][0]["kind"] == "self_close"
    errors = summary["errors"]
    assert errors["force_rmse"]["extended"] < errors["force_rmse"]["baseline"]
    assert errors["position_rmse"]["extended"] < errors["position_rmse"]["baseline"]
    # running again replaces the report whole, leaving no staging folder
    assert rik("sysid", "fit", *files, "--report", str(report)).code == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["report"]


def test_apply_writes_a_preset(rik, simulated: Path, tmp_path: Path) -> None:
    report = tmp_path / "report"
    assert rik("sysid", "fit", *map(str, simulated.glob("*.csv")), "--report", str(report)).code == 0
    res = rik("sysid", "apply", str(report), "--as-preset", "pull-in", "--catalog-dir", str(tmp_path / "cat"))
    assert res.code == 0, res.err
    preset = load_catalog([tmp_path / "cat"]).preset("pull-in")
    assert preset.slide.provenance == "measured" and preset.slide.effects[0].kind == "self_close"
    assert preset.hinge == load_catalog([]).preset("normal").hinge


def test_two_effects_end_to_end(rik, tmp_path: Path) -> None:
    data, report = tmp_path / "data", tmp_path / "report"
    res = rik("sysid", "simulate", "--effect", "soft_close", "--second", "self_close", "--seed", "2", "--out",
              str(data))
    assert res.code == 0 and "soft_close and self_close hidden" in res.out, res.err
    assert rik("sysid", "fit", *map(str, sorted(data.glob("*.csv"))), "--report", str(report)).code == 0
    summary = json.loads((report / "summary.json").read_text())
    assert summary["effects"] == ["soft_close", "self_close"] and summary["pairs"][0]["verdict"] == "pass"
    assert [e["kind"] for e in summary["resistance"]["effects"]] == ["soft_close", "self_close"]
    assert "Pairs of effects, scored against the best single effect" in (report / "report.md").read_text()
    assert rik("sysid", "apply", str(report), "--as-preset", "soft-runner", "--catalog-dir", str(tmp_path / "c")).code == 0
    kinds = [e.kind for e in load_catalog([tmp_path / "c"]).preset("soft-runner").slide.effects]
    assert kinds == ["soft_close", "self_close"]


def test_fit_reads_a_lerobot_dataset(rik, tmp_path: Path) -> None:
    """Trials recorded as LeRobot episodes (position in the state vector, in mm; force in the action) fit like CSVs."""
    from test_sysid_data import lerobot_dataset

    truth = random_truth("tilt", JointType.slide, np.random.default_rng(1))
    trials = simulate_trials(truth, n_trials=3, seed=1, duration_s=10.0)
    episodes = {i: {"q": 1e3 * tr.q, "qd": np.zeros_like(tr.q), "f": tr.f} for i, tr in enumerate(trials)}
    lerobot_dataset(tmp_path / "ds", episodes, fps=200)
    res = rik("sysid", "fit", str(tmp_path / "ds"), "--position", "observation.state[front_qpos]",
              "--position-unit", "mm", "--force", "action[push]", "--force-unit", "N", "--report", str(tmp_path / "r"))
    assert res.code == 0, res.err
    assert "The simulation misses gravity along the joint" in res.out
    summary = json.loads((tmp_path / "r" / "summary.json").read_text())
    assert summary["trials"]["names"] == ["episode_0", "episode_1", "episode_2"]
    assert summary["resistance"]["effects"][0]["force"] == pytest.approx(truth.effect.force, rel=0.15)
    err = _bad(rik, "sysid", "fit", str(tmp_path / "ds"))
    assert err == f"rik: error: {tmp_path / 'ds'}: a LeRobot dataset needs --position and --force naming its features"


def test_fit_reads_a_plain_csv_with_named_columns(rik, tmp_path: Path) -> None:
    """A CSV with plain ``trial,t,q,f`` headers (no units) fits once the columns' units are given as options."""
    from test_sysid_data import write_csv

    truth = random_truth("tilt", JointType.slide, np.random.default_rng(1))
    trials = simulate_trials(truth, n_trials=3, seed=1, duration_s=10.0)
    data = tmp_path / "data.csv"
    write_csv(data, {"trial": [tr.name for tr in trials for _ in range(tr.samples)],
                     "t": np.concatenate([tr.t for tr in trials]), "q": np.concatenate([tr.q for tr in trials]),
                     "f": np.concatenate([tr.f for tr in trials])})
    res = rik("sysid", "fit", str(data), "--time", "t", "--time-unit", "s", "--position", "q", "--position-unit", "m",
              "--force", "f", "--force-unit", "N", "--joint", "slide", "--report", str(tmp_path / "r"))
    assert res.code == 0, res.err
    assert "The simulation misses gravity along the joint" in res.out
    summary = json.loads((tmp_path / "r" / "summary.json").read_text())
    assert summary["trials"]["names"] == ["trial_1", "trial_2", "trial_3"]
    assert summary["resistance"]["effects"][0]["force"] == pytest.approx(truth.effect.force, rel=0.15)


def test_named_columns_bad_input_is_one_line(rik, tmp_path: Path) -> None:
    log = tmp_path / "log.csv"
    log.write_text("timestamp_ms,enc_pos,ft_fx\n" + "".join(f"{5 * i},{i % 7},{i % 3}\n" for i in range(60)))
    assert _bad(rik, "sysid", "fit", str(log), "--time", "timestamp", "--position", "enc_pos", "--force", "ft_fx") == (
        f"rik: error: {log}, column 'timestamp': no such column (--time); did you mean 'timestamp_ms'? "
        "(columns: 'timestamp_ms', 'enc_pos', 'ft_fx')")
    assert _bad(rik, "sysid", "fit", str(log), "--time", "timestamp_ms", "--time-unit", "ms", "--position", "enc_pos",
                "--force", "ft_fx", "--force-unit", "N") == (
        f"rik: error: {log}, column 'enc_pos': no unit in the header; pass --position-unit: a slide's position is in "
        "m, mm or cm")
    assert _bad(rik, "sysid", "fit", str(log), "--time", "timestamp_ms", "--time-unit", "ms", "--position", "enc_pos",
                "--position-unit", "mm", "--force", "ft_fx", "--force-unit", "N·m") == (
        f"rik: error: {log}, column 'ft_fx': --force-unit: 'N·m' is a torque unit but the joint is a slide; a "
        "slide's force is in N or kN")
    plain = tmp_path / "plain.csv"
    plain.write_text("t,q,f\n0,0,1\n")
    assert _bad(rik, "sysid", "fit", str(plain)) == (
        f"rik: error: {plain}, column 't': no unit; write the header as 't [unit]' (e.g. 't [s]') or pass --time-unit: "
        "time is in s or ms")


def _bad(rik, *args: str) -> str:
    res = rik(*args)
    assert res.code == 2 and "Traceback" not in res.err and res.err.count("\n") == 1, res.err
    return res.err.strip()


def test_bad_inputs_are_one_line_errors(rik, simulated: Path, tmp_path: Path) -> None:
    nan = tmp_path / "nan.csv"
    nan.write_text("time [s],position [m],force [N]\n0,0,1\n0.01,nan,2\n")
    err = _bad(rik, "sysid", "fit", str(nan))
    assert err.startswith(f"rik: error: {nan}") and "position" in err
    csv = str(next(simulated.glob("*.csv")))
    err = _bad(rik, "sysid", "fit", csv, "--joint", "hinge")
    assert "column 'position [m]': 'm' is a length unit but the joint is a hinge" in err
    many = [str(p) for p in simulated.glob("*.csv")]
    assert _bad(rik, "sysid", "fit", *many, "--heldout", "0", "--heldout", "1", "--heldout", "2",
                "--report", str(tmp_path / "r")) == ("rik: error: held-out trials must be some but not all of the "
                                                     "3 trials (0 to 2), got [0, 1, 2]")
    assert not (tmp_path / "r").exists() and not list(tmp_path.glob(".r*"))
    assert _bad(rik, "sysid", "simulate", "--effect", "gremlin", "--out", str(tmp_path / "s")).startswith(
        "rik: error: kind 'gremlin' is not an effect kind")
    assert not (tmp_path / "s").exists()
    bad = tmp_path / "summary.json"
    bad.write_text(json.dumps({"format": 1, "joint": "slide", "resistance": {"damping": -1, "frictionloss": 2,
                                                                           "provenance": "measured"}}))
    assert _bad(rik, "sysid", "apply", str(bad), "--as-preset", "x", "--catalog-dir", str(tmp_path / "c")) == (
        f"rik: error: {bad}: field 'resistance.damping': Input should be greater than or equal to 0")
    bad.write_text("{not json")
    assert _bad(rik, "sysid", "apply", str(bad), "--as-preset", "x").startswith(f"rik: error: {bad}: not valid JSON")
    assert _bad(rik, "sysid", "apply", str(tmp_path / "nowhere"), "--as-preset", "x").startswith(
        f"rik: error: {tmp_path / 'nowhere'}: no such report summary")
    assert not (tmp_path / "c").exists()


def test_applied_preset_builds_a_variant_that_matches_held_out_data_better(tmp_path: Path) -> None:
    """Measured data of a drawer whose moving mass is the variant's, with a soft-close damper; the fitted preset's
    variant re-simulates the held-out openings closer than the built-in preset's variant does."""
    import mujoco

    from rik.combinator.build import build_variant
    from rik.registry.ids import VariantKey
    from rik.sysid.resim import resimulate

    base, handle = "drawer/bedside-45", "knob/mushroom-30"
    normal = build_variant(load_catalog([]), VariantKey(base, handle, "normal"), tmp_path / "variants")
    assert normal.status == "built", normal.reason
    model_file = tmp_path / "variants" / "drawer-bedside-45__knob-mushroom-30__normal" / "model.xml"
    model = mujoco.MjModel.from_xml_path(str(model_file))
    assert model.njnt == 1 and model.jnt_type[0] == mujoco.mjtJoint.mjJNT_SLIDE
    mass = float(model.body_subtreemass[model.jnt_bodyid[0]])
    drawn = random_truth("soft_close", JointType.slide, np.random.default_rng(7), mass=mass)
    truth = GroundTruth(drawn.joint, mass, drawn.damping, drawn.frictionloss, tuple(model.jnt_range[0]), drawn.effect)
    trials = simulate_trials(truth, n_trials=4, seed=7)
    write_trials(trials, tmp_path / "data", truth)
    found = discover(trials)
    assert found.chosen is not None and found.chosen.kind == "soft_close"
    write_report(found, tmp_path / "report")
    apply_report(tmp_path / "report", "measured-drawer", tmp_path / "cat")
    fitted = build_variant(load_catalog([tmp_path / "cat"]), VariantKey(base, handle, "measured-drawer"),
                           tmp_path / "variants")
    assert fitted.status == "built", fitted.reason

    from rik.joints.runtime import RuntimeEffects, front_effects

    errors = {}
    for preset in ("normal", "measured-drawer"):
        spec = mujoco.MjSpec.from_file(str(tmp_path / "variants" / f"drawer-bedside-45__knob-mushroom-30__{preset}"
                                           / "model.xml"))
        info = json.loads(spec.text("rik.variant").data)
        m = spec.compile()
        m.opt.gravity[:] = 0.0  # the runner is level: gravity is across the joint
        appliers = front_effects(m, info["fronts"])  # only fronts with runtime effects have one
        applier = appliers[0] if appliers else RuntimeEffects(m, 0, 0, ())
        squared = []
        for i in found.split.heldout_trials:
            p = found.prepared[i]
            sim = resimulate((m, applier), p.t, p.q, p.qd, p.f, window_s=0.5)
            squared.append((sim - p.q) ** 2)
        errors[preset] = float(np.sqrt(np.mean(np.concatenate(squared))))
    assert errors["measured-drawer"] < 0.5 * errors["normal"], errors
