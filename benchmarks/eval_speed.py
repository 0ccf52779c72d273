"""Evaluation speed: a state-only LeRobot policy through ``rik eval`` against rik's scripted strategy on the same
episodes (the overhead of the policy path: lerobot's rollout, its processors and the policy's inference).

Both run the episodes of the same seeds (a draw of the test split, one per handle type x preset cell by default)
in this process, one after the other, best of ``--repeats`` interleaved runs; printed side by side: episodes and
control steps run, wall seconds, episodes per second, control steps per second, and the ratio of the policy's
time per step to the strategy's. Episodes of a policy end when it opens the front or after ``--episode-length``
steps, so the two sides run different numbers of steps: the per-step ratio is the comparable figure.

Without ``--policy``, a small ACT (state only) is trained for a few steps on two scripted demonstrations first
(with lerobot-train), which is enough to time inference: its weights do not change its cost.

Run: ``uv run python benchmarks/eval_speed.py [--policy DIR] [--episodes-per-cell 1] [--repeats 2]``.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path


def tiny_policy(work: Path, variants: Path) -> Path:
    """Two contact-rich demonstrations, exported state-only, and an ACT trained on them for 20 steps."""
    bin_dir = Path(sys.executable).parent
    env = {**os.environ, "HF_HUB_OFFLINE": "1"}

    def run(*cmd: str) -> None:
        subprocess.run(list(cmd), cwd=work, env=env, check=True, capture_output=True, text=True)

    run(str(bin_dir / "rik"), "record", "--split", "train", "--types", "knob", "--presets", "smooth", "--episodes",
        "2", "-s", "contact_rich", "--out", "episodes", "--variants", str(variants))
    run(str(bin_dir / "rik"), "export-lerobot", "episodes", "--out", "dataset", "--repo-id", "local/bench",
        "--streams", "none", "--variants", str(variants))
    run(str(bin_dir / "lerobot-train"), "--dataset.repo_id=local/bench", "--dataset.root=dataset",
        "--policy.type=act", "--policy.push_to_hub=false", "--policy.device=cpu", "--policy.dim_model=128",
        "--policy.dim_feedforward=512", "--policy.n_heads=4", "--policy.chunk_size=20", "--policy.n_action_steps=10",
        '--policy.normalization_mapping={"VISUAL": "MEAN_STD", "STATE": "MEAN_STD", "ENV": "MEAN_STD", '
        '"ACTION": "MEAN_STD"}', "--steps=20", "--batch_size=8", "--save_freq=20", "--env_eval_freq=1000000",
        "--output_dir=train", "--wandb.enable=false", "--num_workers=0")
    return work / "train" / "checkpoints" / "last" / "pretrained_model"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--policy", type=Path, help="a saved state-only policy (default: train a tiny ACT)")
    parser.add_argument("--strategy", default="contact_rich")
    parser.add_argument("--episodes-per-cell", type=int, default=1)
    parser.add_argument("--episode-length", type=int, default=400)
    parser.add_argument("--repeats", type=int, default=2)
    parser.add_argument("--variants", type=Path, default=Path("variants"))
    args = parser.parse_args()

    from rik.evaluation.evaluate import EvalSpec, prepare, run_eval
    from rik.registry.load import load_catalog

    catalog = load_catalog()
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        policy = args.policy or tiny_policy(work, args.variants)
        specs = {side: prepare(catalog, EvalSpec(op, "test", episodes_per_cell=args.episodes_per_cell,
                                                 episode_length=args.episode_length, videos=0,
                                                 variants=str(args.variants)))
                 for side, op in (("strategy", f"strategy:{args.strategy}"), ("policy", str(policy)))}
        for side, spec in specs.items():  # warm-up: variants built, policy and torch loaded, scenes compiled
            run_eval(catalog, replace(spec, episodes_per_cell=1), work / f"warm-{side}")
        best: dict[str, tuple[float, int, int]] = {}
        for r in range(args.repeats):
            for side, spec in specs.items():
                start = time.perf_counter()
                rows = run_eval(catalog, spec, work / f"{side}-{r}")
                wall = time.perf_counter() - start
                steps = sum(int(row["steps"]) for row in rows)
                if side not in best or wall / steps < best[side][0] / best[side][2]:
                    best[side] = (wall, len(rows), steps)
    print(f"{'side':<10} {'episodes':>8} {'steps':>7} {'wall s':>8} {'episodes/s':>11} {'steps/s':>9}")
    for side, (wall, episodes, steps) in best.items():
        print(f"{side:<10} {episodes:>8} {steps:>7} {wall:>8.2f} {episodes / wall:>11.2f} {steps / wall:>9.0f}")
    per_step = {side: wall / steps for side, (wall, _, steps) in best.items()}
    print(f"policy / strategy time per control step: {per_step['policy'] / per_step['strategy']:.2f}  "
          f"(policy {1e3 * per_step['policy']:.2f} ms, strategy {1e3 * per_step['strategy']:.2f} ms per step; "
          f"policy: {specs['policy'].label})")


if __name__ == "__main__":
    main()
