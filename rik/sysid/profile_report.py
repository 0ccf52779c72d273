"""Reports of quasi-static profile fits: per group (mechanism) ``report.md`` with ``profile.png`` (force against
position: each opening thin, held-out ones dashed, the median thick, the selected model over it) and
``summary.json``; with several groups, one sub-directory per group and an index ``report.md``/``summary.json``.

The report directory is written whole or not at all (a hidden sibling first, then renamed into place), like
:func:`rik.sysid.report.write_report`.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from rik.outputs import NEW, save_figure, staged_directory, write_text
from rik.paths import pyplot
from rik.schemas.joints import JointType
from rik.sysid.profile import ProfileData
from rik.sysid.profile_fit import (
    HANDLE_NOTE,
    IDENTIFIED,
    NOT_IDENTIFIED,
    SINGLE_TRIAL_EVERY,
    ProfileFit,
    ProfileRows,
    describe,
    predict,
)
from rik.sysid.report import PROFILE_PLOT, REPORT, REPORT_FOLDER, SUMMARY, effect_dict
from rik.sysid.select import MIN_BIC_DROP, MIN_GAIN, OCCAM, TIE

FORMAT = 1
"""Version of a profile ``summary.json``'s layout."""
GRID_POINTS = 60
"""Positions the median profile is evaluated at."""


def plot_units(joint: JointType) -> tuple[str, float]:
    """Plot unit of positions and its factor from SI: mm or degrees."""
    return ("mm", 1e3) if joint is JointType.slide else ("°", 180.0 / math.pi)


def median_profile(rows: ProfileRows, points: int = GRID_POINTS) -> tuple[np.ndarray, np.ndarray]:
    """Positions over the span every opening covers and the median force of the openings there (each opening
    interpolated linearly in position), SI."""
    spans = [(rows.q[rows.trial == i].min(), rows.q[rows.trial == i].max()) for i in np.unique(rows.trial)]
    lo, hi = max(s[0] for s in spans), min(s[1] for s in spans)
    if hi <= lo:
        lo, hi = float(rows.q.min()), float(rows.q.max())
    grid = np.linspace(lo, hi, points)
    curves = []
    for i in np.unique(rows.trial):
        q, f = rows.q[rows.trial == i], rows.f[rows.trial == i]
        order = np.argsort(q, kind="stable")
        curves.append(np.interp(grid, q[order], f[order]))
    return grid, np.median(np.array(curves), axis=0)


def force_label(fit: ProfileFit) -> str:
    return "force at the handle, N" if fit.force_unit.startswith("N at") else f"force, {fit.force_unit}"


def _text(fit: ProfileFit, text: str) -> str:
    """The library's messages speak of N·m on hinges; a force at the handle is in N."""
    return text.replace("N·m", "N") if fit.force_unit.startswith("N at") else text


def verdict(fit: ProfileFit) -> str:
    """One sentence: what was found, its parameters, the friction level, the held-out gain and the trial count."""
    sel = fit.selection
    unit = "N" if fit.force_unit.startswith("N at") else fit.force_unit
    n = len(fit.rows.names)
    level = f"friction level (or constant force) {fit.level:.3g} {unit}"
    if not sel.found:
        return f"{fit.group}: no position-dependent effect; {level} ({openings(n)})"
    parts = "; ".join(f"{f.title}: {describe(e, fit.joint, fit.force_unit)}"
                      for (f, _), e in zip(sel.final.terms, sel.final.effects, strict=True))
    others = [s.fit for s in (*sel.alternatives, *sel.pair_alternatives)]
    alt = f" (or: {', '.join(' + '.join(a.kinds) for a in others)})" if others else ""
    return f"{fit.group}: {parts}{alt}; {level}; held-out gain {sel.gain:.0%} ({openings(n)})"


def openings(n: int) -> str:
    return f"{n} opening" + ("" if n == 1 else "s")


