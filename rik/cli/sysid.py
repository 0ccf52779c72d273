"""``rik sysid fit``, ``rik sysid simulate`` and ``rik sysid apply``: model discovery from measured joint data.
Only parsing and printing here; :mod:`rik.sysid` does the work."""

from __future__ import annotations

from enum import StrEnum
from pathlib import Path
from typing import Annotated

import typer

from rik.cli.common import CatalogOption, console, overlays
from rik.errors import RikError

app = typer.Typer(help="Model discovery: what the simulation gets wrong about a measured joint, the cause, the "
                       "extended joint model and the gain on held-out data.", no_args_is_help=True)


class JointOpt(StrEnum):
    slide = "slide"
    hinge = "hinge"


class GeneratorOpt(StrEnum):
    rik = "rik"
    foreign = "foreign"


JointOption = Annotated[JointOpt, typer.Option("--joint", help="Joint type: slide (drawer, m and N) or hinge "
                                                               "(door or flap, rad and N·m).")]


@app.command()
def fit(data: Annotated[list[Path], typer.Argument(help="Trial files (.csv, .parquet) or one LeRobot dataset "
                                                        "folder (with --position and --force).", show_default=False)],
        joint: JointOption = JointOpt.slide,
        report: Annotated[Path, typer.Option("--report", "-o", help="Report directory (replaced whole).")] = Path(
            "sysid-report"),
        heldout: Annotated[list[int] | None, typer.Option("--heldout", help="Index of a trial to hold out "
                                                          "(repeatable; default: the last quarter, or the end of a "
                                                          "single trial).")] = None,
        window: Annotated[float | None, typer.Option("--window", min=0.0, help="Smoothing window, s (default: the "
                                                     "shortest whose velocity noise is low enough).")] = None,
        delay: Annotated[float | None, typer.Option("--delay", help="Force-to-position delay, s (default: "
                                                    "estimated).")] = None,
        position: Annotated[str | None, typer.Option(help="LeRobot: the position feature, e.g. "
                                                     "'observation.state[2]'.")] = None,
        position_unit: Annotated[str, typer.Option(help="LeRobot: its unit.")] = "m",
        force: Annotated[str | None, typer.Option(help="LeRobot: the force or torque feature.")] = None,
        force_unit: Annotated[str, typer.Option(help="LeRobot: its unit.")] = "N") -> None:
    """Fit the baseline joint model, find the unmodelled effect, extend the model and measure the gain; write a
    report (report.md with plots, summary.json) that names the cause."""
    from rik.sysid.discover import discover
    from rik.sysid.report import write_report
    from rik.sysid.trials import load_lerobot_trials, load_trials

    con = console()
    if len(data) == 1 and data[0].is_dir():
        if position is None or force is None:
            raise RikError(f"{data[0]}: a LeRobot dataset needs --position and --force naming its features")
        trials = load_lerobot_trials(data[0], joint.value, position=position, position_unit=position_unit,
                                     force=force, force_unit=force_unit)
    else:
        trials = load_trials(data, joint.value)
    with con.status(f"fitting {len(trials)} trials"):
        found = discover(trials, heldout=heldout, window_s=window, delay_s=delay)
        out = write_report(found, report)
    con.print(found.sentence())
    for text in found.selection.separation:
        con.print(f"  cannot tell apart from this data: {text}")
    con.print(f"report: {out / 'report.md'}  (summary: {out / 'summary.json'})")


