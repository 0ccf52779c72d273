"""Small helpers both generators of measured data share (rik's and the foreign one): the joint type from a name,
uniform and log-uniform draws from a (low, high) range, and the phase of a door's tilt."""

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


def tilt_phase(rng: np.random.Generator, share: float = 0.3) -> float:
    """A phase, rad, uniform over the turn but redrawn until both its cosine and its sine are at least ``share`` in
    size: a door's tilt ``cos φ + sin φ·sin q`` with both parts identifiable."""
    while True:
        phase = float(rng.uniform(0.0, 2 * math.pi))
        if min(abs(math.cos(phase)), abs(math.sin(phase))) >= share:
            return phase
