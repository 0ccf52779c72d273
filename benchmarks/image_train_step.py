"""What a training step of an image ACT costs on this machine's CPU, per image size, camera count and batch: the
figure that decides whether an image policy trains here (issue 54) or needs a lent GPU.

The policy is ACT with the recipe's architecture (scripts/act_recipe.sh: ResNet-18 backbone, random weights, 128-wide
transformer, VAE, chunks of 20) reading the robot's 11-number state and 1-4 cameras, without the front's state (an
image policy as a real robot would have it); a step is LeRobot's: ``policy.forward`` on a batch, ``backward``, an
AdamW step. Inputs are random tensors of the dataset's shapes (a step's cost does not depend on their values); no
data loading or video decoding is counted. Each configuration: 2 warm-up steps, then the median of ``--steps``,
side by side in one run, torch on ``--threads`` threads.

Run: ``uv run python benchmarks/image_train_step.py [--sizes 64,80,128] [--cameras 2] [--batches 8,32]``.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sizes", default="64,80,128", help="image sides, px")
    parser.add_argument("--cameras", default="2", help="camera counts, comma-separated")
    parser.add_argument("--batches", default="8,32")
    parser.add_argument("--steps", type=int, default=5)
    parser.add_argument("--threads", type=int, default=2)
    args = parser.parse_args()
    import torch
    from lerobot.configs.types import FeatureType, PolicyFeature
    from lerobot.policies.act.configuration_act import ACTConfig
    from lerobot.policies.act.modeling_act import ACTPolicy

    torch.set_num_threads(args.threads)
    rows = []
    for cameras in (int(c) for c in args.cameras.split(",")):
        for size in (int(s) for s in args.sizes.split(",")):
            inputs = {"observation.state": PolicyFeature(FeatureType.STATE, (11,))}
            for k in range(cameras):
                inputs[f"observation.images.cam{k}"] = PolicyFeature(FeatureType.VISUAL, (3, size, size))
            config = ACTConfig(device="cpu", push_to_hub=False, pretrained_backbone_weights=None, dim_model=128,
                               dim_feedforward=512, n_heads=4, n_encoder_layers=4, n_decoder_layers=1, chunk_size=20,
                               n_action_steps=10, use_vae=True, latent_dim=32, n_vae_encoder_layers=4,
                               input_features=inputs,
                               output_features={"action": PolicyFeature(FeatureType.ACTION, (7,))})
            policy = ACTPolicy(config).train()
            optimiser = torch.optim.AdamW(policy.parameters(), lr=1e-4, weight_decay=1e-4)
            for batch_size in (int(b) for b in args.batches.split(",")):
                gen = torch.Generator().manual_seed(0)
                batch = {key: torch.randn((batch_size, *f.shape), generator=gen) for key, f in inputs.items()}
                batch["action"] = torch.randn((batch_size, 20, 7), generator=gen)
                batch["action_is_pad"] = torch.zeros((batch_size, 20), dtype=torch.bool)
                times = []
                for k in range(2 + args.steps):
                    start = time.perf_counter()
                    loss, _ = policy.forward(batch)
                    optimiser.zero_grad()
                    loss.backward()
                    optimiser.step()
                    if k >= 2:
                        times.append(time.perf_counter() - start)
                rows.append((cameras, size, batch_size, statistics.median(times)))
    print(f"CPU cores: {os.cpu_count()}, torch {torch.__version__} on {args.threads} threads; ACT (ResNet-18, "
          "random weights), the robot's state and the cameras")
    print(f"{'cameras':>7} {'px':>5} {'batch':>6} {'s/step':>8} {'ms/sample':>10} {'steps/h':>8}")
    for cameras, size, batch_size, seconds in rows:
        print(f"{cameras:>7} {size:>5} {batch_size:>6} {seconds:>8.3f} {1e3 * seconds / batch_size:>10.1f} "
              f"{3600 / seconds:>8.0f}")


if __name__ == "__main__":
    main()
