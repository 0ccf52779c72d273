"""The report of a discovery: ``report.md`` with plots, and ``summary.json`` (what ``rik sysid apply`` reads).

Plots (PNG, matplotlib Agg):

- ``residual_time.png``: the baseline's force residual against time, one panel per trial (held-out ones marked),
  with the extended model's residual over it;
- ``residual_position.png``: the baseline residual against position, opening and closing apart (binned means
  over the scattered samples), where zone effects (soft-close, self-close, magnet) show;
- ``residual_velocity.png``: the baseline residual against velocity, where friction laws (stiction, quadratic
  damping, direction-dependent friction) show;
- ``breakaway.png``: the force at each breakaway from rest against where it happened (:mod:`rik.sysid.breakaway`),
  with the static resistance the baseline and the extended model predict there;
- ``resimulated.png``: measured position of each held-out trial and its MuJoCo re-simulation with the baseline
  and with the extended joint.

The report directory is written whole or not at all: into a hidden sibling first, then renamed into place.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypedDict

import numpy as np

from rik.outputs import NEW, MadeFolder, holds_only, save_figure, staged_directory, tree_holds_only, write_text
from rik.paths import json_object, pyplot
from rik.schemas.joints import JointType, Spring
from rik.sysid.discover import Discovery, describe
from rik.sysid.fit import Fit, Rows, concat_rows
from rik.sysid.select import MIN_BIC_DROP, MIN_GAIN

if TYPE_CHECKING:
    from rik.sysid.effects import Effect
    from rik.sysid.select import Score

SUMMARY = "summary.json"
REPORT = "report.md"
PROFILE_PLOT = "profile.png"
"""The plot of a quasi-static profile report (:mod:`rik.sysid.profile_report`, which imports this module): named
here because :func:`is_report` recognises both kinds of report."""
FORMAT = 1
"""Version of ``summary.json``'s layout."""
class _Units(TypedDict):
    position: str
    force: str
    plot_pos: tuple[str, float]
    """Plot unit of positions and its factor from SI."""
    plot_vel: tuple[str, float]


_UNITS: dict[JointType, _Units] = {
          JointType.slide: {"position": "m", "force": "N", "plot_pos": ("mm", 1e3), "plot_vel": ("mm/s", 1e3)},
          JointType.hinge: {"position": "rad", "force": "N·m", "plot_pos": ("°", 180 / np.pi),
                            "plot_vel": ("°/s", 180 / np.pi)}}


def _residuals(fit: Fit, rows: Rows) -> np.ndarray:
    return rows.f - fit.predict(rows)


def effect_dict(effect: Effect | None) -> dict[str, Any] | None:
    if effect is None:
        return None
    data = effect.model_dump(mode="json")
    return {"kind": "spring", **data} if isinstance(effect, Spring) else data


def summary(d: Discovery) -> dict[str, object]:
    """The JSON summary of a discovery (SI units; see :data:`FORMAT`)."""
    sel = d.selection
    base = sel.baseline.baseline
    resistance = d.extended_resistance or d.baseline_resistance
    units = _UNITS[d.joint]
    fb, fe = d.force_rmse
    pb, pe = d.position_rmse
    return {
        "format": FORMAT,
        "joint": d.joint.value,
        "units": {"position": units["position"], "force": units["force"]},
        "cause": d.sentence(),
        "verdict": "effect" if sel.found else "none",
        "effect": sel.final.kinds[0] if sel.found else None,
        "effects": list(sel.final.kinds),
        "alternatives": [s.fit.kind for s in sel.alternatives],
        "pair_alternatives": [list(s.fit.kinds) for s in sel.pair_alternatives],
        "separation": list(sel.separation),
        "trials": {"names": list(d.rows.names), "heldout": [d.rows.names[i] for i in d.split.heldout_trials],
                   "heldout_from_s": d.split.heldout_from},
        "preprocessing": {"rate_hz": d.prepared[0].settings.rate_hz, "window_s": d.prepared[0].settings.window_s,
                          "delay_s": d.delay_s, "fit_velocity": d.fit_velocity, "limits": list(d.limits),
                          "rows_train": len(d.split.train), "rows_heldout": len(d.split.heldout)},
        "baseline": {"inertia": base.inertia, "damping": base.damping, "frictionloss": base.friction},
        "inertia": sel.final.baseline.inertia,
        "resistance": resistance.model_dump(mode="json"),
        "errors": {"force_rmse": {"baseline": fb, "extended": fe},
                   "position_rmse": {"baseline": pb, "extended": pe}},
        "thresholds": {"min_gain": MIN_GAIN, "min_bic_drop": MIN_BIC_DROP},
        "breakaways": [{"trial": d.rows.names[int(r.trial[i])], "t": float(r.t[i]), "position": float(r.q[i]),
                        "direction": int(np.sign(r.qd[i])), "force": float(r.f[i])}
                       for r in (breakaway_rows(d),) for i in range(len(r))],
        "candidates": [_candidate(s) for s in sel.scores],
        "pairs": [_candidate(s) for s in sel.pairs],
    }


