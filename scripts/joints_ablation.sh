#!/usr/bin/env bash
# The pre-registered joints ablation of docs/policies.md ("Pre-registered: real doors' joints against the paper's
# presets"): the same planned demonstrations on the train split's drawers, doors and flaps, recorded (a) with the
# paper's presets and (b) with the train split's real doors on the doors -> state-only ACT (scripts/act_recipe.sh),
# SEEDS training seeds per arm -> every candidate (single checkpoints and the mean of the last quarter, n_action_steps
# 15) on the validation split, both joints -> the one candidate with the most successes there, pooled over every run
# and both joints -> the test split, both joints, once -> docs/policies/joints/ (the report stage).
#
#   bash scripts/joints_ablation.sh [WORK_DIR]          (default experiments/joints; each step skips finished work)
#
# Full size (the plan): the defaults, about 6 x 2.2 CPU-hours of training on 2 cores, two at a time (JOBS=2).
# Reduced size, the same pipeline end to end (its rates are noise: it checks the pipeline, not the result):
#   DEMOS=27 STEPS=120 SEEDS="0" VAL_PER_CELL=1 PER_CELL=1 EPISODE_LENGTH=200 bash scripts/joints_ablation.sh \
#     experiments/joints-small
# STAGES picks the stages (default "data train val test"). The val stage evaluates each run as soon as its training
# has finished (so it may run beside the last trainings) and makes the choice once every run is evaluated.
# Every choice is made on the validation split; the test
# stage refuses to run before the choice is written (chosen.txt) and runs each evaluation once (it skips a folder
# that holds one); at full size it runs the committed protocols (protocols/fronts-measured-test-v1.yaml and
# fronts-paper-test-v1.yaml) with rik eval --protocol.
# The publish stage (not in the default STAGES: it writes into the repository) copies the published policy, chosen on
# the validation split (the (b) run whose chosen candidate has the most validation successes over both draws, ties
# to the lower seed), to PUBLISH (default docs/policies/joints/best): weights, config, processors and rik's contract,
# no optimizer state. It refuses to replace a folder that is already there.
set -euo pipefail
WORK=${1:-experiments/joints}
DEMOS=${DEMOS:-540}            # drawn demonstrations per arm (60 per handle type x preset cell), seeds 0..DEMOS-1
STEPS=${STEPS:-40000}          # training steps; a checkpoint every STEPS/40
SEEDS=${SEEDS:-0 1 2}          # training seeds of each arm
VAL_PER_CELL=${VAL_PER_CELL:-5}  # validation episodes per cell (seeds 3000..), per joints
PER_CELL=${PER_CELL:-10}       # test episodes per cell (seeds 1000..), per joints
EPISODE_LENGTH=${EPISODE_LENGTH:-400}
WORKERS=${WORKERS:-2}
JOBS=${JOBS:-2}                # trainings at once
STAGES=${STAGES:-data train val test}
PUBLISH=$(realpath -m "${PUBLISH:-docs/policies/joints/best}")  # where the publish stage puts the published policy
KINDS=drawer,door,flap
ARMS=(jp jm)                   # jp: the paper's presets; jm: the train split's real doors on the doors
export HF_HUB_OFFLINE=1 MUJOCO_GL=${MUJOCO_GL:-egl} OMP_NUM_THREADS=1 MKL_NUM_THREADS=1
REPO=$(pwd)
RIK=(uv run --project "$REPO" --locked rik)
source "$REPO/scripts/act_recipe.sh"
source "$REPO/scripts/policy_folders.sh"  # chunked, checkpoint, failed
mkdir -p "$WORK/specs"
cd "$WORK"
stage() { [[ " $STAGES " == *" $1 "* ]]; }
spec_of() { case $1 in jp) echo joints-paper ;; jm) echo joints-measured ;; esac; }
candidates() {  # the candidates of a run, in the order that breaks ties: the mean of the last quarter's weights,
  # then single checkpoints from the last back (each evaluated with 15 actions per prediction)
  echo "mean $STEPS $(( STEPS * 3 / 4 )) $(( STEPS / 2 ))"
}
policy() {  # policy RUN CANDIDATE: the folder of a candidate's weights, with n_action_steps 15 (made once)
  local out="policies/$1-$2"
  if [ ! -d "$out" ]; then
    local from
    if [ "$2" = mean ]; then
      from="averaged/$1"
      [ -f "$from/model.safetensors" ] || uv run --project "$REPO" --locked python "$REPO/scripts/average_checkpoints.py" \
        "runs/$1" --from $(( STEPS * 3 / 4 )) --to "$STEPS" --out "$from" > /dev/null
    else
      from=$(checkpoint "$1" "$2")
    fi
    chunked "$from" "$out" 15
  fi
  echo "$out"
}
trained() {  # trained RUN: whether the run has trained its STEPS (a checkpoint at the last step)
  local last="runs/$1/checkpoints/last/pretrained_model"
  [ -f "$last/train_config.json" ] && [ -f "runs/$1/checkpoints/$(printf '%06d' "$STEPS")/pretrained_model/model.safetensors" ] \
    && [ "$(python3 -c 'import json, sys; print(json.load(open(sys.argv[1]))["steps"])' "$last/train_config.json")" \
      -ge "$STEPS" ]
}
evaluate() {  # evaluate SPLIT SEED PER_CELL JOINTS OUT POLICY...: one rik eval of several policies on one draw
  local split=$1 seed=$2 per_cell=$3 joints=$4 out=$5 labels=() p
  shift 5
  [ -f "$out/table.md" ] && return 0
  for p in "$@"; do labels+=(--label "$(basename "$p")"); done
  "${RIK[@]}" eval "$@" "${labels[@]}" --out "$out" --split "$split" --kinds "$KINDS" --joints "$joints" \
    --seed "$seed" --episodes-per-cell "$per_cell" --episode-length "$EPISODE_LENGTH" --videos 0 --workers "$WORKERS" \
    > "$out.log" 2>&1 || failed "$out.log"
}

