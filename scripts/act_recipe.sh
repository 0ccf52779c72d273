# The ACT recipe's pinned flags (docs/policies.md), sourced by scripts/policy_experiment.sh and
# scripts/joints_ablation.sh: one definition of the state-only policy every comparison trains.
# shellcheck disable=SC2034
ACT=(--policy.type=act --policy.dim_model=128 --policy.dim_feedforward=512 --policy.n_heads=4
     --policy.n_encoder_layers=4 --policy.n_decoder_layers=1 --policy.chunk_size=20 --policy.n_action_steps=10
     --policy.optimizer_lr=1e-4 --policy.optimizer_weight_decay=1e-4 --policy.kl_weight=10.0 --policy.dropout=0.1
     --policy.use_vae=true --policy.latent_dim=32 --policy.n_vae_encoder_layers=4
     --policy.normalization_mapping='{"VISUAL": "MEAN_STD", "STATE": "MEAN_STD", "ENV": "MEAN_STD", "ACTION": "MEAN_STD"}')
