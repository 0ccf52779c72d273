"""The pre-registered joints ablation's report (docs/policies.md, "Pre-registered: real doors' joints against the
paper's presets"), exactly the comparisons its plan names, from the test stage's evaluations.

    uv run python scripts/joints_report.py experiments/joints [--out docs/policies/joints/report.md]
    uv run python scripts/joints_report.py experiments/joints --validation [--out docs/policies/joints/val.md]

``--validation``: the validation stage's successes instead (every run's candidates on both draws, from
``eval/val/<candidate>-<draw>/<run>-<candidate>/episodes.csv``, and each candidate's sum, which the choice is
made by), before or after the choice.

Reads ``chosen.txt`` and ``eval/test/<chosen>-measured`` and ``-paper`` (each holding one folder per run,
``act-<arm>-s<seed>-<chosen>/episodes.csv``, and ``strategy-planned``). For each arm (jp: the paper's presets in
training; jm: the train split's real doors) and each test draw: successes pooled over the seeds with a 95 % Wilson
interval, each seed's rate, and a 95 % interval resampling seeds and handles; per front layout the pooled counts.
The primary comparison: on the measured draw, the doors' S of jm against jp, the difference of the pooled rates
with Newcombe's interval and the paired seed differences. Secondary: every front; each arm's doors on the paper
draw against the measured one; the misses on the real test doors by the door's mechanism class (catch,
self-closing, tilted, plain) and by what the opening did (:func:`miss`), and the same per front layout. Writes
nothing but ``--out``; prints the report.
"""

from __future__ import annotations

import argparse
import csv
import sys
from pathlib import Path

ARMS = {"jp": "(a) paper presets in training", "jm": "(b) real doors in training"}
DRAWS = ("measured", "paper")
LAYOUTS = ("drawer", "door-left", "door-right", "flap-lift-up", "flap-drop-down")
MISSES = ("fell back", "stalled", "never opened")
FELL_BACK = 0.10
"""A miss whose front was at some point this much further open (a fraction of its range) than where it ended."""


def miss(row: dict[str, str]) -> str:
    """What a missed episode's opening did (every miss runs to the episode's limit, so a time out says nothing):
    ``fell back`` (the front opened at least :data:`FELL_BACK` of its range further than where it ended: the
    grasp let go and the front went back), ``stalled`` (it ended partly open, P, near the furthest it got) or
    ``never opened`` (F: under 5 % of its range)."""
    if round(float(row["max_opening"]) - float(row["final_opening"]), 4) >= FELL_BACK:  # as written: 4 decimals
        return "fell back"
    return "stalled" if row["outcome"] == "P" else "never opened"


def _runs(folder: Path, arm: str, chosen: str) -> list[list[dict[str, str]]]:
    """The episodes of each seed's run of ``arm`` in one evaluation folder, seed order."""
    runs = sorted(folder.glob(f"act-{arm}-s*-{chosen}/episodes.csv"))
    return [list(csv.DictReader(path.open(encoding="utf-8"))) for path in runs]


def _miss_cells(rows: list[dict[str, str]]) -> str:
    """A miss table's cells for some episodes: their number, the successes and each :data:`MISSES` class's count."""
    missed = [miss(r) for r in rows if r["outcome"] != "S"]
    return f"{len(rows)} | {len(rows) - len(missed)} | " + " | ".join(str(missed.count(m)) for m in MISSES)


