"""The hand's excitation plans: strokes, slow strokes, holds, throws and releases."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np

from rik.schemas.joints import JointType
from rik.sysid.synthetic.draws import joint_type as _joint
from rik.sysid.synthetic.draws import log_uniform as _log_uniform
from rik.sysid.synthetic.draws import uniform as _uniform
from rik.sysid.synthetic.generate.constants import BLOCK_MOVE_TIME, EXCITE, MOVE_TIME, SLOW_RAMP

SegmentKind = Literal["move", "slow", "creep", "hold", "release", "throw"]


@dataclass(frozen=True)
class Segment:
    """One step of an excitation plan (m, m/s or rad, rad/s; s).

    - ``move``: minimum-jerk stroke from the current target (or, after a release, the position) to ``goal`` at
      peak speed ``speed``, lasting 1.875 |Δ| / speed clipped to ``duration`` (its longest) and 0.25 s;
    - ``slow``: constant-speed stroke at ``speed`` to ``goal`` with 0.2 s smooth ramps;
    - ``creep``: a ``slow`` stroke from the position (not the target: a hand pressing the front on a stop lets
      off first) with a :data:`CREEP_STIFFNESS` times stiffer hand: the force builds slowly from rest until the
      front breaks away, then it follows at constant speed;
    - ``hold``: target fixed for ``duration``;
    - ``release``: hand force exactly 0 for ``duration``;
    - ``throw``: a closing minimum-jerk stroke at peak ``speed`` whose midpoint is ``goal`` (so its end is past
      closed), cut when the position reaches ``goal``; a following ``release`` lets the front go."""

    kind: SegmentKind
    goal: float = 0.0
    speed: float = 0.0
    duration: float = 0.0


@dataclass(frozen=True)
class ExcitationPlan:
    """Where a trial starts (m or rad, at rest) and what the hand does."""

    start: float
    segments: tuple[Segment, ...]

    def nominal_duration(self) -> float:
        """Duration of the plan, s, were every target reached (a let-go front taken to stop at closed)."""
        total, at = 0.0, self.start
        for seg in self.segments:
            if seg.kind == "move":
                total += _move_time(abs(seg.goal - at), seg.speed, seg.duration)
                at = seg.goal
            elif seg.kind in ("slow", "creep"):
                total += abs(seg.goal - (0.0 if seg.kind == "creep" and at < 0 else at)) / seg.speed + SLOW_RAMP
                at = seg.goal
            elif seg.kind == "throw":
                total += _move_time(2 * abs(seg.goal - at), seg.speed, math.inf) / 2 + 0.2  # + the lag
                at = 0.0
            else:
                total += seg.duration
        return total


def _move_time(distance: float, speed: float, longest: float) -> float:
    return min(max(1.875 * distance / speed, MOVE_TIME[0]), max(longest, MOVE_TIME[0]))


def excitation_plan(joint: JointType | str, upper: float, rng: np.random.Generator, *, duration_s: float = 12.0,
                    start: float | None = None) -> ExcitationPlan:
    """A random excitation for a joint with range (0, ``upper``) (m or rad) filling ``duration_s`` s: in random
    order a push held against the closed stop then a creep open from rest there, a push towards closed let go
    near closed, a hold and release from rest at mid-range, a hold then a slow stroke, a push held against the far
    stop; then
    strokes of random speed (and short holds) to the end. The required blocks are redrawn (up to 50 times) until
    they fit ``duration_s`` - 0.5 s nominally: always at 12 s, about 97 % at 10 s; shorter trials lose the last
    blocks. ``start`` (default: closed or a random position) is where the front rests at t = 0."""
    joint = _joint(joint)
    x = EXCITE[joint]
    u = float(upper)
    best: ExcitationPlan | None = None
    for _ in range(50):
        if start is None:
            begin = 0.0 if rng.random() < 0.4 else _uniform(rng, (0.1 * u, 0.6 * u))
        else:
            begin = start

        def move(lo: float, hi: float) -> Segment:
            return Segment("move", _uniform(rng, (lo * u, hi * u)), _log_uniform(rng, x.block_speed), BLOCK_MOVE_TIME)

        slow_speed = _uniform(rng, x.slow)
        slow_from = _uniform(rng, (0.25 * u, 0.75 * u))
        slow_length = slow_speed * _uniform(rng, (1.2, 2.0))
        slow_to = slow_from + (slow_length if rng.random() < 0.5 else -slow_length)
        blocks = [
            [Segment("move", -_uniform(rng, x.push), _log_uniform(rng, x.block_speed), BLOCK_MOVE_TIME),
             Segment("hold", duration=_uniform(rng, (0.5, 1.0))),
             Segment("creep", _uniform(rng, x.creep_length), _uniform(rng, x.creep))],
            [move(0.2, 0.45), Segment("throw", _uniform(rng, x.near_closed), _uniform(rng, x.throw)),
             Segment("release", duration=_uniform(rng, (0.5, 0.8)))],
            [move(0.3, 0.7), Segment("hold", duration=_uniform(rng, (0.6, 0.9))),
             Segment("release", duration=_uniform(rng, (0.5, 0.8)))],
            [Segment("move", slow_from, _log_uniform(rng, x.block_speed), BLOCK_MOVE_TIME),
             Segment("hold", duration=0.3), Segment("slow", slow_to, slow_speed)],
            [Segment("move", u + _uniform(rng, x.push), _log_uniform(rng, x.block_speed), BLOCK_MOVE_TIME),
             Segment("hold", duration=_uniform(rng, (0.5, 0.8)))],
        ]
        order = rng.permutation(len(blocks))
        plan = ExcitationPlan(begin, tuple(seg for i in order for seg in blocks[i]))
        if best is None or plan.nominal_duration() < best.nominal_duration():
            best = plan
        if plan.nominal_duration() <= duration_s - 0.5:
            break
    assert best is not None
    segments = list(best.segments)
    while ExcitationPlan(best.start, tuple(segments)).nominal_duration() < duration_s + 1.0:
        segments.append(Segment("move", _uniform(rng, (0.05 * u, 0.95 * u)), _log_uniform(rng, x.speed),
                                MOVE_TIME[1]))
        if rng.random() < 0.3:
            segments.append(Segment("hold", duration=_uniform(rng, (0.3, 0.6))))
    return ExcitationPlan(best.start, tuple(segments))


def _min_jerk(a: float, b: float, n: int, total: int, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Steps 1..n of a minimum-jerk profile from ``a`` to ``b`` over ``total`` steps: (target, target velocity)."""
    s = np.arange(1, n + 1) / total
    shape = s**3 * (10.0 - 15.0 * s + 6.0 * s**2)
    rate = 30.0 * s**2 * (1.0 - s) ** 2
    return a + (b - a) * shape, (b - a) * rate / (total * dt)


