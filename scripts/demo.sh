#!/usr/bin/env bash
# README command 1: set everything up, then run rik's main job on its built-in defaults.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
source "$root/scripts/setup.sh"
cd "$root" && uv run --locked rik demo
