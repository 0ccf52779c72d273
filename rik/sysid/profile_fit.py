"""What a quasi-static force profile can identify, fitted and selected like the dynamic path.

The data is the force that opens the front against its position, slowly: no time, so no velocity or
acceleration. The model is

    F(q) = c + Σ θ_j·φ_j(q; h)

with ``c`` the **friction level (or constant force)**: on opening-only data Coulomb friction and a constant force
(a tilt's constant part, a spring's preload) add up to one number and cannot be split; and ``φ_j`` the regressors
of the position-dependent families of the library (:mod:`rik.sysid.effects`), evaluated with the velocity fixed
to opening (:data:`OPENING`):

- ``magnetic_catch``: a pull towards closed fading within a short decay (a magnet, a fridge's door seal);
- ``self_close``: a spring pulling the front shut over its last stretch;
- ``spring``: a closer spring over the whole travel (its stiffness; the preload is in ``c``);
- ``tilt`` (hinges): gravity on an out-of-plumb door, ``a + b·sin q`` (its ``b``; ``a`` and the cosine part,
  nearly constant over an opening, are in ``c``). On a slide a tilt is a constant force: only ``c``.

Not identifiable from such data, and never fitted: damping, inertia and every speed effect (stiction, quadratic
damping, a soft-close damper, friction that differs by direction). Forces and coefficients are in the data's
force unit: N, N·m, or N at the handle of a hinge whose lever arm is not known.

Selection is :func:`rik.sysid.select.select` (then :func:`~rik.sysid.select.select_pair`) with its thresholds
(:data:`~rik.sysid.select.MIN_GAIN`, :data:`~rik.sysid.select.MIN_BIC_DROP`, OCCAM, TIE) on held-out openings
of the same mechanism: the last quarter of the trials (at least one), or with one trial every
:data:`SINGLE_TRIAL_EVERY`-th point.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from rik.errors import RikError
from rik.schemas.joints import JointType
from rik.sysid.effects import FAMILY, Baseline, Effect, Family, Motion
from rik.sysid.fit import Fit, Term, grid_then_refine, heldout_trials, projected_rss, weighted_solve
from rik.sysid.profile import ProfileGroup
from rik.sysid.select import Selection, pair_allowed, select, select_pair

OPENING = 1.0
"""The velocity the regressors are evaluated at: opening (positive), m/s or rad/s (its size does not matter for
the position families)."""
SINGLE_TRIAL_EVERY = 4
"""With a single opening, every this-many-th point is held out."""
MIN_FIT_POINTS = 16
"""Fewest points the training openings, and the held-out ones, may have (a profile has far fewer points than a
time series: about 36 per door opening in the shared profiles)."""
QUASI_STATIC_COLUMNS: dict[JointType, dict[str, tuple[int, ...]]] = {
    JointType.slide: {"magnetic_catch": (0,), "self_close": (0,), "spring": (0,)},
    JointType.hinge: {"magnetic_catch": (0,), "self_close": (0,), "spring": (0,), "tilt": (1,)},
}
"""The families a profile can identify, per joint, and which of each family's coefficients (columns of its
regressors) are kept: the others are constant over an opening (a spring's preload, a tilt's constant part and,
on a hinge, its cosine part, which changes by under 20 % over 36°) and fold into the friction level."""

IDENTIFIED = ("position-dependent forces: a catch or seal near closed, a self-closing spring, a closer spring, "
              "gravity on a tilted hinge (a + b·sin q)", "the friction level (or constant force)")
NOT_IDENTIFIED = (
    "damping, inertia and speed effects (stiction, quadratic damping, a soft-close damper): the data has no time "
    "axis, so no velocity or acceleration",
    "friction against a constant force: on opening-only data they are the same thing, reported as one friction "
    "level (or constant force); so are a spring's preload and a tilt's constant part",
    "friction that differs by direction: only opening is measured",
)
HANDLE_NOTE = ("no lever arm is given: forces are at the handle, in N, against the angle (a torque needs the "
               "handle's distance from the hinge axis)")


@dataclass(frozen=True, eq=False)
class ProfileRows:
    """Points of a group's openings, concatenated (SI)."""

    q: np.ndarray
    f: np.ndarray
    trial: np.ndarray
    """Index of each point's opening in :attr:`names`."""
    names: tuple[str, ...]

    def take(self, mask: np.ndarray) -> ProfileRows:
        return ProfileRows(self.q[mask], self.f[mask], self.trial[mask], self.names)

    def __len__(self) -> int:
        return len(self.q)


