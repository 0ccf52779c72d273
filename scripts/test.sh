#!/usr/bin/env bash
# README command 2: set everything up (a no-op when done), then run the test suite. Extra arguments go to pytest.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
source "$root/scripts/setup.sh"
cd "$root" && uv run --locked pytest "$@"
