"""Distances between two sets of image features: FID, KID and EMD, with bootstrap intervals and a split-half floor.

Pure numpy/scipy (no torch). Features are arrays of shape (n, d), one row per image; every distance is in the
units of the feature space (FID: squared feature units; KID: kernel units, dimensionless; EMD: feature units).

The protocol (see :func:`split_half` and docs/visual-gap.md): with N images per set, FID and EMD on small N are
dominated by a sample-size bias that is often 10-300x the real gap, so a number on its own means little. Every
comparison is therefore made between two sets of the same size h = N // 2, and the same-domain noise floor
(real half A against real half B) is reported next to the gaps. KID is unbiased, so its floor is near 0.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field

import numpy as np
from scipy import sparse
from scipy.linalg import eigh, eigvalsh
from scipy.optimize import linear_sum_assignment, linprog
from scipy.spatial.distance import cdist

from rik.errors import RikError

EMD_LP_MAX_VARIABLES = 250_000
"""Unequal-size EMD solves a transport LP with n_a * n_b variables; above this it is refused (too slow)."""
FLOOR = "real split-half floor"


def _features(x: np.ndarray, what: str, min_rows: int = 1) -> np.ndarray:
    """``x`` as a float64 (n, d) array; a RikError when it is not one or has fewer than ``min_rows`` rows."""
    arr = np.asarray(x, dtype=np.float64)
    if arr.ndim != 2:
        raise RikError(f"{what}: features must be a 2-D array (images x dimensions), got shape {arr.shape}")
    if arr.shape[0] < min_rows:
        raise RikError(f"{what}: needs at least {min_rows} images, got {arr.shape[0]}")
    if not np.all(np.isfinite(arr)):
        raise RikError(f"{what}: features contain NaN or infinite values")
    return arr


def _same_dim(a: np.ndarray, b: np.ndarray) -> None:
    if a.shape[1] != b.shape[1]:
        raise RikError(f"feature dimensions differ: {a.shape[1]} and {b.shape[1]}")


def _psd_sqrt(s: np.ndarray) -> np.ndarray:
    """Square root of a symmetric positive semi-definite matrix; tiny negative eigenvalues (round-off) become 0."""
    w, v = eigh(s)
    return (v * np.sqrt(np.clip(w, 0.0, None))) @ v.T


def frechet_distance(mu1: np.ndarray, sigma1: np.ndarray, mu2: np.ndarray, sigma2: np.ndarray) -> float:
    """Fréchet distance between Gaussians N(mu1, sigma1) and N(mu2, sigma2) (squared feature units).

    |mu1 - mu2|² + tr S1 + tr S2 - 2 tr sqrt(sqrt(S1) S2 sqrt(S1)), in the symmetric form: the inner matrix is
    symmetric PSD, so its eigenvalues are real and clipped at 0; the result is never complex or NaN.
    """
    mu1, mu2 = np.atleast_1d(np.asarray(mu1, np.float64)), np.atleast_1d(np.asarray(mu2, np.float64))
    s1, s2 = np.atleast_2d(np.asarray(sigma1, np.float64)), np.atleast_2d(np.asarray(sigma2, np.float64))
    d = mu1.shape[0]
    if mu2.shape != (d,) or s1.shape != (d, d) or s2.shape != (d, d):
        raise RikError(f"frechet_distance: shapes do not agree: mu {mu1.shape}, {mu2.shape}; "
                       f"sigma {s1.shape}, {s2.shape}")
    s1, s2 = (s1 + s1.T) / 2, (s2 + s2.T) / 2
    r1 = _psd_sqrt(s1)
    inner = r1 @ s2 @ r1
    cross = np.sqrt(np.clip(eigvalsh((inner + inner.T) / 2), 0.0, None)).sum()
    diff = mu1 - mu2
    return max(0.0, float(diff @ diff + np.trace(s1) + np.trace(s2) - 2.0 * cross))


def fid(feats_a: np.ndarray, feats_b: np.ndarray) -> float:
    """Fréchet distance between the Gaussians fitted to two feature sets (unbiased covariances), in squared
    feature units; equal to ``frechet_distance(mean_a, cov_a, mean_b, cov_b)``.

    Computed from the centred data: tr sqrt(sqrt(S_a) S_b sqrt(S_a)) is the nuclear norm of
    X_a X_bᵀ / sqrt((n_a-1)(n_b-1)), so with few images and many dimensions only an n_a x n_b SVD is needed
    (exact, no d x d matrix square root). Needs at least 2 images per set.
    """
    a, b = _features(feats_a, "fid: first set", 2), _features(feats_b, "fid: second set", 2)
    _same_dim(a, b)
    return _fid_data(a, b)


def _fid_data(a: np.ndarray, b: np.ndarray) -> float:
    mu_a, mu_b = a.mean(axis=0), b.mean(axis=0)
    xa, xb = a - mu_a, b - mu_b
    ca, cb = a.shape[0] - 1, b.shape[0] - 1
    d = a.shape[1]
    if min(a.shape[0], b.shape[0]) <= d:
        cross = np.linalg.svd(xa @ xb.T, compute_uv=False).sum() / math.sqrt(ca * cb)
    else:
        sa, sb = xa.T @ xa / ca, xb.T @ xb / cb
        ra = _psd_sqrt(sa)
        inner = ra @ sb @ ra
        cross = np.sqrt(np.clip(eigvalsh((inner + inner.T) / 2), 0.0, None)).sum()
    diff = mu_a - mu_b
    total = diff @ diff + (xa * xa).sum() / ca + (xb * xb).sum() / cb - 2.0 * cross
    return max(0.0, float(total))


@dataclass(frozen=True)
class KidValue:
    """KID: the unbiased MMD² with the cubic polynomial kernel, averaged over random subsets (kernel units)."""

    mean: float
    std: float
    """Standard deviation over the subsets (0 when every subset is the whole set)."""


def polynomial_kernel(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """k(x, y) = (x·y / d + 1)³, the kernel of KID (Bińkowski et al. 2018; clean-fid), for all row pairs."""
    k = x @ y.T / x.shape[1] + 1.0
    return k * k * k


def _mmd2_unbiased(kxx: np.ndarray, kyy: np.ndarray, kxy: np.ndarray,
                   same_x: np.ndarray | None = None, same_y: np.ndarray | None = None) -> float:
    """Unbiased MMD² from kernel blocks: within-set means over pairs i != j, minus twice the cross mean.

    ``same_x``/``same_y`` mark extra pairs to leave out (used by the bootstrap: two copies of one image are not
    an independent pair)."""
    def within(k: np.ndarray, same: np.ndarray | None) -> float:
        if same is None:
            m = k.shape[0]
            return float((k.sum() - np.trace(k)) / (m * (m - 1)))
        keep = ~same
        return float(k[keep].mean()) if keep.any() else 0.0

    return within(kxx, same_x) + within(kyy, same_y) - 2.0 * float(kxy.mean())


def kid(feats_a: np.ndarray, feats_b: np.ndarray, subsets: int = 100, subset_size: int = 1000,
        seed: int = 0) -> KidValue:
    """Kernel Inception Distance: unbiased MMD² with k(x, y) = (x·y/d + 1)³, mean and std over ``subsets``
    random subsets of ``min(subset_size, n_a, n_b)`` images drawn without replacement from each set (as
    clean-fid). When that size is the whole of both sets one evaluation is made and std is 0. Its expectation
    is 0 for two samples of one distribution, whatever N (so it may come out slightly negative)."""
    a, b = _features(feats_a, "kid: first set", 2), _features(feats_b, "kid: second set", 2)
    _same_dim(a, b)
    if subsets < 1 or subset_size < 2:
        raise RikError(f"kid: needs subsets >= 1 and subset_size >= 2, got {subsets} and {subset_size}")
    m = min(subset_size, a.shape[0], b.shape[0])
    if m == a.shape[0] == b.shape[0]:
        value = _mmd2_unbiased(polynomial_kernel(a, a), polynomial_kernel(b, b), polynomial_kernel(a, b))
        return KidValue(value, 0.0)
    rng = np.random.default_rng(seed)
    values = np.empty(subsets)
    for i in range(subsets):
        x = a[rng.choice(a.shape[0], m, replace=False)]
        y = b[rng.choice(b.shape[0], m, replace=False)]
        values[i] = _mmd2_unbiased(polynomial_kernel(x, x), polynomial_kernel(y, y), polynomial_kernel(x, y))
    return KidValue(float(values.mean()), float(values.std()))


def emd(feats_a: np.ndarray, feats_b: np.ndarray) -> float:
    """Earth mover's distance (Wasserstein-1, Euclidean ground cost) between the uniform distributions on two
    feature sets, in feature units. Exact: for equal sizes an optimal assignment (``linear_sum_assignment``);
    for unequal sizes the transport linear programme (HiGHS), refused above ``EMD_LP_MAX_VARIABLES`` pairs."""
    a, b = _features(feats_a, "emd: first set"), _features(feats_b, "emd: second set")
    _same_dim(a, b)
    cost = cdist(a, b)
    if a.shape[0] == b.shape[0]:
        return _emd_assignment(cost)
    return _emd_transport(cost)


def _emd_assignment(cost: np.ndarray) -> float:
    rows, cols = linear_sum_assignment(cost)
    return float(cost[rows, cols].mean())


def _emd_transport(cost: np.ndarray) -> float:
    na, nb = cost.shape
    if na * nb > EMD_LP_MAX_VARIABLES:
        raise RikError(f"emd: sets of {na} and {nb} images need a {na}x{nb} transport problem (more than "
                       f"{EMD_LP_MAX_VARIABLES} pairs); subsample both to the same size (--n) for the exact "
                       f"assignment")
    rows = sparse.kron(sparse.eye(na), np.ones((1, nb)))  # row sums: each a-point sends 1/na
    cols = sparse.kron(np.ones((1, na)), sparse.eye(nb))  # column sums: each b-point receives 1/nb
    eq = sparse.vstack([rows, cols]).tocsr()
    rhs = np.concatenate([np.full(na, 1.0 / na), np.full(nb, 1.0 / nb)])
    # scipy-stubs type A_eq as a dense array; scipy's HiGHS methods take a sparse matrix too
    res = linprog(cost.ravel(), A_eq=eq[:-1], b_eq=rhs[:-1], bounds=(0, None), method="highs")  # type: ignore[call-overload]
    if res.status != 0:
        raise RikError(f"emd: the transport problem did not solve ({res.message})")
    return float(res.fun)


# --- bootstrap and the split-half protocol -------------------------------------------------------------------


@dataclass(frozen=True)
class Interval:
    """A point estimate with its bootstrap interval (:func:`percentile_interval`), in the metric's units."""

    value: float
    low: float
    high: float
    std: float | None = None
    """KID only: standard deviation over subsets."""


