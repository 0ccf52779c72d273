"""How precisely a saved policy imitates held-out demonstrations, in metres: the diagnosis behind the learning curves
of docs/policies.md.

Runs the policy teacher-forced on every frame of a LeRobot dataset it was not trained on (for example planned
demonstrations on the test split: ``rik record --split test --strategy planned`` exported with ``--streams none``):
the first action of the chunk it predicts from the recorded observation, against the recorded action. Prints the
position error (m) over all frames and over the frames around the grasp (the gripper command turning from open to
closed, where a centimetre decides between holding the handle and missing it), and the angle errors (rad).

    uv run python scripts/policy_precision.py runs/act-pl/checkpoints/010000/pretrained_model ds-heldout
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

GRASP_WINDOW = 10
"""Frames before the gripper command first closes that count as 'around the grasp' (0.5 s at 20 Hz)."""


def errors(policy_dir: Path, dataset: Path) -> dict[str, np.ndarray]:
    """Per-frame absolute errors of the policy's first predicted action: ``position`` (m, 3 columns), ``angles``
    (rad, 3), and the mask ``near_grasp``."""
    import torch
    from lerobot.configs.policies import PreTrainedConfig
    from lerobot.datasets.lerobot_dataset import LeRobotDataset
    from lerobot.policies.factory import make_policy, make_pre_post_processors

    repo = json.loads((dataset / "meta" / "info.json").read_text(encoding="utf-8")).get("repo_id") or \
        f"local/{dataset.name}"
    ds = LeRobotDataset(repo, root=dataset)
    config = PreTrainedConfig.from_pretrained(policy_dir)
    config.pretrained_path = policy_dir
    policy = make_policy(cfg=config, ds_meta=ds.meta)
    policy.eval()
    pre, post = make_pre_post_processors(policy_cfg=config, pretrained_path=str(policy_dir))
    keys = [k for k in config.input_features]
    predicted, near = [], []
    table = ds.hf_dataset.with_format("numpy")
    episode_index = np.asarray(table["episode_index"])
    actions = np.stack(table["action"])
    inputs = {k: np.stack(table[k]) for k in keys}
    with torch.no_grad():
        for start in range(0, len(actions), 256):
            batch = {k: torch.as_tensor(v[start:start + 256], dtype=torch.float32) for k, v in inputs.items()}
            chunk = policy.predict_action_chunk(pre(batch))
            predicted.append(post(chunk[:, 0]).numpy())
    for e in np.unique(episode_index):
        rows = np.flatnonzero(episode_index == e)
        closed = np.flatnonzero(actions[rows, 6] > 0.5)
        mask = np.zeros(len(rows), bool)
        if len(closed):
            mask[max(0, closed[0] - GRASP_WINDOW):closed[0] + 1] = True
        near.append(mask)
    diff = np.abs(np.concatenate(predicted) - actions)
    return {"position": diff[:, :3], "angles": diff[:, 3:6], "near_grasp": np.concatenate(near)}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("policy", type=Path, help="a saved policy (.../pretrained_model)")
    parser.add_argument("dataset", type=Path, help="a state-only LeRobot dataset it was not trained on")
    args = parser.parse_args(argv)
    e = errors(args.policy, args.dataset)
    near = e["near_grasp"]
    for name, rows in (("all frames", slice(None)), (f"the {GRASP_WINDOW + 1} frames up to the grasp", near)):
        pos, ang = e["position"][rows], e["angles"][rows]
        dist = np.linalg.norm(pos, axis=1)
        print(f"{args.policy} on {args.dataset}, {name} ({len(dist)}): position error median "
              f"{1000 * np.median(dist):.1f} mm, 90th percentile {1000 * np.percentile(dist, 90):.1f} mm "
              "(x, y, z medians "
              f"{', '.join(f'{1000 * v:.1f}' for v in np.median(pos, axis=0))} mm); angles median "
              f"{', '.join(f'{v:.3f}' for v in np.median(ang, axis=0))} rad")
    return 0


if __name__ == "__main__":
    sys.exit(main())
