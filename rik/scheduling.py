"""Keeping rik's threads at normal scheduling when a library raises them to real time.

SVT-AV1 (``libsvtav1``, LeRobot's default video codec, in PyAV) sets the thread that encodes to ``SCHED_FIFO`` at
priority 99 when the process runs as root, and leaves it so. Every thread and process started from that thread
afterwards inherits it: a browser started after an export (the web app's tests, a user's script) then ran its
spinning helper processes at real-time priority and starved the machine (measured: two Chromium zygotes at 94 %
of both cores each, SIGKILL left pending for seconds). :func:`normal_scheduling` puts the calling thread's policy
back after a block that encodes video.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from contextlib import contextmanager


@contextmanager
def normal_scheduling() -> Iterator[None]:
    """Run the block, then give the calling thread back the scheduling policy and priority it had before it (when
    the platform has them: Linux)."""
    if not hasattr(os, "sched_getscheduler"):  # pragma: no cover - not Linux
        yield
        return
    policy, param = os.sched_getscheduler(0), os.sched_getparam(0)
    try:
        yield
    finally:
        if os.sched_getscheduler(0) != policy or os.sched_getparam(0) != param:
            os.sched_setscheduler(0, policy, param)