@dataclass(frozen=True)
class PairMetrics:
    """FID, KID and EMD for one row of the table, each with its bootstrap interval."""

    name: str
    """``sim``, ``rerendered`` or the floor (``real split-half floor``)."""
    n: int
    """Images on each side of every comparison (h = N // 2)."""
    fid: Interval
    kid: Interval
    emd: Interval
    comparisons: str
    """What was compared, in words."""


class RowTable:
    """A dataclass holding ``rows`` of :class:`PairMetrics`: lookup by name and the JSON form."""

    rows: list[PairMetrics]

    def row(self, name: str) -> PairMetrics:
        """The row called ``name`` (``sim``, ``rerendered`` or :data:`FLOOR`); a KeyError when there is none."""
        for r in self.rows:
            if r.name == name:
                return r
        raise KeyError(name)

    def to_dict(self) -> dict[str, object]:
        return asdict(self)  # type: ignore[call-overload]  # RowTable is only mixed into dataclasses


@dataclass
class SplitHalfResult(RowTable):
    """The rows of one encoder's table: every other set, then the floor last; serialises to JSON."""

    n_per_set: int
    n_half: int
    bootstrap: int
    level: float
    seed: int
    rows: list[PairMetrics] = field(default_factory=list)


def _fid_gram(gaa: np.ndarray, gbb: np.ndarray, gab: np.ndarray) -> float:
    """FID from the Gram blocks of two sets (inner products of rows, taken about any common origin): the same
    number as :func:`fid`, without touching the d feature dimensions."""
    ma, mb = gaa.shape[0], gbb.shape[0]
    sa, sb, sab = gaa.sum(), gbb.sum(), gab.sum()
    mean_gap = sa / ma**2 + sb / mb**2 - 2.0 * sab / (ma * mb)  # |mu_a - mu_b|^2
    tr_a = (np.trace(gaa) - sa / ma) / (ma - 1)
    tr_b = (np.trace(gbb) - sb / mb) / (mb - 1)
    cross = gab - gab.mean(axis=1, keepdims=True) - gab.mean(axis=0, keepdims=True) + sab / (ma * mb)  # Xa Xb^T
    small = cross @ cross.T if ma <= mb else cross.T @ cross
    nuclear = np.sqrt(np.clip(np.linalg.eigvalsh(small), 0.0, None)).sum()
    return max(0.0, float(mean_gap + tr_a + tr_b - 2.0 * nuclear / math.sqrt((ma - 1) * (mb - 1))))


