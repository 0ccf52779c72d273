"""Start-up of ``rik catalog list --type knob`` against a plain ``python -c "import pydantic, typer"``.

Both commands run in this interpreter's environment, interleaved, after one warm-up run each (which writes
the catalog index cache and bytecode, as any user's first run does). Prints the median wall time of each and
their ratio (target: at most 1.5). Run: ``uv run python benchmarks/cli_startup.py [--runs N]``.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path


def wall_time(cmd: list[str], env: dict[str, str]) -> float:
    start = time.perf_counter()
    subprocess.run(cmd, env=env, check=True, stdout=subprocess.DEVNULL)
    return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=21)
    args = parser.parse_args()
    env = dict(os.environ)
    env.pop("PYTHONDONTWRITEBYTECODE", None)  # measure as users run: with bytecode caching
    rik_cmd = [str(Path(sys.executable).with_name("rik")), "catalog", "list", "--type", "knob"]
    base_cmd = [sys.executable, "-c", "import pydantic, typer"]
    for cmd in (rik_cmd, base_cmd):  # warm-up: cache and bytecode written
        wall_time(cmd, env)
    rik_times, base_times = [], []
    for _ in range(args.runs):
        rik_times.append(wall_time(rik_cmd, env))
        base_times.append(wall_time(base_cmd, env))
    rik_med, base_med = statistics.median(rik_times), statistics.median(base_times)
    print(f"runs: {args.runs} each, interleaved; python {sys.version.split()[0]}")
    print(f"rik catalog list --type knob     median {rik_med * 1000:7.1f} ms")
    print(f"python -c 'import pydantic, typer' median {base_med * 1000:7.1f} ms")
    print(f"ratio: {rik_med / base_med:.2f} (target <= 1.5)")


if __name__ == "__main__":
    main()
