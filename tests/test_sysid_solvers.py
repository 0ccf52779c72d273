"""The fast least-squares paths of ``rik sysid`` give what the plain solves give: the hyperparameter search's
projected residual (one QR of the fixed columns, each candidate fitted to what they leave over) against a full
weighted solve per candidate, and the delay search's projection against ``lstsq``, on well-posed data and on the
degenerate cases each path must survive (a candidate the fixed columns already span, an all-zero candidate,
dependent fixed columns, a front that moved one way only)."""

from __future__ import annotations

import numpy as np
import pytest

from rik.sysid.fit import projected_rss, weighted_solve
from rik.sysid.preprocess import _regressors, best_lag


def _problem(seed: int, n: int = 400) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    base = np.column_stack([rng.normal(size=n) * 3.0, rng.normal(size=n) * 1e-3, np.sign(rng.normal(size=n))])
    y = base @ np.array([2.0, 500.0, -1.0]) + rng.normal(size=n) * 0.1
    return base, y, rng.uniform(0.5, 2.0, size=n)


def _candidates(base: np.ndarray, rng: np.random.Generator) -> dict[str, np.ndarray]:
    n = len(base)
    return {
        "one column": np.tanh(rng.normal(size=(n, 1)) * 4.0),
        "two columns": rng.normal(size=(n, 2)) * [1e3, 1e-4],
        "spanned by the fixed columns": base[:, :1] * 7.0 - base[:, 2:3],
        "one spanned, one new": np.column_stack([base[:, 1] * 3.0, rng.normal(size=n)]),
        "all zero": np.zeros((n, 1)),
    }


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_projected_residual_equals_the_full_weighted_solve(seed: int) -> None:
    base, y, w = _problem(seed)
    rss = projected_rss(base, y, w)
    for name, z in _candidates(base, np.random.default_rng(100 + seed)).items():
        full = weighted_solve(np.hstack([base, z]), y, w)[1]
        assert rss(z) == pytest.approx(full, rel=1e-9, abs=1e-12), name


def test_projected_residual_with_dependent_fixed_columns_solves_in_full() -> None:
    base, y, w = _problem(3)
    dependent = np.column_stack([base, base[:, 0] - base[:, 2]])  # a fourth column the first three span
    z = np.random.default_rng(4).normal(size=(len(y), 1))
    assert projected_rss(dependent, y, w)(z) == pytest.approx(weighted_solve(np.hstack([dependent, z]), y, w)[1], rel=1e-9)


def _lstsq_lag(q, qd, qdd, f, moving, max_lag) -> int:
    rows = np.arange(max_lag, len(q) - max_lag)
    rows = rows[moving[rows]]
    x = _regressors(q[rows], qd[rows], qdd[rows])
    lags = np.arange(-max_lag, max_lag + 1)
    y = f[rows[:, None] - lags[None, :]]
    coef, *_ = np.linalg.lstsq(x, y, rcond=None)
    return int(lags[int(np.argmin(np.sum((y - x @ coef) ** 2, axis=0)))])


@pytest.mark.parametrize(("one_way", "delay"), [(False, 4), (False, -3), (True, 6)])
def test_delay_search_finds_the_lag_lstsq_finds(one_way: bool, delay: int) -> None:
    """``one_way``: the front only opens, so the velocity's sign is the constant column (dependent regressors)."""
    rng = np.random.default_rng(delay + 10)
    t = np.arange(1500) * 0.005
    q = 0.2 * t if one_way else 0.2 * np.sin(1.3 * t) + 0.05 * np.sin(4.1 * t)
    qd, qdd = np.gradient(q, t), np.gradient(np.gradient(q, t), t)
    force = 1.5 * qdd + 8.0 * qd + 2.0 * np.sign(qd) + 0.5 * q + 0.05 * rng.normal(size=len(t))
    f = np.roll(force, -delay)  # force sample i - delay pairs with motion sample i
    moving = np.abs(qd) > 0.01
    lag, used = best_lag(q, qd, qdd, f, moving, max_lag=10)
    assert lag == _lstsq_lag(q, qd, qdd, f, moving, 10) and used > 100
    if not one_way:  # a ramp's regressors are smooth in time: every lag explains it almost as well
        assert lag == delay
