"""``rik sysid fit``, ``rik sysid simulate`` and ``rik sysid apply``: model discovery from measured joint data.
Only parsing and printing here; :mod:`rik.sysid` does the work."""

from __future__ import annotations

from enum import StrEnum
from pathlib import Path
from typing import Annotated, Any

import typer

from rik.cli.common import CatalogOption, console, overlays
from rik.demo import DEMO_CATALOG, DEMO_DATA, DEMO_PRESET, DEMO_REPORT
from rik.errors import RikError
from rik.outputs import check_replaceable

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


def _column(role: str, header: str, feature: str) -> Any:
    return typer.Option(f"--{role}", help=f"The {role} column when not found by its usual name: a header such as "
                                          f"'{header}', or a LeRobot feature such as '{feature}'.",
                        show_default=False)


def _unit(role: str, units: str) -> Any:
    return typer.Option(f"--{role}-unit", help=f"Unit of the {role} column ({units}), when its header has none "
                                               "(LeRobot: always).", show_default=False)


@app.command()
def fit(data: Annotated[list[Path], typer.Argument(help="Trial files (.csv, .parquet) or one LeRobot dataset "
                                                        "folder (with --position and --force).", show_default=False)],
        joint: JointOption = JointOpt.slide,
        report: Annotated[Path, typer.Option("--report", "-o", help="Report directory (replaced whole, if it is an "
                                                                     "earlier report).")] = Path(
            "sysid-report"),
        heldout: Annotated[list[int] | None, typer.Option("--heldout", help="Index of a trial to hold out "
                                                          "(repeatable; default: the last quarter, or the end of a "
                                                          "single trial).")] = None,
        window: Annotated[float | None, typer.Option("--window", min=0.0, help="Smoothing window, s (default: the "
                                                     "shortest whose velocity noise is low enough).")] = None,
        delay: Annotated[float | None, typer.Option("--delay", help="Force-to-position delay, s (default: "
                                                    "estimated).")] = None,
        time: Annotated[str | None, _column("time", "timestamp_ms", "timestamp")] = None,
        time_unit: Annotated[str | None, _unit("time", "s or ms")] = None,
        position: Annotated[str | None, _column("position", "enc_pos", "observation.state[2]")] = None,
        position_unit: Annotated[str | None, _unit("position", "m, mm, cm; hinge: rad, deg")] = None,
        force: Annotated[str | None, _column("force", "ft_fx", "action[0]")] = None,
        force_unit: Annotated[str | None, _unit("force", "N, kN; hinge: N·m, N·mm")] = None,
        velocity: Annotated[str | None, _column("velocity", "enc_vel", "observation.state[3]")] = None,
        velocity_unit: Annotated[str | None, _unit("velocity", "m/s, mm/s, cm/s; hinge: rad/s, deg/s")] = None,
        trial: Annotated[str | None, typer.Option("--trial", help="The column that tells trials apart in a file "
                                                  "(default: 'trial', if any).", show_default=False)] = None,
        quasi_static: Annotated[bool, typer.Option("--quasi-static", help="The data is a force-against-position "
                                                   "profile with no time axis (default when it has no time "
                                                   "column); position unit 'bin' reads 1° angle bins, a force in "
                                                   "N on a hinge is a force at the handle.")] = False,
        group: Annotated[str | None, typer.Option("--group", help="Profile: the column naming each mechanism; one "
                                                  "report per group.", show_default=False)] = None,
        drop_nan: Annotated[bool, typer.Option("--drop-nan", help="Profile: leave out rows with an empty or NaN "
                                               "cell (counted) instead of stopping.")] = False) -> None:
    """Fit the baseline joint model, find the unmodelled effect, extend the model and measure the gain; write a
    report (report.md with plots, summary.json) that names the cause."""
    from rik.sysid.discover import discover
    from rik.sysid.profile import has_time_column
    from rik.sysid.report import REPORT_FOLDER, write_report
    from rik.sysid.trials import ColumnMap, load_lerobot_trials, load_trials

    check_replaceable(report, REPORT_FOLDER)  # before any work: a folder of the user's is never replaced
    con = console()
    folder = len(data) == 1 and data[0].is_dir()
    if quasi_static or (not folder and time is None and not has_time_column(data)):
        if not quasi_static:
            con.print("no time column: reading the data as a quasi-static force profile (force against position; "
                      "pass --time COLUMN if it has one)")
        fit_profiles(data, joint, report, heldout, position=position, position_unit=position_unit, force=force,
                     force_unit=force_unit, trial=trial, group=group, drop_nan=drop_nan)
        return
    columns = ColumnMap(time=time, position=position, force=force, velocity=velocity, trial=trial,
                        time_unit=time_unit, position_unit=position_unit, force_unit=force_unit,
                        velocity_unit=velocity_unit)
    if folder:
        trials = load_lerobot_trials(data[0], joint.value, columns)
    else:
        trials = load_trials(data, joint.value, columns=columns)
    with con.status(f"fitting {len(trials)} trials"):
        found = discover(trials, heldout=heldout, window_s=window, delay_s=delay)
        out = write_report(found, report)
    con.print(found.sentence())
    for text in found.selection.separation:
        con.print(f"  cannot tell apart from this data: {text}")
    con.print(f"report: {out / 'report.md'}  (summary: {out / 'summary.json'})")


