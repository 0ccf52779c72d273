#!/usr/bin/env bash
# The experiment of docs/policies.md: scripted demonstrations on the train split -> state-only LeRobot datasets ->
# ACT and diffusion trained with lerobot-train on the CPU -> evaluated with rik eval on the test split (unseen
# handles) and on fresh episodes of the train split (seen handles), beside the scripted strategies on the same
# episodes; and the fidelity ablation: the same demonstrations recorded with convex-hull handle collision.
#
#   bash scripts/policy_experiment.sh [WORK_DIR]     (default: experiments/policies; each step skips finished work)
#
# Scale it with the variables below: DEMOS demonstrations per strategy (a multiple of 9: handle types x presets),
# STEPS training steps, PER_CELL evaluated episodes per handle type x preset. On 2 CPU cores the defaults take
# about 90 minutes; on a GPU machine add --policy.device=cuda and train on images (--streams sim, --env.cameras).
set -euo pipefail
WORK=${1:-experiments/policies}
DEMOS=${DEMOS:-90}
STEPS=${STEPS:-3000}
PER_CELL=${PER_CELL:-10}
WORKERS=${WORKERS:-2}
# one thread per process: training and evaluations beside each other otherwise fight over the cores
export HF_HUB_OFFLINE=1 MUJOCO_GL=${MUJOCO_GL:-egl} OMP_NUM_THREADS=1
REPO=$(pwd)
RIK=(uv run --project "$REPO" --locked rik)
mkdir -p "$WORK"
cd "$WORK"

record() {  # record NAME STRATEGY VARIANTS_DIR
  [ -d "demos-$1" ] || "${RIK[@]}" record --split train --strategy "$2" --episodes "$DEMOS" --seed 0 \
    --out "demos-$1" --variants "$3" --workers "$WORKERS"
}
export_ds() {  # export_ds NAME VARIANTS_DIR [EPISODE_FOLDERS...]: successful demonstrations, state only
  local name=$1 variants=$2; shift 2
  [ -d "ds-$name" ] && return
  mkdir -p "sel-$name"
  for d in "$@"; do
    if grep -q '"outcome": "S"' "$d/meta.json"; then ln -sfn "$(realpath "$d")" "sel-$name/$(basename "$d")"; fi
  done
  "${RIK[@]}" export-lerobot "sel-$name" --out "ds-$name" --repo-id "local/rik-$name" --streams none \
    --variants "$variants"
}
train() {  # train NAME DATASET act|diffusion [SEED]
  [ -f "runs/$1/checkpoints/last/pretrained_model/model.safetensors" ] && return
  rm -rf "runs/$1"
  local common=(--dataset.repo_id="local/rik-$2" --dataset.root="ds-$2" --policy.push_to_hub=false
                --policy.device=cpu --steps="$STEPS" --batch_size=32 --log_freq=200 --save_freq="$STEPS"
                --env_eval_freq=1000000 --output_dir="runs/$1" --wandb.enable=false --num_workers=0 --seed="${4:-0}")
  if [ "$3" = act ]; then
    uv run --project "$REPO" --locked lerobot-train "${common[@]}" --policy.type=act --policy.dim_model=128 \
      --policy.dim_feedforward=512 --policy.n_heads=4 --policy.chunk_size=20 --policy.n_action_steps=10 \
      --policy.optimizer_lr=1e-4 \
      --policy.normalization_mapping='{"VISUAL": "MEAN_STD", "STATE": "MEAN_STD", "ENV": "MEAN_STD", "ACTION": "MEAN_STD"}'
  else
    uv run --project "$REPO" --locked lerobot-train "${common[@]}" --policy.type=diffusion \
      --policy.down_dims='[64, 128, 256]' --policy.horizon=16 --policy.n_action_steps=8 --policy.n_obs_steps=2 \
      --policy.noise_scheduler_type=DDIM --policy.num_inference_steps=10 \
      --policy.normalization_mapping='{"VISUAL": "MEAN_STD", "STATE": "MIN_MAX", "ENV": "MIN_MAX", "ACTION": "MIN_MAX"}'
  fi
}
evaluate() {  # evaluate OPERATOR LABEL SPLIT SEED
  [ -f "eval/$2-$3/eval_info.json" ] || "${RIK[@]}" eval "$1" --label "$2" --split "$3" --seed "$4" \
    --episodes-per-cell "$PER_CELL" --videos 2 --workers "$WORKERS" --out "eval/$2-$3" --variants variants
}

# 1. demonstrations (CoACD collision; and convex-hull collision, whose rejected variants are skipped)
record cr contact_rich variants
record gv grasp_vertical variants
[ -f variants-hull/collision.json ] || "${RIK[@]}" variants build drawer-chest-80__two_point-bow-128__normal \
  --collision hull --out variants-hull
record cr-hull contact_rich variants-hull
# 2. state-only datasets of the successful demonstrations; cr72: the CoACD demonstrations of the seeds that also
#    succeeded with hull collision (the same episodes, so the ablation compares collision, not data size)
export_ds cr variants demos-cr/*
export_ds gv variants demos-gv/*
export_ds hull variants-hull demos-cr-hull/*
matched=(); for d in demos-cr-hull/*; do
  grep -q '"outcome": "S"' "$d/meta.json" && matched+=("demos-cr/$(basename "$d")"); done
export_ds cr72 variants "${matched[@]}"
# 3. training (timed)
for job in "act-cr cr act" "act-gv gv act" "act-hull hull act" "act-cr72 cr72 act" "dp-cr cr diffusion" \
           "act-hull-s1 hull act 1" "act-cr72-s1 cr72 act 1"; do
  set -- $job
  start=$SECONDS
  if [ ! -f "runs/$1/checkpoints/last/pretrained_model/model.safetensors" ]; then
    train "$1" "$2" "$3" "${4:-0}" > "train-$1.log" 2>&1
    echo "$1 $((SECONDS - start)) s" >> train-times.txt
  fi
done
# 4. evaluation: unseen handles (test split) and seen handles (train split, seeds the demonstrations did not use)
for split_seed in "test 1000" "train 5000"; do
  set -- $split_seed
  evaluate strategy:contact_rich contact_rich "$1" "$2"
  evaluate strategy:grasp_vertical grasp_vertical "$1" "$2"
  for run in act-cr act-gv act-hull act-cr72 dp-cr act-hull-s1 act-cr72-s1; do
    evaluate "runs/$run/checkpoints/last/pretrained_model" "$run" "$1" "$2"
  done
done
# (docs/policies.md evaluates the train split with 5 episodes per cell, for the scripted strategies, act-cr and act-gv)
