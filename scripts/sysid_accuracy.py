"""How often ``rik sysid`` names a hidden effect first, on data of rik's own generator or of the foreign one.

    uv run --locked python scripts/sysid_accuracy.py --generator foreign --joint slide --seeds 0,1,2 \
        [--kinds stiction,tilt] [--trials 3]

For every (kind, seed) it draws a truth, simulates ``--trials`` trials of 12 s at 200 Hz, runs
:func:`rik.sysid.discover.discover` (without the re-simulation) and prints a markdown table: the hidden kind,
the seed, the effect(s) named first, the alternatives it cannot tell from them, the held-out force gain, the
grade and, when nothing was chosen, the best candidate and why it failed. Grading as in
tests/test_sysid_discover.py: ``right`` when exactly the hidden kind is chosen (``none``: nothing chosen);
``pair`` when the other member of an indistinguishable pair (:data:`rik.sysid.effects.INDISTINGUISHABLE`) is
chosen with the hidden kind among its alternatives and the separating experiment stated; ``miss`` otherwise.
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np


def _cases(generator: str, joint: str, kinds: list[str] | None) -> list[str]:
    if generator == "foreign":
        from rik.sysid.synthetic.foreign import FOREIGN_KINDS

        known = list(FOREIGN_KINDS)
    else:
        from rik.sysid.synthetic.generate import EFFECT_KINDS

        known = ["none", *EFFECT_KINDS]
    if kinds is None:
        return known
    if bad := [k for k in kinds if k not in known]:
        raise SystemExit(f"sysid_accuracy: --kinds {', '.join(bad)} not known to the {generator} generator; use "
                         f"{', '.join(known)}")
    return kinds


def _trials(generator: str, kind: str, joint: str, seed: int, n_trials: int) -> list:
    rng = np.random.default_rng(seed)
    if generator == "foreign":
        from rik.sysid.synthetic.foreign import foreign_truth, simulate_foreign

        return simulate_foreign(foreign_truth(kind, joint, rng), n_trials=n_trials, seed=seed)
    from rik.sysid.synthetic.generate import random_truth, simulate_trials

    truth = random_truth(None if kind == "none" else kind, joint, rng)
    return simulate_trials(truth, n_trials=n_trials, seed=seed)


def grade(selection, kind: str) -> str:
    """``right``, ``pair`` or ``miss`` (see the module docstring)."""
    from rik.sysid.effects import INDISTINGUISHABLE

    if kind == "none":
        return "right" if not selection.found else "miss"
    if not selection.found or len(selection.final.kinds) != 1:
        return "miss"
    chosen = selection.final.kinds[0]
    if chosen == kind:
        return "right"
    pair = frozenset({chosen, kind})
    if (pair in INDISTINGUISHABLE and kind in {s.fit.kind for s in selection.alternatives}
            and selection.separation):
        return "pair"
    return "miss"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--generator", choices=("rik", "foreign"), default="foreign")
    parser.add_argument("--joint", choices=("slide", "hinge"), default="slide")
    parser.add_argument("--seeds", default="0,1,2", help="comma-separated seeds")
    parser.add_argument("--kinds", default=None, help="comma-separated kinds (default: all of the generator's)")
    parser.add_argument("--trials", type=int, default=3)
    args = parser.parse_args(argv)
    from rik.sysid.discover import discover

    seeds = [int(s) for s in args.seeds.split(",") if s.strip()]
    kinds = _cases(args.generator, args.joint, args.kinds.split(",") if args.kinds else None)
    print(f"generator {args.generator}, joint {args.joint}, seeds {seeds}, {args.trials} trials of 12 s at 200 Hz\n")
    print("| kind | seed | named first | alternatives | held-out gain | grade | best rejected candidate |")
    print("|---|---|---|---|---|---|---|")
    counts = {"right": 0, "pair": 0, "miss": 0}
    started = time.monotonic()
    for kind in kinds:
        for seed in seeds:
            sel = discover(_trials(args.generator, kind, args.joint, seed, args.trials), resimulate=False).selection
            g = grade(sel, kind)
            counts[g] += 1
            named = " + ".join(sel.final.kinds) if sel.found else "none"
            others = sel.pair_alternatives if sel.pair else sel.alternatives
            alts = ", ".join(" + ".join(s.fit.kinds) for s in others) or "-"
            gain = f"{sel.gain:.1%}" if sel.found else "-"
            rejected = "-"
            if not sel.found and sel.scores:
                best = sel.scores[0]
                rejected = f"{best.fit.kind} ({best.gain:.1%}): {best.verdict}"
            print(f"| {kind} | {seed} | {named} | {alts} | {gain} | {g} | {rejected} |", flush=True)
    total = sum(counts.values())
    print(f"\nnamed first right in {counts['right']} of {total}; {counts['right'] + counts['pair']} of {total} "
          f"counting an indistinguishable pair stated as such ({counts['pair']}); "
          f"{time.monotonic() - started:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