@dataclass(frozen=True, eq=False)
class ProfileFit:
    """The quasi-static discovery of one group (mechanism)."""

    group: str
    joint: JointType
    force_unit: str
    rows: ProfileRows
    train: ProfileRows
    heldout: ProfileRows
    heldout_trials: tuple[int, ...]
    """Held-out openings (indices in ``rows.names``); with one opening, ``(0,)`` and every
    :data:`SINGLE_TRIAL_EVERY`-th point."""
    selection: Selection
    """The candidates as :class:`rik.sysid.fit.Fit`: ``theta`` is ``[c, kept coefficients...]`` (not the dynamic
    model's, so use :func:`predict`, never ``Fit.predict``), ``baseline.friction`` the friction level."""

    @property
    def level(self) -> float:
        """The selected model's friction level (or constant force)."""
        return float(self.selection.final.theta[0])

    @property
    def effects(self) -> tuple[Effect, ...]:
        return self.selection.final.effects if self.selection.found else ()


def profile_rows(group: ProfileGroup) -> ProfileRows:
    """The group's openings as one set of rows."""
    q = np.concatenate([p.q for p in group.profiles])
    f = np.concatenate([p.f for p in group.profiles])
    trial = np.concatenate([np.full(len(p.q), i) for i, p in enumerate(group.profiles)])
    return ProfileRows(q, f, trial.astype(int), tuple(p.name for p in group.profiles))


def split_profile(rows: ProfileRows, heldout: Sequence[int] | None = None, group: str = "profile"
                  ) -> tuple[ProfileRows, ProfileRows, tuple[int, ...]]:
    """Training and held-out points (module docstring); errors name ``group``."""
    n = len(rows.names)
    if n == 1:
        out = np.arange(len(rows)) % SINGLE_TRIAL_EVERY == SINGLE_TRIAL_EVERY - 1
        chosen: tuple[int, ...] = (0,)
    else:
        chosen = heldout_trials(n, heldout, f"its {n} openings", f"{group}: ")
        out = np.isin(rows.trial, chosen)
    train, test = rows.take(~out), rows.take(out)
    for part, r in (("training", train), ("held-out", test)):
        if len(r) < MIN_FIT_POINTS:
            raise RikError(f"{group}: only {len(r)} points in the {part} openings ({', '.join(rows.names)}), at "
                           f"least {MIN_FIT_POINTS} needed: measure more openings or more points per opening")
    return train, test, chosen


def families(joint: JointType) -> tuple[Family, ...]:
    """The library families a profile of a ``joint`` can identify."""
    return tuple(FAMILY[k] for k in QUASI_STATIC_COLUMNS[joint])


def features(family: Family, q: np.ndarray, hyper: float | None, joint: JointType) -> np.ndarray:
    """The kept regressors (:data:`QUASI_STATIC_COLUMNS`) of ``family`` at positions ``q``, opening."""
    full = family.features(Motion(q, np.full_like(q, OPENING)), hyper, joint)
    return full[:, list(QUASI_STATIC_COLUMNS[joint][family.kind])]


def design(q: np.ndarray, terms: Sequence[Term], joint: JointType) -> np.ndarray:
    """``[1, kept regressors of each term...]`` at ``q``."""
    return np.column_stack([np.ones_like(q), *(features(fam, q, h, joint) for fam, h in terms)])


def predict(fit: Fit, q: np.ndarray, joint: JointType) -> np.ndarray:
    """The profile model ``fit`` (from this module) at positions ``q``: force, in the data's unit."""
    return design(np.asarray(q, dtype=np.float64), fit.terms, joint) @ fit.theta


def _best_hyper(rows: ProfileRows, family: Family, fixed: Sequence[Term], joint: JointType) -> float:
    assert family.grid is not None
    rss_with = projected_rss(design(rows.q, fixed, joint), rows.f, np.ones(len(rows.f)))  # one QR per search
    return grid_then_refine(lambda h: rss_with(features(family, rows.q, h, joint)), family.grid(joint))


