#!/usr/bin/env bash
# README command 2: set everything up (a no-op when done), then run the test suite: one pytest-xdist worker per core
# (RIK_TEST_WORKERS=N for another number, 0 for none), each test file on one worker (their module fixtures are
# built once), the slowest tests listed at the end. Extra arguments go to pytest: `-m "not slow"` is the everyday
# tier, a file or `-k NAME` picks tests.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
source "$root/scripts/setup.sh"
cd "$root" && uv run --locked pytest -n "${RIK_TEST_WORKERS:-auto}" --maxprocesses 8 --dist loadfile --no-loadscope-reorder --durations 15 "$@"