if stage data; then
  for arm in "${ARMS[@]}"; do
    sed -E -e "s/^  draw: 540( |$)/  draw: $DEMOS\1/" "$REPO/examples/policies/$(spec_of "$arm").yaml" > "specs/$arm.yaml"
    [ -d "ds-$arm" ] || "${RIK[@]}" dataset build "specs/$arm.yaml" --out "ds-$arm" --work "work-$arm" \
      --variants variants -j "$WORKERS"
  done
fi

if stage train; then
  pids=()
  # seed by seed, both arms each (jp s0, jm s0, jp s1, ...): a session that ends early leaves whole pairs, not one arm
  for seed in $SEEDS; do
    for arm in "${ARMS[@]}"; do
      run="act-$arm-s$seed"
      last="runs/$run/checkpoints/last/pretrained_model"
      if [ -f "$last/model.safetensors" ]; then
        trained "$run" && continue
        while [ "$(jobs -rp | wc -l)" -ge "$JOBS" ]; do sleep 1; done
        # a run a session left unfinished: on from its last checkpoint (its optimizer state, data order and flags)
        uv run --project "$REPO" --locked lerobot-train --config_path="$last/train_config.json" --resume=true \
          --steps="$STEPS" > "train-$run-resume-$(date +%s).log" 2>&1 &
        pids+=($!)
        continue
      fi
      while [ "$(jobs -rp | wc -l)" -ge "$JOBS" ]; do sleep 1; done
      rm -rf "runs/$run"
      uv run --project "$REPO" --locked lerobot-train --dataset.repo_id="local/rik-$arm" --dataset.root="ds-$arm" \
        --policy.push_to_hub=false --policy.device=cpu --steps="$STEPS" --batch_size=32 --log_freq=500 \
        --save_freq=$(( STEPS / 40 > 1 ? STEPS / 40 : 1 )) --env_eval_freq=1000000 --output_dir="runs/$run" \
        --wandb.enable=false --num_workers=0 --seed="$seed" "${ACT[@]}" > "train-$run.log" 2>&1 &
      pids+=($!)
    done
  done
  for pid in "${pids[@]}"; do
    wait "$pid" || { echo "joints_ablation.sh: a training failed (its log: train-act-*.log in $PWD)" >&2; exit 1; }
  done
fi

RUNS=()
for arm in "${ARMS[@]}"; do for seed in $SEEDS; do RUNS+=("act-$arm-s$seed"); done; done

