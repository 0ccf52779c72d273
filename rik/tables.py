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
