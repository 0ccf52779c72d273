#!/usr/bin/env bash
# README command 2: set everything up (a no-op when done), then run the test suite: pytest-xdist workers, one per
# core and one more (RIK_TEST_WORKERS=N for another number, 0 for none), each test file on one worker (their module
# fixtures are built once), the slowest tests listed at the end. Extra arguments go to pytest: `-m "not slow"` is the
# everyday tier, a file or `-k NAME` picks tests.
# The extra worker: about a tenth of the suite's worker time waits on real time (a browser or an X window driven at a
# person's pace, a Ray cluster starting), which leaves a core idle; on 2 cores the whole suite took 486-507 s with 2
# workers and 470 s with 3, the cores 98 % busy (2026-11-27).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
source "$root/scripts/setup.sh"
# Bytecode: the workers and the commands the tests start import the same modules; where PYTHONDONTWRITEBYTECODE is
# set each of them compiled rik's modules again and pytest rewrote every test file's asserts again (about 3.5 CPU-s
# per worker). Python then writes __pycache__/ beside the sources (git ignores it, .ci/run does not count it).
unset PYTHONDONTWRITEBYTECODE
cd "$root" && uv run --locked pytest -n "${RIK_TEST_WORKERS:-$(( $(nproc) + 1 ))}" --maxprocesses 8 --dist loadfile --no-loadscope-reorder --durations 15 "$@"