def _candidate(s: Score) -> dict[str, object]:
    return {"kind": s.fit.kind, "kinds": list(s.fit.kinds), "title": " + ".join(f.title for f, _ in s.fit.terms),
            "hyper": s.fit.hyper, "effects": [effect_dict(e) for e in s.fit.effects], "gain": s.gain,
            "bic_drop": s.bic_drop,
            "rmse_train": s.fit.rmse_train, "rmse_heldout": s.fit.rmse_heldout, "parameters": s.fit.parameters,
            "verdict": s.verdict}


# ------------------------------------------------------------------------------------------------------ plots

Residuals = tuple[Rows, np.ndarray, np.ndarray | None, np.ndarray]
"""All fit rows, the baseline's residuals, the chosen model's (None without one), held-out flags."""


def all_residuals(d: Discovery) -> Residuals:
    """The moving fit rows (training then held-out; breakaways have their own plot), the baseline's and the
    chosen model's residuals, held-out flags."""
    sel = d.selection
    every = concat_rows(d.split.train, d.split.heldout)
    moving = ~every.breakaways
    rows = every.take(moving)
    held = np.concatenate([np.zeros(len(d.split.train), bool), np.ones(len(d.split.heldout), bool)])[moving]
    chosen = sel.final if sel.found else None
    return rows, _residuals(sel.baseline, rows), _residuals(chosen, rows) if chosen else None, held


def _binned(x: np.ndarray, y: np.ndarray, bins: int = 30) -> tuple[np.ndarray, np.ndarray]:
    if len(x) < 2:
        return x, y
    edges = np.linspace(x.min(), x.max(), bins + 1)
    idx = np.clip(np.digitize(x, edges) - 1, 0, bins - 1)
    centres, means = [], []
    for b in range(bins):
        m = idx == b
        if m.sum() >= 5:
            centres.append(0.5 * (edges[b] + edges[b + 1]))
            means.append(float(y[m].mean()))
    return np.array(centres), np.array(means)


def plot_residual_time(d: Discovery, res: Residuals, path: Path) -> Path:
    rows, rb, re, held = res
    plt = pyplot()
    n = len(d.rows.names)
    fig, axes = plt.subplots(n, 1, figsize=(9, 1.8 * n + 0.6), sharey=True, squeeze=False)
    unit = _UNITS[d.joint]["force"]
    for i, ax in enumerate(axes[:, 0]):
        m = rows.trial == i
        ax.plot(rows.t[m], rb[m], ".", ms=1.5, color="tab:red", label="baseline")
        if re is not None:
            ax.plot(rows.t[m], re[m], ".", ms=1.5, color="tab:blue", label="extended")
        ax.axhline(0, color="grey", lw=0.6)
        tag = " (held out)" if held[m].any() and not (~held[m]).any() else (" (end held out)" if held[m].any()
                                                                            else "")
        ax.set_title(f"{d.rows.names[i]}{tag}", fontsize=8, loc="left")
        ax.set_ylabel(f"residual [{unit}]", fontsize=7)
    axes[-1, 0].set_xlabel("time [s]")
    axes[0, 0].legend(fontsize=7, markerscale=6, loc="upper right")
    fig.tight_layout()
    return save_figure(fig, path, NEW)