if stage val; then
  # run by run, each candidate on both draws into eval/val/CANDIDATE-JOINTS/RUN-CANDIDATE: a run is evaluated as soon
  # as its training has finished (the same episodes as evaluated beside the other runs: the draw fixes them), so the
  # stage may run while the last trainings go on; the choice waits for every run
  waiting=()
  for run in "${RUNS[@]}"; do
    trained "$run" || { waiting+=("$run"); continue; }
    for candidate in $(candidates); do
      folder=$(policy "$run" "$candidate")
      for joints in paper measured; do
        mkdir -p "eval/val/$candidate-$joints"
        evaluate val 3000 "$VAL_PER_CELL" "$joints" "eval/val/$candidate-$joints/$run-$candidate" "$folder"
      done
    done
  done
  if [ ${#waiting[@]} -gt 0 ]; then
    echo "joints_ablation.sh: not trained yet: ${waiting[*]}; the choice waits for their validation (run STAGES=val" \
      "again when they have finished)" >&2
    exit 1
  fi
  # the choice: the candidate with the most successes over every run and both joints; ties to the earlier listed
  python3 - $(candidates) > chosen.txt <<'PY'
import csv, glob, sys
best, best_s = None, -1
for candidate in sys.argv[1:]:
    s = sum(row["outcome"] == "S" for f in glob.glob(f"eval/val/{candidate}-*/*/episodes.csv")
            for row in csv.DictReader(open(f)))
    print(f"# {candidate}: {s} successes", file=sys.stderr)
    if s > best_s:
        best, best_s = candidate, s
print(best)
PY
  echo "chosen on the validation split: $(cat chosen.txt)"
fi

if stage test; then
  [ -s chosen.txt ] || { echo "joints_ablation.sh: no choice on the validation split yet (chosen.txt)" >&2; exit 1; }
  chosen=$(cat chosen.txt)
  folders=()
  for run in "${RUNS[@]}"; do folders+=("$(policy "$run" "$chosen")"); done
  mkdir -p eval/test
  for joints in measured paper; do
    out="eval/test/$chosen-$joints"
    if [ "$PER_CELL" = 10 ] && [ "$EPISODE_LENGTH" = 400 ]; then  # the full size: the committed protocol, exactly
      [ -f "$out/table.md" ] && continue
      labels=()
      for p in "${folders[@]}" strategy:planned; do labels+=(--label "$(basename "$p")"); done
      "${RIK[@]}" eval "${folders[@]}" strategy:planned "${labels[@]}" --out "$out" --videos 0 --workers "$WORKERS" \
        --protocol "$REPO/protocols/fronts-$joints-test-v1.yaml" > "$out.log" 2>&1 || failed "$out.log"
    else
      evaluate test 1000 "$PER_CELL" "$joints" "$out" "${folders[@]}" "strategy:planned"
    fi
  done
  echo "test evaluations: eval/test/$chosen-measured, eval/test/$chosen-paper"
fi

if stage publish; then
  [ -s chosen.txt ] || { echo "joints_ablation.sh: no choice on the validation split yet (chosen.txt)" >&2; exit 1; }
  chosen=$(cat chosen.txt)
  [ -e "$PUBLISH" ] && { echo "joints_ablation.sh: $PUBLISH is already there; not replaced" >&2; exit 1; }
  # the (b) run with the most validation successes of the chosen candidate, both draws pooled; ties to the lower seed
  run=$(python3 - "$chosen" $SEEDS <<'PY'
import csv, sys
chosen, seeds = sys.argv[1], sys.argv[2:]
def successes(seed):
    return sum(row["outcome"] == "S" for joints in ("measured", "paper")
               for row in csv.DictReader(open(f"eval/val/{chosen}-{joints}/act-jm-s{seed}-{chosen}/episodes.csv")))
counts = {seed: successes(seed) for seed in seeds}
for seed, n in counts.items():
    print(f"# act-jm-s{seed}-{chosen}: {n} validation successes", file=sys.stderr)
print(f"act-jm-s{max(seeds, key=lambda s: (counts[s], -int(s)))}")
PY
)
  from=$(policy "$run" "$chosen")
  mkdir -p "$(dirname "$PUBLISH")"
  rm -rf "$PUBLISH.tmp"
  mkdir "$PUBLISH.tmp"
  cp "$from"/config.json "$from"/model.safetensors "$from"/policy_*processor*.json "$from"/policy_*.safetensors \
    "$from"/rik_policy_io.json "$PUBLISH.tmp"/
  printf '%s\n' "$run-$chosen (chosen on the validation split; copied from $WORK/$from)" > "$PUBLISH.tmp/SOURCE.txt"
  mv "$PUBLISH.tmp" "$PUBLISH"
  echo "published: $PUBLISH ($run-$chosen)"
fi
