"""The simulator's force error against each real door: rik's door pulled open quasi-statically through its handle
with the door's fitted preset and with the nearest paper preset, against the door's held-out openings.

Usage (from the repository root)::

    uv run --locked python scripts/real_door_sim_error.py ../shared/data/real/everyday-door-force-profiles.csv \\
        --table docs/img/sysid-doors/sim-error.md --img docs/img/sysid-doors/sim-vs-real.png

Your own doors, in the same CSV format (``trial,mechanism,class,angle bin,force [N]``: one row per 1° bin of an
opening, the force at the handle)::

    uv run --locked python scripts/real_door_presets.py my-doors.csv --out my-catalog/doors.yaml
    uv run --locked python scripts/real_door_sim_error.py my-doors.csv --catalog my-catalog/doors.yaml

The work is :mod:`rik.benchmark.real_doors` (what is compared, and how); this prints its table and writes the table
and the plot grid. Variants are built into ``--variants`` (a temporary folder unless given).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("csv", type=Path, help="everyday-door-force-profiles.csv")
    parser.add_argument("--table", type=Path, help="write the markdown table here")
    parser.add_argument("--img", type=Path, help="write the plot grid (PNG) here")
    parser.add_argument("--variants", type=Path, help="build the door variants here (default: a temporary folder)")
    parser.add_argument("--catalog", type=Path, action="append", default=[],
                        help="a user catalog holding the doors' presets (your own doors: the file "
                             "scripts/real_door_presets.py YOUR.csv --out FILE wrote); repeatable")
    args = parser.parse_args(argv)

    from rik.benchmark.real_doors import error_table, plot_grid, simulate_doors
    from rik.errors import RikError
    from rik.outputs import REGENERATED, write_text
    from rik.registry import load_catalog

    start = time.perf_counter()
    try:
        with tempfile.TemporaryDirectory(prefix="rik-real-doors-") as scratch:
            variants = args.variants or Path(scratch)
            results = simulate_doors(load_catalog(args.catalog or None), args.csv, variants,
                                     progress=lambda door: print(f"  {door}", file=sys.stderr, flush=True))
    except RikError as exc:
        print(f"real_door_sim_error: error: {exc}", file=sys.stderr)
        return 2
    table = error_table(results)
    print(table)
    print(f"{len(results)} doors in {time.perf_counter() - start:.0f} s", file=sys.stderr)
    if args.table:
        write_text(args.table, table, REGENERATED)
    if args.img:
        plot_grid(results, args.img, replaces=REGENERATED)
    return 0


if __name__ == "__main__":
    sys.exit(main())
