"""End stops and breakaway from rest in ``rik sysid``: long pushes held against both stops leak no force into any
effect, and breakaways measured from rest (creeps from closed, starts after holds) are found with their force.
"""

from __future__ import annotations

import numpy as np
import pytest

from rik.schemas.joints import JointType
from rik.sysid.breakaway import find_breakaways
from rik.sysid.discover import discover, prepare_all
from rik.sysid.preprocess import touching
from rik.sysid.synthetic.generate import ExcitationPlan, Segment, measure, random_truth, simulate, simulate_trials

SLIDE = JointType.slide


def _pushing_trials(seed: int, n: int = 3) -> tuple[object, list]:
    """Trials of a drawer with nothing hidden whose hand pushes the front hard against each stop and holds it
    there for 1.5 s, several times, between ordinary strokes."""
    truth = random_truth(None, SLIDE, np.random.default_rng(seed))
    upper = truth.range[1]
    trials = []
    for i in range(n):
        rng = np.random.default_rng(100 * seed + i)
        segments: list[Segment] = []
        for _ in range(2):
            segments += [Segment("move", -rng.uniform(0.02, 0.04), 0.3, 1.0), Segment("hold", duration=1.5),
                         Segment("move", rng.uniform(0.3, 0.6) * upper, rng.uniform(0.15, 0.4), 1.2),
                         Segment("move", upper + rng.uniform(0.02, 0.04), 0.3, 1.0), Segment("hold", duration=1.5),
                         Segment("move", rng.uniform(0.2, 0.7) * upper, rng.uniform(0.1, 0.4), 1.2)]
        sim = simulate(truth, ExcitationPlan(0.0, tuple(segments)), duration_s=16.1)
        trials.append(measure(sim, np.random.default_rng(seed + 10 * i), name=f"trial_{i + 1}", duration_s=16.0))
    return truth, trials


@pytest.mark.parametrize("seed", [0, 1])
def test_long_pushes_against_both_stops_leak_into_no_effect(seed: int) -> None:
    truth, trials = _pushing_trials(seed)
    d = discover(trials, resimulate=False)
    pushing = [float(np.abs(t.f).max()) for t in trials]
    assert min(pushing) > 3 * truth.frictionloss  # the hand really pressed on the stops
    assert not d.selection.found, d.sentence()
    leaks = [(s.fit.kind, round(s.gain, 3), s.verdict) for s in d.selection.scores if s.gain >= 0.1]
    assert not leaks, leaks  # no effect (not even a refused one, like a catch that repels) absorbs the stops' force


def test_departure_from_a_stop_is_left_out_like_an_arrival() -> None:
    q = np.concatenate([np.zeros(50), np.linspace(0.0, 0.1, 50)])
    near = touching(q, (0.0, 0.1), 0.001, 5)
    leaving = int(np.argmax(q > 0.001))
    assert near[leaving:leaving + 5].all()  # smoothing smears the pushing hand's force past the departure
    assert not near[leaving + 6:-10].any()


def test_breakaways_from_rest_give_the_static_resistance() -> None:
    """A drawer with stiction: every kept breakaway away from the stops is at the static friction (Coulomb plus
    the breakaway excess), within the force noise and the slow rise; creeps from closed are found."""
    truth = random_truth("stiction", SLIDE, np.random.default_rng(1))
    prepared, _ = prepare_all(simulate_trials(truth, n_trials=3, seed=1))
    limits = (min(float(p.q.min()) for p in prepared), max(float(p.q.max()) for p in prepared))
    events = [e for p in prepared for e in find_breakaways(p, limits)]
    static = truth.frictionloss + truth.effect.breakaway
    assert len(events) >= 3
    assert sum(e.from_stop for e in events) >= 2  # the creeps open from closed
    for e in events:
        assert abs(abs(e.force) - static) < 0.15 * static, (e, static)


def test_breakaway_excess_names_stiction_and_a_catch() -> None:
    """Breakaway evidence separates stiction from sliding friction on a drawer whose Stribeck speed lies under
    the velocity noise floor (invisible to the moving samples alone)."""
    truth = random_truth("stiction", SLIDE, np.random.default_rng(2))
    assert truth.effect.stribeck_velocity < 0.03
    d = discover(simulate_trials(truth, n_trials=3, seed=2), resimulate=False)
    assert d.selection.found and d.selection.final.kinds[0] == "stiction", d.sentence()
    assert abs(d.selection.final.effect.breakaway - truth.effect.breakaway) < 0.35 * truth.effect.breakaway


def test_departure_pulled_from_rest_keeps_its_samples() -> None:
    """Where the hand pulled the front off the stop (no push before), the samples just off it stay: a catch acts
    there."""
    q = np.concatenate([np.zeros(50), np.linspace(0.0, 0.1, 50)])
    pulling = np.full(100, 5.0)
    near = touching(q, (0.0, 0.1), 0.001, 5, pulling)
    leaving = int(np.argmax(q > 0.001))
    assert not near[leaving:-10].any()
    pushed = np.concatenate([np.full(47, -20.0), np.full(53, 5.0)])  # pressed on the stop until just before
    assert touching(q, (0.0, 0.1), 0.001, 5, pushed)[leaving:leaving + 5].all()
