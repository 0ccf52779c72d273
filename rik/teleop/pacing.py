"""Real-time pacing of a teleop loop that steps the world at the control rate and renders between steps (the
viewer window, the browser station): when a frame takes longer than a control period, the steps that came due
meanwhile run before the next frame, so a slow render drops frames instead of slowing the simulated world; after
a stall, steps missed beyond a cap are dropped, so a late frame never turns into a burst of steps (a jump)."""

from __future__ import annotations

CATCH_UP = 2
"""Control steps at most per frame in the viewer window when the loop has fallen behind real time."""


def due_steps(now: float, next_tick: float, dt: float, cap: int = CATCH_UP) -> tuple[int, float]:
    """How many control steps are due at ``now`` (s, a monotonic clock) when the next was due at ``next_tick`` and
    they come every ``dt`` s, and when the next one is due after them: at most ``cap``; steps missed beyond those
    are dropped."""
    steps = 0
    while next_tick <= now and steps < cap:
        steps += 1
        next_tick += dt
    return steps, max(next_tick, now)