class _PairSampler:
    """Precomputed Gram, kernel and distance blocks for one pair of sets, so one bootstrap resample costs index
    operations, an n x n symmetric eigenvalue problem and an n x n assignment, whatever the feature dimension."""

    def __init__(self, a: np.ndarray, b: np.ndarray):
        self.a, self.b = a, b
        origin = np.vstack([a, b]).mean(axis=0)  # FID is translation-invariant; centring keeps the Grams accurate
        ac, bc = a - origin, b - origin
        self.gaa, self.gbb, self.gab = ac @ ac.T, bc @ bc.T, ac @ bc.T
        self.kaa, self.kbb, self.kab = polynomial_kernel(a, a), polynomial_kernel(b, b), polynomial_kernel(a, b)
        self.dist = cdist(a, b)

    def point(self, kid_subsets: int, seed: int) -> tuple[float, KidValue, float]:
        """FID, KID and EMD on the sets as they are."""
        return fid(self.a, self.b), kid(self.a, self.b, subsets=kid_subsets, seed=seed), emd(self.a, self.b)

    def resample(self, ia: np.ndarray, ib: np.ndarray) -> tuple[float, float, float]:
        """FID, KID and EMD on the resample (indices with repeats). In KID, pairs of copies of one image are left
        out of the within-set means, as the diagonal is in the unbiased estimator."""
        same_a, same_b = ia[:, None] == ia[None, :], ib[:, None] == ib[None, :]
        k = _mmd2_unbiased(self.kaa[np.ix_(ia, ia)], self.kbb[np.ix_(ib, ib)], self.kab[np.ix_(ia, ib)],
                           same_a, same_b)
        cost = self.dist[np.ix_(ia, ib)]
        e = _emd_assignment(cost) if len(ia) == len(ib) else _emd_transport(cost)
        f = _fid_gram(self.gaa[np.ix_(ia, ia)], self.gbb[np.ix_(ib, ib)], self.gab[np.ix_(ia, ib)])
        return f, k, e


