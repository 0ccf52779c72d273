"""Metadata of measured joint trajectories (``rik sysid``): what a trial is, the units its file declared, and the
settings its preprocessing ran with.

The numbers themselves (time, position, force) are numpy arrays in SI units, held by
:class:`rik.sysid.trials.Trial` and :class:`rik.sysid.preprocess.Prepared`; these models only describe them.
Units follow the joint type (see :mod:`rik.schemas.joints`): position m or rad, force N or N·m, time s.
"""

from __future__ import annotations

from typing import Annotated

from pydantic import Field

from rik.schemas.common import Frozen, Real
from rik.schemas.joints import JointType

Positive = Annotated[float, Field(gt=0, allow_inf_nan=False)]
NonNeg = Annotated[float, Field(ge=0, allow_inf_nan=False)]


class TrialUnits(Frozen):
    """The units a trial's file declared for its columns, as written (``ms``, ``mm``, ``N·mm``), before rik
    converted the values to SI."""

    time: str = Field(min_length=1)
    position: str = Field(min_length=1)
    force: str = Field(min_length=1)
    """Force (slide) or torque (hinge) unit."""
    velocity: str | None = None
    """None when the trial has no measured velocity."""


class TrialColumns(Frozen):
    """The columns (or LeRobot features) a trial's quantities were read from, as named in the file, e.g.
    ``position [mm]`` or ``observation.state[3]``: how later messages name the data at fault."""

    time: str = Field(min_length=1)
    position: str = Field(min_length=1)
    force: str = Field(min_length=1)
    velocity: str | None = None


class TrialMeta(Frozen):
    """One measured trial: a stretch of joint motion under a measured applied force or torque."""

    name: str = Field(min_length=1)
    """The value of the file's ``trial`` column, the file's stem when it has none, or ``episode_<n>`` for a
    LeRobot episode. A trial is identified by (source, name)."""
    source: str = Field(min_length=1)
    """The file the trial was read from (for a LeRobot dataset: the data Parquet file holding the episode)."""
    joint: JointType
    """``slide`` (position m, force N) or ``hinge`` (position rad, torque N·m)."""
    units: TrialUnits
    columns: TrialColumns
    samples: int = Field(ge=1)
    """Number of samples (rows) in the trial."""
    duration: NonNeg
    """Time from the first to the last sample, s."""


class PreprocessSettings(Frozen):
    """The settings a trial was preprocessed with, all resolved (no defaults left open); SI units of the joint:
    position m or rad, velocity m/s or rad/s, force N or N·m."""

    rate_hz: Positive
    """Uniform sample rate after resampling, Hz."""
    window_s: Positive
    """Savitzky–Golay window asked for, s."""
    window_samples: int = Field(ge=3)
    """The window used: ``window_s`` at ``rate_hz`` rounded to an odd number of samples, at least
    ``polyorder + 1``."""
    polyorder: int = Field(ge=2, le=6)
    """Savitzky–Golay polynomial order (≥ 2, so that the acceleration is defined)."""
    delay_s: Real
    """Delay applied between force and position, s: positive when the position is recorded later than the force
    (the force at time t is paired with the position at t + delay)."""
    delay_estimated: bool
    """Whether ``delay_s`` was estimated from the data (else it was given)."""
    max_delay_s: NonNeg
    """Half-width of the lag grid the delay was searched over, s."""
    moving_velocity: Positive
    """|velocity| at or above which a sample counts as moving, m/s or rad/s."""
    sticking_force: Positive
    """|force| at or above which a sample that is not moving counts as sticking, N or N·m."""
    limit_margin: NonNeg
    """Distance from a position limit within which a sample counts as near the limit, m or rad."""
    limits: tuple[Real, Real]
    """The (lower, upper) position limits the ``near_limit`` mask used, m or rad: given, or the trial's observed
    minimum and maximum (smoothed) position."""
    limits_observed: bool
    """Whether ``limits`` are the trial's observed extremes (else they were given)."""
