"""rik.scheduling: SVT-AV1 (LeRobot's default codec) leaves the thread that encodes at real-time priority when run
as root; rik's encoding calls give it back its normal scheduling. With the real encoder (PyAV's libsvtav1)."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from rik.scheduling import normal_scheduling

ENCODE = """
import os, numpy as np, av
def encode(path):
    c = av.open(path, "w"); s = c.add_stream("libsvtav1", rate=20); s.width = s.height = 64; s.pix_fmt = "yuv420p"
    for i in range(4):
        for p in s.encode(av.VideoFrame.from_ndarray(np.full((64, 64, 3), 40 * i, np.uint8), format="rgb24")):
            c.mux(p)
    for p in s.encode():
        c.mux(p)
    c.close()
"""


def _policy_after(tmp_path, guarded: bool) -> int:
    code = ENCODE + ("from rik.scheduling import normal_scheduling\nwith normal_scheduling():\n    " if guarded
                     else "") + f"encode({str(tmp_path / 'v.mp4')!r})\nprint(os.sched_getscheduler(0))\n"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=True)
    return int(out.stdout.split()[-1])


@pytest.mark.skipif(not hasattr(os, "sched_getscheduler"), reason="Linux scheduling only")
def test_an_encode_leaves_normal_scheduling_behind_it(tmp_path) -> None:
    if os.geteuid() == 0:  # what the guard is for: as root, SVT-AV1 raises the encoding thread to SCHED_FIFO
        assert _policy_after(tmp_path, guarded=False) == os.SCHED_FIFO
    assert _policy_after(tmp_path, guarded=True) == os.SCHED_OTHER


def test_the_guard_restores_a_policy_changed_inside_it() -> None:
    before = os.sched_getscheduler(0), os.sched_getparam(0)
    with normal_scheduling():
        os.sched_setscheduler(0, os.SCHED_BATCH, os.sched_param(0))  # allowed without privileges
        assert os.sched_getscheduler(0) == os.SCHED_BATCH
    assert (os.sched_getscheduler(0), os.sched_getparam(0)) == before
