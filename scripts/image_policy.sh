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
# Which stream teaches better (issue 54, point 4; for a GPU machine: Mitsuba renders the data set and every
# evaluation of the rerendered arm): STREAM=rerendered runs the same plan on Mitsuba's pictures of the same
# demonstrations (its own data set ds-px-rr and runs act-px-rr-s<seed>, its own choice on the validation split),
# and the gap stage evaluates each arm's chosen checkpoints on the test episodes drawn by the other renderer
# (rik eval --renderer): the visual gap a policy pays, both ways. The stage needs both arms' choices:
#   bash scripts/image_policy.sh; STREAM=rerendered bash scripts/image_policy.sh; STAGES=gap bash scripts/image_policy.sh
set -euo pipefail
WORK=${1:-experiments/pixels}
DEMOS=${DEMOS:-360}            # drawn demonstrations (seeds 0..DEMOS-1)
STEPS=${STEPS:-20000}          # training steps; the candidates are every STEPS/5 (save_every saves more often)
SEEDS=${SEEDS:-0 1}            # training seeds
BATCH=${BATCH:-32}
VAL_PER_CELL=${VAL_PER_CELL:-5}  # validation episodes per handle type x preset cell (seeds 3000..)
PER_CELL=${PER_CELL:-10}       # test episodes per cell (seeds 1000..): the protocol's at full size
EPISODE_LENGTH=${EPISODE_LENGTH:-400}
WORKERS=${WORKERS:-2}
DEVICE=${DEVICE:-cpu}
LOADERS=${LOADERS:-0}          # lerobot-train's --num_workers
STAGES=${STAGES:-data train val test}
STREAM=${STREAM:-sim}          # the stream the policy is trained on: sim (MuJoCo) or rerendered (Mitsuba)
case $STREAM in sim) ARM=px ;; rerendered) ARM=px-rr ;; *) echo "image_policy.sh: STREAM=$STREAM: use sim or rerendered" >&2; exit 2 ;; esac
export HF_HUB_OFFLINE=1 MUJOCO_GL=${MUJOCO_GL:-egl}
REPO=$(pwd)
RIK=(uv run --project "$REPO" --locked rik)
source "$REPO/scripts/act_recipe.sh"
source "$REPO/scripts/policy_folders.sh"  # checkpoint, failed
mkdir -p "$WORK/specs"
cd "$WORK"
stage() { [[ " $STAGES " == *" $1 "* ]]; }
steps() { local k; for k in 1 2 3 4 5; do echo $(( STEPS * k / 5 )); done; }  # the candidates: each saved fifth
save_every() {  # lerobot-train's --save_freq: a quarter of a fifth where that divides (a session that ends mid-run
  # loses less; resuming starts at the last save), else the fifth; the candidates stay the fifths
  local fifth=$(( STEPS / 5 > 1 ? STEPS / 5 : 1 ))
  if [ $(( fifth % 4 )) -eq 0 ]; then echo $(( fifth / 4 )); else echo "$fifth"; fi
}
runs() { local seed; for seed in $SEEDS; do echo "act-${1:-$ARM}-s$seed"; done; }  # runs [ARM]
eval_dir() { case ${1:-$ARM} in px) echo eval ;; px-rr) echo eval-rr ;; esac; }  # eval_dir [ARM]: an arm's evaluations
chosen_file() { case ${1:-$ARM} in px) echo chosen.txt ;; px-rr) echo chosen-rr.txt ;; esac; }
chosen_step() {  # chosen_step [ARM]: the step chosen on the validation split
  local file
  file=$(chosen_file "${1:-$ARM}")
  [ -s "$file" ] || { echo "image_policy.sh: no choice on the validation split yet ($file)" >&2; exit 1; }
  cat "$file"
}
EV=$(eval_dir)
run_of() { basename "$(dirname "$(dirname "$(dirname "$1")")")"; }  # runs/RUN/checkpoints/STEP/pretrained_model -> RUN
split_policies() {  # split_policies POLICY... [-- RIK_EVAL_OPTION...]: sets POLICIES, their LABELS (the runs' names)
  # and the OPTIONS after --
  POLICIES=() LABELS=() OPTIONS=()
  while [ $# -gt 0 ] && [ "$1" != -- ]; do POLICIES+=("$1"); LABELS+=(--label "$(run_of "$1")"); shift; done
  [ $# -gt 0 ] && shift
  OPTIONS=("$@")
}
evaluate() {  # evaluate SPLIT SEED PER_CELL OUT POLICY... [-- RIK_EVAL_OPTION...]: one rik eval of several policies on
  # one draw
  local split=$1 seed=$2 per_cell=$3 out=$4
  shift 4
  [ -f "$out/table.md" ] && return 0
  split_policies "$@"
  "${RIK[@]}" eval "${POLICIES[@]}" "${LABELS[@]}" --out "$out" --split "$split" --kinds drawer --seed "$seed" \
    --episodes-per-cell "$per_cell" --episode-length "$EPISODE_LENGTH" --videos 0 --workers "$WORKERS" \
    "${OPTIONS[@]}" > "$out.log" 2>&1 || failed "$out.log"
}
own_renderer() {  # the option an arm's policies need to be drawn by their own renderer: Mitsuba for the rerendered arm
  [ "${1:-$ARM}" = px-rr ] && echo --rerendered
  return 0
}
protocol_eval() {  # protocol_eval OUT POLICY... [-- RIK_EVAL_OPTION...]: the test episodes, once: at full size the
  # committed protocol exactly, otherwise the reduced draw
  local out=$1
  shift
  if [ "$PER_CELL" = 10 ] && [ "$EPISODE_LENGTH" = 400 ]; then
    [ -f "$out/table.md" ] && return 0
    split_policies "$@"
    "${RIK[@]}" eval "${POLICIES[@]}" "${LABELS[@]}" --out "$out" --videos 4 --workers "$WORKERS" \
      --protocol "$REPO/protocols/drawers-test-v1.yaml" "${OPTIONS[@]}" > "$out.log" 2>&1 || failed "$out.log"
  else
    evaluate test 1000 "$PER_CELL" "$out" "$@"
  fi
}

if stage data; then
  sed -E -e "s/^  draw: 360( |$)/  draw: $DEMOS\1/" -e "s/^streams: \[sim\]/streams: [$STREAM]/" \
    -e "s|^repo_id: local/rik-px$|repo_id: local/rik-$ARM|" "$REPO/examples/policies/planned-360-pixels.yaml" \
    > "specs/$ARM.yaml"
  [ -d "ds-$ARM" ] || "${RIK[@]}" dataset build "specs/$ARM.yaml" --out "ds-$ARM" --work "work-$ARM" \
    --variants variants -j "$WORKERS"
fi

if stage train; then
  for run in $(runs); do
    seed=${run##*-s}
    last="runs/$run/checkpoints/last/pretrained_model"
    if [ -f "runs/$run/checkpoints/$(printf '%06d' "$STEPS")/pretrained_model/model.safetensors" ]; then continue; fi
    if [ -f "$last/model.safetensors" ]; then  # a run a session left unfinished: on from its last checkpoint
      log="train-$run-resume-$(date +%s).log"
      uv run --project "$REPO" --locked lerobot-train --config_path="$last/train_config.json" --resume=true \
        --steps="$STEPS" > "$log" 2>&1 || failed "$log"
      continue
    fi
    rm -rf "runs/$run"
    uv run --project "$REPO" --locked lerobot-train --dataset.repo_id="local/rik-$ARM" --dataset.root="ds-$ARM" \
      --policy.push_to_hub=false --policy.device="$DEVICE" --steps="$STEPS" --batch_size="$BATCH" --log_freq=100 \
      --save_freq="$(save_every)" --env_eval_freq=1000000 --output_dir="runs/$run" \
      --wandb.enable=false --num_workers="$LOADERS" --seed="$seed" "${ACT[@]}" \
      --policy.pretrained_backbone_weights=null --dataset.image_transforms.enable=true > "train-$run.log" 2>&1 \
      || failed "train-$run.log"
  done
fi

if stage val; then
  mkdir -p "$EV/val"
  for step in $(steps); do
    folders=()
    for run in $(runs); do folders+=("$(checkpoint "$run" "$step")"); done
    evaluate val 3000 "$VAL_PER_CELL" "$EV/val/step-$step" "${folders[@]}" -- $(own_renderer)
  done
  # the learning curve (Wilson intervals, pooled over the seeds and per seed) and the choice: the step with the most
  # successes pooled over the seeds; ties to the earlier step
  uv run --project "$REPO" --locked python - "$EV" $(steps) > "$(chosen_file)" <<'PY'
import csv, glob, sys
from rik.tables import rate_text
ev, steps = sys.argv[1], sys.argv[2:]
best, best_s, lines = None, -1, ["| step | pooled | per seed |", "|---:|---|---|"]
for step in steps:
    # one policy's episodes.csv lies in the evaluation's folder, several policies' each in its label's folder
    files = sorted(glob.glob(f"{ev}/val/step-{step}/**/episodes.csv", recursive=True))
    rows = [row for f in files for row in csv.DictReader(open(f))]
    if not rows:
        sys.exit(f"image_policy.sh: no episodes of step {step} in {ev}/val/step-{step}")
    s = sum(row["outcome"] == "S" for row in rows)
    seeds = sorted({row["strategy"] for row in rows})
    per = "; ".join(f"{k}: {rate_text(sum(r['outcome'] == 'S' for r in rows if r['strategy'] == k), sum(r['strategy'] == k for r in rows))}"
                    for k in seeds)
    lines.append(f"| {step} | {rate_text(s, len(rows))} | {per} |")
    if s > best_s:
        best, best_s = step, s
open(f"{ev}/val/curve.md", "w").write("\n".join(lines) + "\n")
print(best)
PY
  echo "learning curve: $EV/val/curve.md; chosen on the validation split: step $(cat "$(chosen_file)")"
fi

if stage test; then
  chosen=$(chosen_step)
  folders=()
  for run in $(runs); do folders+=("$(checkpoint "$run" "$chosen")"); done
  mkdir -p "$EV/test"
  protocol_eval "$EV/test/step-$chosen" "${folders[@]}" -- $(own_renderer)
  echo "test evaluation: $EV/test/step-$chosen"
fi

if stage gap; then  # each arm's chosen checkpoints on the test episodes drawn by the other renderer: the visual gap
  for arm in px px-rr; do
    case $arm in px) other=rerendered ;; px-rr) other=sim ;; esac
    chosen=$(chosen_step "$arm")
    folders=()
    for run in $(runs "$arm"); do folders+=("$(checkpoint "$run" "$chosen")"); done
    out="$(eval_dir "$arm")/test/step-$chosen-drawn-by-$other"
    mkdir -p "$(dirname "$out")"
    protocol_eval "$out" "${folders[@]}" -- --renderer "$other"
    echo "the visual gap of $arm: $out against $(eval_dir "$arm")/test/step-$chosen"
  done
fi
