"""Model discovery end to end: measured trials → the baseline fit, the cause, the extended joint model, the gain.

:func:`discover` preprocesses every trial (one force-to-position delay for all: the median of the per-trial
estimates, since one sensor rig made them), fits the baseline and every effect of the library by equation error
on the training trials, selects (:mod:`rik.sysid.select`), and measures the gain on the held-out trials twice:

- in force: the held-out RMSE of the equation error before and after (N or N·m);
- in position: MuJoCo re-simulates each held-out trial driven by its measured force, restarted from the measured
  state every ``resim_window_s`` (multiple shooting: friction makes long open-loop runs drift), with the fitted
  baseline joint and with the extended one, both materialised the way variants are (:mod:`rik.sysid.resim`).
"""

from __future__ import annotations

import statistics
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from rik.errors import RikError
from rik.schemas import joints as j
from rik.schemas.common import Provenance
from rik.schemas.joints import JointResistance, JointType, Spring
from rik.sysid.effects import FAMILIES, Baseline, Effect
from rik.sysid.fit import Fit, Rows, Split, all_rows, fit_all, fit_model, fit_velocity, split_rows
from rik.sysid.preprocess import Prepared, preprocess
from rik.sysid.resim import joint_spec_model, resimulate
from rik.sysid.select import Selection, pair_allowed, select, select_pair
from rik.sysid.trials import Trial

WINDOWS_S = (0.1, 0.15, 0.2, 0.3)
"""Savitzky–Golay windows tried, shortest first, s."""
NOISE_FLOOR = {JointType.slide: 0.02, JointType.hinge: 0.1}
"""Highest acceptable fit velocity (noise floor), m/s or rad/s: the automatic window is the shortest whose floor is
below it. A longer window passes less noise into velocity and acceleration (their noise falls with the window's
length to the power 1.5 and 2.5) but blurs fast changes."""
RESIM_WINDOW_S = 0.5
"""Restart interval of the multiple-shooting re-simulation, s."""
_FORCE = {JointType.slide: "N", JointType.hinge: "N·m"}
_POS = {JointType.slide: ("mm", 1e3), JointType.hinge: ("°", 180.0 / np.pi)}


@dataclass(frozen=True)
class Resimulated:
    """One held-out stretch re-simulated with the baseline and the extended joint."""

    trial: str
    t: np.ndarray
    q: np.ndarray
    """Measured (smoothed) position, m or rad."""
    baseline: np.ndarray
    extended: np.ndarray | None


@dataclass(frozen=True, eq=False)
class Discovery:
    """Everything :func:`discover` found."""

    joint: JointType
    prepared: tuple[Prepared, ...]
    rows: Rows
    split: Split
    selection: Selection
    delay_s: float
    limits: tuple[float, float]
    baseline_resistance: JointResistance
    extended_resistance: JointResistance | None
    resimulated: tuple[Resimulated, ...]
    position_rmse: tuple[float, float | None]
    """Held-out re-simulated position RMSE (baseline, extended), m or rad."""
    fit_velocity: float
    """Speed from which samples entered the fit, m/s or rad/s."""
    resim_window_s: float
    """Restart interval of the re-simulation, s."""

    @property
    def inertia(self) -> float:
        """Fitted moving mass (kg) or inertia (kg·m²) of the baseline."""
        return self.selection.baseline.baseline.inertia

    @property
    def chosen(self) -> Fit | None:
        """The selected model (the baseline plus every chosen effect), None when no effect was chosen."""
        return self.selection.final if self.selection.found else None

    @property
    def force_rmse(self) -> tuple[float, float | None]:
        """Held-out equation-error RMSE (baseline, extended), N or N·m."""
        return self.selection.baseline.rmse_heldout, self.chosen.rmse_heldout if self.chosen else None

    def sentence(self) -> str:
        """The cause, in one sentence."""
        unit = _FORCE[self.joint]
        pos_unit, scale = _POS[self.joint]
        fb, fe = self.force_rmse
        pb, pe = self.position_rmse
        if not self.selection.found:
            best = self.selection.scores[0] if self.selection.scores else None
            tail = (f"; the best candidate, {best.fit.title}, fails: {best.verdict}" if best else "")
            return (f"No significant unmodelled effect: damping and Coulomb friction explain the held-out data "
                    f"(force error {fb:.3g} {unit}){tail}.")
        final = self.selection.final
        also = ""
        others = self.selection.pair_alternatives if self.selection.pair else self.selection.alternatives
        if others:
            names = " or ".join(" + ".join(f.title for f, _ in s.fit.terms) for s in others)
            also = f" (this data cannot tell {'them' if self.selection.pair else 'it'} from {names}; see below)"
        position = ""
        if pe is not None:
            position = (f" and the re-simulated position error from {pb * scale:.3g} to {pe * scale:.3g} "
                        f"{pos_unit}")
        causes = [f"{family.cause}: {describe(effect, self.joint)}"
                  for (family, _), effect in zip(final.terms, final.effects, strict=True)]
        it = "it" if len(causes) == 1 else "them"
        return (f"The simulation misses {'; and '.join(causes)}{also}; adding {it} cuts the held-out force error "
                f"from {fb:.3g} to {fe:.3g} {unit} ({self.selection.gain:.0%}){position}.")


