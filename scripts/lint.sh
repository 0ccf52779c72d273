#!/usr/bin/env bash
# The lint step of CI: the same set-up as the README's commands (a no-op once done), then ruff (no cache written into
# the tree) and the type checker (mypy, configured in pyproject.toml; no cache kept). Exits non-zero when either
# finds something.
set -uo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
source "$root/scripts/setup.sh" || exit 1
cd "$root" || exit 1
status=0
uv run --locked ruff check --no-cache rik tests benchmarks scripts packages || status=1
uv run --locked mypy --cache-dir /dev/null || status=1
exit "$status"