def _profile(seg: Segment, at: float, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """(target, target velocity) per fine step of a hand segment starting at target ``at``."""
    if seg.kind == "hold":
        n = max(int(round(seg.duration / dt)), 1)
        return np.full(n, at), np.zeros(n)
    if seg.kind == "move":
        n = max(int(round(_move_time(abs(seg.goal - at), seg.speed, seg.duration) / dt)), 1)
        return _min_jerk(at, seg.goal, n, n, dt)
    if seg.kind == "throw":
        end = seg.goal + (seg.goal - at)
        total = max(int(round(_move_time(abs(end - at), seg.speed, math.inf) / dt)), 2)
        return _min_jerk(at, end, total, total, dt)
    if seg.kind in ("slow", "creep"):
        distance = abs(seg.goal - at)
        n = max(int(round((distance / seg.speed + SLOW_RAMP) / dt)), 2)
        t = (np.arange(n) + 0.5) * dt
        w = np.minimum(np.clip(t / SLOW_RAMP, 0.0, 1.0), np.clip((n * dt - t) / SLOW_RAMP, 0.0, 1.0))
        w = 0.5 * (1.0 - np.cos(np.pi * w))
        vel = np.sign(seg.goal - at) * w
        path = np.cumsum(vel) * dt
        scale = (seg.goal - at) / path[-1] if path[-1] != 0.0 else 0.0
        return at + path * scale, vel * scale
    raise AssertionError(seg.kind)  # pragma: no cover