def _reading(theta: np.ndarray, terms: Sequence[Term], joint: JointType) -> tuple[tuple[Effect, ...], str | None]:
    # the placeholder baseline has no inertia or damping to judge (NaN); the level may be negative (a door that
    # gravity pushes open), which is no reason to call an effect unphysical
    base = Baseline(math.nan, math.nan, max(float(theta[0]), 0.0))
    effects, problem, at = [], None, 1
    for family, hyper in terms:
        kept = QUASI_STATIC_COLUMNS[joint][family.kind]
        width = family.features(Motion(np.zeros(1), np.ones(1)), hyper, joint).shape[1]
        full = np.zeros(width)
        full[list(kept)] = theta[at:at + len(kept)]
        effect, _, trouble = family.reading(full, hyper, base, joint)
        effects.append(effect)
        problem = problem or trouble
        at += len(kept)
    return tuple(effects), problem


def _rms(x: np.ndarray) -> float:
    return float(np.sqrt(np.mean(x * x))) if len(x) else math.nan


def fit_terms(train: ProfileRows, heldout: ProfileRows, joint: JointType, family: Family | None,
              base: Fit | None = None) -> Fit:
    """The friction level plus ``base``'s terms (hyperparameters kept) plus ``family``, fitted on ``train`` and
    scored on ``heldout``."""
    terms: tuple[Term, ...] = base.terms if base is not None else ()
    if family is not None:
        hyper = _best_hyper(train, family, terms, joint) if family.grid is not None else None
        terms = (*terms, (family, hyper))
    x = design(train.q, terms, joint)
    theta, rss = weighted_solve(x, train.f, np.ones(len(train.f)))  # unweighted
    effects, problem = _reading(theta, terms, joint)
    r_train = train.f - x @ theta
    r_held = heldout.f - design(heldout.q, terms, joint) @ theta
    params = x.shape[1] + sum(h is not None for _, h in terms)
    level = Baseline(math.nan, math.nan, float(theta[0]))
    return Fit(terms, theta, level, effects, problem, params, rss, len(train), _rms(r_train), _rms(r_held),
               r_train, r_held)


def fit_profile(group: ProfileGroup, joint: JointType, force_unit: str,
                heldout: Sequence[int] | None = None) -> ProfileFit:
    """Fit every identifiable family (and pairs of them) to a group's openings and select on held-out ones."""
    rows = profile_rows(group)
    train, test, chosen = split_profile(rows, heldout, group.name)
    baseline = fit_terms(train, test, joint, None)
    singles = [fit_terms(train, test, joint, f) for f in families(joint)]
    selection = select(baseline, singles)
    helped = [s.fit for s in selection.scores if s.gain > 0 and not s.fit.problem]
    pairs = [fit_terms(train, test, joint, f, base=first) for first in helped for f in families(joint)
             if pair_allowed(first.kind, f.kind)]
    if pairs:
        selection = select_pair(selection, pairs)
    return ProfileFit(group.name, joint, force_unit, rows, train, test, chosen, selection)


def describe(effect: Effect, joint: JointType, force_unit: str) -> str:
    """A profile effect's parameters in words, in the data's force unit (per degree on a hinge)."""
    from rik.schemas import joints as j

    f = "N" if force_unit.startswith("N at") else force_unit
    slide = joint is JointType.slide
    length, to_len = ("mm", 1e3) if slide else ("°", 180.0 / math.pi)
    match effect:
        case j.MagneticCatch():
            return (f"a pull of {effect.force:.3g} {f} at closed, down to a quarter {effect.decay * to_len:.3g} "
                    f"{length} open")
        case j.SelfClose():
            return (f"a pull of {effect.stiffness * effect.zone:.3g} {f} at closed, falling linearly to 0 at "
                    f"{effect.zone * to_len:.3g} {length}")
        case j.Tilt():
            way = "open" if effect.sine > 0 else "closed"
            return f"{abs(effect.sine):.3g} {f} × sin(angle) pushing it {way}"
        case j.Spring():
            return f"a closer spring: {effect.stiffness / to_len:.3g} {f} more resistance per {length} open"
    return str(effect)