def summary(fit: ProfileFit, data: ProfileData) -> dict[str, object]:
    """The JSON summary of one group's fit (SI positions; forces in ``units.force``)."""
    sel = fit.selection

    def candidate(s: Any) -> dict[str, object]:
        return {"kinds": list(s.fit.kinds), "title": " + ".join(f.title for f, _ in s.fit.terms),
                "effects": [effect_dict(e) for e in s.fit.effects], "level": float(s.fit.theta[0]),
                "gain": s.gain, "bic_drop": s.bic_drop, "rmse_train": s.fit.rmse_train,
                "rmse_heldout": s.fit.rmse_heldout, "parameters": s.fit.parameters, "verdict": _text(fit, s.verdict)}

    return {
        "format": FORMAT, "mode": "quasi-static", "group": fit.group, "joint": fit.joint.value,
        "units": {"position": "m" if fit.joint is JointType.slide else "rad", "force": fit.force_unit},
        "verdict": "effect" if sel.found else "none",
        "sentence": verdict(fit),
        "effects": list(sel.final.kinds),
        "parameters": [effect_dict(e) for e in fit.effects],
        "friction_level": fit.level,
        "gain": sel.gain,
        "alternatives": [list(s.fit.kinds) for s in (*sel.alternatives, *sel.pair_alternatives)],
        "separation": list(sel.separation),
        "trials": {"names": list(fit.rows.names), "heldout": [fit.rows.names[i] for i in fit.heldout_trials],
                   "points_train": len(fit.train), "points_heldout": len(fit.heldout)},
        "identified": list(IDENTIFIED),
        "not_identified": list(NOT_IDENTIFIED) + ([HANDLE_NOTE] if data.handle_force else []),
        "position_bins": ("angle bins read as 1 bin = 1 degree" if data.bins else None),
        "dropped_rows": data.dropped,
        "thresholds": {"min_gain": MIN_GAIN, "min_bic_drop": MIN_BIC_DROP, "occam": OCCAM, "tie": TIE},
        "candidates": [candidate(s) for s in sel.scores],
        "pairs": [candidate(s) for s in sel.pairs],
    }


def plot_profile(fit: ProfileFit, path: Path, ax: Any = None, title: str | None = None,
                 legend: bool = True) -> Path | None:
    """Force against position: openings thin (held-out dashed), median thick, the selected model over it. Draws
    into ``ax`` when given (returns None), else saves a figure at ``path``."""
    plt = pyplot()
    fig = None
    if ax is None:
        fig, ax = plt.subplots(figsize=(6.0, 3.6))
    unit, scale = plot_units(fit.joint)
    rows = fit.rows
    held = set(fit.heldout_trials) if len(rows.names) > 1 else set()
    labelled: set[bool] = set()
    for i in np.unique(rows.trial):
        q, f = rows.q[rows.trial == i], rows.f[rows.trial == i]
        order = np.argsort(q, kind="stable")
        out = int(i) in held
        ax.plot(q[order] * scale, f[order], color="tab:blue" if out else "0.6", lw=0.6, ls="--" if out else "-",
                label=None if out in labelled else ("held-out opening" if out else "opening"))
        labelled.add(out)
    grid, med = median_profile(rows)
    ax.plot(grid * scale, med, color="k", lw=2.2, label="median")
    fine = np.linspace(float(rows.q.min()), float(rows.q.max()), 200)
    name = " + ".join(fit.selection.final.kinds) or "no effect"
    ax.plot(fine * scale, predict(fit.selection.final, fine, fit.joint), color="tab:red", lw=1.6,
            label=f"fit: {name}")
    ax.set_title(title or fit.group, fontsize=8)
    ax.set_xlabel(f"position, {unit}" if fit.joint is JointType.slide else f"angle, {unit}", fontsize=7)
    ax.set_ylabel(force_label(fit), fontsize=7)
    ax.tick_params(labelsize=6)
    if legend:
        ax.legend(fontsize=6, frameon=False)
    if fig is not None:
        fig.tight_layout()
        return save_figure(fig, path, NEW)
    return None


