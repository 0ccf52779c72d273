"""Hidden-effect tests on data rik did not generate: the foreign generator (:mod:`rik.sysid.synthetic.foreign`: its own
integrator, LuGre friction, compliant end stops, a cubic magnet, a preloaded spring with play, a |v|^0.8 damper,
a PID hand with its own excitation: strokes, creeps, pushes held against both stops, holds and releases).

Drawers, three trials of 12 s at 200 Hz (one held out), three seeds per effect. The effect named first must be
the hidden one (or an indistinguishable partner, stated as such); with nothing hidden nothing is named; in no
case does a catch that repels within a millimetre of closed reach the 10 % held-out gain that would have chosen
it (the signature of an end stop's force leaking into the fit; a repelling catch decaying over centimetres is a
shape fitted to something else, refused as unphysical like any other). The cases rik gets wrong are strict
xfails with the measured reason (docs/sysid.md has the table).
"""

from __future__ import annotations

import numpy as np
import pytest

from rik.schemas.joints import JointType, MagneticCatch
from rik.sysid.discover import discover
from rik.sysid.effects import INDISTINGUISHABLE
from rik.sysid.synthetic.foreign import FOREIGN_KINDS, foreign_truth, simulate_foreign

pytestmark = pytest.mark.slow  # end-to-end runs: out of the everyday tier (-m "not slow")

SEEDS = (0, 1, 2)
MISSED = {("stiction", 1): "measured miss: stiction's held-out gain is 9.9 % (10 % needed)"}


def _case(kind: str, seed: int):
    reason = MISSED.get((kind, seed))
    return pytest.param(kind, seed, marks=[pytest.mark.xfail(strict=True, reason=reason)] if reason else [],
                        id=f"{kind}-{seed}")


@pytest.mark.parametrize(("kind", "seed"), [_case(k, s) for k in FOREIGN_KINDS for s in SEEDS])
def test_foreign_drawer_effect_is_named_first(kind: str, seed: int) -> None:
    truth = foreign_truth(kind, JointType.slide, np.random.default_rng(seed))
    d = discover(simulate_foreign(truth, n_trials=3, seed=seed), resimulate=False)
    sel = d.selection
    leaks = [(s.fit.kinds, round(s.gain, 3), s.fit.effects) for s in (*sel.scores, *sel.pairs) if s.gain >= 0.1
             and "repels" in s.verdict and any(isinstance(e, MagneticCatch) and e.decay < 1e-3 for e in s.fit.effects)]
    assert not leaks, leaks  # a catch that repels within a millimetre: the closed stop's force, leaked
    if kind == "none":
        assert not sel.found, d.sentence()
        return
    assert sel.found and len(sel.final.kinds) == 1, d.sentence()
    chosen = sel.final.kinds[0]
    if chosen != kind:  # the other member of a pair the data cannot tell apart, stated with its experiment
        assert frozenset({chosen, kind}) in INDISTINGUISHABLE, d.sentence()
        assert kind in {s.fit.kind for s in sel.alternatives} and sel.separation, d.sentence()
    assert sel.gain >= 0.1


@pytest.mark.parametrize("seed", [0, 1])
def test_foreign_pushes_on_compliant_stops_leak_into_no_effect(seed: int) -> None:
    """The foreign stops are compliant penalty contacts; every trial presses the front on both of them: with
    nothing hidden no candidate, refused or not, gains 10 % on held-out data."""
    truth = foreign_truth("none", JointType.slide, np.random.default_rng(10 + seed))
    trials = simulate_foreign(truth, n_trials=3, seed=10 + seed)
    lower = [float(t.q.min()) for t in trials]
    assert max(lower) < -1e-5  # pressed beyond closed: the stop gave way under the push
    d = discover(trials, resimulate=False)
    assert not d.selection.found, d.sentence()
    assert all(s.gain < 0.1 for s in d.selection.scores), [(s.fit.kind, s.gain, s.verdict) for s in d.selection.scores]
