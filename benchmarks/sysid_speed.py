"""Speed of model discovery: ``rik sysid fit`` on 3 trials of 12 s at 200 Hz (target: at most 10 s on 2 cores).

Set-up, not timed: ``rik sysid simulate``'s generator makes 3 trials of a drawer with a hidden soft-close damper
(then a damper with its pull-in spring, then nothing hidden), written as CSV. Timed, best of ``--repeats`` after
one warm-up, in one process:

- load: reading and checking the CSVs (:func:`rik.sysid.trials.load_trials`);
- preprocess: window choice, delay estimate and the final smoothing of every trial
  (:func:`rik.sysid.discover.prepare_all`);
- fit and select, singles: the baseline and the 9 effect families (grid and refinement each) and the selection;
- fit and select, with pairs: the above plus the round of pairs of effects; and the same again with each
  candidate shape of the hyperparameter search solved as one whole weighted least-squares problem (how it was
  before 2026-11-29) instead of fitted to what the fixed columns leave over (one QR of them per search,
  :func:`rik.sysid.fit.projected_rss`), side by side: the ratio is that change's speed-up;
- discover without and with re-simulation (MuJoCo multiple shooting of the held-out trial with the baseline and
  the extended joint), the difference being the re-simulation (small: below the timing noise when nothing is
  found, since then only the baseline is re-simulated);
- report: the five plots, report.md and summary.json;

and the total of what ``rik sysid fit`` runs, with its ratio to the 10 s target.

Run: ``uv run python benchmarks/sysid_speed.py [--repeats 3]``.
"""

from __future__ import annotations

import argparse
import contextlib
import tempfile
import time
from pathlib import Path

import numpy as np


def _best(fn, repeats: int) -> tuple[float, object]:
    best, out = float("inf"), None
    for _ in range(repeats):
        start = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - start)
    return best, out


@contextlib.contextmanager
def _whole_solves():
    """Within it, the hyperparameter search solves each candidate's whole system (the former way)."""
    from rik.sysid import fit

    projected = fit.projected_rss
    fit.projected_rss = lambda base, y, w: (lambda z: fit.weighted_solve(np.hstack([base, z]), y, w)[1])
    try:
        yield
    finally:
        fit.projected_rss = projected


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()

    from rik.sysid.discover import discover, prepare_all, select_effects
    from rik.sysid.fit import all_rows, fit_all, fit_velocity, split_rows
    from rik.sysid.report import write_report
    from rik.sysid.select import select
    from rik.sysid.synthetic.generate import random_truth, simulate_trials, write_trials
    from rik.sysid.trials import load_trials

    with tempfile.TemporaryDirectory() as tmp:
        for kind, second in (("soft_close", None), ("soft_close", "self_close"), (None, None)):
            truth = random_truth(kind, "slide", np.random.default_rng(2 if second else 0), second=second)
            name = f"{kind}+{second}" if second else str(kind)
            paths = write_trials(simulate_trials(truth, n_trials=3, seed=2 if second else 0), Path(tmp) / name, truth)
            discover(load_trials(paths, "slide"))  # warm-up: imports, scipy, mujoco

            t_load, trials = _best(lambda p=paths: load_trials(p, "slide"), args.repeats)
            t_prep, (prepared, _) = _best(lambda t=trials: prepare_all(t), args.repeats)

            def fit_select(prepared=prepared):
                rows = all_rows(prepared, velocity=fit_velocity(prepared))
                split = split_rows(rows, prepared)
                return select(*fit_all(split))

            t_fit, selection = _best(fit_select, args.repeats)

            def with_pairs(prepared=prepared):
                rows = all_rows(prepared, velocity=fit_velocity(prepared))
                return select_effects(split_rows(rows, prepared))

            t_pairs, selection = _best(with_pairs, args.repeats)
            with _whole_solves():
                t_whole, whole = _best(with_pairs, args.repeats)
            same = whole.final.kinds == selection.final.kinds if selection.found else not whole.found
            t_all, found = _best(lambda t=trials: discover(t), args.repeats)
            t_plain, _ = _best(lambda t=trials: discover(t, resimulate=False), args.repeats)
            t_report, _ = _best(lambda f=found, k=name: write_report(f, Path(tmp) / f"report-{k}"), args.repeats)
            total = t_load + t_all + t_report
            chosen = " + ".join(selection.final.kinds) if selection.found else "none"
            print(f"hidden: {name}; found: {chosen}; 3 trials x 12 s at 200 Hz, best of "
                  f"{args.repeats}")
            print(f"  load            {t_load:7.3f} s")
            print(f"  preprocess      {t_prep:7.3f} s")
            print(f"  fit and select  {t_fit:7.3f} s   (single effects)")
            print(f"  ... with pairs  {t_pairs:7.3f} s   (single effects, then pairs)")
            print(f"  ... whole solves {t_whole:6.3f} s   (each candidate's whole system: {t_whole / t_pairs:.1f}x "
                  f"the time; same choice: {same})")
            print(f"  discover, no re-simulation {t_plain:7.3f} s")
            print(f"  discover total  {t_all:7.3f} s   (preprocess + fit + select + re-simulate)")
            print(f"  report          {t_report:7.3f} s")
            print(f"  rik sysid fit   {total:7.3f} s   = {total / 10.0:.2f} x the 10 s target")


if __name__ == "__main__":
    main()
