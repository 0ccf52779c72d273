"""Equation-error fits of the baseline joint model and of each effect of the library, scored on held-out data.

The rows a fit uses, per preprocessed trial:

- **moving** samples (|v| above :func:`fit_velocity`: at least :data:`FIT_VELOCITY`, raised to :data:`NOISE_SIGMAS`
  times the velocity noise) whose smoothing window holds no reversal and no rest away from a stop
  (:func:`steady`: the smoothed force there carries a friction step, or static friction's hold, which
  regressors at the smoothed velocity do not);
- **breakaways** from rest (:func:`rik.sysid.breakaway.find_breakaways`): the force at which a resting front
  started to move, at an infinitesimal velocity in its direction and the acceleration there, weighted as one smoothing
  window of samples (the moving samples are correlated over a window); they carry the static resistance, which
  the moving samples do not see below the noise floor;
- **creeping** samples, slower than that floor but resolved by a long difference
  (:func:`rik.sysid.breakaway.creeping`), at that difference's speed and zero acceleration, at least that
  difference's span away from a stop and its arrivals and departures (a front let go on a compliant stop creeps
  off it unforced: fitted, such samples gave a "catch that repels" a 20 % held-out gain on foreign data);

all away from the range's ends: samples within :data:`CONTACT_MARGIN` of a limit, and those within half a
smoothing window of an arrival there or a departure from there, are left out, because the end stop's contact
force is in no model and smoothing smears it over the window (:func:`rik.sysid.preprocess.touching`). Forces are
the smoothed ones (``f_smooth``), filtered like the derivatives.

Errors are the weighted root mean square of ``F_measured − F_model`` (N or N·m), on the training rows and on the
held-out rows; BIC is ``n·ln(RSS/n) + p·ln(n)`` on the training rows. A family's hyperparameter is searched on its grid,
then refined by a bounded 1-D search between the best grid point's neighbours (variable projection: for each
value the coefficients are a linear least-squares solution).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from rik.errors import RikError
from rik.schemas.joints import JointType
from rik.sysid.breakaway import CREEP_SPAN_S, STEP, creeping, find_breakaways
from rik.sysid.effects import FAMILIES, Baseline, Effect, Family, Motion, baseline_features
from rik.sysid.preprocess import CONTACT_MARGIN, RANK_TOLERANCE, Prepared, orthonormal_basis, smoothing_noise, touching

FIT_VELOCITY = {JointType.slide: 0.004, JointType.hinge: 0.01}
"""Lowest speed from which a sample enters the fit: m/s (4 mm/s) or rad/s (about 0.6°/s); raised to
:data:`NOISE_SIGMAS` times the velocity's noise (see :func:`velocity_noise`) where that is higher."""
NOISE_SIGMAS = 4.0
"""A sample moves when its speed exceeds this many standard deviations of the velocity noise: a front at rest
with noisy position readings must not count as moving (its friction direction would be a coin toss)."""
HELDOUT_FRACTION = 0.3
"""Share of a single trial's duration held out (its end) when there is only one trial."""
MIN_ROWS = 30
"""Fewest rows a fit (training or held-out) needs."""


@dataclass(frozen=True, eq=False)
class Rows:
    """Samples the equation error is evaluated at, concatenated over trials (SI, equal lengths)."""

    joint: JointType
    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    f: np.ndarray
    """Smoothed applied force, N or N·m."""
    trial: np.ndarray
    """Index of each row's trial in :attr:`names`."""
    names: tuple[str, ...]
    weight: np.ndarray | None = None
    """Least-squares weight of each row (None: all 1): a breakaway row stands for one smoothing window."""
    breakaway: np.ndarray | None = None
    """Which rows are breakaways from rest (:mod:`rik.sysid.breakaway`), not moving samples (None: none)."""

    def __len__(self) -> int:
        return len(self.q)

    @property
    def weights(self) -> np.ndarray:
        return np.ones(len(self.q)) if self.weight is None else self.weight

    @property
    def breakaways(self) -> np.ndarray:
        return np.zeros(len(self.q), bool) if self.breakaway is None else self.breakaway

    def take(self, mask: np.ndarray) -> Rows:
        """The rows where ``mask`` holds."""
        return Rows(self.joint, self.t[mask], self.q[mask], self.qd[mask], self.qdd[mask], self.f[mask],
                    self.trial[mask], self.names, self.weights[mask], self.breakaways[mask])

    @property
    def motion(self) -> Motion:
        return Motion(self.q, self.qd)


