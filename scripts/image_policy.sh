#!/usr/bin/env bash
# issue 54's image policy, as pre-registered in docs/policies.md ("Pre-registered: an image policy without the
# simulator's state"): the 360 planned demonstrations on the train split's drawers with both MuJoCo cameras at 64 px
# and no observation.environment_state (examples/policies/planned-360-pixels.yaml) -> the ACT recipe
# (scripts/act_recipe.sh) with a ResNet-18 from scratch and LeRobot's image transforms (random affine shifts and
# colour jitter), SEEDS training seeds -> every saved fifth of the run on the validation split (the learning curve)
# -> the step with the most successes there, pooled over the seeds -> the drawers' test protocol, once.
#
#   bash scripts/image_policy.sh [WORK_DIR]          (default experiments/pixels; each step skips finished work)
#
# Full size: the defaults (about 2 x 2.9 CPU-hours of training at 0.51 s a step on 2 cores, one at a time, plus
# data loading; minutes on a GPU: DEVICE=cuda LOADERS=8). Reduced size, the same pipeline end to end (its rates are
# noise: it checks the pipeline, not the result):
#   DEMOS=9 STEPS=40 SEEDS="0" VAL_PER_CELL=1 PER_CELL=1 EPISODE_LENGTH=100 bash scripts/image_policy.sh \
#     experiments/pixels-small
set -euo pipefail
WORK=${1:-experiments/pixels}
DEMOS=${DEMOS:-360}            # drawn demonstrations (seeds 0..DEMOS-1)
STEPS=${STEPS:-20000}          # training steps; a checkpoint every STEPS/5
SEEDS=${SEEDS:-0 1}            # training seeds
BATCH=${BATCH:-32}
VAL_PER_CELL=${VAL_PER_CELL:-5}  # validation episodes per handle type x preset cell (seeds 3000..)
PER_CELL=${PER_CELL:-10}       # test episodes per cell (seeds 1000..): the protocol's at full size
EPISODE_LENGTH=${EPISODE_LENGTH:-400}
WORKERS=${WORKERS:-2}
DEVICE=${DEVICE:-cpu}
LOADERS=${LOADERS:-0}          # lerobot-train's --num_workers
STAGES=${STAGES:-data train val test}
export HF_HUB_OFFLINE=1 MUJOCO_GL=${MUJOCO_GL:-egl}
REPO=$(pwd)
RIK=(uv run --project "$REPO" --locked rik)
source "$REPO/scripts/act_recipe.sh"
source "$REPO/scripts/policy_folders.sh"  # checkpoint
mkdir -p "$WORK/specs"
cd "$WORK"
stage() { [[ " $STAGES " == *" $1 "* ]]; }
steps() { local k; for k in 1 2 3 4 5; do echo $(( STEPS * k / 5 )); done; }  # the candidates: each saved fifth
runs() { local seed; for seed in $SEEDS; do echo "act-px-s$seed"; done; }
run_of() { basename "$(dirname "$(dirname "$(dirname "$1")")")"; }  # runs/RUN/checkpoints/STEP/pretrained_model -> RUN
evaluate() {  # evaluate SPLIT SEED PER_CELL OUT POLICY...: one rik eval of several policies on one draw
  local split=$1 seed=$2 per_cell=$3 out=$4 labels=() p
  shift 4
  [ -f "$out/table.md" ] && return 0
  for p in "$@"; do labels+=(--label "$(run_of "$p")"); done
  "${RIK[@]}" eval "$@" "${labels[@]}" --out "$out" --split "$split" --kinds drawer --seed "$seed" \
    --episodes-per-cell "$per_cell" --episode-length "$EPISODE_LENGTH" --videos 0 --workers "$WORKERS" > "$out.log" 2>&1
}

if stage data; then
  sed -E -e "s/^  draw: 360( |$)/  draw: $DEMOS\1/" "$REPO/examples/policies/planned-360-pixels.yaml" > specs/px.yaml
  [ -d ds-px ] || "${RIK[@]}" dataset build specs/px.yaml --out ds-px --work work-px --variants variants -j "$WORKERS"
fi