def markdown(fit: ProfileFit, data: dict[str, Any]) -> str:
    """``report.md`` of one group."""
    sel = fit.selection
    unit = "N" if fit.force_unit.startswith("N at") else fit.force_unit
    lines = [f"# Quasi-static profile: {fit.group}", "", data["sentence"], "",
             f"![force against position]({PROFILE_PLOT})", "",
             f"{openings(len(fit.rows.names))}, {len(fit.rows)} points; held out: "
             f"{', '.join(data['trials']['heldout'])}"
             + (f" (every {SINGLE_TRIAL_EVERY}th point)" if len(fit.rows.names) == 1 else "") + ".", ""]
    if data["position_bins"]:
        lines += [f"Positions: {data['position_bins']} (about one degree per bin).", ""]
    if data["dropped_rows"]:
        lines += [f"{data['dropped_rows']} rows with an empty or NaN cell were left out (--drop-nan).", ""]
    lines += ["## What this data can and cannot identify", "", "Identified (fitted and selected):", ""]
    lines += [f"- {t}" for t in data["identified"]]
    lines += ["", "Not identifiable from a force-against-position profile:", ""]
    lines += [f"- {t}" for t in data["not_identified"]]
    lines += ["", "## Candidates", "",
              f"Each is the friction level plus one effect (then pairs), fitted on the training openings and scored "
              f"on the held-out ones; it passes with a held-out gain of at least {MIN_GAIN:.0%}, a BIC drop of at "
              f"least {MIN_BIC_DROP:g} and physical parameters (rik.sysid.select).", "",
              f"| model | held-out RMSE, {unit} | gain | BIC drop | level, {unit} | verdict |",
              "|---|---:|---:|---:|---:|---|",
              f"| friction level only | {sel.baseline.rmse_heldout:.3g} | | | {float(sel.baseline.theta[0]):.3g} | |"]
    for s in (*sel.scores, *sel.pairs):
        lines.append(f"| {' + '.join(s.fit.kinds)} | {s.fit.rmse_heldout:.3g} | {s.gain:.0%} | {s.bic_drop:.1f} | "
                     f"{float(s.fit.theta[0]):.3g} | {_text(fit, s.verdict)} |")
    if sel.separation:
        lines += ["", "Cannot tell apart from this data:", ""] + [f"- {t}" for t in sel.separation]
    return "\n".join(lines) + "\n"


def slug(name: str) -> str:
    """A directory name for a group."""
    return re.sub(r"[^A-Za-z0-9._-]+", "_", name).strip("._") or "group"


def _write_group(fit: ProfileFit, data: ProfileData, directory: Path) -> dict[str, object]:
    directory.mkdir(parents=True, exist_ok=True)
    info = summary(fit, data)
    plot_profile(fit, directory / PROFILE_PLOT)
    write_text(directory / SUMMARY, json.dumps(info, indent=2) + "\n", NEW)
    write_text(directory / REPORT, markdown(fit, info), NEW)
    return info


def write_profile_report(data: ProfileData, fits: Sequence[ProfileFit], directory: Path) -> Path:
    """Write the report(s) of ``fits`` into ``directory`` (replaced whole if it is an earlier report,
    :data:`rik.sysid.report.REPORT_FOLDER`; any other folder that is not empty is refused); returns it."""
    directory = Path(directory)
    with staged_directory(directory, REPORT_FOLDER) as stage:
        if len(fits) == 1:
            _write_group(fits[0], data, stage)
        else:
            infos = [_write_group(f, data, stage / slug(f.group)) for f in fits]
            groups = [{"group": f.group, "directory": slug(f.group), "sentence": i["sentence"],
                       "effects": i["effects"], "gain": i["gain"], "trials": len(f.rows.names)}
                      for f, i in zip(fits, infos, strict=True)]
            index = {"format": FORMAT, "mode": "quasi-static", "groups": groups, "dropped_rows": data.dropped}
            lines = ["# Quasi-static profiles", "", "| group | openings | found | held-out gain | report |",
                     "|---|---:|---|---:|---|"]
            for f, g in zip(fits, groups, strict=True):
                found = str(g["sentence"])[len(f.group) + 2:]
                lines.append(f"| {f.group} | {g['trials']} | {found} | {f.selection.gain:.0%} | "
                             f"[{g['directory']}]({g['directory']}/{REPORT}) |")
            write_text(stage / SUMMARY, json.dumps(index, indent=2) + "\n", NEW)
            write_text(stage / REPORT, "\n".join(lines) + "\n", NEW)
    return directory
