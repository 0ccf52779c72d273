"""Learning curves and tables of the policy experiment (scripts/policy_experiment.sh, docs/policies.md).

Reads every ``rik eval`` output under ``WORK/eval`` (its ``eval_info.json``: the policy's folder and every episode's
outcome), finds each policy's training run, step and data set size from its folder
(``runs/<run>/checkpoints/<step>/pretrained_model`` and its ``train_config.json``), and writes:

- ``OUT/curves.md``: one row per evaluation (operator, training data, demonstrations, steps, the simulator it was
  evaluated in, F/P/S, S with its 95 % Wilson interval);
- ``OUT/curves.png``: S on the test split against training steps, one line per run, with the intervals, beside
  each run's training loss; ``OUT/losses.csv``: that loss (from ``train-<run>.log``);
- ``OUT/table3/``: Table 3 (F/P/S per handle type x preset) of the best learned policy beside the scripted
  strategies evaluated on the same episodes (``table.md``, ``episodes.csv``, ``success.png``).

    uv run python scripts/policy_curves.py experiments/policies --out docs/img/policies-curves
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from pathlib import Path
from typing import Any

from rik.outputs import REGENERATED, save_figure, write_text
from rik.paths import pyplot
from rik.tables import wilson


def _steps(steps: int) -> str:
    """Training steps as tables and axes name them: 10k, 2.5k; 60 below a thousand (the reduced size's runs)."""
    return f"{steps / 1000:g}k" if steps >= 1000 else str(steps)


def _train_facts(policy: Path) -> dict[str, Any]:
    """Run name, step and data set (root, episodes) of a saved checkpoint; empty for a scripted operator."""
    if not (policy / "train_config.json").is_file():
        return {}
    averaged = policy / "averaged.json"  # scripts/average_checkpoints.py's folder: the run's mean weights
    if averaged.is_file():
        note = json.loads(averaged.read_text(encoding="utf-8"))
        facts = _train_facts(policy.parent.parent / "runs" / note["run"] / "checkpoints" / f"{note['steps'][-1]:06d}"
                             / "pretrained_model")
        return {**facts, "run": f"{note['run']}, weights averaged {_steps(note['steps'][0])}-"
                f"{_steps(note['steps'][-1])}", "averaged": True}
    config = json.loads((policy / "train_config.json").read_text(encoding="utf-8"))
    saved = policy.name == "pretrained_model" and policy.parents[1].name == "checkpoints"
    work = policy.parents[4] if saved else policy.parents[1]  # runs/<run>/checkpoints/<step>/..., or <folder>/<copy>
    root = Path(config["dataset"]["root"])
    if not root.is_absolute():
        root = work / root  # lerobot-train ran in the work folder
    info = json.loads((root / "meta" / "info.json").read_text(encoding="utf-8"))
    facts: dict[str, Any] = {"run": policy.parents[2].name if saved else policy.name, "data": root.name,
                             "demos": int(info["total_episodes"]), "seed": int(config.get("seed") or 0)}
    if saved:  # a copy with other settings (chunking) has no step of its own on the curves
        step = policy.parent.name
        facts["step"] = int(config["steps"]) if step == "last" else int(step)
    return facts


def _simulator(work: Path, variants: str) -> str:
    """The simulator an evaluation ran in, from its variants folder's modes: ``coacd`` or ``hull`` collision, and
    ``, creeping joints`` where the joint friction creeps (a folder no longer there: by its name, held)."""
    from rik.combinator.build import COLLISION, JOINT_FRICTION

    folder = Path(variants) if Path(variants).is_absolute() else work / variants
    collision = COLLISION.of_folder(folder) or ("hull" if "hull" in folder.name else "coacd")
    friction = JOINT_FRICTION.of_folder(folder) or JOINT_FRICTION.default
    return collision if friction == JOINT_FRICTION.default else f"{collision}, {friction} joints"


def rows(work: Path) -> list[dict[str, Any]]:
    """One row per evaluation under ``work/eval`` (with its ``spec`` and ``episodes`` for :func:`table3`)."""
    out = []
    for info_file in sorted((work / "eval").glob("*/eval_info.json")):
        info = json.loads(info_file.read_text(encoding="utf-8"))
        spec, episodes = info["rik"]["spec"], info["rik"]["per_episode"]
        operator = spec["operator"]
        facts = {} if operator.startswith("strategy:") else _train_facts((work / operator).resolve()
                                                                         if not Path(operator).is_absolute()
                                                                         else Path(operator))
        counts = {o: sum(e["outcome"] == o for e in episodes) for o in "FPS"}
        lo, hi = wilson(counts["S"], len(episodes))
        out.append({"label": spec.get("label") or operator, "folder": info_file.parent.name,
                    "simulator": _simulator(work, spec["variants"]),
                    "n": len(episodes), **counts, "rate": counts["S"] / len(episodes), "lo": lo, "hi": hi, **facts,
                    "scripted": operator.startswith("strategy:"), "spec": spec, "episodes": episodes})
    return out


def table3(found: list[dict[str, Any]], out: Path) -> str | None:
    """Table 3 of the best learned policy (highest S in the CoACD simulator) beside the scripted operators that ran
    the same episodes; returns its label (None without both)."""
    from rik.evaluation.evaluate import EvalSpec, write_tables

    coacd = [r for r in found if r["simulator"] == "coacd"]
    learned = [r for r in coacd if "run" in r and r["spec"]["split"] == "test"]
    if not learned:
        return None
    best = max(learned, key=lambda r: (r["S"], r.get("step", 0)))
    same = [r for r in coacd if r["scripted"] and r["spec"]["seed"] == best["spec"]["seed"]
            and r["n"] == best["n"] and r["spec"]["split"] == best["spec"]["split"]]
    if not same:
        return None
    chosen = [*same, best]
    specs = [EvalSpec.from_data(r["spec"]) for r in chosen]
    write_tables(out, specs, [e for r in chosen for e in r["episodes"]])
    return str(best["label"])


def table(found: list[dict[str, Any]]) -> str:
    lines = ["| operator | run | data | demos | steps | seed | simulator | episodes | F | P | S | S, 95 % Wilson |",
             "|---|---|---|---:|---:|---:|---|---:|---:|---:|---:|---|"]
    for r in sorted(found, key=lambda r: (r.get("run", ""), r.get("step", 0), r["simulator"])):
        lines.append(f"| {r['label']} | {r.get('run', '-')} | {r.get('data', '-')} | {r.get('demos', '-')} | "
                     f"{r.get('step', '-')} | {r.get('seed', '-')} | {r['simulator']} | {r['n']} | {r['F']} | "
                     f"{r['P']} | {r['S']} | {100 * r['rate']:.0f} % [{100 * r['lo']:.0f}, {100 * r['hi']:.0f}] |")
    return "\n".join(lines) + "\n"


STEP_LOG = re.compile(r" step:\S+ .*? l1_loss:([0-9.]+)")
LOG_FREQ = 500
"""lerobot-train's ``--log_freq`` in scripts/policy_experiment.sh: its log rounds the step to thousands ("step:6K"),
so the k-th logged loss is taken at step k x LOG_FREQ."""


def training_losses(work: Path) -> dict[str, list[tuple[int, float]]]:
    """Run -> (step, ACT's L1 loss on normalised actions) from lerobot-train's logs ``train-<run>.log``."""
    out: dict[str, list[tuple[int, float]]] = {}
    # a run resumed from its last checkpoint (lerobot-train --resume=true) logs into train-<run>-resume.log, its
    # steps counted on from the first log's last one
    for log in sorted(work.glob("train-*.log"), key=lambda p: p.stem.endswith("-resume")):
        run = log.stem.removeprefix("train-").removesuffix("-resume")
        start = out[run][-1][0] if log.stem.endswith("-resume") and out.get(run) else 0
        points = [(start + (k + 1) * LOG_FREQ, float(m.group(1)))
                  for k, m in enumerate(STEP_LOG.finditer(log.read_text(encoding="utf-8", errors="replace")))]
        if points:
            out[run] = out.get(run, []) + points if start else points
    return out


def plot(found: list[dict[str, Any]], png: Path, losses: dict[str, list[tuple[int, float]]] | None = None) -> Path:
    plt = pyplot()
    fig, (ax, loss_ax) = plt.subplots(1, 2, figsize=(12, 6.4), gridspec_kw={"width_ratios": [3, 2]})
    for axes in (ax, loss_ax):  # a colour per run (more runs than matplotlib's ten default colours)
        axes.set_prop_cycle(color=plt.get_cmap("tab20").colors)
    runs: dict[str, list[dict[str, Any]]] = {}
    for r in found:
        if "step" in r and r["simulator"] == "coacd":
            runs.setdefault(f"{r['run']} ({r['demos']} demos)", []).append(r)
    for k, (name, points) in enumerate(sorted(runs.items())):
        points.sort(key=lambda r: r["step"])
        x = [p["step"] * (1 + 0.02 * k) for p in points]  # a little apart, so equal points stay visible
        y = [100 * p["rate"] for p in points]
        err = [[100 * (p["rate"] - p["lo"]) for p in points], [100 * (p["hi"] - p["rate"]) for p in points]]
        averaged = points[0].get("averaged", False)
        ax.errorbar(x, y, yerr=err, marker="*" if averaged else "o", markersize=12 if averaged else 6, capsize=3,
                    label=name)
    scripted: dict[float, list[str]] = {}
    for r in found:
        if r["scripted"] and r["simulator"] == "coacd" and r["spec"]["split"] == "test":
            scripted.setdefault(round(100 * r["rate"], 1), []).append(str(r["label"]))
    for rate, labels in scripted.items():
        ax.axhline(rate, ls="--", color="grey", lw=1)
        ax.text(ax.get_xlim()[0], rate - 5, f"{', '.join(labels)} (scripted)", color="grey", fontsize=8)
    ax.axhline(60, ls=":", color="black", lw=1)
    ax.set_xscale("log")
    steps = sorted({r["step"] for r in found if "step" in r})
    ax.set_xticks(steps, [_steps(s) for s in steps])
    ax.minorticks_off()
    ax.set_xlabel("training steps (batch 32)")
    ax.set_ylabel("S on unseen handles (test split), %")
    ax.set_ylim(0, 105)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(0.0, -0.16), ncol=3)
    ax.set_title("State-only policies: S against training steps (95 % Wilson intervals)", fontsize=10)
    for run, points in sorted((losses or {}).items()):
        loss_ax.plot([p[0] for p in points], [p[1] for p in points], label=run)
    loss_ax.set_yscale("log")
    loss_ax.set_xlabel("training steps")
    loss_ax.set_ylabel("L1 loss (normalised actions)")
    loss_ax.grid(alpha=0.3, which="both")
    if losses:
        loss_ax.legend(fontsize=6, loc="upper left", bbox_to_anchor=(0.0, -0.16), ncol=2)
    loss_ax.set_title("training loss (lerobot-train's log; 500-step means)", fontsize=10)
    fig.tight_layout()
    return save_figure(fig, png, REGENERATED)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("work", type=Path, help="the experiment's folder (scripts/policy_experiment.sh's WORK_DIR)")
    parser.add_argument("--out", type=Path, default=None, help="where to write curves.md and curves.png")
    args = parser.parse_args(argv)
    found = rows(args.work)
    if not found:
        print(f"{args.work}/eval: no rik eval outputs yet", file=sys.stderr)
        return 2
    out = args.out or args.work / "report"
    out.mkdir(parents=True, exist_ok=True)
    write_text(out / "curves.md", table(found), REGENERATED)
    losses = training_losses(args.work)
    plot(found, out / "curves.png", losses)
    write_text(out / "losses.csv", "run,step,l1_loss\n" + "".join(
        f"{run},{step},{loss}\n" for run, points in sorted(losses.items()) for step, loss in points), REGENERATED)
    best = table3(found, out / "table3")
    print(table(found), end="")
    print(f"wrote {out / 'curves.md'}, {out / 'curves.png'}"
          + (f" and {out / 'table3'} (the best policy, {best}, beside the scripted strategies)" if best else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main())
