"""The outcome of an episode, defined once: F (fail), P (partial), S (success), from how far the front opened.

- **S**: the front ended at least 90% open (a fraction of its joint range);
- **P**: it ended at least 5% open but short of 90%: the grasp slipped or the pull stalled on the way;
- **F**: it ended less than 5% open: no meaningful progress.
"""

from __future__ import annotations

SUCCESS_OPENING = 0.90
PARTIAL_OPENING = 0.05
OUTCOMES = ("F", "P", "S")


def classify(opening: float) -> str:
    """``S``, ``P`` or ``F`` for a final opening given as a fraction of the front's range."""
    if opening >= SUCCESS_OPENING:
        return "S"
    if opening >= PARTIAL_OPENING:
        return "P"
    return "F"