def concat_rows(*parts: Rows) -> Rows:
    """The rows of ``parts`` (of one joint and one set of trials) one after the other, weights and flags kept."""
    def joined(name: str) -> np.ndarray:
        return np.concatenate([getattr(p, name) for p in parts])

    return Rows(parts[0].joint, joined("t"), joined("q"), joined("qd"), joined("qdd"), joined("f"), joined("trial"),
                parts[0].names, joined("weights"), joined("breakaways"))


@dataclass(frozen=True, eq=False)
class Split:
    """Training and held-out rows, and which trials (or which part of a single trial) went where."""

    train: Rows
    heldout: Rows
    heldout_trials: tuple[int, ...]
    """Indices of the held-out trials; with one trial, ``(0,)`` and :attr:`heldout_from` says from when."""
    heldout_from: float | None = None
    """With a single trial: the time, s, from which it is held out."""
    window_samples: int = 1
    """Samples of the smoothing window: residuals within it are correlated."""


def velocity_noise(p: Prepared) -> float:
    """Standard deviation of the noise the position's noise puts on the Savitzky–Golay velocity, m/s or rad/s:
    the position noise, estimated from what smoothing removed (:func:`rik.sysid.preprocess.smoothing_noise`),
    times the norm of the derivative filter."""
    from scipy.signal import savgol_coeffs

    sigma_q, _ = smoothing_noise(p.q_raw, p.q, p.settings)
    window, order = p.settings.window_samples, p.settings.polyorder
    return sigma_q * float(np.linalg.norm(savgol_coeffs(window, order, deriv=1, delta=p.dt)))


def fit_velocity(prepared: Sequence[Prepared]) -> float:
    """The speed from which samples enter the fit: :data:`FIT_VELOCITY` or :data:`NOISE_SIGMAS` times the median
    velocity noise of the trials, whichever is higher; m/s or rad/s."""
    joint = prepared[0].trial.joint
    noise = float(np.median([velocity_noise(p) for p in prepared]))
    return max(FIT_VELOCITY[joint], NOISE_SIGMAS * noise)


def steady(qd: np.ndarray, velocity: float, half: int, on_stop: np.ndarray | None = None) -> np.ndarray:
    """Samples moving at least ``velocity`` fast (m/s or rad/s) whose smoothing window (``half`` samples each side)
    holds no reversal and no rest away from a stop (``on_stop``: the samples on a range end; None: none): the
    smoothed force around a reversal carries the filtered step of the friction from one direction to the other,
    and around a start from rest the hand's force while static friction still held the front, neither of which
    regressors evaluated at the smoothed velocity have (fitted, starts gave "negative stiction" held-out gains of
    10-30 % on foreign drawers). Starts off a stop stay: a drawer's catch shows only there, in a front pulled
    briskly off the closed stop (left out, every catch of the foreign generator was lost; docs/sysid.md)."""
    from numpy.lib.stride_tricks import sliding_window_view

    moving = np.abs(qd) >= velocity
    direction = np.sign(qd) * moving
    if half <= 0:
        return moving
    resting = ~moving if on_stop is None else ~moving & ~on_stop
    pad = np.zeros(half)
    windows = sliding_window_view(np.concatenate([pad, direction, pad]), 2 * half + 1)
    rests = sliding_window_view(np.concatenate([pad, resting.astype(float), pad]), 2 * half + 1)
    return moving & ~((windows.min(axis=1) < 0) & (windows.max(axis=1) > 0)) & (rests.max(axis=1) == 0)


