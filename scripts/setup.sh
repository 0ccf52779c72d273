#!/usr/bin/env bash
# Install everything rik needs on a fresh Debian/Ubuntu machine: the Debian packages it uses, uv (if
# missing), Python 3.12 and the locked environment (uv.lock). Safe to run again. Sourced by demo.sh and
# test.sh, so its exports (PATH, UV_SYSTEM_CERTS) reach their `uv run`.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"

# Debian packages, one per line in scripts/apt-packages.txt (none may be needed yet).
mapfile -t apt_pkgs < <(grep -v '^\s*#' "$root/scripts/apt-packages.txt" | grep -v '^\s*$' || true)
if ((${#apt_pkgs[@]})) && command -v dpkg-query >/dev/null; then
  missing=()
  for p in "${apt_pkgs[@]}"; do dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "ok installed" || missing+=("$p"); done
  if ((${#missing[@]})); then
    # As root (every container) apt-get runs directly, else through sudo. The environment variable goes
    # through env(1): a `VAR=value` after an expanded "$sudo" would be read as a command name when it is empty.
    as_root=(); [ "$(id -u)" -ne 0 ] && as_root=(sudo)
    echo "setup: installing Debian packages: ${missing[*]}"
    "${as_root[@]}" env DEBIAN_FRONTEND=noninteractive apt-get update -qq
    "${as_root[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${missing[@]}" >/dev/null
  fi
fi

# uv: from PyPI into the user's ~/.local (no download from elsewhere needed). uv trusts the system's
# certificate store (as pip and curl do), so it works behind proxies whose CA the system trusts.
export PATH="$HOME/.local/bin:$PATH"
export UV_SYSTEM_CERTS="${UV_SYSTEM_CERTS:-1}"
if ! uv --version >/dev/null 2>&1; then
  echo "setup: installing uv from PyPI"
  py=""; for c in python3.12 python3 python; do if "$c" -c "import sys; assert sys.version_info >= (3, 8)" 2>/dev/null; then py="$c"; break; fi; done
  [ -n "$py" ] || { echo "setup: error: no Python 3 found to install uv with" >&2; exit 1; }
  "$py" -m pip install --quiet --user --disable-pip-version-check uv 2>/dev/null \
    || "$py" -m pip install --quiet --user --disable-pip-version-check --break-system-packages uv
fi

# The locked environment, with bytecode compiled (start-up time of `rik` depends on it). uv uses a
# Python 3.12 found on the machine (.python-version) and downloads one only if none is; where that download
# fails too (no access to github.com), one line says what to do instead of uv's chain of causes.
cd "$root"
if ! uv python find >/dev/null 2>&1 && ! uv python install --quiet >/dev/null 2>&1; then
  version="$(cat .python-version)"
  echo "setup: error: no Python $version on this machine, and uv could not download one (is github.com reachable?):" \
    "install Python $version (pyenv, or your distribution's python$version) so that it is on PATH, and run this" \
    "again" >&2
  exit 1
fi
uv sync --locked --compile-bytecode --quiet
