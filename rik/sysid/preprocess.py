"""Preprocessing of a measured trial: uniform resampling, smoothed derivatives, force-to-position delay, masks.

Steps of :func:`preprocess`, all in SI units of the joint (m or rad, N or N·m, s):

1. **Resampling** onto a uniform grid from the first sample at ``rate_hz`` (default: the median sample rate of
   the trial, rounded to a whole Hz, at least 1). At or above the median source rate values are linearly
   interpolated; below 0.9 × that rate each output sample is the mean of the (linearly interpolated) signal over
   its own interval of 1/``rate_hz`` s, a box filter that keeps noise from folding in.
2. **Smoothing and derivatives** with a Savitzky–Golay filter (:func:`scipy.signal.savgol_filter`, ``mode=
   "interp"``): a polynomial of order ``polyorder`` (default 3) fitted over a window of ``window_s`` seconds
   (default 0.1 s; rounded to an odd number of samples, at least ``polyorder + 1``). It gives the smoothed
   position, velocity and acceleration, and the force smoothed by the same filter (``f_smooth``): fit
   ``f_smooth`` against the derivatives so that both sides of the equation carry the same filter.
3. **Delay** between force and position. Positive delay: the position is recorded later than the force, so the
   force at time t is paired with the position at t + delay. Unless ``delay_s`` is given, it is the lag, on a
   grid of whole samples within ±``max_delay_s`` (default 0.1 s), whose shifted ``f_smooth`` is best explained
   by least squares on the moving samples away from the range's ends (within ``limit_margin`` of the observed or
   given limits, widened by one window: an end stop's impact is in no model) by
   ``[acceleration, velocity, sign(velocity), position, 1]``: mass,
   damping, Coulomb friction, a spring and a bias, enough for the alignment even where the model is not the
   final one. The delay is applied in whole samples (a given ``delay_s`` is rounded to one): force and motion
   are shifted against each other and the samples left without a partner are dropped.
4. **Masks**, from the smoothed signals after alignment:

   - ``moving``: |velocity| ≥ ``moving_velocity`` (default :data:`MOVING_VELOCITY`: 0.01 m/s or 0.02 rad/s);
   - ``opening`` / ``closing``: velocity ≥ ``moving_velocity`` / ≤ −``moving_velocity`` (positive = opening);
   - ``sticking``: not moving while |``f_smooth``| ≥ ``sticking_force`` (default :data:`STICKING_FORCE`: 0.5 N
     or 0.05 N·m); samples neither moving nor sticking are at rest;
   - ``near_limit``: smoothed position within ``limit_margin`` (default :data:`LIMIT_MARGIN`: 5 mm or 2°) of
     ``limits`` (default: the trial's observed minimum and maximum; pass the joint's range, or
     :func:`observed_limits` over all trials, where the trial does not reach both ends).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from rik.errors import RikError
from rik.schemas.joints import JointType
from rik.schemas.trajectory import PreprocessSettings
from rik.sysid.trials import Trial, TrialError

DEFAULT_WINDOW_S = 0.1
"""Savitzky–Golay window, s."""
DEFAULT_POLYORDER = 3
DEFAULT_MAX_DELAY_S = 0.1
"""Half-width of the delay search, s."""
MOVING_VELOCITY = {JointType.slide: 0.01, JointType.hinge: 0.02}
"""Speed from which a sample counts as moving: m/s (slide: 10 mm/s) or rad/s (hinge: about 1.1°/s)."""
STICKING_FORCE = {JointType.slide: 0.5, JointType.hinge: 0.05}
"""|force| from which a sample that is not moving counts as sticking: N (slide) or N·m (hinge)."""
CONTACT_MARGIN = {JointType.slide: 0.001, JointType.hinge: math.radians(0.5)}
"""Distance to a range end within which a sample counts as touching the stop (the fit, :mod:`rik.sysid.fit`) or
a resting front as resting on it (:mod:`rik.sysid.breakaway`): m or rad."""
LIMIT_MARGIN = {JointType.slide: 0.005, JointType.hinge: math.radians(2.0)}
"""Distance to a limit within which a sample counts as near the limit: m (slide: 5 mm) or rad (hinge: 2°)."""
DOWNSAMPLE_BELOW = 0.9
"""A target rate below this fraction of the source's median rate is reached by interval means, not
interpolation."""
_SPEED = {JointType.slide: "m/s", JointType.hinge: "rad/s"}
MIN_DELAY_SAMPLES = 20
"""Fewest moving samples the delay estimate needs."""
MAX_GRID_SAMPLES = 5_000_000
"""Most samples a trial is resampled to (each preprocessed signal is an array of this many float64s)."""
MAX_GRID_FACTOR = 100
"""Most resampled samples per measured one: more means the time jumps, or is read in the wrong unit."""


@dataclass(frozen=True, eq=False)
class Prepared:
    """A trial on a uniform time grid, aligned, smoothed and differentiated, with its masks. Arrays are
    read-only, of equal length, in SI units of the joint (m or rad; N or N·m)."""

    trial: Trial
    settings: PreprocessSettings
    t: np.ndarray
    """Time, s, uniform at ``settings.rate_hz`` (the position's timestamps)."""
    q_raw: np.ndarray
    """Resampled position before smoothing, m or rad."""
    q: np.ndarray
    """Smoothed position, m or rad."""
    qd: np.ndarray
    """Velocity (Savitzky–Golay derivative), m/s or rad/s."""
    qdd: np.ndarray
    """Acceleration (Savitzky–Golay second derivative), m/s² or rad/s²."""
    f: np.ndarray
    """Applied force or torque, resampled and shifted by the delay, N or N·m."""
    f_smooth: np.ndarray
    """``f`` through the same Savitzky–Golay filter as the position, N or N·m."""
    qd_measured: np.ndarray | None
    """The trial's measured velocity, resampled (not smoothed), m/s or rad/s; None if it had none."""
    moving: np.ndarray
    opening: np.ndarray
    closing: np.ndarray
    sticking: np.ndarray
    near_limit: np.ndarray

    def __post_init__(self) -> None:
        n = len(self.t)
        for name, value in vars(self).items():
            if isinstance(value, np.ndarray):
                if value.shape != (n,):
                    raise ValueError(f"Prepared.{name} has shape {value.shape}, expected ({n},)")
                value.flags.writeable = False

    @property
    def dt(self) -> float:
        """Sample interval, s."""
        return 1.0 / self.settings.rate_hz

    @property
    def delay_s(self) -> float:
        return self.settings.delay_s


# ------------------------------------------------------------------------------------------------ resampling

def median_rate(t: np.ndarray) -> float:
    """Median sample rate of strictly increasing times ``t`` (s), Hz."""
    return float(1.0 / np.median(np.diff(t)))


def grid_samples(t: np.ndarray, rate_hz: float) -> int:
    """Number of samples of :func:`uniform_grid`."""
    return int(math.floor((t[-1] - t[0]) * rate_hz + 1e-9)) + 1


def uniform_grid(t: np.ndarray, rate_hz: float) -> np.ndarray:
    """Times from ``t[0]`` to at most ``t[-1]`` every 1/``rate_hz`` s."""
    return t[0] + np.arange(grid_samples(t, rate_hz)) / rate_hz


def _check_grid(trial: Trial, rate: float) -> None:
    """Refuse to resample ``trial`` onto more than :data:`MAX_GRID_SAMPLES` samples, or more than
    :data:`MAX_GRID_FACTOR` per measured sample, before allocating them: one line naming the largest time step."""
    count = (trial.t[-1] - trial.t[0]) * rate + 1
    limit = min(MAX_GRID_SAMPLES, MAX_GRID_FACTOR * len(trial.t))
    if count <= limit:
        return
    steps = np.diff(trial.t)
    k = int(np.argmax(steps))
    raise TrialError(trial.source, trial.name, trial.meta.columns.time,
                     f"the trial spans {trial.meta.duration:.6g} s: at {rate:g} Hz that is {count:.4g} samples to "
                     f"resample from {len(trial.t)} measured (at most {limit:,}); "
                     f"the time jumps by {steps[k]:.6g} s after sample {k} (median step {np.median(steps):.6g} s): "
                     "split the trial there, or check the time column's unit")


def interval_means(t: np.ndarray, x: np.ndarray, grid: np.ndarray) -> np.ndarray:
    """Mean of the piecewise-linear signal (t, x) over [g − h, g + h] around each grid time (h half the grid
    step), clipped to the record: a box anti-aliasing filter for downsampling."""
    half = 0.5 * (grid[1] - grid[0]) if len(grid) > 1 else 0.0
    integral = np.concatenate([[0.0], np.cumsum(0.5 * (x[1:] + x[:-1]) * np.diff(t))])
    lo = np.clip(grid - half, t[0], t[-1])
    hi = np.clip(grid + half, t[0], t[-1])
    width = hi - lo
    means = (np.interp(hi, t, integral) - np.interp(lo, t, integral)) / np.where(width > 0, width, 1.0)
    return np.where(width > 0, means, np.interp(grid, t, x))


def resample(t: np.ndarray, x: np.ndarray, grid: np.ndarray) -> np.ndarray:
    """``x`` sampled at times ``t`` (s) on the uniform ``grid`` (s): linear interpolation, or interval means when
    the grid is coarser than :data:`DOWNSAMPLE_BELOW` × the source's median rate."""
    rate = 1.0 / (grid[1] - grid[0]) if len(grid) > 1 else math.inf
    if rate < DOWNSAMPLE_BELOW * median_rate(t):
        return interval_means(t, x, grid)
    return np.interp(grid, t, x)


# ---------------------------------------------------------------------------------------------- derivatives

def window_samples(window_s: float, rate_hz: float, polyorder: int) -> int:
    """Odd number of samples of a ``window_s`` s window at ``rate_hz``, at least ``polyorder + 1``."""
    n = max(int(round(window_s * rate_hz)), polyorder + 1)
    return n if n % 2 else n + 1


def savgol(x: np.ndarray, window: int, polyorder: int, deriv: int, rate_hz: float) -> np.ndarray:
    """Savitzky–Golay smoothing (deriv 0) or derivative (per s**deriv) of uniformly sampled ``x``."""
    from scipy.signal import savgol_filter

    return savgol_filter(x, window, polyorder, deriv=deriv, delta=1.0 / rate_hz, mode="interp")


# ------------------------------------------------------------------------------------------------ the delay

def _regressors(q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
    """The baseline regressors of the delay fit: acceleration, velocity, its sign, position, 1."""
    return np.column_stack([qdd, qd, np.sign(qd), q, np.ones_like(q)])


RANK_TOLERANCE = 1e-9
"""Columns count as dependent where QR's diagonal holds an entry below this fraction of its largest (or a column's
remainder, after projecting out others, falls below this fraction of its size)."""


def orthonormal_basis(x: np.ndarray) -> np.ndarray | None:
    """An orthonormal basis of the columns of ``x`` (QR's Q), or None where they are dependent
    (:data:`RANK_TOLERANCE`): least-squares residuals are then ``y`` less its projection on the basis."""
    q, r = np.linalg.qr(x)
    diagonal = np.abs(np.diag(r))
    if diagonal.size and diagonal.min() <= RANK_TOLERANCE * diagonal.max():
        return None
    return q


def best_lag(q: np.ndarray, qd: np.ndarray, qdd: np.ndarray, f: np.ndarray, moving: np.ndarray,
             max_lag: int) -> tuple[int, int]:
    """(lag in samples within ±``max_lag`` that best explains ``f[i − lag]`` by the baseline regressors at the
    moving samples i, number of moving samples used). Motion and force are uniformly sampled on one grid."""
    n = len(q)
    rows = np.arange(max_lag, n - max_lag)
    rows = rows[moving[rows]]
    if len(rows) < MIN_DELAY_SAMPLES:
        return 0, len(rows)
    x = _regressors(q[rows], qd[rows], qdd[rows])
    lags = np.arange(-max_lag, max_lag + 1)
    y = f[rows[:, None] - lags[None, :]]
    basis = orthonormal_basis(x)
    if basis is not None:  # each lag's least-squares residual: y less its projection on x
        rss = np.sum((y - basis @ (basis.T @ y)) ** 2, axis=0)
    else:  # x's columns are dependent (one direction of motion: the sign is the constant)
        coef, *_ = np.linalg.lstsq(x, y, rcond=None)
        rss = np.sum((y - x @ coef) ** 2, axis=0)
    return int(lags[int(np.argmin(rss))]), len(rows)


def _align(lag: int, motion: dict[str, np.ndarray], force: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Pair motion sample i with force sample i − ``lag``; drops the samples without a partner."""
    n = len(next(iter(motion.values())))
    m0, m1 = (lag, n) if lag >= 0 else (0, n + lag)
    f0, f1 = (0, n - lag) if lag >= 0 else (-lag, n)
    out = {k: v[m0:m1] for k, v in motion.items()}
    out.update({k: v[f0:f1] for k, v in force.items()})
    return out


# ---------------------------------------------------------------------------------------------------- masks

def masks(q: np.ndarray, qd: np.ndarray, f: np.ndarray, *, moving_velocity: float, sticking_force: float,
          limits: tuple[float, float], limit_margin: float) -> dict[str, np.ndarray]:
    """The boolean masks of the module docstring from position ``q``, velocity ``qd`` and force ``f`` (SI)."""
    moving = np.abs(qd) >= moving_velocity
    lower, upper = limits
    return {
        "moving": moving,
        "opening": qd >= moving_velocity,
        "closing": qd <= -moving_velocity,
        "sticking": ~moving & (np.abs(f) >= sticking_force),
        "near_limit": (q <= lower + limit_margin) | (q >= upper - limit_margin),
    }


def smoothing_noise(raw: np.ndarray, smoothed: np.ndarray, settings: PreprocessSettings) -> tuple[float, float]:
    """(noise on ``raw``, noise left on ``smoothed``): standard deviations, in the signal's unit, estimated from
    what the Savitzky–Golay filter of ``settings`` removed, corrected for the share of white noise it keeps (its
    centre coefficient)."""
    from scipy.signal import savgol_coeffs

    window = settings.window_samples
    keep = float(savgol_coeffs(window, settings.polyorder)[window // 2])
    sigma = float(np.std(raw - smoothed)) / math.sqrt(max(1.0 - keep, 1e-6))
    return sigma, sigma * math.sqrt(keep)


def touching(q: np.ndarray, limits: tuple[float, float], margin: float, widen: int,
             f: np.ndarray | None = None) -> np.ndarray:
    """Samples within ``margin`` of a range end (m or rad), and those within ``widen`` samples of an arrival there
    or of a departure from there right after the hand pushed the front onto the stop or within a window of the
    arrival (a bounce): an end stop's force is in no model, and smoothing smears it over the window on both sides
    (an impact's acceleration; on such a departure, the push the stop held, which reaches the samples after the
    front has left). A departure pulled from rest keeps its samples: the contact force is gone before the front
    moves off, and the samples just off the stop are where a catch acts. ``f`` (N or N·m, smoothed) tells the two
    apart; without it every departure is widened. Pass the smoothed position and limits from it: the raw
    position's extremes lie several noise deviations beyond the stop."""
    lower = q <= limits[0] + margin
    upper = q >= limits[1] - margin
    near = lower | upper
    if not near.any() or widen <= 0:
        return near
    before = np.concatenate([near[:1], near[:-1]])
    edges = near & ~before  # arrivals
    for side, into in ((lower, -1.0), (upper, 1.0)):
        left = np.nonzero(np.concatenate([[False], side[:-1] & ~side[1:]]))[0]  # first sample off the stop
        arrived = np.nonzero(side & ~np.concatenate([[False], side[:-1]]))[0]
        for k in left:
            since = arrived[arrived < k]
            bounce = len(since) == 0 or k - since[-1] <= 2 * widen  # the impact is still in the window
            if f is None or bounce or np.any(into * f[max(k - widen, 0):k] > 0):
                edges[k] = True
    return near | (np.convolve(edges.astype(float), np.ones(2 * widen + 1), mode="same") > 0)


def observed_limits(trials: Sequence[Trial]) -> tuple[float, float]:
    """The lowest and highest measured position over ``trials``, m or rad: limits for :func:`preprocess` that
    one trial alone may not reach."""
    if not trials:
        raise RikError("observed_limits needs at least one trial")
    return float(min(t.q.min() for t in trials)), float(max(t.q.max() for t in trials))


# ------------------------------------------------------------------------------------------------ preprocess

def _check_settings(trial: Trial, **values: float | None) -> None:
    for name, value in values.items():
        if value is not None and not (math.isfinite(value) and value > 0):
            raise TrialError(trial.source, trial.name, None, f"preprocessing setting {name} must be a positive "
                                                             f"number, got {value}")


def preprocess(trial: Trial, rate_hz: float | None = None, *, window_s: float = DEFAULT_WINDOW_S,
               polyorder: int = DEFAULT_POLYORDER, delay_s: float | None = None,
               max_delay_s: float = DEFAULT_MAX_DELAY_S, moving_velocity: float | None = None,
               sticking_force: float | None = None, limit_margin: float | None = None,
               limits: tuple[float, float] | None = None) -> Prepared:
    """Resample, smooth, differentiate, align and mask ``trial`` (see the module docstring for each step).

    ``rate_hz`` Hz (default: median rate, rounded); ``window_s`` s; ``delay_s`` s (None: estimate within
    ±``max_delay_s`` s; 0 to apply none); ``moving_velocity`` m/s or rad/s, ``sticking_force`` N or N·m,
    ``limit_margin`` m or rad (defaults per joint type: :data:`MOVING_VELOCITY`, :data:`STICKING_FORCE`,
    :data:`LIMIT_MARGIN`); ``limits`` (lower, upper) m or rad (default: observed). Raises :class:`TrialError` when
    the trial is too short for the window and the delay search, or has too few moving samples to estimate the
    delay."""
    joint = trial.joint
    moving_velocity = MOVING_VELOCITY[joint] if moving_velocity is None else moving_velocity
    sticking_force = STICKING_FORCE[joint] if sticking_force is None else sticking_force
    limit_margin = LIMIT_MARGIN[joint] if limit_margin is None else limit_margin
    _check_settings(trial, rate_hz=rate_hz, window_s=window_s, moving_velocity=moving_velocity,
                    sticking_force=sticking_force)
    if not (2 <= polyorder <= 6 and max_delay_s >= 0 and limit_margin >= 0):
        raise TrialError(trial.source, trial.name, None, f"preprocessing settings: polyorder must be 2 to 6 (got "
                                                         f"{polyorder}), max_delay_s ({max_delay_s}) and limit_margin "
                                                         f"({limit_margin}) at least 0")
    for name, value in (("delay_s (--delay)", delay_s), ("max_delay_s", max_delay_s)):
        if value is not None and not (math.isfinite(value) and abs(value) < trial.meta.duration):
            raise TrialError(trial.source, trial.name, None, f"preprocessing setting {name} must be a "
                                                             f"number of seconds shorter than the trial "
                                                             f"({trial.meta.duration:.6g} s), got {value}")
    if limits is not None and not limits[0] < limits[1]:
        raise TrialError(trial.source, trial.name, None, f"limits must be (lower, upper) with lower < upper, "
                                                         f"got {limits}")
    rate = float(rate_hz) if rate_hz is not None else float(max(1, round(median_rate(trial.t))))
    _check_grid(trial, rate)
    grid = uniform_grid(trial.t, rate)
    window = window_samples(window_s, rate, polyorder)
    lag_max = int(round(max_delay_s * rate)) if delay_s is None else abs(int(round(delay_s * rate)))
    if len(grid) < window + 2 * lag_max:
        raise TrialError(trial.source, trial.name, None, f"{len(grid)} samples at {rate:g} Hz "
                                                         f"({trial.meta.duration:.6g} s) are too few for a "
                                                         f"{window}-sample smoothing window plus a ±{lag_max}-sample "
                                                         f"delay; lower window_s or max_delay_s")
    q_raw = resample(trial.t, trial.q, grid)
    f_raw = resample(trial.t, trial.f, grid)
    q = savgol(q_raw, window, polyorder, 0, rate)
    qd = savgol(q_raw, window, polyorder, 1, rate)
    qdd = savgol(q_raw, window, polyorder, 2, rate)
    f_smooth = savgol(f_raw, window, polyorder, 0, rate)
    if delay_s is None:
        bounds = (float(q.min()), float(q.max())) if limits is None else limits
        usable = (np.abs(qd) >= moving_velocity) & ~touching(q, bounds, limit_margin, window)
        lag, used = best_lag(q, qd, qdd, f_smooth, usable, lag_max)
        if used < MIN_DELAY_SAMPLES:
            unit = (f" (the samples are {1 / median_rate(trial.t):.3g} s apart: is the time in ms read as s?)"
                    if median_rate(trial.t) <= 1.0 else "")
            raise TrialError(trial.source, trial.name, trial.meta.columns.position,
                             f"only {used} moving samples (|velocity| ≥ {moving_velocity:g} {_SPEED[joint]}) to "
                             f"estimate the delay from, at least {MIN_DELAY_SAMPLES} needed{unit}; pass delay_s")
    else:
        lag = int(round(delay_s * rate))
    motion = {"t": grid, "q_raw": q_raw, "q": q, "qd": qd, "qdd": qdd}
    if trial.qd is not None:
        motion["qd_measured"] = resample(trial.t, trial.qd, grid)
    aligned = _align(lag, motion, {"f": f_raw, "f_smooth": f_smooth})
    observed = limits is None
    bounds = ((float(aligned["q"].min()), float(aligned["q"].max())) if limits is None
              else (float(limits[0]), float(limits[1])))
    settings = PreprocessSettings(
        rate_hz=rate, window_s=window_s, window_samples=window, polyorder=polyorder, delay_s=lag / rate,
        delay_estimated=delay_s is None, max_delay_s=max_delay_s, moving_velocity=moving_velocity,
        sticking_force=sticking_force, limit_margin=limit_margin, limits=bounds, limits_observed=observed)
    flags = masks(aligned["q"], aligned["qd"], aligned["f_smooth"], moving_velocity=moving_velocity,
                  sticking_force=sticking_force, limits=bounds, limit_margin=limit_margin)
    return Prepared(trial=trial, settings=settings, qd_measured=aligned.pop("qd_measured", None), **aligned,
                    **flags)