def describe(effect: Effect | None, joint: JointType) -> str:
    """The effect's parameters in words with units."""
    if effect is None:
        return "none"
    slide = joint is JointType.slide
    f, length = ("N", "mm") if slide else ("N·m", "°")
    to_len = 1e3 if slide else 180.0 / np.pi
    damp = "N·s/m" if slide else "N·m·s/rad"
    stiff = "N/m" if slide else "N·m/rad"
    speed = "mm/s" if slide else "°/s"
    match effect:
        case j.Stiction():
            return (f"breakaway friction {effect.breakaway:.3g} {f} above sliding, fading by "
                    f"{effect.stribeck_velocity * to_len:.3g} {speed}")
        case j.SoftClose():
            return f"damping {effect.damping:.3g} {damp} within {effect.zone * to_len:.3g} {length} of closed"
        case j.SelfClose():
            return (f"stiffness {effect.stiffness:.3g} {stiff} over the last {effect.zone * to_len:.3g} {length}, "
                    f"a pull of {effect.stiffness * effect.zone:.3g} {f} at closed")
        case j.MagneticCatch():
            return f"a pull of {effect.force:.3g} {f} at contact, decaying over {effect.decay * to_len:.3g} {length}"
        case j.Tilt():
            extra = f" and {effect.sine:.3g} {f} × sin(angle)" if not slide else ""
            return f"a constant {effect.force:.3g} {f} pushing it {'open' if effect.force > 0 else 'closed'}{extra}"
        case j.DirectionFriction():
            return f"{effect.extra:.3g} {f} more friction when {effect.direction}"
        case j.QuadraticDamping():
            sq = "N·s²/m²" if slide else "N·m·s²/rad²"
            return f"a coefficient of {effect.coefficient:.3g} {sq}"
        case j.LoadFriction():
            return f"{effect.per_extension / (1e3 if slide else to_len):.3g} {f} more friction per {length} open"
        case j.Spring():
            return (f"stiffness {effect.stiffness:.3g} {stiff} with its rest at {effect.reference * to_len:.3g} "
                    f"{length}")
    return str(effect)


def resistance_of(base: Baseline, effects: Sequence[Effect], notes: str) -> JointResistance:
    """A measured :class:`JointResistance` from fitted values (negative damping or friction clipped to 0)."""
    spring = next((e for e in effects if isinstance(e, Spring)), None)
    return JointResistance(damping=max(base.damping, 0.0), frictionloss=max(base.friction, 0.0), spring=spring,
                           effects=tuple(e for e in effects if not isinstance(e, Spring)),
                           provenance=Provenance.measured, notes=notes)


def prepare_all(trials: Sequence[Trial], *, rate_hz: float | None = None, window_s: float | None = None,
                delay_s: float | None = None) -> tuple[list[Prepared], float]:
    """Preprocess every trial with one smoothing window and one delay, s. The window, unless given, is the
    shortest of :data:`WINDOWS_S` whose velocity noise floor (:func:`rik.sysid.fit.fit_velocity`) is below
    :data:`NOISE_FLOOR`, else the longest. The delay, unless given, is the median of the per-trial estimates on
    samples moving faster than the floor."""
    if not trials:
        raise RikError("no trials to fit")
    joints = {t.joint for t in trials}
    if len(joints) > 1:
        raise RikError(f"trials of different joint types: {', '.join(sorted(j.value for j in joints))}")
    joint = next(iter(joints))
    for window in (window_s,) if window_s else WINDOWS_S:
        moving = fit_velocity([preprocess(t, rate_hz, window_s=window, delay_s=0.0) for t in trials])
        if moving <= NOISE_FLOOR[joint]:
            break
    if delay_s is None:
        delay_s = statistics.median(preprocess(t, rate_hz, window_s=window, moving_velocity=moving).delay_s
                                    for t in trials)
    return [preprocess(t, rate_hz, window_s=window, delay_s=delay_s) for t in trials], float(delay_s)


def select_effects(split: Split) -> Selection:
    """Both rounds of :mod:`rik.sysid.select` on ``split``: every single effect against the baseline, then the
    pairs (the first member any single effect that helped, with its fitted shape)."""
    baseline, fits = fit_all(split)
    selection = select(baseline, fits)
    firsts = [s.fit for s in selection.scores if s.gain > 0]
    return select_pair(selection, [fit_model(split, second, first) for first in firsts
                                   for second in FAMILIES if pair_allowed(first.kind, second.kind)])


