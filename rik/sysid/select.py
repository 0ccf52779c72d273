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

Then a second effect (real soft-close runners pair a damper with a pull-in spring): pairs of effects, the first
any candidate of the first round that helped (its fitted shape kept), the second any other family (not one the
data cannot tell from the first: they would model the same force twice), are fitted. A pair passes the same
three tests against the chosen single effect (or the baseline, when none passed) and must also beat each of its
members fitted alone by :data:`MIN_GAIN`, so that both effects earn their place; the best passing pair replaces
the single effect, with the same preference for fewer parameters and the same statement of pairs it cannot be
told from. Searching pairs, not only additions to the first round's winner, matters: a constant force can win
the first round by absorbing half of a self-closing spring and a quadratic damper together, and a damper and a
spring that act in the same zone can each look unphysical alone.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, replace

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
    pair: Score | None = None
    """The chosen pair of effects, scored against the chosen single effect; None when no pair passes."""
    pairs: tuple[Score, ...] = ()
    """Every pair tried, best held-out error first."""
    pair_alternatives: tuple[Score, ...] = ()
    """Pairs the data cannot tell from the chosen pair."""

    @property
    def found(self) -> bool:
        """Whether any effect was chosen (alone or in a pair)."""
        return self.chosen is not None or self.pair is not None

    @property
    def final(self) -> Fit:
        """The selected model: the baseline with every chosen effect."""
        if self.pair:
            return self.pair.fit
        return self.chosen.fit if self.chosen else self.baseline

    @property
    def gain(self) -> float:
        """Relative drop of the held-out force RMSE from the baseline to :attr:`final`."""
        b = self.baseline.rmse_heldout
        return 1.0 - self.final.rmse_heldout / b if b > 0 else 0.0




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
    chosen, alternatives = _pick(scores)
    if chosen is None:
        return Selection(baseline, scores, None)
    separation = [_separation(chosen, s) for s in alternatives]
    if chosen.fit.kind == "magnetic_catch":
        separation.append(MAGNET_AMBIGUITY)
    return Selection(baseline, scores, chosen, alternatives, tuple(separation))


def _pick(scores: Sequence[Score]) -> tuple[Score | None, tuple[Score, ...]]:
    """The passing score with the lowest held-out error (or a simpler one with :data:`OCCAM` of its gain), and the
    passing ones within :data:`TIE` of its gain with no more parameters."""
    passing = [s for s in scores if s.passed]
    if not passing:
        return None, ()
    chosen = passing[0]
    simpler = [s for s in passing if s.fit.parameters < chosen.fit.parameters and _gain_share(s, chosen) >= OCCAM]
    if simpler:
        chosen = min(simpler, key=lambda s: (s.fit.parameters, s.fit.rmse_heldout))
    return chosen, tuple(s for s in passing if s is not chosen and s.fit.parameters <= chosen.fit.parameters
                         and _gain_share(s, chosen) >= TIE)


def _separation(chosen: Score, other: Score) -> str:
    """What would tell ``other``'s model from ``chosen``'s: the text for the effects in which they differ."""
    mine, theirs = set(chosen.fit.kinds) - set(other.fit.kinds), set(other.fit.kinds) - set(chosen.fit.kinds)
    if len(mine) == 1 and len(theirs) == 1:
        known = INDISTINGUISHABLE.get(frozenset(mine | theirs))
        if known:
            return known
    return _generic(chosen, other)


def pair_allowed(first: str, second: str) -> bool:
    """Whether two effects may be fitted together: different, and not a pair the data cannot tell apart."""
    return first != second and frozenset({first, second}) not in INDISTINGUISHABLE


def pair_score(reference: Fit, singles: dict[str, Fit], fit: Fit) -> Score:
    """:func:`score` of a two-effect ``fit`` against ``reference``, failing it unless it also beats each of its
    members fitted alone (``singles``, by kind) by :data:`MIN_GAIN` on held-out data."""
    result = score(reference, fit)
    if not result.passed:
        return result
    for kind in fit.kinds:
        alone = singles[kind].rmse_heldout
        gain = 1.0 - fit.rmse_heldout / alone if alone > 0 else 0.0
        if gain < MIN_GAIN:
            return replace(result, verdict=f"held-out gain over {singles[kind].title} alone {gain:.1%} "
                                           f"below {MIN_GAIN:.0%}")
    return result


def select_pair(selection: Selection, fits: Sequence[Fit]) -> Selection:
    """The second round: ``fits`` are models with two effects; the best passing one (module docstring) becomes
    the selection's final model. Pairs of the same two kinds count once (the lower held-out error)."""
    best: dict[frozenset[str], Fit] = {}
    for f in fits:
        key = frozenset(f.kinds)
        if key not in best or f.rmse_heldout < best[key].rmse_heldout:
            best[key] = f
    reference = selection.chosen.fit if selection.chosen else selection.baseline
    singles = {s.fit.kind: s.fit for s in selection.scores}
    scores = tuple(sorted((pair_score(reference, singles, f) for f in best.values()),
                          key=lambda s: s.fit.rmse_heldout))
    chosen, alternatives = _pick(scores)
    if chosen is None:
        return replace(selection, pairs=scores)
    separation = (*selection.separation, *(_separation(chosen, s) for s in alternatives))
    if "magnetic_catch" in chosen.fit.kinds and MAGNET_AMBIGUITY not in separation:
        separation = (*separation, MAGNET_AMBIGUITY)
    return replace(selection, pair=chosen, pairs=scores, pair_alternatives=alternatives, separation=separation)


def _generic(chosen: Score, other: Score) -> str:
    def title(fit: Fit) -> str:
        return " + ".join(f.title for f, _ in fit.terms) or fit.kind

    return (f"{title(chosen.fit)} and {title(other.fit)} explain these strokes equally well; record strokes at "
            f"other speeds and positions, holds and free releases, where their forces differ")
