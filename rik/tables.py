"""The tables of outcomes that ``rik bench`` and ``rik eval`` both write: F/P/S per handle type, strategy (or
policy) and preset (the paper's Table 3, :func:`table_markdown`), the Wilson interval of a success rate, and the
rows as CSV."""

from __future__ import annotations

import csv
import io
import math
from collections import Counter
from collections.abc import Sequence
from typing import Any

from rik.episodes.draw import DEFAULT_PRESETS
from rik.sim.outcome import OUTCOMES


def summarise(rows: Sequence[dict[str, Any]], by: Sequence[str] = ("handle_type", "strategy", "preset")
              ) -> dict[tuple, dict[str, float]]:
    """F/P/S fractions (and the count ``n``) per group."""
    groups: dict[tuple, Counter] = {}
    for r in rows:
        groups.setdefault(tuple(r[k] for k in by), Counter())[r["outcome"]] += 1
    out = {}
    for key, c in sorted(groups.items()):
        n = sum(c.values())
        out[key] = {"n": n, **{o: c[o] / n for o in OUTCOMES}}
    return out


def wilson(successes: int, n: int, z: float = 1.96) -> tuple[float, float]:
    """The Wilson score interval of a success rate (95 % for ``z`` = 1.96): (low, high), fractions."""
    if n == 0:
        return 0.0, 1.0
    p = successes / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return max(0.0, float(centre - half)), min(1.0, float(centre + half))


def rate_text(successes: int, n: int, between: str = " of ") -> str:
    """``successes`` of ``n`` with the rate and its 95 % Wilson interval: ``21 of 90: 23% [16%, 33%]`` (``between``
    "/" gives ``21/90: ...``)."""
    low, high = wilson(successes, n)
    return f"{successes}{between}{n}: {successes / n:.0%} [{low:.0%}, {high:.0%}]"


def newcombe(s1: int, n1: int, s2: int, n2: int, z: float = 1.96) -> tuple[float, float]:
    """Newcombe's hybrid score interval (his method 10, 1998) of the difference of two independent success rates,
    ``s1 / n1 - s2 / n2``: (low, high), fractions; built from each rate's :func:`wilson` interval."""
    p1, p2 = s1 / n1, s2 / n2
    l1, u1 = wilson(s1, n1, z)
    l2, u2 = wilson(s2, n2, z)
    low = p1 - p2 - math.sqrt((p1 - l1) ** 2 + (u2 - p2) ** 2)
    high = p1 - p2 + math.sqrt((u1 - p1) ** 2 + (p2 - l2) ** 2)
    return max(-1.0, low), min(1.0, high)


def seed_handle_interval(success: Sequence[Sequence[bool]], handles: Sequence[str], resamples: int = 10_000,
                         seed: int = 0) -> tuple[float, float]:
    """A 95 % interval of a pooled success rate over training seeds and handles: ``success[s][e]`` is episode ``e``
    of training seed ``s`` (every seed on the same episodes), ``handles[e]`` its handle. Each resample draws the
    seeds with replacement and the handles with replacement (each with all its episodes); (low, high) are the
    2.5 and 97.5 percentiles of the resampled rates, fractions. Deterministic for a ``seed``."""
    import numpy as np

    table = np.asarray(success, dtype=float)
    names = sorted(set(handles))
    of_handle = [np.flatnonzero(np.asarray(handles) == name) for name in names]
    rng = np.random.default_rng(seed)
    rates = np.empty(resamples)
    for i in range(resamples):
        seeds = rng.integers(table.shape[0], size=table.shape[0])
        drawn = np.concatenate([of_handle[h] for h in rng.integers(len(names), size=len(names))])
        rates[i] = table[seeds][:, drawn].mean()
    low, high = np.percentile(rates, [2.5, 97.5])
    return float(low), float(high)


MEASURED_COLUMN = "measured"
"""The column of episodes whose door had a real door's hinge (``--joints measured``): their presets are many, one
per door; ``episodes.csv`` and ``results.csv`` keep each door's."""


def joint_columns(rows: Sequence[dict[str, Any]], presets: Sequence[str]) -> list[dict[str, Any]]:
    """``rows`` with each ``preset`` outside ``presets`` (a real door's) replaced by :data:`MEASURED_COLUMN`."""
    return [r if r["preset"] in presets else {**r, "preset": MEASURED_COLUMN} for r in rows]


def table_markdown(rows: Sequence[dict[str, Any]], presets: Sequence[str] = DEFAULT_PRESETS, *,
                   ci: bool = False) -> str:
    """Table 3 of the paper, rik's version: per handle type, one row per strategy (scripted, or a learned policy
    in ``rik eval``'s rows), F/P/S per preset, the episodes on real doors' hinges in one :data:`MEASURED_COLUMN`
    after them (:func:`joint_columns`); with ``ci`` the S cell also gives its 95 % Wilson interval."""
    rows = joint_columns(rows, presets)
    presets = [*presets, MEASURED_COLUMN]
    summary = summarise(rows)
    types = list(dict.fromkeys(r["handle_type"] for r in rows))
    strategies = list(dict.fromkeys(r["strategy"] for r in rows))
    presets = [p for p in presets if any(r["preset"] == p for r in rows)]
    lines = []
    for t in types:
        lines += [f"**{t}**", "", "| strategy | " + " | ".join(f"{p} F | {p} P | {p} S" for p in presets) + " | n |",
                  "|---|" + "---:|" * (3 * len(presets) + 1)]
        for s in strategies:
            cells: list[str] = []
            n = 0
            for p in presets:
                v = summary.get((t, s, p))
                if not v:
                    cells += ["-"] * 3
                    continue
                cells += [f"{v[o]:.2f}" for o in OUTCOMES]
                if ci:
                    lo, hi = wilson(round(v["S"] * v["n"]), int(v["n"]))
                    cells[-1] += f" [{lo:.2f}, {hi:.2f}]"
                n = max(n, int(v["n"]))
            lines.append(f"| {s} | " + " | ".join(cells) + f" | {n} |")
        lines.append("")
    return "\n".join(lines)


def rows_csv(rows: Sequence[dict[str, Any]]) -> str:
    """``rows`` as CSV: the union of their fields, in order, as the header."""
    buf = io.StringIO()
    if rows:  # the union of the rows' fields, in order: an operator's rows may carry fields another's lack
        w = csv.DictWriter(buf, fieldnames=list(dict.fromkeys(k for r in rows for k in r)), restval="",
                           lineterminator="\n")
        w.writeheader()
        w.writerows(rows)
    return buf.getvalue()