def discover(trials: Sequence[Trial], *, heldout: Sequence[int] | None = None, rate_hz: float | None = None,
             window_s: float | None = None, delay_s: float | None = None,
             resim_window_s: float = RESIM_WINDOW_S, resimulate: bool = True) -> Discovery:
    """Fit, diagnose, select and measure the gain on ``trials`` (see the module docstring). ``heldout``: indices
    of the trials to hold out (default: the last quarter, or the end of a single trial)."""
    prepared, delay = prepare_all(trials, rate_hz=rate_hz, window_s=window_s, delay_s=delay_s)
    velocity = fit_velocity(prepared)
    rows = all_rows(prepared, velocity=velocity)
    limits = (min(float(p.q.min()) for p in prepared), max(float(p.q.max()) for p in prepared))
    split = split_rows(rows, prepared, heldout)
    selection = select_effects(split)
    check_finite_fits(trials, [selection.baseline, *(sc.fit for sc in (*selection.scores, *selection.pairs))])
    baseline = selection.baseline
    base_res = resistance_of(baseline.baseline, (), "rik sysid: baseline fit")
    chosen = selection.final if selection.found else None
    ext_res = resistance_of(chosen.baseline, chosen.effects, "rik sysid: " + " + ".join(
        f.title for f, _ in chosen.terms)) if chosen else None
    resim: list[Resimulated] = []
    rmse: tuple[float, float | None] = (float("nan"), None)
    if resimulate:
        resim, rmse = _resimulate(prepared, split, limits, baseline.baseline.inertia, base_res, ext_res,
                                  chosen.baseline.inertia if chosen else None, resim_window_s)
        if not all(np.isfinite(e) for e in rmse if e is not None):
            raise _not_finite(trials, "position", "the re-simulated position error")
    return Discovery(prepared[0].trial.joint, tuple(prepared), rows, split, selection, delay, limits, base_res,
                     ext_res, tuple(resim), rmse, velocity, resim_window_s)


def check_finite_fits(trials: Sequence[Trial], fits: Sequence[Fit]) -> None:
    """Refuse fits with a non-finite coefficient or error (an overflow): no NaN may reach a report or a preset.
    (Measured values are bounded when read, :data:`rik.sysid.trials.MAX_MAGNITUDE`; this is the last guard.)"""
    for fit in fits:
        numbers = [*fit.theta, fit.rss, fit.rmse_train, fit.rmse_heldout]
        if not all(np.isfinite(x) for x in numbers):
            raise _not_finite(trials, "force", f"the fit of {fit.title}")


def _not_finite(trials: Sequence[Trial], role: str, what: str) -> RikError:
    """One line naming the trials' files and their ``role`` column: ``what`` came out NaN or infinite."""
    files = list(dict.fromkeys(t.source for t in trials))
    column = getattr(trials[0].meta.columns, role)
    shown = ", ".join(files[:3]) + (f" and {len(files) - 3} more" if len(files) > 3 else "")
    return RikError(f"{shown}, column '{column}': {what} is not a finite number (an overflow): the values are too "
                    "large or too degenerate to fit; check the units")


def _resimulate(prepared: Sequence[Prepared], split: Split, limits: tuple[float, float], inertia: float,
                base: JointResistance, extended: JointResistance | None, ext_inertia: float | None,
                window_s: float) -> tuple[list[Resimulated], tuple[float, float | None]]:
    joint = prepared[0].trial.joint
    span = (min(limits[0], 0.0), max(limits[1], 0.0))
    base_model = joint_spec_model(joint, max(inertia, 1e-6), base, span)
    ext_model = joint_spec_model(joint, max(ext_inertia or inertia, 1e-6), extended, span) if extended else None
    out, errs_b, errs_e = [], [], []
    for i in split.heldout_trials:
        p = prepared[i]
        keep = p.t >= split.heldout_from if split.heldout_from is not None else np.ones(len(p.t), bool)
        t, q, qd, f = p.t[keep], p.q[keep], p.qd[keep], p.f[keep]
        qb = resimulate(base_model, t, q, qd, f, window_s=window_s)
        qe = resimulate(ext_model, t, q, qd, f, window_s=window_s) if ext_model else None
        out.append(Resimulated(p.trial.name, t, q, qb, qe))
        errs_b.append(qb - q)
        if qe is not None:
            errs_e.append(qe - q)
    rb = float(np.sqrt(np.mean(np.concatenate(errs_b) ** 2)))
    re = float(np.sqrt(np.mean(np.concatenate(errs_e) ** 2))) if errs_e else None
    return out, (rb, re)
