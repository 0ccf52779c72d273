"""Breakaway from rest: the force at which a resting front starts to move, found in each trial.

A start of motion from rest says what the moving samples cannot: the *static* resistance at that position and
in that direction. Stiction shows as breakaway above the sliding friction everywhere; a magnetic catch as
breakaway that grows sharply near closed; both can hide from an equation-error fit on moving samples (stiction
below the velocity noise floor, a catch within a millimetre of the stop whose samples are left out). Creeps at
constant slow speed are the best source: the force builds slowly, and the peak before the front gets going is
the breakaway force.

:func:`find_breakaways` scans the smoothed position of a preprocessed trial (SI: m or rad, N or N·m, s):

1. **rest**: a run of at least :data:`REST_S` during which the position stays within :func:`rest_band` of the
   run's first sample;
2. **departure**: the first sample after it more than ``2 × band`` from the rest position (or, resting on a
   range end, beyond :data:`~rik.sysid.preprocess.CONTACT_MARGIN` of it, so a stop's compliance springing back is
   not a start), followed by at least :data:`CONFIRM` further travel in the same direction within
   :data:`CONFIRM_S`: a real start, not presliding or noise;
3. **breakaway force**: the largest smoothed force in the direction of motion between the last time it pushed
   the other way (a hand letting off a push on the stop) and the departure, within :data:`LOOKBACK_S`;
4. **kept** only when the force rose slowly to that peak (it was within :data:`SLOW_RISE` of it
   :data:`RISE_S` earlier, or within three force-noise deviations): then the peak is the static threshold, not a
   force that overshot it while the position caught up; and not when the hand was off (the force near 0: a
   released front that drifts is moved by the joint's own forces, which the moving samples already show).

Each kept event becomes a row of the equation-error fit (:func:`rik.sysid.fit.all_rows`), at its position, with
the velocity an infinitesimal step in its direction and the filtered acceleration there (the force a hand puts
past the threshold while the position catches up accelerates the front: with the acceleration left out, doors
with nothing hidden came out with twice their friction): every law is evaluated at rest, so a model's static
resistance is compared with the measured breakaway.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rik.schemas.joints import JointType
from rik.sysid.preprocess import CONTACT_MARGIN, Prepared, smoothing_noise

REST_S = 0.15
"""Shortest rest before a start counts, s."""
REST_BAND = {JointType.slide: 1e-4, JointType.hinge: math.radians(0.05)}
"""Smallest half-width of the rest band, m or rad (raised to three times the smoothed position's noise)."""
CONFIRM = {JointType.slide: 1.5e-3, JointType.hinge: math.radians(0.4)}
"""Travel after the departure that confirms a start, m or rad."""
CONFIRM_S = 0.6
"""Time within which that travel must happen, s."""
LOOKBACK_S = 1.0
"""How far before the departure the peak force is looked for, s."""
RISE_S = 0.05
"""Interval of the slow-rise check, s."""
SLOW_RISE = 0.15
"""Largest share of the breakaway force it may have risen by in the last :data:`RISE_S` before the peak."""
STEP = 1e-9
"""The velocity of a breakaway row: an infinitesimal step in its direction, m/s or rad/s."""


@dataclass(frozen=True)
class Breakaway:
    """One start of motion from rest (SI units of the joint)."""

    t: float
    """Time of the peak force, s."""
    q: float
    """Position at the peak force, m or rad."""
    direction: int
    """+1 opening, -1 closing."""
    force: float
    """The applied force at breakaway, signed, N or N·m."""
    index: int
    """Sample index of the peak force in the trial."""
    qdd: float
    """Acceleration there, m/s² or rad/s² (the force past the threshold starts to accelerate the front)."""
    from_stop: bool
    """Whether the front rested on a range end."""


def rest_band(p: Prepared) -> float:
    """Half-width of the rest band, m or rad: :data:`REST_BAND`, or three times the noise left on the smoothed
    position (:func:`rik.sysid.preprocess.smoothing_noise`), if higher."""
    return max(REST_BAND[p.trial.joint], 3.0 * smoothing_noise(p.q_raw, p.q, p.settings)[1])


def force_noise(p: Prepared) -> float:
    """Standard deviation of the noise on the smoothed force, N or N·m (from what smoothing removed)."""
    return smoothing_noise(p.f, p.f_smooth, p.settings)[1]


def _rests(q: np.ndarray, band: float, shortest: int) -> list[tuple[int, int]]:
    """(first, last + 1) of each run of at least ``shortest`` samples within ``band`` of its first sample."""
    runs, i, n = [], 0, len(q)
    while i < n:
        j = i + 1
        while j < n and abs(q[j] - q[i]) <= band:
            j += 1
        if j - i >= shortest:
            runs.append((i, j))
            i = j
        else:
            i += 1
    return runs


def find_breakaways(p: Prepared, limits: tuple[float, float]) -> list[Breakaway]:
    """The kept starts of motion from rest of one trial (module docstring); ``limits`` the range's observed ends,
    m or rad."""
    joint = p.trial.joint
    q, f, qdd = p.q, p.f_smooth, p.qdd
    rate = p.settings.rate_hz
    band = rest_band(p)
    sigma_f = force_noise(p)
    stop = CONTACT_MARGIN[joint]
    confirm_n = int(round(CONFIRM_S * rate))
    lookback = int(round(LOOKBACK_S * rate))
    rise = max(int(round(RISE_S * rate)), 1)
    events: list[Breakaway] = []
    for first, end in _rests(q, band, max(int(round(REST_S * rate)), 2)):
        rest = float(np.median(q[first:end]))
        on_lower, on_upper = rest <= limits[0] + stop, rest >= limits[1] - stop
        depart = end
        while depart < len(q) and depart - end <= lookback:
            if on_lower:
                beyond = q[depart] > limits[0] + stop
            elif on_upper:
                beyond = q[depart] < limits[1] - stop
            else:
                beyond = abs(q[depart] - rest) > 2.0 * band
            if beyond:
                break
            depart += 1
        else:
            continue
        direction = 1 if q[depart] > rest else -1
        ahead = q[depart:depart + confirm_n] - q[depart]
        if len(ahead) == 0 or float(np.max(direction * ahead)) < CONFIRM[joint]:
            continue
        start = max(first, depart - lookback)
        pushing = direction * f[start:depart + 1]
        against = np.nonzero(pushing < 0)[0]
        if len(against):
            start += int(against[-1]) + 1
        if start > depart:
            continue
        peak = start + int(np.argmax(direction * f[start:depart + 1]))
        force = float(f[peak])
        if direction * force <= 3.0 * sigma_f:  # the hand was off: a drift, not a breakaway
            continue
        before = float(direction * f[max(peak - rise, 0)])
        if direction * force - before > max(SLOW_RISE * direction * force, 3.0 * sigma_f):
            continue
        if events and events[-1].index == peak:  # the same start seen from two rests (a push, then let off)
            continue
        events.append(Breakaway(float(p.t[peak]), float(q[peak]), direction, force, peak, float(qdd[peak]),
                                on_lower or on_upper))
    return events


CREEP_SPAN_S = 0.2
"""Half-span of the long difference that gives a creep's speed, s."""
CREEP_SIGMAS = 6.0
"""A sample creeps when its long-difference speed exceeds this many noise deviations of that speed."""


def creeping(p: Prepared, velocity: float) -> tuple[np.ndarray, np.ndarray]:
    """Samples moving slower than ``velocity`` (the fit's floor, m/s or rad/s; by the filtered velocity and by the
    long difference) whose motion the long difference still resolves: (mask, speed). The speed is
    ``(q[i + L] − q[i − L]) / (2·L·dt)`` over :data:`CREEP_SPAN_S`, kept where it exceeds :data:`CREEP_SIGMAS` of
    its noise and the front moves the same way, by similar distances (within a factor of 2), over both halves of the
    span (a creep at constant slow speed, not the turn of a stroke, a start or a stop). The caller leaves out
    creeps next to a stop (a front let go on a compliant stop creeps off it unforced)."""
    q = p.q
    n = len(q)
    span = max(int(round(CREEP_SPAN_S * p.settings.rate_hz)), 1)
    speed = np.zeros(n)
    mask = np.zeros(n, bool)
    if n <= 2 * span:
        return mask, speed
    band = rest_band(p) / 3.0  # the smoothed position's noise
    i = np.arange(span, n - span)
    ahead, behind = q[i + span] - q[i], q[i] - q[i - span]
    speed[i] = (ahead + behind) / (2 * span * p.dt)
    noise = math.sqrt(2.0) * band / (2 * span * p.dt)
    low, high = np.minimum(np.abs(ahead), np.abs(behind)), np.maximum(np.abs(ahead), np.abs(behind))
    same = (np.sign(ahead) == np.sign(behind)) & (low > 2.0 * band) & (low >= 0.5 * high)  # steady, not a start
    slow = (np.abs(speed[i]) < velocity) & (np.abs(p.qd[i]) < velocity)
    mask[i] = same & slow & (np.abs(speed[i]) > CREEP_SIGMAS * noise)
    return mask, speed