def all_rows(prepared: Sequence[Prepared], *, velocity: float | None = None, margin: float | None = None,
             limits: tuple[float, float] | None = None, breakaways: bool = True) -> Rows:
    """The fit rows of every trial (see the module docstring): the steady moving samples and (``breakaways``: the
    evidence from slow motion and rest) the creeps, then each trial's breakaways from rest, weighted as one
    smoothing window each. ``velocity`` default
    :func:`fit_velocity`; ``limits`` default: the lowest and highest smoothed position over all trials."""
    joint = prepared[0].trial.joint
    velocity = fit_velocity(prepared) if velocity is None else velocity
    margin = CONTACT_MARGIN[joint] if margin is None else margin
    if limits is None:
        limits = (min(float(p.q.min()) for p in prepared), max(float(p.q.max()) for p in prepared))
    parts = []
    for i, p in enumerate(prepared):
        window = p.settings.window_samples
        keep = ~touching(p.q, limits, margin, window // 2, p.f_smooth) & steady(
            p.qd, velocity, window // 2, touching(p.q, limits, margin, 0))
        qd, qdd = p.qd, p.qdd
        if breakaways:  # creeps, away from the stops by a long difference's span
            slow, speed = creeping(p, velocity)
            slow &= ~touching(p.q, limits, margin, int(round(CREEP_SPAN_S * p.settings.rate_hz)))
            keep |= slow
            qd = np.where(slow, speed, p.qd)
            qdd = np.where(slow, 0.0, p.qdd)  # a creep is at constant speed; its filtered acceleration is noise
        n = int(keep.sum())
        parts.append((p.t[keep], p.q[keep], qd[keep], qdd[keep], p.f_smooth[keep], np.full(n, i),
                      np.ones(n), np.zeros(n, bool)))
        if breakaways:
            events = find_breakaways(p, limits)
            m = len(events)
            parts.append((np.array([e.t for e in events]), np.array([e.q for e in events]),
                          np.array([e.direction * STEP for e in events]), np.array([e.qdd for e in events]),
                          np.array([e.force for e in events]), np.full(m, i), np.full(m, float(window)),
                          np.ones(m, bool)))
    t, q, qd, qdd, f, trial, weight, event = (np.concatenate(c) for c in zip(*parts, strict=True))
    return Rows(joint, t, q, qd, qdd, f, trial.astype(int), tuple(p.trial.name for p in prepared), weight,
                event.astype(bool))


def heldout_trials(n: int, heldout: Sequence[int] | None, what: str, where: str = "") -> tuple[int, ...]:
    """The indices of the trials to hold out of ``n`` (``n`` ≥ 2): ``heldout`` (sorted, repeats dropped) or by
    default the last quarter, at least one. A choice that is not some but not all of them is a one-line error
    naming ``what`` ("the 4 trials"), prefixed by ``where`` when given."""
    chosen = tuple(sorted(set(heldout))) if heldout is not None else tuple(range(n - max(1, n // 4), n))
    if not chosen or any(not 0 <= i < n for i in chosen) or len(chosen) == n:
        raise RikError(f"{where}held-out trials must be some but not all of {what} (0 to {n - 1}), "
                       f"got {list(heldout or [])}")
    return chosen


def split_rows(rows: Rows, prepared: Sequence[Prepared], heldout: Sequence[int] | None = None) -> Split:
    """Training and held-out rows: the trials ``heldout`` (default: the last quarter of the trials, at least
    one) or, with a single trial, its last :data:`HELDOUT_FRACTION` of time."""
    n = len(prepared)
    if n == 1:
        p = prepared[0]
        start = float(p.t[0] + (1.0 - HELDOUT_FRACTION) * (p.t[-1] - p.t[0]))
        late = rows.t >= start
        split = Split(rows.take(~late), rows.take(late), (0,), start, p.settings.window_samples)
    else:
        chosen = heldout_trials(n, heldout, f"the {n} trials")
        out = np.isin(rows.trial, chosen)
        split = Split(rows.take(~out), rows.take(out), chosen, None, prepared[0].settings.window_samples)
    for part, rows_ in (("training", split.train), ("held-out", split.heldout)):
        if len(rows_) < MIN_ROWS:
            raise RikError(f"only {len(rows_)} moving samples away from the range's ends in the {part} data "
                           f"(trials {', '.join(rows.names)}), at least {MIN_ROWS} needed: record longer or "
                           f"more strokes")
    return split


# --------------------------------------------------------------------------------------------------- fitting

Term = tuple[Family, float | None]
"""One effect in a model: its family and hyperparameter (None for families without one)."""


@dataclass(frozen=True, eq=False)
class Fit:
    """One model fitted by equation error: the baseline plus the effects of ``terms`` (none: the baseline)."""

    terms: tuple[Term, ...]
    theta: np.ndarray
    """Coefficients: M, b, Fc, then each term's."""
    baseline: Baseline
    """Inertia, damping and friction (adjusted where an effect's reading moves the friction level)."""
    effects: tuple[Effect, ...]
    """The terms' effects in physical form, in order."""
    problem: str | None
    """Why a fitted effect is unphysical, or None."""
    parameters: int
    rss: float
    """Weighted residual sum of squares on the training rows."""
    n: float
    """Total weight of the training rows (their count, a breakaway counting as a smoothing window)."""
    rmse_train: float
    rmse_heldout: float
    residual_train: np.ndarray = field(repr=False)
    residual_heldout: np.ndarray = field(repr=False)

    @property
    def family(self) -> Family | None:
        """The family this model adds last (the candidate it was fitted for), None for the baseline."""
        return self.terms[-1][0] if self.terms else None

    @property
    def title(self) -> str:
        """The title of :attr:`family`, ``baseline`` for the baseline."""
        return self.family.title if self.family else "baseline"

    @property
    def hyper(self) -> float | None:
        return self.terms[-1][1] if self.terms else None

    @property
    def effect(self) -> Effect | None:
        """The effect this model adds last."""
        return self.effects[-1] if self.effects else None

    @property
    def kind(self) -> str:
        return self.family.kind if self.family else "baseline"

    @property
    def kinds(self) -> tuple[str, ...]:
        return tuple(f.kind for f, _ in self.terms)

    @property
    def bic(self) -> float:
        return self.n * math.log(max(self.rss, 1e-300) / self.n) + self.parameters * math.log(self.n)

    def predict(self, rows: Rows) -> np.ndarray:
        """Modelled applied force at ``rows``, N or N·m."""
        return design(rows, self.terms) @ self.theta


def design(rows: Rows, terms: Sequence[Term] = ()) -> np.ndarray:
    """The regressor matrix of the baseline plus ``terms`` at ``rows``."""
    base = baseline_features(rows.q, rows.qd, rows.qdd)
    if not terms:
        return base
    return np.hstack([base, *(family.features(rows.motion, hyper, rows.joint) for family, hyper in terms)])


def weighted_solve(x: np.ndarray, y: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, float]:
    """Weighted least squares (weights ``w`` per row): the coefficients and the weighted residual sum of squares."""
    root = np.sqrt(w)
    xw, yw = x * root[:, None], y * root
    scale = np.maximum(np.abs(xw).max(axis=0), 1e-12)
    theta, *_ = np.linalg.lstsq(xw / scale, yw, rcond=None)
    theta = theta / scale
    r = yw - xw @ theta
    return theta, float(r @ r)


def projected_rss(base: np.ndarray, y: np.ndarray, w: np.ndarray) -> Callable[[np.ndarray], float]:
    """``rss(z)``: the weighted residual sum of squares of ``y`` on the columns of ``base`` and ``z``, as
    :func:`weighted_solve` gives it, for many ``z`` beside one ``base``: ``base`` is factorised once (QR of its
    weighted, scaled columns) and each ``z`` fitted to what ``base`` leaves over. A column of ``z`` that ``base``
    already spans (a remainder below :data:`~rik.sysid.preprocess.RANK_TOLERANCE` of its size) adds nothing, as
    :func:`weighted_solve`'s rank cut-off has it. Where ``base`` itself is rank-deficient, each call solves the
    whole system."""
    root = np.sqrt(w)
    bw, yw = base * root[:, None], y * root
    scale = np.maximum(np.abs(bw).max(axis=0), 1e-12)
    q = orthonormal_basis(bw / scale)
    if q is None:
        return lambda z: weighted_solve(np.hstack([base, z]), y, w)[1]
    y_rest = yw - q @ (q.T @ yw)

    def rss(z: np.ndarray) -> float:
        zw = z * root[:, None]
        z_rest = zw - q @ (q.T @ zw)
        size = np.linalg.norm(zw, axis=0)
        z_rest = z_rest[:, np.linalg.norm(z_rest, axis=0) > RANK_TOLERANCE * np.maximum(size, 1e-300)]
        if z_rest.shape[1] == 0:
            return float(y_rest @ y_rest)
        z_rest = z_rest / np.abs(z_rest).max(axis=0)
        coef, *_ = np.linalg.lstsq(z_rest, y_rest, rcond=None)
        rest = y_rest - z_rest @ coef
        return float(rest @ rest)

    return rss


def grid_then_refine(rss_at: Callable[[float], float], grid: np.ndarray) -> float:
    """The hyperparameter minimising ``rss_at`` over ``grid`` (ascending, positive), refined by a bounded 1-D search
    in log space between the best grid point's neighbours; the grid point where the refinement is no better."""
    from scipy.optimize import minimize_scalar

    rss = np.array([rss_at(h) for h in grid])
    k = int(np.argmin(rss))
    lo, hi = np.log(grid[max(k - 1, 0)]), np.log(grid[min(k + 1, len(grid) - 1)])
    if hi <= lo:
        return float(grid[k])
    res = minimize_scalar(lambda u: rss_at(math.exp(u)), bounds=(lo, hi), method="bounded", options={"xatol": 1e-3})
    return float(math.exp(res.x)) if res.fun <= rss[k] else float(grid[k])


def best_hyper(rows: Rows, family: Family, fixed: Sequence[Term] = ()) -> float:
    """The hyperparameter of ``family`` (added to the ``fixed`` terms) minimising the training RSS
    (:func:`grid_then_refine`)."""
    if family.grid is None:
        raise ValueError(f"effect family {family.kind} has no hyperparameter to search")
    rss_with = projected_rss(design(rows, fixed), rows.f, rows.weights)
    return grid_then_refine(lambda h: rss_with(family.features(rows.motion, h, rows.joint)), family.grid(rows.joint))


def _damping_se(x: np.ndarray, rss: float, correlated: int) -> float:
    """Standard error of the damping coefficient (column 1) of a least-squares fit with design ``x``, inflated by
    the square root of ``correlated``, the number of consecutive samples smoothing makes dependent."""
    n, k = x.shape
    if n <= k:
        return 0.0
    scale = np.maximum(np.abs(x).max(axis=0), 1e-12)
    xs = x / scale
    try:
        cov = np.linalg.pinv(xs.T @ xs)
    except np.linalg.LinAlgError:  # pragma: no cover - pinv converges for finite input
        return 0.0
    return float(math.sqrt(max(cov[1, 1], 0.0) * rss / (n - k) * correlated) / scale[1])


def _reading(theta: np.ndarray, terms: Sequence[Term], joint: JointType,
             damping_se: float = 0.0) -> tuple[Baseline, tuple[Effect, ...], str | None]:
    """The baseline and each term's effect from the coefficients, each reading adjusting the baseline in turn."""
    base = Baseline(float(theta[0]), float(theta[1]), float(theta[2]), damping_se)
    effects, problem, at = [], None, 3
    for family, hyper in terms:
        width = family.features(Motion(np.zeros(1), np.zeros(1)), hyper, joint).shape[1]
        effect, base, trouble = family.reading(theta[at:at + width], hyper, base, joint)
        effects.append(effect)
        problem = problem or trouble
        at += width
    if not terms and (base.inertia <= 0 or base.friction < 0):
        problem = f"the baseline fit is unphysical (inertia {base.inertia:.3g}, friction {base.friction:.3g})"
    return base, tuple(effects), problem


def fit_model(split: Split, family: Family | None, base: Fit | None = None) -> Fit:
    """Fit the baseline plus ``base``'s terms (their hyperparameters kept) plus ``family`` on the training rows,
    and score it on the held-out rows."""
    rows = split.train
    terms: tuple[Term, ...] = base.terms if base is not None else ()
    if family is not None:
        hyper = best_hyper(rows, family, terms) if family.grid is not None else None
        terms = (*terms, (family, hyper))
    x = design(rows, terms)
    theta, rss = weighted_solve(x, rows.f, rows.weights)
    baseline, effects, problem = _reading(theta, terms, rows.joint, _damping_se(x, rss, split.window_samples))
    residual_train = rows.f - x @ theta
    residual_heldout = split.heldout.f - design(split.heldout, terms) @ theta
    params = x.shape[1] + sum(h is not None for _, h in terms)
    n = float(rows.weights.sum())
    return Fit(terms, theta, baseline, effects, problem, params, rss, n, _rms(residual_train, rows.weights),
               _rms(residual_heldout, split.heldout.weights), residual_train, residual_heldout)


def _rms(x: np.ndarray, w: np.ndarray) -> float:
    """Weighted root mean square."""
    return float(np.sqrt(np.sum(w * x * x) / np.sum(w))) if len(x) else math.nan


def fit_all(split: Split, families: Sequence[Family] = FAMILIES) -> tuple[Fit, list[Fit]]:
    """The baseline fit and one fit per family of the library."""
    return fit_model(split, None), [fit_model(split, f) for f in families]

