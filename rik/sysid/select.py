"""Which effect, if any, the data shows: selection by held-out gain, information criterion and physical sign.

A candidate (the baseline plus one effect of the library) *passes* when all three hold:

- its held-out force error is at least :data:`MIN_GAIN` (10 %) below the baseline's: the effect predicts data
  it was not fitted to, which colored residuals cannot fake the way they inflate an information criterion;
- its BIC on the training rows is at least :data:`MIN_BIC_DROP` (10) below the baseline's;
- its parameters are physical (a damper that dissipates, a magnet that attracts, friction that is not negative).

Among passing candidates the one with the lowest held-out error wins, except that a candidate with fewer
parameters which achieves at least :data:`OCCAM` (95 %) of the winner's improvement is preferred (a spring does
not beat a constant force by the width of its extra coefficient). Other passing candidates with as many or
fewer parameters whose improvement reaches :data:`TIE` (90 %) of the chosen one's cannot be told apart from it
in this data: the verdict says so, with the experiment that would separate them. When nothing passes, the
answer is "no significant unmodelled effect".
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

from rik.sysid.effects import INDISTINGUISHABLE, MAGNET_AMBIGUITY
from rik.sysid.fit import Fit

MIN_GAIN = 0.10
"""Smallest relative drop of the held-out force RMSE that counts as a gain."""
MIN_BIC_DROP = 10.0
"""Smallest drop of the training BIC."""
OCCAM = 0.95
"""Share of the winner's improvement at which a simpler candidate is preferred."""
TIE = 0.90
"""Share of the chosen candidate's improvement from which another candidate explains the data as well."""


@dataclass(frozen=True)
class Score:
    """How one candidate fares against the baseline."""

    fit: Fit
    gain: float
    """Relative drop of the held-out force RMSE (0.25: 25 % lower)."""
    bic_drop: float
    """Baseline BIC minus the candidate's (positive: better)."""
    verdict: str
    """``pass``, or the reason it fails."""

    @property
    def passed(self) -> bool:
        return self.verdict == "pass"

    @property
    def improvement(self) -> float:
        """Drop of the held-out force RMSE, N or N·m."""
        return self.gain * self.fit.rmse_heldout / (1.0 - self.gain) if self.gain < 1 else float("inf")


@dataclass(frozen=True)
class Selection:
    """The verdict: the chosen effect (or none), the candidates it cannot be told from, and why."""

    baseline: Fit
    scores: tuple[Score, ...]
    """Every candidate, best held-out error first."""
    chosen: Score | None
    alternatives: tuple[Score, ...] = ()
    """Candidates the data cannot tell from the chosen one."""
    separation: tuple[str, ...] = field(default=())
    """For each alternative (and for a magnet's amplitude-decay trade-off): what would separate them."""

    @property
    def ambiguous(self) -> bool:
        return bool(self.alternatives)


def score(baseline: Fit, fit: Fit) -> Score:
    """Gain, BIC drop and pass/fail reason of ``fit`` against ``baseline``."""
    gain = 1.0 - fit.rmse_heldout / baseline.rmse_heldout if baseline.rmse_heldout > 0 else 0.0
    bic_drop = baseline.bic - fit.bic
    if fit.problem:
        verdict = f"unphysical: {fit.problem}"
    elif gain < MIN_GAIN:
        verdict = f"held-out gain {gain:.1%} below {MIN_GAIN:.0%}"
    elif bic_drop < MIN_BIC_DROP:
        verdict = f"BIC drop {bic_drop:.1f} below {MIN_BIC_DROP:g}"
    else:
        verdict = "pass"
    return Score(fit, gain, bic_drop, verdict)


def _gain_share(candidate: Score, reference: Score) -> float:
    return candidate.gain / reference.gain if reference.gain > 0 else 0.0


def select(baseline: Fit, fits: Sequence[Fit]) -> Selection:
    """Apply the rules of the module docstring to the candidates ``fits``."""
    scores = tuple(sorted((score(baseline, f) for f in fits), key=lambda s: s.fit.rmse_heldout))
    passing = [s for s in scores if s.passed]
    if not passing:
        return Selection(baseline, scores, None)
    chosen = passing[0]
    simpler = [s for s in passing if s.fit.parameters < chosen.fit.parameters and _gain_share(s, chosen) >= OCCAM]
    if simpler:
        chosen = min(simpler, key=lambda s: (s.fit.parameters, s.fit.rmse_heldout))
    alternatives = tuple(s for s in passing if s is not chosen and s.fit.parameters <= chosen.fit.parameters
                         and _gain_share(s, chosen) >= TIE)
    separation = [INDISTINGUISHABLE.get(frozenset({chosen.fit.kind, s.fit.kind}), _generic(chosen, s))
                  for s in alternatives]
    if chosen.fit.kind == "magnetic_catch":
        separation.append(MAGNET_AMBIGUITY)
    return Selection(baseline, scores, chosen, alternatives, tuple(separation))


def _generic(chosen: Score, other: Score) -> str:
    a, b = chosen.fit.family, other.fit.family
    return (f"{a.title if a else chosen.fit.kind} and {b.title if b else other.fit.kind} explain these strokes "
            f"equally well; record strokes at other speeds and positions, holds and free releases, where their "
            f"forces differ")
