#!/usr/bin/env bash
# The lint step of CI: the same set-up as the README's commands (a no-op once done), then ruff (no cache written into
# the tree) and the type checker (mypy, configured in pyproject.toml; its incremental cache kept outside the tree, in
# ~/.cache/rik/mypy/, one folder per checkout: 35 CPU-s cold, a few warm, beside a test suite that needs every core).
# Exits non-zero when either finds something.
set -uo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
source "$root/scripts/setup.sh" || exit 1
cd "$root" || exit 1
status=0
uv run --locked ruff check --no-cache rik tests benchmarks scripts packages || status=1
cache="${XDG_CACHE_HOME:-$HOME/.cache}/rik/mypy/$(printf '%s' "$root" | sha256sum | cut -c1-16)"
mkdir -p "$cache" 2>/dev/null || cache=/dev/null  # an unwritable home: no cache, as before
uv run --locked mypy --cache-dir "$cache" || status=1
exit "$status"