def percentile_interval(point: float, samples: np.ndarray, level: float = 0.95) -> tuple[float, float]:
    """The central ``level`` percentile interval of bootstrap ``samples``, re-centred on ``point``: the samples
    are first shifted by ``point - median(samples)``, so the interval always contains the point estimate.

    Why: a resample drawn with replacement holds only about 63 % distinct images, and FID and EMD grow as the
    number of distinct images falls, so the raw bootstrap distribution sits above the point estimate (often
    entirely, for N in the hundreds) while its spread is still a fair estimate of the sampling spread."""
    shifted = np.asarray(samples, np.float64) + (point - float(np.median(samples)))
    lo, hi = np.percentile(shifted, [50 * (1 - level), 50 * (1 + level)])
    return float(lo), float(hi)


def bootstrap_pairs(pairs: list[tuple[np.ndarray, np.ndarray]], resamples: int = 200, level: float = 0.95,
                    seed: int = 0, kid_subsets: int = 100, name: str = "pair", comparisons: str = "") -> PairMetrics:
    """FID, KID and EMD averaged over ``pairs`` of feature sets, with percentile bootstrap intervals.

    Each resample draws every set of every pair with replacement (independently, seeded) and recomputes the
    three averages; the interval is the central ``level`` fraction of the ``resamples`` values, re-centred on
    the point estimate (:func:`percentile_interval` says why). It shows the sampling spread of each number.
    """
    if not pairs:
        raise RikError("bootstrap_pairs: no pairs to compare")
    if resamples < 1 or not 0 < level < 1:
        raise RikError(f"bootstrap: needs resamples >= 1 and 0 < level < 1, got {resamples} and {level}")
    samplers = []
    for i, (a, b) in enumerate(pairs):
        fa, fb = _features(a, f"{name}: pair {i} first set", 2), _features(b, f"{name}: pair {i} second set", 2)
        _same_dim(fa, fb)
        samplers.append(_PairSampler(fa, fb))
    points = [s.point(kid_subsets, seed) for s in samplers]
    fid_pt = float(np.mean([p[0] for p in points]))
    kid_pt = float(np.mean([p[1].mean for p in points]))
    kid_std = math.sqrt(sum(p[1].std ** 2 for p in points)) / len(points)  # std of the mean of independent KIDs
    emd_pt = float(np.mean([p[2] for p in points]))
    rng = np.random.default_rng([seed, 0x5EED])
    draws = np.empty((resamples, 3))
    for r in range(resamples):
        vals = [s.resample(rng.integers(0, len(s.a), len(s.a)), rng.integers(0, len(s.b), len(s.b)))
                for s in samplers]
        draws[r] = np.mean(vals, axis=0)
    (f_lo, f_hi), (k_lo, k_hi), (e_lo, e_hi) = (percentile_interval(pt, draws[:, j], level)
                                                for j, pt in enumerate((fid_pt, kid_pt, emd_pt)))
    n = min(min(len(s.a), len(s.b)) for s in samplers)
    return PairMetrics(name=name, n=n, fid=Interval(fid_pt, f_lo, f_hi), kid=Interval(kid_pt, k_lo, k_hi, kid_std),
                       emd=Interval(emd_pt, e_lo, e_hi), comparisons=comparisons)


