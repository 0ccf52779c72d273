"""Helpers shared by the generator's modules: argument checks (one-line :class:`~rik.errors.RikError`) and random
draws."""

from __future__ import annotations

import math

import numpy as np

from rik.errors import RikError
from rik.schemas.joints import JointType
from rik.sysid.generate.constants import Range


def _joint(joint: JointType | str) -> JointType:
    try:
        return JointType(joint)
    except ValueError:
        raise RikError(f"joint '{joint}' is not a joint type; use 'slide' or 'hinge'") from None



def _uniform(rng: np.random.Generator, bounds: Range) -> float:
    return float(rng.uniform(*bounds))


def _log_uniform(rng: np.random.Generator, bounds: Range) -> float:
    return float(math.exp(rng.uniform(math.log(bounds[0]), math.log(bounds[1]))))



def _positive(**values: float) -> None:
    for name, value in values.items():
        if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
            raise RikError(f"{name} must be a finite number > 0, got {value!r}")


def _non_negative(**values: float | None) -> None:
    for name, value in values.items():
        if value is not None and not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0):
            raise RikError(f"{name} must be a finite number ≥ 0, got {value!r}")
