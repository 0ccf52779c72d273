"""Hidden-effect tests of ``rik sysid``: measured data from a ground truth the pipeline does not see (MuJoCo at a
0.5 ms timestep against the fit's 5 ms samples, one effect drawn from realistic ranges in a shape slightly unlike
the library's, sensor noise, a 10 ms delay, strokes, slow strokes, holds, releases and throws), and the pipeline
must name the effect, recover its key parameters and report a held-out gain; with no effect it must say so.

What the data cannot support is stated, not hidden: stiction is named only when its Stribeck speed lies above
the fit's velocity noise floor (the test draws it there on drawers and checks the floor); on doors at the
default 0.2° position noise the generator's Stribeck speeds (0.03–0.08 rad/s) lie under the 0.1 rad/s floor, so
the hinge runs cover the other effects (docs/sysid.md has the measured cases).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from rik.joints.laws import effect_force
from rik.schemas.joints import JointType, Spring, Stiction
from rik.sysid.discover import discover
from rik.sysid.effects import INDISTINGUISHABLE
from rik.sysid.synthetic.generate import EFFECT_KINDS, GroundTruth, ground_truth_force, random_truth, simulate_trials

pytestmark = pytest.mark.slow  # end-to-end runs: out of the everyday tier (-m "not slow")

SEEDS = (0, 1, 2)
HINGE_KINDS = tuple(k for k in EFFECT_KINDS if k != "stiction")
"""The hinge cases: every kind but stiction (tested on slides only)."""


def _truth(kind: str | None, joint: JointType, seed: int) -> GroundTruth:
    truth = random_truth(kind, joint, np.random.default_rng(seed))
    if kind == "stiction" and joint is JointType.slide:  # Stribeck speed above the noise floor (~15 mm/s)
        effect = truth.effect
        truth = GroundTruth(truth.joint, truth.mass, truth.damping, truth.frictionloss, truth.range,
                            Stiction(breakaway=effect.breakaway, stribeck_velocity=0.02 + 0.005 * seed))
    return truth


def _discover(kind: str | None, joint: JointType, seed: int):
    truth = _truth(kind, joint, seed)
    return truth, discover(simulate_trials(truth, n_trials=4, seed=seed))


def _named(d, kind: str) -> bool:
    """``kind`` is the one effect found, or a member of an indistinguishable pair with the other one found."""
    sel = d.selection
    if not sel.found or len(sel.final.kinds) != 1:  # a single hidden effect must not come with a second one
        return False
    chosen = sel.final.kinds[0]
    if chosen == kind:
        return True
    # an indistinguishable pair: either member, with the ambiguity stated and the separating experiment given
    pair = frozenset({chosen, kind})
    return pair in INDISTINGUISHABLE and kind in {s.fit.kind for s in sel.alternatives} and bool(sel.separation)


def _close(fitted: float, true: float, rel: float) -> bool:
    return abs(fitted - true) <= rel * abs(true)


def _law_error(truth: GroundTruth, d, q: np.ndarray, v: np.ndarray) -> float:
    """RMS difference between the fitted library law and the truth's own law on a grid, relative to the truth's RMS."""
    fitted = d.chosen.effect
    if isinstance(fitted, Spring):
        mine = -fitted.stiffness * (q - fitted.reference)
    else:
        mine = effect_force(fitted, q, v, truth.joint)
    true = ground_truth_force(truth, q, v)
    return float(np.sqrt(np.mean((mine - true) ** 2)) / np.sqrt(np.mean(true**2)))


def _check_parameters(truth: GroundTruth, d) -> None:
    e, f = truth.effect, d.chosen.effect
    kind = d.chosen.kind
    if kind != (e.kind if not isinstance(e, Spring) else "spring"):
        return  # the other member of an indistinguishable pair: its parameters mean something else
    upper = truth.range[1]
    if kind in ("soft_close", "self_close"):
        assert _close(f.zone, e.zone, 0.2), (f.zone, e.zone)
        gain = (f.damping, e.damping) if kind == "soft_close" else (f.stiffness, e.stiffness)
        assert _close(*gain, 0.35), gain
    elif kind == "magnetic_catch":  # amplitude and decay trade off: compare the pull just off closed
        q = np.linspace(0.002, 0.01, 9) if truth.joint is JointType.slide else np.linspace(0.01, 0.03, 9)
        assert _law_error(truth, d, q, np.zeros_like(q)) < 0.5
    elif kind == "tilt":
        q = np.linspace(0.0, upper, 21)
        assert _law_error(truth, d, q, np.zeros_like(q)) < 0.15
    elif kind == "direction_friction":
        assert f.direction == e.direction and _close(f.extra, e.extra, 0.3), (f, e)
    elif kind == "quadratic_damping":
        assert _close(f.coefficient, e.coefficient, 0.35), (f, e)
    elif kind == "load_friction":
        assert _close(f.per_extension, e.per_extension, 0.35), (f, e)
    elif kind == "spring":
        q = np.linspace(0.0, upper, 21)
        assert _law_error(truth, d, q, np.zeros_like(q)) < 0.2
        assert _close(f.stiffness, e.stiffness, 0.25), (f, e)
    elif kind == "stiction":  # the breakaway, measured from rest, and the excess friction over the speeds the fit
        # sees (the floor up to 3x it), where the truth's Stribeck exponent of 1.5 differs from the library's 2
        assert _close(f.breakaway, e.breakaway, 0.35), (f, e)
        v = np.linspace(d.fit_velocity, 3 * d.fit_velocity, 9)
        assert _law_error(truth, d, np.full_like(v, upper / 2), v) < 0.8


CASES = [(k, JointType.slide, s) for k in EFFECT_KINDS for s in SEEDS] + \
        [(k, JointType.hinge, s) for k in HINGE_KINDS for s in SEEDS[:2]]
MISSED = {
    ("direction_friction", JointType.hinge, 0): "measured miss (docs/sysid.md): held-out gain 2 % (10 % needed)",
    ("load_friction", JointType.hinge, 1): "measured miss: the door's friction growing with the angle is not chosen",
}
"""Cases the pipeline is known to get wrong: strict xfails, so a fix shows up as a failure to update them."""


def _case(kind: str, joint: JointType, seed: int):
    reason = MISSED.get((kind, joint, seed))
    marks = [pytest.mark.xfail(strict=True, reason=reason)] if reason else []
    return pytest.param(kind, joint, seed, marks=marks, id=f"{joint.value}-{kind}-{seed}")


@pytest.mark.parametrize(("kind", "joint", "seed"), [_case(*c) for c in CASES])
def test_hidden_effect_is_named_fitted_and_gains(kind: str, joint: JointType, seed: int) -> None:
    truth, d = _discover(kind, joint, seed)
    assert _named(d, kind), (d.sentence(), [(s.fit.kind, round(s.gain, 3), s.verdict) for s in d.selection.scores])
    _check_parameters(truth, d)
    chosen = d.selection.chosen
    assert chosen.gain >= 0.1 and chosen.bic_drop >= 10 and d.selection.pair is None
    fb, fe = d.force_rmse
    pb, pe = d.position_rmse
    assert fe < 0.9 * fb
    if kind != "stiction":  # stiction's is measured, not asserted (docs/sysid.md): with creeps and pushes in the
        # excitation the fitted stiction re-simulates the held-out trials worse than the baseline in two seeds of
        # three (the true joint does better); whether a re-simulated front sticks or slips flips on small differences
        assert pe < pb, (pb, pe)  # the extended joint re-simulates the held-out trials closer
    assert d.sentence().startswith("The simulation misses")
    if kind == "stiction":
        assert d.fit_velocity < truth.effect.stribeck_velocity


@pytest.mark.parametrize(("joint", "seed"), [(JointType.slide, s) for s in SEEDS] + [(JointType.hinge, s)
                                                                                     for s in SEEDS])
def test_no_hidden_effect_gives_no_significant_effect(joint: JointType, seed: int) -> None:
    truth, d = _discover(None, joint, seed)
    assert not d.selection.found, d.sentence()
    assert d.sentence().startswith("No significant unmodelled effect")
    assert d.extended_resistance is None
    assert all(s.gain < 0.1 or not s.passed for s in d.selection.scores)
    base = d.selection.baseline.baseline  # and the baseline itself is right
    assert _close(base.inertia, truth.mass, 0.1)
    noise = 0.3 if joint is JointType.slide else 0.03  # the force noise, N or N·m
    assert abs(base.friction - truth.frictionloss) <= 0.25 * truth.frictionloss + noise
    assert abs(base.damping - truth.damping) <= 0.2 * truth.damping + noise


def test_delay_is_recovered_for_all_trials() -> None:
    truth = random_truth(None, JointType.slide, np.random.default_rng(5))
    d = discover(simulate_trials(truth, n_trials=3, seed=5, delay_s=0.02), resimulate=False)
    assert math.isclose(d.delay_s, 0.02, abs_tol=1e-9)


PAIRS = [(a, b, JointType.slide, s) for a, b in (("soft_close", "self_close"), ("self_close", "soft_close"),
                                                  ("quadratic_damping", "self_close"), ("load_friction", "soft_close"),
                                                  ("soft_close", "tilt")) for s in SEEDS] + \
        [(a, b, JointType.hinge, s) for a, b in (("self_close", "soft_close"), ("tilt", "soft_close")) for s in SEEDS]


@pytest.mark.parametrize(("first", "second", "joint", "seed"), PAIRS,
                         ids=[f"{j.value}-{a}+{b}-{s}" for a, b, j, s in PAIRS])
def test_two_hidden_effects_are_both_named(first: str, second: str, joint: JointType, seed: int) -> None:
    """A soft-close runner's damper with its pull-in spring, and other pairs: both effects are named (or a member
    is swapped for one the data cannot tell it from, with the statement), and the pair beats each alone."""
    truth = random_truth(first, joint, np.random.default_rng(seed), second=second)
    d = discover(simulate_trials(truth, n_trials=4, seed=seed))
    sel = d.selection
    found = set(sel.final.kinds) if sel.found else set()
    truth_kinds = {first, second}
    if found != truth_kinds:
        swapped = frozenset(found ^ truth_kinds)
        stated = any(set(a.fit.kinds) == truth_kinds for a in sel.pair_alternatives)
        assert swapped in INDISTINGUISHABLE and stated and sel.separation, (d.sentence(), [
            (s.fit.kinds, round(s.gain, 3), s.verdict) for s in sel.pairs[:4]])
    assert sel.pair is not None and sel.pair.passed
    assert "; and " in d.sentence() and "adding them cuts" in d.sentence()
    soft = [e for e in sel.final.effects if getattr(e, "kind", None) == "soft_close"]
    if soft:
        true_zone = next(e.zone for e in (truth.effect, truth.second) if getattr(e, "kind", None) == "soft_close")
        assert _close(soft[0].zone, true_zone, 0.25), (soft[0].zone, true_zone)
    pb, pe = d.position_rmse
    assert pe < pb
    assert len(d.extended_resistance.effects) + (d.extended_resistance.spring is not None) == 2