def halves(count: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Two disjoint random halves of ``range(count)``, each of ``count // 2`` indices (one left over if odd)."""
    perm = rng.permutation(count)
    h = count // 2
    return np.sort(perm[:h]), np.sort(perm[h:2 * h])


def split_half(real: np.ndarray, others: Mapping[str, np.ndarray], resamples: int = 200, level: float = 0.95,
               seed: int = 0, kid_subsets: int = 100) -> SplitHalfResult:
    """The split-half protocol: every comparison is between two sets of h = N // 2 images.

    - The real set (N images) is split at random into halves A and B; the floor is d(A, B): what the metric
      says for two samples of one domain of this size. Small-sample FID is dominated by bias, so only gaps
      above this floor (and outside its interval) mean anything.
    - Each other set X (same N) is split into halves X1, X2; its gap is (d(A, X1) + d(B, X2)) / 2, so every
      image is used once and every distance is at the same size h as the floor.
    - Each row has percentile bootstrap intervals (:func:`bootstrap_pairs`).
    Splits and resamples are seeded by ``seed``.
    """
    real = _features(real, "real", 4)
    n = real.shape[0]
    checked = {name: _features(x, name, 4) for name, x in others.items()}
    for name, x in checked.items():
        if x.shape[0] != n:
            raise RikError(f"split-half: '{name}' has {x.shape[0]} images and real has {n}; compare at equal N")
    rng = np.random.default_rng(seed)
    ra, rb = halves(n, rng)
    h = len(ra)
    result = SplitHalfResult(n_per_set=n, n_half=h, bootstrap=resamples, level=level, seed=seed)
    floor = bootstrap_pairs([(real[ra], real[rb])], resamples, level, seed, kid_subsets, FLOOR,
                            f"real half A vs real half B, {h} images each")
    for name, x in checked.items():
        x1, x2 = halves(n, rng)
        result.rows.append(bootstrap_pairs([(real[ra], x[x1]), (real[rb], x[x2])], resamples, level, seed,
                                           kid_subsets, name,
                                           f"mean of real half A vs {name} half 1 and real half B vs {name} "
                                           f"half 2, {h} images each"))
    result.rows.append(floor)
    return result
