"""Image evaluation speed: an episode of ``rik eval`` with a two-camera image policy, as it ran before issue 54 and
as it runs now, side by side in one process on one core.

The policy is ACT with the recipe's architecture (scripts/act_recipe.sh: ResNet-18 image backbone, 128-wide
transformer, chunks of 20 actions played 10 at a time) reading the ``front`` and ``wrist`` cameras at 64 px and the
robot's and front's states; its weights are random (no download), which does not change its cost, and it never
opens the front, so every episode runs its full length (400 control steps by default): the worst case. Modes:

- ``before``: every step's observation rendered, with rik's scenes' own 2048 px shadow maps (rik 0.x until issue
  54);
- ``read only``: only the observations the policy reads rendered (:mod:`rik.lerobot.observation_use`), 2048 px
  shadow maps;
- ``now``: only those, with the sim stream's settings for the size (:func:`rik.render.streams.sim_settings`).

Each mode runs the same episodes (the test split's draw, the bow drawer's cells) after one warm-up episode; the
figure is wall seconds per episode, best of ``--repeats``. Torch and the renderer get one thread.

Run: ``uv run python benchmarks/image_eval_speed.py [--episodes 2] [--episode-length 400] [--repeats 1]``.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from dataclasses import replace
from pathlib import Path

SIZE = (64, 64)
CAMERAS = ("front", "wrist")


def image_policy(folder: Path) -> Path:
    """The recipe's ACT reading two 64 px cameras, random weights, saved with its processors and rik's contract."""
    import torch
    from lerobot.configs.types import FeatureType
    from lerobot.policies.act.configuration_act import ACTConfig
    from lerobot.policies.act.modeling_act import ACTPolicy
    from lerobot.policies.factory import make_pre_post_processors
    from lerobot.utils.feature_utils import dataset_to_policy_features

    from rik.lerobot.policy_io import POLICY_IO_FILE, PolicyIO

    io = PolicyIO(cameras=CAMERAS, streams=("sim",), image_size=SIZE)
    features = dataset_to_policy_features(io.features())  # as lerobot's make_policy makes them from a dataset
    inputs = {k: f for k, f in features.items() if f.type is not FeatureType.ACTION}
    outputs = {k: f for k, f in features.items() if f.type is FeatureType.ACTION}
    config = ACTConfig(device="cpu", push_to_hub=False, pretrained_backbone_weights=None, dim_model=128,
                       dim_feedforward=512, n_heads=4, n_encoder_layers=4, n_decoder_layers=1, chunk_size=20,
                       n_action_steps=10, use_vae=True, latent_dim=32, n_vae_encoder_layers=4,
                       input_features=inputs, output_features=outputs)
    policy = ACTPolicy(config)
    stats = {}
    for key, feature in {**inputs, **outputs}.items():
        extra = [1, 1] if len(feature.shape) == 3 else []
        stats[key] = {"mean": torch.zeros(feature.shape[0], *extra), "std": torch.ones(feature.shape[0], *extra)}
    pre, post = make_pre_post_processors(config, dataset_stats=stats)
    for part in (policy, pre, post):
        part.save_pretrained(folder)
    (folder / POLICY_IO_FILE).write_text(io.to_json())
    return folder


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--episodes", type=int, default=2)
    parser.add_argument("--episode-length", type=int, default=400)
    parser.add_argument("--repeats", type=int, default=1)
    parser.add_argument("--variants", type=Path, default=Path("variants"))
    args = parser.parse_args()
    os.environ.setdefault("MUJOCO_GL", "egl")
    os.environ.setdefault("LP_NUM_THREADS", "1")  # llvmpipe's rasteriser threads: one core, as torch
    import torch

    from rik.evaluation import evaluate
    from rik.registry.load import load_catalog
    from rik.render import streams

    torch.set_num_threads(1)
    own_sizes = streams.SHADOW_SIZES
    modes = {"before": ((2048,), False), "read only": ((2048,), True), "now": (own_sizes, True)}
    catalog = load_catalog()
    with tempfile.TemporaryDirectory() as tmp:
        folder = image_policy(Path(tmp) / "policy")
        spec = evaluate.prepare(catalog, evaluate.EvalSpec(
            str(folder), split="test", handle_types=("two_point",), presets=("normal",), kinds=("drawer",),
            episodes_per_cell=args.episodes, episode_length=args.episode_length, videos=0,
            variants=str(args.variants)))
        seeds = spec.seeds()
        best: dict[str, tuple[float, int, int]] = {}
        for _ in range(args.repeats):
            for mode, (sizes, read_only) in modes.items():
                streams.SHADOW_SIZES = sizes  # the renderers are made after this, at the first observation
                evaluate._CONTEXT.clear()
                vec = evaluate._context(spec)["vec"]
                env = vec.envs[0].unwrapped
                if not read_only:
                    env.reads_next = None
                evaluate.run_episode(replace(spec), seeds[0])  # warm-up: scene, renderer, policy
                rendered, start = env.frames_rendered, time.perf_counter()
                steps = sum(int(evaluate.run_episode(spec, seed)["steps"]) for seed in seeds)
                wall = time.perf_counter() - start
                rendered = env.frames_rendered - rendered
                if mode not in best or wall < best[mode][0]:
                    best[mode] = (wall, steps, rendered)
                vec.close()
                evaluate._CONTEXT.clear()
        streams.SHADOW_SIZES = own_sizes
    print(f"CPU cores: {os.cpu_count()} (torch and the renderer on one thread); policy: ACT, ResNet-18, "
          f"{len(CAMERAS)} cameras at {SIZE[1]}x{SIZE[0]} px, {len(seeds)} episodes of {args.episode_length} steps")
    print(f"{'mode':<10} {'episodes':>8} {'steps':>6} {'renders':>8} {'s/episode':>10} {'ms/step':>8} {'x before':>9}")
    base = best["before"][0] / len(seeds)
    for mode, (wall, steps, rendered) in best.items():
        per = wall / len(seeds)
        print(f"{mode:<10} {len(seeds):>8} {steps:>6} {rendered:>8} {per:>10.2f} {1e3 * wall / steps:>8.1f} "
              f"{base / per:>9.2f}")


if __name__ == "__main__":
    main()