if stage train; then
  for run in $(runs); do
    seed=${run##*-s}
    last="runs/$run/checkpoints/last/pretrained_model"
    if [ -f "runs/$run/checkpoints/$(printf '%06d' "$STEPS")/pretrained_model/model.safetensors" ]; then continue; fi
    if [ -f "$last/model.safetensors" ]; then  # a run a session left unfinished: on from its last checkpoint
      uv run --project "$REPO" --locked lerobot-train --config_path="$last/train_config.json" --resume=true \
        --steps="$STEPS" > "train-$run-resume-$(date +%s).log" 2>&1
      continue
    fi
    rm -rf "runs/$run"
    uv run --project "$REPO" --locked lerobot-train --dataset.repo_id=local/rik-px --dataset.root=ds-px \
      --policy.push_to_hub=false --policy.device="$DEVICE" --steps="$STEPS" --batch_size="$BATCH" --log_freq=100 \
      --save_freq=$(( STEPS / 5 > 1 ? STEPS / 5 : 1 )) --env_eval_freq=1000000 --output_dir="runs/$run" \
      --wandb.enable=false --num_workers="$LOADERS" --seed="$seed" "${ACT[@]}" \
      --policy.pretrained_backbone_weights=null --dataset.image_transforms.enable=true > "train-$run.log" 2>&1
  done
fi

if stage val; then
  mkdir -p eval/val
  for step in $(steps); do
    folders=()
    for run in $(runs); do folders+=("$(checkpoint "$run" "$step")"); done
    evaluate val 3000 "$VAL_PER_CELL" "eval/val/step-$step" "${folders[@]}"
  done
  # the learning curve (Wilson intervals, pooled over the seeds and per seed) and the choice: the step with the most
  # successes pooled over the seeds; ties to the earlier step
  uv run --project "$REPO" --locked python - $(steps) > chosen.txt <<'PY'
import csv, glob, sys
from rik.tables import rate_text
best, best_s, lines = None, -1, ["| step | pooled | per seed |", "|---:|---|---|"]
for step in sys.argv[1:]:
    # one policy's episodes.csv lies in the evaluation's folder, several policies' each in its label's folder
    files = sorted(glob.glob(f"eval/val/step-{step}/**/episodes.csv", recursive=True))
    rows = [row for f in files for row in csv.DictReader(open(f))]
    if not rows:
        sys.exit(f"image_policy.sh: no episodes of step {step} in eval/val/step-{step}")
    s = sum(row["outcome"] == "S" for row in rows)
    seeds = sorted({row["strategy"] for row in rows})
    per = "; ".join(f"{k}: {rate_text(sum(r['outcome'] == 'S' for r in rows if r['strategy'] == k), sum(r['strategy'] == k for r in rows))}"
                    for k in seeds)
    lines.append(f"| {step} | {rate_text(s, len(rows))} | {per} |")
    if s > best_s:
        best, best_s = step, s
open("eval/val/curve.md", "w").write("\n".join(lines) + "\n")
print(best)
PY
  echo "learning curve: eval/val/curve.md; chosen on the validation split: step $(cat chosen.txt)"
fi

if stage test; then
  [ -s chosen.txt ] || { echo "image_policy.sh: no choice on the validation split yet (chosen.txt)" >&2; exit 1; }
  chosen=$(cat chosen.txt)
  folders=()
  for run in $(runs); do folders+=("$(checkpoint "$run" "$chosen")"); done
  out="eval/test/step-$chosen"
  mkdir -p eval/test
  if [ "$PER_CELL" = 10 ] && [ "$EPISODE_LENGTH" = 400 ]; then  # the full size: the committed protocol, exactly
    if [ ! -f "$out/table.md" ]; then
      labels=()
      for p in "${folders[@]}"; do labels+=(--label "$(run_of "$p")"); done
      "${RIK[@]}" eval "${folders[@]}" "${labels[@]}" --out "$out" --videos 4 --workers "$WORKERS" \
        --protocol "$REPO/protocols/drawers-test-v1.yaml" > "$out.log" 2>&1
    fi
  else
    evaluate test 1000 "$PER_CELL" "$out" "${folders[@]}"
  fi
  echo "test evaluation: $out"
fi
