"""Small helpers both generators of measured data share (rik's and the foreign one): the joint type from a name,
and uniform and log-uniform draws from a (low, high) range."""

from __future__ import annotations

import math

import numpy as np

from rik.errors import RikError
from rik.schemas.joints import JointType


def joint_type(joint: JointType | str) -> JointType:
    """``joint`` as a :class:`JointType`; a one-line error for anything else."""
    try:
        return JointType(joint)
    except ValueError:
        raise RikError(f"joint '{joint}' is not a joint type; use 'slide' or 'hinge'") from None


def uniform(rng: np.random.Generator, bounds: tuple[float, float]) -> float:
    """A uniform draw from ``bounds`` (low, high)."""
    return float(rng.uniform(*bounds))


def log_uniform(rng: np.random.Generator, bounds: tuple[float, float]) -> float:
    """A draw uniform in log from ``bounds`` (low, high), both positive."""
    return float(math.exp(rng.uniform(math.log(bounds[0]), math.log(bounds[1]))))