def plot_residual_position(d: Discovery, res: Residuals, path: Path) -> Path:
    rows, rb, re, _ = res
    plt = pyplot()
    label, scale = _UNITS[d.joint]["plot_pos"]
    unit = _UNITS[d.joint]["force"]
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.6), sharey=True)
    for ax, name, mask in ((axes[0], "opening", rows.qd > 0), (axes[1], "closing", rows.qd < 0)):
        x = rows.q[mask] * scale
        ax.plot(x, rb[mask], ".", ms=1.2, color="tab:red", alpha=0.25)
        ax.plot(*_binned(x, rb[mask]), "-", color="tab:red", lw=1.8, label="baseline, binned mean")
        if re is not None:
            ax.plot(*_binned(x, re[mask]), "-", color="tab:blue", lw=1.8, label="extended, binned mean")
        ax.axhline(0, color="grey", lw=0.6)
        ax.set_title(name, fontsize=9)
        ax.set_xlabel(f"position [{label}]")
    axes[0].set_ylabel(f"force residual [{unit}]")
    axes[0].legend(fontsize=7)
    fig.tight_layout()
    return save_figure(fig, path, NEW)


def plot_residual_velocity(d: Discovery, res: Residuals, path: Path) -> Path:
    rows, rb, re, _ = res
    plt = pyplot()
    label, scale = _UNITS[d.joint]["plot_vel"]
    fig, ax = plt.subplots(figsize=(7, 3.6))
    x = rows.qd * scale
    ax.plot(x, rb, ".", ms=1.2, color="tab:red", alpha=0.25)
    for sign in (1, -1):
        m = np.sign(rows.qd) == sign
        ax.plot(*_binned(x[m], rb[m], 20), "-", color="tab:red", lw=1.8,
                label="baseline, binned mean" if sign > 0 else None)
        if re is not None:
            ax.plot(*_binned(x[m], re[m], 20), "-", color="tab:blue", lw=1.8,
                    label="extended, binned mean" if sign > 0 else None)
    ax.axhline(0, color="grey", lw=0.6)
    ax.set_xlabel(f"velocity [{label}]")
    ax.set_ylabel(f"force residual [{_UNITS[d.joint]['force']}]")
    ax.legend(fontsize=7)
    fig.tight_layout()
    return save_figure(fig, path, NEW)


def plot_resimulated(d: Discovery, res: Residuals, path: Path) -> Path:
    plt = pyplot()
    label, scale = _UNITS[d.joint]["plot_pos"]
    n = max(len(d.resimulated), 1)
    fig, axes = plt.subplots(n, 1, figsize=(9, 2.2 * n + 0.6), squeeze=False)
    for ax, r in zip(axes[:, 0], d.resimulated, strict=False):
        ax.plot(r.t, r.q * scale, color="black", lw=1.4, label="measured")
        ax.plot(r.t, r.baseline * scale, color="tab:red", lw=1.0, label="baseline joint")
        if r.extended is not None:
            ax.plot(r.t, r.extended * scale, color="tab:blue", lw=1.0, label="extended joint")
        ax.set_title(f"{r.trial}: re-simulated from the measured state every {d.resim_window_s:g} s, driven by the "
                     f"measured force", fontsize=8, loc="left")
        ax.set_ylabel(f"position [{label}]")
    axes[-1, 0].set_xlabel("time [s]")
    axes[0, 0].legend(fontsize=7)
    fig.tight_layout()
    return save_figure(fig, path, NEW)


def breakaway_rows(d: Discovery) -> Rows:
    """The breakaway rows of the fit (training then held-out)."""
    every = concat_rows(d.split.train, d.split.heldout)
    return every.take(every.breakaways)


