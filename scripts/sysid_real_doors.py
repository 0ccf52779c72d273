"""What rik's quasi-static profile fit finds on each real door of the shared everyday-door force profiles.

Usage (from the repository root)::

    uv run --locked python scripts/sysid_real_doors.py ../shared/data/real/everyday-door-force-profiles.csv \\
        --table docs/img/sysid-doors/table.md --img docs/img/sysid-doors

Reads the CSV (columns ``trial``, ``mechanism``, ``class``, ``angle bin``, ``force [N]``; bins read as 1° each,
the 8 NaN forces left out and counted), fits each mechanism with :func:`rik.sysid.profile_fit.fit_profile`
(exactly what ``rik sysid fit FILE --quasi-static --joint hinge --group mechanism ...`` does), and writes a
markdown table (one row per mechanism; the study's ``noisy``/``known_rad`` variants marked as such) and two PNG
grids of panels (refrigerators and freezers; cabinets): each opening thin, the median thick, the fit over it.
Forces are at the handle, in N: the data gives no lever arm.
"""

from __future__ import annotations

import argparse
import csv
import math
import sys
from pathlib import Path

VARIANT_MARKS = ("noisy", "known_rad")


def classes(path: Path) -> dict[str, str]:
    """Mechanism → its class (Fridge, Freezer, Kitchen Cabinet, Office Cabinet)."""
    with path.open(encoding="utf-8", newline="") as handle:
        return {row["mechanism"]: row["class"] for row in csv.DictReader(handle)}


def variant_of(name: str) -> str | None:
    """The mark (``noisy``, ``known_rad``) of a study variant, or None for a door of its own."""
    return next((m for m in VARIANT_MARKS if m in name), None)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("csv", type=Path, help="everyday-door-force-profiles.csv")
    parser.add_argument("--table", type=Path, help="write the markdown table here (default: stdout)")
    parser.add_argument("--img", type=Path, help="directory for the PNG grids (default: no plots)")
    args = parser.parse_args(argv)

    from rik.outputs import REGENERATED, save_figure, write_text
    from rik.paths import pyplot
    from rik.sysid.profile import read_profiles
    from rik.sysid.profile_fit import describe, fit_profile
    from rik.sysid.profile_report import plot_profile

    kinds = classes(args.csv)
    data = read_profiles(args.csv, "hinge", position="angle bin", position_unit="bin", force="force [N]",
                         trial="trial", group="mechanism", drop_nan=True)
    order = sorted(data.groups, key=lambda g: (kinds[g.name] not in ("Fridge", "Freezer"), kinds[g.name],
                                               variant_of(g.name) is not None, g.name))
    fits = {g.name: fit_profile(g, data.joint, data.force_unit) for g in order}

    lines = ["| door | class | openings | named | parameters (force at the handle) | friction level (or constant "
             "force), N | held-out gain | cannot tell from |", "|---|---|---:|---|---|---:|---:|---|"]
    for g in order:
        fit = fits[g.name]
        sel = fit.selection
        mark = variant_of(g.name)
        door = f"{g.name} (*variant*: {mark})" if mark else g.name
        named = " + ".join(sel.final.kinds) if sel.found else "no position-dependent effect"
        params = "; ".join(describe(e, fit.joint, fit.force_unit) for e in fit.effects) or "–"
        others = ", ".join(" + ".join(s.fit.kinds) for s in (*sel.alternatives, *sel.pair_alternatives)) or "–"
        gain = f"{sel.gain:.0%}" if sel.found else "–"
        lines.append(f"| {door} | {kinds[g.name]} | {len(g.profiles)} | {named} | {params} | {fit.level:.3g} | "
                     f"{gain} | {others} |")
    table = "\n".join(lines) + "\n"
    note = f"{data.dropped} rows with a NaN force left out (first: {', '.join(data.dropped_rows)})"
    if args.table:
        args.table.parent.mkdir(parents=True, exist_ok=True)
        write_text(args.table, table, REGENERATED)
    else:
        sys.stdout.write(table)
    print(note, file=sys.stderr)

    if args.img:
        plt = pyplot()
        panels = {"appliances.png": [g for g in order if kinds[g.name] in ("Fridge", "Freezer")],
                  "cabinets.png": [g for g in order if kinds[g.name] not in ("Fridge", "Freezer")]}
        for name, groups in panels.items():
            doors = [g for g in groups if variant_of(g.name) is None]
            cols = 4
            rows = math.ceil(len(doors) / cols)
            fig, axes = plt.subplots(rows, cols, figsize=(3.2 * cols, 2.4 * rows), squeeze=False)
            for k, (ax, g) in enumerate(zip(axes.flat, doors, strict=False)):
                fit = fits[g.name]
                named = " + ".join(fit.selection.final.kinds) or "no effect"
                plot_profile(fit, Path("unused"), ax=ax, title=f"{g.name}\n{kinds[g.name]}: {named}", legend=k == 0)
            for ax in list(axes.flat)[len(doors):]:
                ax.axis("off")
            fig.tight_layout()
            save_figure(fig, args.img / name, REGENERATED, dpi=72)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