def validation_report(work: Path) -> str:
    """The validation stage's table: each run's successes of each candidate on each draw, and each candidate's
    sum over every run and both draws (the rule's count); candidates and runs as the folders hold them."""
    val = work / "eval" / "val"
    found = sorted(val.glob("*-*/*/episodes.csv"))
    cells: dict[tuple[str, str, str], tuple[int, int]] = {}
    for path in found:
        candidate, draw = path.parent.parent.name.rsplit("-", 1)
        run = path.parent.name.removesuffix(f"-{candidate}")
        rows = list(csv.DictReader(path.open(encoding="utf-8")))
        cells[(run, candidate, draw)] = (sum(r["outcome"] == "S" for r in rows), len(rows))
    candidates = sorted({c for _, c, _ in cells}, key=lambda c: (c != "mean", -int(c) if c.isdigit() else 0))
    runs = sorted({r for r, _, _ in cells})
    head = [f"{c} {d}" for c in candidates for d in DRAWS]
    lines = ["# The joints ablation: the validation split (every candidate of every run, both draws)", "",
             "Successes of the episodes evaluated (`S/n`); the rule picks the candidate with the most successes "
             "summed over every run and both draws (ties to the one listed first: the mean, then 40k, 30k, 20k).", "",
             "| run | " + " | ".join(head) + " |", "|---|" + "---:|" * len(head)]
    for run in runs:
        row = [cells.get((run, c, d)) for c in candidates for d in DRAWS]
        lines.append(f"| {run} | " + " | ".join(f"{x[0]}/{x[1]}" if x else "-" for x in row) + " |")
    sums = {c: [cells[k] for k in cells if k[1] == c] for c in candidates}
    lines += ["", "| candidate | S over every run and both draws | evaluations |", "|---|---:|---:|"]
    for c in candidates:
        lines.append(f"| {c} | {sum(x[0] for x in sums[c])}/{sum(x[1] for x in sums[c])} | {len(sums[c])} |")
    chosen = work / "chosen.txt"
    lines += ["", f"Chosen: `{chosen.read_text().strip()}` (chosen.txt)." if chosen.is_file() else
              "No choice yet: the stage chooses once every run is evaluated."]
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("work", type=Path, help="the ablation's folder (scripts/joints_ablation.sh WORK_DIR)")
    parser.add_argument("--out", type=Path, help="write the report (markdown) here")
    parser.add_argument("--validation", action="store_true", help="the validation stage's table instead")
    args = parser.parse_args(argv)

    from rik.outputs import RECORDED, write_text

    if args.validation:
        text = validation_report(args.work)
        print(text)
        if args.out:
            write_text(args.out, text, RECORDED)
        return 0

    from rik.registry.ids import parse_variant_id
    from rik.registry.load import load_catalog
    from rik.tables import newcombe, rate_text, seed_handle_interval

    chosen_file = args.work / "chosen.txt"
    if not chosen_file.is_file():
        print(f"joints_report: {chosen_file}: no choice on the validation split yet", file=sys.stderr)
        return 2
    chosen = chosen_file.read_text().strip()
    catalog = load_catalog()

    def layout(row: dict[str, str]) -> str:
        base = catalog.base_units[parse_variant_id(catalog, row["variant"]).base]
        return next(f for f in base.fronts if f.id == row["front"]).layout

    runs = {(arm, draw): _runs(args.work / "eval" / "test" / f"{chosen}-{draw}", arm, chosen)
            for arm in ARMS for draw in DRAWS}
    missing = [f"{arm} on {draw}" for (arm, draw), r in runs.items() if not r]
    if missing:
        print(f"joints_report: no test evaluation of {', '.join(missing)} in {args.work}/eval/test", file=sys.stderr)
        return 2

    def doors(rows: list[dict[str, str]]) -> list[dict[str, str]]:
        return [r for r in rows if layout(r).startswith("door")]

    lines = [f"# The joints ablation: the test split, once (candidate `{chosen}`, chosen on the validation split)", ""]
    for draw in DRAWS:
        lines += [f"## Test draw `--joints {draw}`", "",
                  "| arm | seeds | S pooled (95 % Wilson) | per seed | seeds and handles (95 %) | "
                  + " | ".join(LAYOUTS) + " |", "|---|---:|---|---|---|" + "---|" * len(LAYOUTS)]
        for arm, name in ARMS.items():
            seeds = runs[(arm, draw)]
            success = [[r["outcome"] == "S" for r in run] for run in seeds]
            s, n = sum(map(sum, success)), sum(map(len, success))
            lo, hi = seed_handle_interval(success, [r["variant"].split("__")[1] for r in seeds[0]])
            per = ", ".join(f"{sum(x) / len(x):.0%}" for x in success)
            cells = []
            for lay in LAYOUTS:
                sel = [r["outcome"] == "S" for run in seeds for r in run if layout(r) == lay]
                cells.append(f"{sum(sel)}/{len(sel)}" if sel else "-")
            lines.append(f"| {name} | {len(seeds)} | {rate_text(s, n)} | {per} | [{lo:.0%}, {hi:.0%}] | "
                         + " | ".join(cells) + " |")
        lines.append("")
    # the primary comparison: doors on the measured draw, (b) against (a)
    a, b = runs[("jp", "measured")], runs[("jm", "measured")]
    sa = [sum(r["outcome"] == "S" for r in doors(run)) for run in a]
    sb = [sum(r["outcome"] == "S" for r in doors(run)) for run in b]
    na, nb = len(doors(a[0])), len(doors(b[0]))
    lo, hi = newcombe(sum(sb), nb * len(b), sum(sa), na * len(a))
    paired = [f"{y / nb - x / na:+.0%}" for x, y in zip(sa, sb, strict=False)]
    lines += ["## The primary comparison: real test doors, (b) against (a)", "",
              f"Doors of the measured test draw: (a) {rate_text(sum(sa), na * len(a))}, "
              f"(b) {rate_text(sum(sb), nb * len(b))}; "
              f"difference (b) - (a) {sum(sb) / (nb * len(b)) - sum(sa) / (na * len(a)):+.0%}, 95 % Newcombe "
              f"[{lo:+.0%}, {hi:+.0%}]; paired by training seed: {', '.join(paired)}.", ""]
    for arm, name in ARMS.items():
        on = {draw: [r["outcome"] == "S" for run in runs[(arm, draw)] for r in doors(run)] for draw in DRAWS}
        lines.append(f"- {name}, doors: paper draw {rate_text(sum(on['paper']), len(on['paper']))}, measured draw "
                     f"{rate_text(sum(on['measured']), len(on['measured']))}.")
    from rik.schemas.joints import MECHANISMS

    lines += ["", "## Misses on the real test doors, by mechanism class (the measured draw)", "",
              "| arm | class | episodes | S | " + " | ".join(MISSES) + " |",
              "|---|---|---:|---:|" + "---:|" * len(MISSES)]
    for arm, name in ARMS.items():
        by_class: dict[str, list[dict[str, str]]] = {m: [] for m in MECHANISMS}
        for run in runs[(arm, "measured")]:
            for r in doors(run):
                preset = parse_variant_id(catalog, r["variant"]).preset
                if preset in catalog.preset_splits:  # a real door (the draw's doors all are)
                    by_class[catalog.presets[preset].hinge.mechanism()].append(r)
        for mechanism, rows in by_class.items():
            lines.append(f"| {name} | {mechanism} | {_miss_cells(rows)} |")
    lines += ["", "## Misses by front layout (the measured draw, every front kind)", "",
              "| arm | layout | episodes | S | " + " | ".join(MISSES) + " |",
              "|---|---|---:|---:|" + "---:|" * len(MISSES)]
    for arm, name in ARMS.items():
        for lay in LAYOUTS:
            rows = [r for run in runs[(arm, "measured")] for r in run if layout(r) == lay]
            lines.append(f"| {name} | {lay} | {_miss_cells(rows)} |")
    lines.append("")
    planned = args.work / "eval" / "test" / f"{chosen}-measured" / "strategy-planned" / "episodes.csv"
    if planned.is_file():
        rows = list(csv.DictReader(planned.open(encoding="utf-8")))
        lines.append(f"- The demonstrator (`planned`) on the measured draw: "
                     f"{rate_text(sum(r['outcome'] == 'S' for r in rows), len(rows))}.")
    text = "\n".join(lines) + "\n"
    print(text)
    if args.out:
        write_text(args.out, text, RECORDED)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