def plot_breakaway(d: Discovery, res: Residuals, path: Path) -> Path:
    """Each breakaway from rest: the measured force against where it happened, opening and closing apart, with
    the static resistance the baseline and the chosen model predict there."""
    rows = breakaway_rows(d)
    plt = pyplot()
    label, scale = _UNITS[d.joint]["plot_pos"]
    fig, ax = plt.subplots(figsize=(7, 3.6))
    sel = d.selection
    for sign, marker, name in ((1, "^", "opening"), (-1, "v", "closing")):
        m = np.sign(rows.qd) == sign
        if not m.any():
            continue
        x = rows.q[m] * scale
        ax.plot(x, rows.f[m], marker, color="black", ms=6, label=f"measured breakaway, {name}")
        ax.plot(x, sel.baseline.predict(rows.take(m)), marker, mfc="none", color="tab:red", ms=8,
                label="baseline" if sign > 0 else None)
        if sel.found:
            ax.plot(x, sel.final.predict(rows.take(m)), marker, mfc="none", color="tab:blue", ms=11,
                    label="extended" if sign > 0 else None)
    ax.axhline(0, color="grey", lw=0.6)
    ax.set_xlabel(f"position [{label}]")
    ax.set_ylabel(f"force at breakaway [{_UNITS[d.joint]['force']}]")
    ax.set_title(f"{len(rows)} starts of motion from rest", fontsize=8, loc="left")
    if len(rows):
        ax.legend(fontsize=7)
    fig.tight_layout()
    return save_figure(fig, path, NEW)


PLOTS = {"residual_time.png": plot_residual_time, "residual_position.png": plot_residual_position,
         "residual_velocity.png": plot_residual_velocity, "breakaway.png": plot_breakaway,
         "resimulated.png": plot_resimulated}


# --------------------------------------------------------------------------------------------------- markdown

def markdown(d: Discovery, data: dict[str, Any]) -> str:
    """The report's text."""
    sel = d.selection
    u = _UNITS[d.joint]
    pos_label, pos_scale = u["plot_pos"]
    base = sel.baseline.baseline
    inertia = "kg" if d.joint is JointType.slide else "kg·m²"
    damp = "N·s/m" if d.joint is JointType.slide else "N·m·s/rad"
    lines = [f"# rik sysid report ({d.joint.value} joint)", "", f"**{d.sentence()}**", ""]
    if sel.alternatives or sel.separation:
        lines += ["## What this data cannot decide", ""]
        for text in sel.separation:
            lines.append(f"- {text[0].upper()}{text[1:]}.")
        lines.append("")
    pb, pe = d.position_rmse
    fb, fe = d.force_rmse
    lines += ["## Held-out errors", "",
              f"| model | force RMSE [{u['force']}] | re-simulated position RMSE [{pos_label}] |", "|---|---:|---:|",
              f"| baseline (inertia, damping, friction) | {fb:.4g} | {pb * pos_scale:.4g} |"]
    if fe is not None:
        lines.append(f"| extended ({' + '.join(f.title for f, _ in sel.final.terms)}) | {fe:.4g} | "
                     f"{(pe * pos_scale if pe is not None else float('nan')):.4g} |")
    lines += ["", f"Held out: {', '.join(data['trials']['heldout'])}"
              + (f" from {d.split.heldout_from:.2f} s on" if d.split.heldout_from is not None else "")
              + f" ({len(d.split.heldout)} moving samples; {len(d.split.train)} for fitting). Re-simulation: MuJoCo, "
              f"the joint materialised as variants get it, driven by the measured force and restarted from the "
              f"measured state every {d.resim_window_s:g} s.", "",
              "## Baseline fit (rik's joint model)", "",
              f"inertia {base.inertia:.4g} {inertia}, damping {base.damping:.4g} {damp}, friction "
              f"{base.friction:.4g} {u['force']}; training RMSE {sel.baseline.rmse_train:.4g} {u['force']}.", "",
              "![residual against time](residual_time.png)", "",
              "![residual against position](residual_position.png)", "",
              "![residual against velocity](residual_velocity.png)", "",
              f"Breakaways from rest ({int(d.rows.breakaways.sum())} found: the force at which a resting front "
              f"started to move, which holds the static resistance the moving samples do not show; they enter the fit "
              f"as samples at rest):", "",
              "![breakaway force against position](breakaway.png)", "",
              "![re-simulated held-out trials](resimulated.png)", "",
              "## Candidates", "",
              f"Each is the baseline plus one effect, fitted on the training data. It passes with a held-out gain of "
              f"at least {MIN_GAIN:.0%}, a BIC drop of at least {MIN_BIC_DROP:g} and physical parameters.", "",
              "| effect | fitted | held-out gain | BIC drop | verdict |", "|---|---|---:|---:|---|"]
    for s in sel.scores:
        lines.append(f"| {s.fit.title} | {describe(s.fit.effect, d.joint)} | {s.gain:.1%} | "
                     f"{s.bic_drop:.0f} | {s.verdict} |")
    if sel.pairs:
        against = sel.chosen.fit.title if sel.chosen else "the baseline: no single effect passed"
        lines += ["", f"Pairs of effects, scored against the best single effect ({against}) and required to beat "
                      f"each member alone by {MIN_GAIN:.0%}; the ten best:", "",
                  "| effects | fitted | held-out gain | BIC drop | verdict |", "|---|---|---:|---:|---|"]
        for s in sel.pairs[:10]:
            fitted = "; ".join(describe(e, d.joint) for e in s.fit.effects)
            lines.append(f"| {' + '.join(f.title for f, _ in s.fit.terms)} | {fitted} | {s.gain:.1%} | "
                         f"{s.bic_drop:.0f} | {s.verdict} |")
    lines += ["", "## Data", "",
              f"{len(d.rows.names)} trials ({', '.join(d.rows.names)}) at {data['preprocessing']['rate_hz']:g} Hz; "
              f"force-to-position delay {d.delay_s * 1e3:.1f} ms (one for all trials); samples enter the fit above "
              f"{d.fit_velocity * pos_scale:.3g} {pos_label}/s (4 times the velocity noise, at least the default) and "
              f"away from the range's ends ({d.limits[0] * pos_scale:.3g} to {d.limits[1] * pos_scale:.3g} "
              f"{pos_label}).", "",
              "Make it a preset: `rik sysid apply DIR --as-preset NAME --catalog CATALOG_DIR`, with this report's "
              "directory as DIR.", ""]
    return "\n".join(lines)