@app.command()
def simulate(effect: Annotated[str, typer.Option("--effect", help="Hidden effect: none, stiction, soft_close, "
                                                 "self_close, magnetic_catch, tilt, direction_friction, "
                                                 "quadratic_damping, load_friction or spring.")] = "soft_close",
             second: Annotated[str | None, typer.Option("--second", help="A second hidden effect acting together "
                                                       "with --effect (e.g. self_close with soft_close, as on "
                                                       "soft-close runners).")] = None,
             joint: JointOption = JointOpt.slide,
             out: Annotated[Path, typer.Option("--out", "-o", help="Directory for the trial CSVs and truth.json.")]
             = Path("sysid-data"),
             trials: Annotated[int, typer.Option("--trials", "-n", min=2, help="Trials to simulate.")] = 4,
             seed: Annotated[int, typer.Option("--seed", help="Seed of the truth and the excitation.")] = 0,
             duration: Annotated[float, typer.Option("--duration", min=1.0, help="Seconds per trial.")] = 12.0,
             mass: Annotated[float | None, typer.Option("--mass", min=0.0, help="Moving mass, kg (slide) or "
                                                        "inertia, kg·m² (hinge); default drawn.")] = None,
             generator: Annotated[GeneratorOpt, typer.Option("--generator", help="rik (MuJoCo, shapes near the "
                                                             "library's) or foreign (own integrator, LuGre "
                                                             "friction, compliant stops, other shapes; no --second "
                                                             "or --mass).")] = GeneratorOpt.rik) -> None:
    """Generate demonstration data: a joint with one hidden effect (realistic parameters from --seed) driven by a
    simulated hand through strokes, holds and releases, measured with noise and delay (MuJoCo at 0.5 ms)."""
    import numpy as np

    from rik.sysid.generate import random_truth, simulate_trials, write_trials

    kind = None if effect == "none" else effect
    if generator is GeneratorOpt.foreign:
        from rik.sysid.foreign import FOREIGN_KINDS, foreign_truth, simulate_foreign, write_foreign

        if effect not in FOREIGN_KINDS:
            raise RikError(f"--effect '{effect}' is not an effect of the foreign generator; use one of "
                           f"{', '.join(FOREIGN_KINDS)}")
        if second is not None or mass is not None:
            raise RikError("--second and --mass work with --generator rik only; the foreign generator draws one "
                           "effect and its own mass")
        foreign = foreign_truth(kind, joint.value, np.random.default_rng(seed))
        with console().status(f"simulating {trials} trials"):
            paths = write_foreign(simulate_foreign(foreign, n_trials=trials, seed=seed, duration_s=duration), out,
                                  foreign)
    else:
        truth = random_truth(kind, joint.value, np.random.default_rng(seed), mass=mass, second=second)
        with console().status(f"simulating {trials} trials"):
            made = simulate_trials(truth, n_trials=trials, seed=seed, duration_s=duration)
            paths = write_trials(made, out, truth)
    con = console()
    hidden = effect + (f" and {second}" if second else "")
    con.print(f"{len(paths)} trials of a {joint.value} joint with {hidden} hidden → {out}/ (truth in "
              f"{out / 'truth.json'})")
    con.print(f"fit them: rik sysid fit {out}/*.csv --joint {joint.value} --report {out}-report")


@app.command()
def apply(report: Annotated[Path, typer.Argument(help="A report directory of rik sysid fit (or its summary.json).",
                                                 show_default=False)],
          as_preset: Annotated[str, typer.Option("--as-preset", help="Id of the new resistance preset.",
                                                 show_default=False)],
          catalog_dir: Annotated[Path, typer.Option("--catalog-dir", help="User catalog directory to write the "
                                                    "preset into.")] = Path("my-catalog"),
          base: Annotated[str, typer.Option("--base", help="Preset whose values the other joint type keeps.")]
          = "normal",
          catalog: CatalogOption = None) -> None:
    """Add the fitted (extended) joint to a user catalog as a resistance preset, so variants are built with it."""
    from rik.sysid.preset import apply_report

    file = apply_report(report, as_preset, catalog_dir, base=base, overlays=overlays(catalog))
    con = console()
    con.print(f"preset '{as_preset}' → {file}")
    con.print(f"build variants with it: rik variants build --catalog {catalog_dir} --preset {as_preset} ...")


DEMO_DATA, DEMO_REPORT, DEMO_CATALOG = Path("sysid-data"), Path("sysid-report"), Path("sysid-catalog")
DEMO_PRESET = "demo-measured"


def print_demo_sysid(overlay_paths: list[Path]) -> None:
    """The demo's model discovery: simulated measurements of a drawer with a hidden soft-close damper into
    sysid-data/, the fit and its report into sysid-report/, the fitted joint as a preset in sysid-catalog/."""
    import shutil

    import numpy as np

    from rik.sysid.discover import discover
    from rik.sysid.generate import random_truth, simulate_trials, write_trials
    from rik.sysid.preset import apply_report
    from rik.sysid.report import write_report

    con = console()
    for old in (DEMO_DATA, DEMO_CATALOG):
        if old.exists():  # the demo's own earlier output
            shutil.rmtree(old)
    with con.status("model discovery on simulated measurements of a drawer ..."):
        truth = random_truth("soft_close", "slide", np.random.default_rng(0))
        trials = simulate_trials(truth, n_trials=4, seed=0)
        write_trials(trials, DEMO_DATA, truth)
        found = discover(trials)
        write_report(found, DEMO_REPORT)
        preset = apply_report(DEMO_REPORT, DEMO_PRESET, DEMO_CATALOG, overlays=overlay_paths)
    con.print(f"{len(trials)} measured trials of a drawer with a hidden effect ({DEMO_DATA}/; the truth in "
              f"{DEMO_DATA / 'truth.json'}): {found.sentence()}")
    con.print(f"report {DEMO_REPORT / 'report.md'}; preset '{DEMO_PRESET}' in {preset} (use it with --catalog "
              f"{DEMO_CATALOG} --preset {DEMO_PRESET})")