def fit_profiles(data: list[Path], joint: JointOpt, report: Path, heldout: list[int] | None, *,
                 position: str | None, position_unit: str | None, force: str | None, force_unit: str | None,
                 trial: str | None, group: str | None, drop_nan: bool) -> None:
    """``rik sysid fit --quasi-static``: fit force-against-position profiles (rik.sysid.profile_fit) and write one
    report per group."""
    from rik.sysid.profile import read_profiles
    from rik.sysid.profile_fit import NOT_IDENTIFIED, fit_profile
    from rik.sysid.profile_report import verdict, write_profile_report

    con = console()
    profiles = read_profiles(data, joint.value, position=position, position_unit=position_unit, force=force,
                             force_unit=force_unit, trial=trial, group=group, drop_nan=drop_nan)
    if profiles.dropped:
        con.print(f"left out {profiles.dropped} rows with an empty or NaN cell (first: "
                  f"{profiles.dropped_rows[0]})")
    if profiles.bins:
        con.print("positions are angle bins, read as 1 bin = 1°")
    with con.status(f"fitting {len(profiles.groups)} quasi-static profile group(s)"):
        fits = [fit_profile(g, profiles.joint, profiles.force_unit, heldout) for g in profiles.groups]
        out = write_profile_report(profiles, fits, report)
    for f in fits:
        con.print(verdict(f))
    if profiles.handle_force:
        con.print("forces are at the handle, in N (no lever arm given)")
    con.print("not identifiable from a quasi-static profile: " + "; ".join(t.split(":")[0] for t in NOT_IDENTIFIED))
    con.print(f"report: {out / 'report.md'}  (summary: {out / 'summary.json'})")


@app.command()
def simulate(effect: Annotated[str, typer.Option("--effect", help="Hidden effect: none, stiction, soft_close, "
                                                 "self_close, magnetic_catch, tilt, direction_friction, "
                                                 "quadratic_damping, load_friction or spring.")] = "soft_close",
             second: Annotated[str | None, typer.Option("--second", help="A second hidden effect acting together "
                                                       "with --effect (e.g. self_close with soft_close, as on "
                                                       "soft-close runners).")] = None,
             joint: JointOption = JointOpt.slide,
             out: Annotated[Path, typer.Option("--out", "-o", help="Directory for the trial CSVs and truth.json "
                                                 "(replaced whole, if it holds earlier simulated trials).")]
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

    from rik.sysid.synthetic.generate import random_truth, simulate_trials, write_trials
    from rik.sysid.trials import simulated_folder

    check_replaceable(out, simulated_folder())  # before any work: a folder of the user's is never replaced
    kind = None if effect == "none" else effect
    if generator is GeneratorOpt.foreign:
        from rik.sysid.synthetic.foreign import FOREIGN_KINDS, foreign_truth, simulate_foreign, write_foreign

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


def print_demo_sysid(overlay_paths: list[Path]) -> None:
    """The demo's model discovery (:func:`rik.demo.discover_sysid`), printed: what the fit found in simulated
    measurements of a drawer, where the report and the fitted preset are."""
    from rik.demo import discover_sysid

    con = console()
    with con.status("model discovery on simulated measurements of a drawer ..."):
        found = discover_sysid(overlay_paths)
    con.print(f"{found.trials} measured trials of a drawer with a hidden effect ({DEMO_DATA}/; the truth in "
              f"{DEMO_DATA / 'truth.json'}): {found.sentence}")
    con.print(f"report {DEMO_REPORT / 'report.md'}; preset '{DEMO_PRESET}' in {found.preset} (use it with --catalog "
              f"{DEMO_CATALOG} --preset {DEMO_PRESET})")
