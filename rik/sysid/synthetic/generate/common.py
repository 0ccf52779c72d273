"""Argument checks shared by the generator's modules (one-line :class:`~rik.errors.RikError`); its random draws are
in :mod:`rik.sysid.synthetic.draws`, shared with the foreign generator."""

from __future__ import annotations

import math

from rik.errors import RikError


def _positive(**values: float) -> None:
    for name, value in values.items():
        if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
            raise RikError(f"{name} must be a finite number > 0, got {value!r}")


def _non_negative(**values: float | None) -> None:
    for name, value in values.items():
        if value is not None and not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0):
            raise RikError(f"{name} must be a finite number ≥ 0, got {value!r}")