def is_report(folder: Path) -> bool:
    """Whether ``folder`` is a report ``rik sysid fit`` wrote (of trials, or of quasi-static profiles, one group or
    several): its ``summary.json`` is a rik summary and it holds nothing else but the files rik writes there."""
    data = json_object(folder / SUMMARY)
    if data is None or data.get("format") != FORMAT:
        return False
    groups = data.get("groups") if data.get("mode") == "quasi-static" else None
    if not isinstance(groups, list):
        return tree_holds_only(folder, {SUMMARY, REPORT, PROFILE_PLOT, *PLOTS})
    named = [g.get("directory") if isinstance(g, dict) else None for g in groups]
    subdirs = {s for s in named if isinstance(s, str) and "/" not in s and s not in ("", ".", "..")}
    return (len(subdirs) == len(named)
            and holds_only(folder, {SUMMARY, REPORT, *subdirs})
            and all(not (folder / s).exists() or ((folder / s).is_dir() and is_report(folder / s)) for s in subdirs))


REPORT_FOLDER = MadeFolder("a report of rik sysid fit", is_report, "choose another --report")
"""The report folder: replaced whole on a rerun, and only if :func:`is_report` recognises it."""


def write_report(d: Discovery, directory: Path) -> Path:
    """Write ``report.md``, ``summary.json`` and the plots into ``directory`` (replaced whole if it is an earlier
    report, :data:`REPORT_FOLDER`; any other folder that is not empty is refused)."""
    directory = Path(directory)
    with staged_directory(directory, REPORT_FOLDER) as stage:
        data = summary(d)
        res = all_residuals(d)
        for name, plot in PLOTS.items():
            plot(d, res, stage / name)
        write_text(stage / SUMMARY, json.dumps(data, indent=2) + "\n", NEW)
        write_text(stage / REPORT, markdown(d, data), NEW)
    return directory
