#!/usr/bin/env bash
# The experiment of docs/policies.md: demonstrations built from the specs of examples/policies (the planned
# strategy, whose grasps come from the catalog's visual meshes; with and without DART-style action noise; in CoACD
# and convex-hull collision variants; in joints that hold and joints that creep) -> state-only LeRobot datasets ->
# ACT trained with lerobot-train on the CPU, a checkpoint every STEPS/30 steps -> every chosen checkpoint evaluated
# with rik eval on the test split (unseen handles) beside the scripted strategy on the same episodes -> learning
# curves and tables (scripts/policy_curves.py).
#
#   bash scripts/policy_experiment.sh [WORK_DIR]     (default: experiments/policies; each step skips finished work)
#
# Full size (docs/policies.md; tens of CPU-hours on 2 cores): the defaults. Reduced size, the same pipeline end to
# end (every data set, training and evaluation; docs/policies.md gives its measured time), two steps at once:
#   DEMOS=18 STEPS=180 SHORT_STEPS=45 PER_CELL=1 EPISODE_LENGTH=200 JOBS=2 WORKERS=1 VIDEOS=0 \
#     bash scripts/policy_experiment.sh experiments/policies-small
# STAGES picks the stages to run (default "data train eval report"), DATASETS the data sets of the data stage, SEED
# the first drawn seed (tests/test_policy_experiment.py runs the data stage at DEMOS=2 SEED=378). IMAGES=1 adds the
# image run (both cameras at 80x80; on a GPU machine: IMAGES=1 DEVICE=cuda LOADERS=12). JOBS runs that many
# independent steps at once (data sets after the first, trainings; the evaluations of the same episodes are dealt
# out to JOBS rik eval processes, many policies each; default 1: one after another).
# Every hyper-parameter of the training is pinned below; one thread per process, so two trainings share 2 cores.
set -euo pipefail
WORK=${1:-experiments/policies}
DEMOS=${DEMOS:-360}            # drawn demonstrations per data set (40 per handle type x preset cell)
SEED=${SEED:-0}                # the first drawn seed: the data sets hold seeds SEED .. SEED+DEMOS-1
STEPS=${STEPS:-30000}          # training steps of the main run (act-pl); act-pl-quarter trains STEPS/3
SHORT_STEPS=${SHORT_STEPS:-5000}  # steps of the comparison runs (DART, hull, matched CoACD), two seeds each
PER_CELL=${PER_CELL:-10}       # evaluated episodes per handle type x preset cell (9 cells)
WORKERS=${WORKERS:-2}          # rik's worker processes per recording or evaluation
JOBS=${JOBS:-1}                # independent steps at once (with JOBS=2 on 2 cores, set WORKERS=1)
VIDEOS=${VIDEOS:-2}            # videos each evaluation keeps (rendering them is most of a small evaluation's time)
EPISODE_LENGTH=${EPISODE_LENGTH:-400}  # control steps before an evaluated episode is cut off (20 per second)
STAGES=${STAGES:-data train eval report}
DATASETS=${DATASETS:-pl pl-quarter pln hull cm plh pla plah pls plk plt plg plgc plgh}  # the data sets the data stage builds
IMAGES=${IMAGES:-0}            # 1: also the image run (pl-images: both 80x80 cameras; train it where a GPU is)
DEVICE=${DEVICE:-cpu}          # lerobot-train's --policy.device (cuda on a GPU machine)
LOADERS=${LOADERS:-0}          # lerobot-train's --num_workers (data-loading processes; 12 for images on a GPU)
if [ "$IMAGES" = 1 ]; then DATASETS="$DATASETS pl-images"; fi
export HF_HUB_OFFLINE=1 MUJOCO_GL=${MUJOCO_GL:-egl} OMP_NUM_THREADS=1 MKL_NUM_THREADS=1
REPO=$(pwd)
RIK=(uv run --project "$REPO" --locked rik)
mkdir -p "$WORK/specs"
cd "$WORK"
stage() { [[ " $STAGES " == *" $1 "* ]]; }
PIDS=()
declare -A SPAWNED=()
spawn() {  # spawn COMMAND...: a step that depends on no other step of its phase; JOBS of them at once (a command
  # asked for twice, as small sizes' windows and steps can coincide, runs once)
  local key="${*@Q}"
  [ -z "${SPAWNED[$key]:-}" ] || return 0
  SPAWNED[$key]=1
  if [ "$JOBS" -le 1 ]; then "$@"; return; fi
  while [ "$(jobs -rp | wc -l)" -ge "$JOBS" ]; do sleep 0.2; done
  "$@" &
  PIDS+=($!)
}
settle() {  # wait for every spawned step; stop if one failed (each step's log says why)
  local pid failed=0
  for pid in "${PIDS[@]}"; do wait "$pid" || failed=1; done
  PIDS=()
  [ "$failed" = 0 ] || { echo "policy_experiment.sh: a step failed (see the logs in $PWD)" >&2; exit 1; }
}

build() {  # build NAME SPEC VARIANTS [DRAW]: a spec of examples/policies at DEMOS (or DRAW) drawn episodes from SEED
  [[ " $DATASETS " == *" $1 "* ]] || return 0
  local spec="specs/$1.yaml"
  sed -E -e "s/^  draw: 360( |$)/  draw: ${4:-$DEMOS}\1/" -e "s|^repo_id: .*|repo_id: local/rik-$1|" -e "s/^seed: 0$/seed: $SEED/" \
    "$REPO/examples/policies/$2.yaml" > "$spec"
  [ -d "ds-$1" ] || "${RIK[@]}" dataset build "$spec" --out "ds-$1" --work "work-$1" --variants "$3" -j "$WORKERS"
}
source "$REPO/scripts/act_recipe.sh"  # ACT=(...): the recipe's pinned flags
# diffusion with the pre-May-2026 horizon (16/8)
DIFFUSION_POLICY=(--policy.type=diffusion --policy.n_obs_steps=2 --policy.horizon=16 --policy.n_action_steps=8
     --policy.down_dims='[64, 128, 256]' --policy.kernel_size=5 --policy.n_groups=8
     --policy.diffusion_step_embed_dim=128 --policy.noise_scheduler_type=DDIM --policy.num_train_timesteps=100
     --policy.num_inference_steps=10 --policy.optimizer_lr=1e-4
     --policy.normalization_mapping='{"VISUAL": "MEAN_STD", "STATE": "MIN_MAX", "ENV": "MIN_MAX", "ACTION": "MIN_MAX"}')
train() {  # train RUN DATASET STEPS SEED POLICY_FLAGS...: a policy, every hyper-parameter pinned
  [ -f "runs/$1/checkpoints/last/pretrained_model/model.safetensors" ] && return
  rm -rf "runs/$1"
  local run=$1 data=$2 steps=$3 seed=$4 start=$SECONDS
  shift 4
  uv run --project "$REPO" --locked lerobot-train --dataset.repo_id="local/rik-$data" --dataset.root="ds-$data" \
    --policy.push_to_hub=false --policy.device="$DEVICE" --steps="$steps" --batch_size=32 --log_freq=500 \
    --save_freq=$(( STEPS / 30 > 1 ? STEPS / 30 : 1 )) --env_eval_freq=1000000 --output_dir="runs/$run" \
    --wandb.enable=false --num_workers="$LOADERS" --seed="$seed" "$@" > "train-$run.log" 2>&1
  echo "$run $steps steps $((SECONDS - start)) s" >> train-times.txt
}
resume() {  # resume RUN STEPS: a run trained on from its last checkpoint to STEPS (its optimizer state, data order, flags)
  local last
  last=$(ls "runs/$1/checkpoints" | grep -E '^[0-9]+$' | sort -n | tail -n 1)
  [ "$((10#$last))" -ge "$2" ] && return
  local start=$SECONDS
  uv run --project "$REPO" --locked lerobot-train --config_path="runs/$1/checkpoints/last/pretrained_model/train_config.json" \
    --resume=true --steps="$2" > "train-$1-resume-$2.log" 2>&1
  echo "$1 resumed to $2 steps $((SECONDS - start)) s" >> train-times.txt
}
declare -A QUEUED=()
QUEUE=()
queue() {  # queue SETTINGS OPERATOR LABEL OUT: an evaluation for run_evaluations (none where OUT holds it already)
  if [ -f "$4/eval_info.json" ] || [ -n "${QUEUED[$4]:-}" ]; then return 0; fi
  QUEUED[$4]=1
  QUEUE+=("$1|$2|$3|$4")
}
evaluate() {  # evaluate OPERATOR LABEL [VARIANTS]: the test split, seeds 1000.., PER_CELL episodes per cell (queued)
  queue "test 1000 $PER_CELL $VIDEOS ${3:-variants}" "$1" "$2" "eval/$2-test${3:+-${3#variants-}}"
}
evaluate_val() {  # evaluate_val OPERATOR LABEL: the validation split (choosing settings), seeds 3000.., PER_CELL/2 per
  # cell (queued)
  queue "val 3000 $(( PER_CELL / 2 > 0 ? PER_CELL / 2 : 1 )) 0 variants" "$1" "$2-val" "eval/$2-val"
}
eval_batch() {  # eval_batch SETTINGS OPERATOR|LABEL|OUT...: one rik eval process for several evaluations of the same
  # episodes, each into its own folder (a process's start-up, ~7 s, is most of a small evaluation's time)
  local split seed per_cell videos variants item operator label out operators=() named=()
  read -r split seed per_cell videos variants <<< "$1"
  shift
  for item in "$@"; do
    IFS='|' read -r operator label out <<< "$item"
    operators+=("$operator")
    named+=(--label "$label" --out "$out")
  done
  "${RIK[@]}" eval "${operators[@]}" "${named[@]}" --split "$split" --seed "$seed" --episodes-per-cell "$per_cell" \
    --episode-length "$EPISODE_LENGTH" --videos "$videos" --workers "$WORKERS" --variants "$variants"
}
run_evaluations() {  # the queued evaluations: those of the same episodes and variants folder dealt out round-robin
  # to JOBS processes (or fewer); then wait for them all
  local settings item i n chunk
  local -a groups=() mine part
  local -A seen=()
  for item in "${QUEUE[@]}"; do
    settings=${item%%|*}
    [ -n "${seen[$settings]:-}" ] || { seen[$settings]=1; groups+=("$settings"); }
  done
  for settings in "${groups[@]}"; do
    mine=()
    for item in "${QUEUE[@]}"; do [ "${item%%|*}" != "$settings" ] || mine+=("${item#*|}"); done
    n=$(( JOBS < ${#mine[@]} ? JOBS : ${#mine[@]} ))
    for (( chunk = 0; chunk < n; chunk++ )); do
      part=()
      for (( i = chunk; i < ${#mine[@]}; i += n )); do part+=("${mine[$i]}"); done
      spawn eval_batch "$settings" "${part[@]}"
    done
  done
  settle
  QUEUE=()
}
source "$REPO/scripts/policy_folders.sh"  # chunked, checkpoint: saved policies of the runs

export_frame() {  # export_frame NAME FROM FLAG: FROM's recorded episodes exported again with one export flag
  [[ " $DATASETS " == *" $1 "* ]] && [ ! -d "ds-$1" ] || return 0
  "${RIK[@]}" export-lerobot "work-$2/episodes" --out "ds-$1" --repo-id "local/rik-$1" --streams none \
    --outcomes S --variants variants "$3"
}
export_cm() {  # the CoACD demonstrations of exactly the episodes the hull data set holds (the ablation compares
  # collision, not data size): same seeds, same demonstrator, same plans (tests/test_collision_mode.py)
  [[ " $DATASETS " == *" cm "* ]] && [ ! -d ds-cm ] || return 0
  rm -rf sel-cm; mkdir -p sel-cm
  local meta seed match
  for meta in work-hull/episodes/*/meta.json; do
    grep -q '"outcome": "S"' "$meta" || continue
    seed=$(sed -n 's/.*"seed": \([0-9]*\).*/\1/p' "$meta")
    match=$(grep -l "\"seed\": $seed," work-pl/episodes/*/meta.json | head -n 1)
    ln -sfn "$(realpath "$(dirname "$match")")" "sel-cm/$(basename "$(dirname "$match")")"
  done
  "${RIK[@]}" export-lerobot sel-cm --out ds-cm --repo-id local/rik-cm --streams none --outcomes S --variants variants
}

if stage data; then
  # CoACD variants (the catalog's default) and convex-hull ones, whose single hull per handle is the low-fidelity
  # arm; and for the joint side of the fidelity ablation, variants whose joint friction creeps (MuJoCo's default
  # impedance) instead of holding
  [ -f variants-hull/collision.json ] || "${RIK[@]}" variants build drawer-chest-80__two_point-bow-128__normal \
    --collision hull --out variants-hull
  if [[ " $DATASETS " == *" plgc "* ]] && [ ! -f variants-creep/joint_friction.json ]; then
    "${RIK[@]}" variants build drawer-chest-80__two_point-bow-128__normal --joint-friction creeping --out variants-creep
  fi
  build pl planned-360 variants  # the main data set, first: it builds the drawn variants the others reuse
  spawn build pl-quarter planned-360 variants $(( DEMOS / 4 > 0 ? DEMOS / 4 : 1 ))  # the first quarter of them
  spawn build pln planned-dart-360 variants              # the same episodes, DART-style
  spawn build hull planned-hull-360 variants-hull        # the same episodes in hull variants (rejected ones left out)
  spawn build pla planned-above-360 variants             # the same seeds, planned_above: one way to hold each handle
  spawn build plt planned-typed-360 variants             # the same seeds, planned_typed: one hook side per handle type
  spawn build pl-images planned-360-images variants      # the main data set with both cameras (IMAGES=1)
  spawn build plgc planned-360-gripper variants-creep    # plg's spec recorded in joints that creep
  spawn build plgh planned-360-gripper variants  # its control: plg's content (held joints) in plgc's episode order
  # the main data set's episodes with the action in the handle frame (what examples/policies/planned-360-handle.yaml
  # builds, without recording the same episodes again), and with the handle's shape in the front's state
  # (examples/policies/planned-360-shape.yaml; plk: its type and mount flags alone), and with the action and the
  # grasp point measured from the gripper (examples/policies/planned-360-gripper.yaml)
  spawn export_frame plh pl --action-frame=handle
  spawn export_frame pls pl --handle-shape=full
  spawn export_frame plk pl --handle-shape=kind
  spawn export_frame plg pl --action-frame=gripper
  settle
  spawn export_frame plah pla --action-frame=handle
  spawn export_cm
  settle
fi
pl_s1() {  # the main run again with training seed 1 (its mean of the last third), and on past STEPS: is STEPS the
  # flat end of the curve?
  train act-pl-s1 pl "$STEPS" 1 "${ACT[@]}"
  resume act-pl-s1 $(( STEPS * 5 / 3 ))
}
plg_seed() {  # plg_seed SEED: the best recipe (the action and grasp point from the gripper), compared at 2/3 STEPS,
  # then trained on to STEPS and 4/3 STEPS (it still climbed from 2/3 STEPS to STEPS)
  train "act-plg-s$1" plg $(( STEPS * 2 / 3 )) "$1" "${ACT[@]}"
  resume "act-plg-s$1" "$STEPS"
  resume "act-plg-s$1" $(( STEPS * 4 / 3 ))
}
plgc_seed() {  # plgc_seed SEED: plg's recipe on demonstrations whose joints creep, STEPS/3, then on to 2/3 STEPS (the
  # joint ablation at 20k, planned after the 10k result)
  train "act-plgc-s$1" plgc $(( STEPS / 3 )) "$1" "${ACT[@]}"
  resume "act-plgc-s$1" $(( STEPS * 2 / 3 ))
}
plg_s2() {  # its third seed: first the joint ablation's third held run (STEPS/3), then the recipe's (4/3 STEPS)
  train act-plg-s2 plg $(( STEPS / 3 )) 2 "${ACT[@]}"
  resume act-plg-s2 $(( STEPS * 4 / 3 ))
}
if stage train; then
  spawn train act-pl pl "$STEPS" 0 "${ACT[@]}"
  spawn pl_s1
  spawn train act-pl-quarter pl-quarter $(( STEPS / 3 )) 0 "${ACT[@]}"
  spawn train act-plh plh $(( STEPS / 3 )) 0 "${ACT[@]}"   # the same recipe, the action from the handle's grasp point
  spawn train act-pla pla $(( STEPS * 2 / 3 )) 0 "${ACT[@]}"  # the same recipe, planned_above's demonstrations
  spawn train act-plt plt $(( STEPS * 2 / 3 )) 0 "${ACT[@]}"  # planned_typed's demonstrations
  spawn train act-plah plah $(( STEPS / 3 )) 0 "${ACT[@]}"  # both changes
  for seed in 0 1; do  # the same recipe and data, the handle's shape in the front's state; two training seeds
    spawn train "act-pls-s$seed" pls $(( STEPS * 2 / 3 )) "$seed" "${ACT[@]}"
    spawn train "act-plk-s$seed" plk $(( STEPS / 3 )) "$seed" "${ACT[@]}"  # its type and mount flags alone
    spawn plg_seed "$seed"
    spawn plgc_seed "$seed"  # plg's recipe on demonstrations whose joints creep
    spawn train "act-plgh-s$seed" plgh $(( STEPS / 3 )) "$seed" "${ACT[@]}"  # and on the held control
  done
  spawn plg_s2  # a third seed of each joint arm, and of the recipe
  spawn plgc_seed 2
  spawn train act-plg-s3 plg $(( STEPS * 4 / 3 )) 3 "${ACT[@]}"  # the recipe's fourth seed, in one go
  # diffusion (DIFFUSION=1; not in docs/policies.md's runs: CPU time), the same data and steps as act-pl
  if [ "${DIFFUSION:-0}" = 1 ]; then spawn train dp-pl pl "$STEPS" 0 "${DIFFUSION_POLICY[@]}"; fi
  # the image run (IMAGES=1): the same recipe with both cameras; ResNet-18 from scratch (no ImageNet weights
  # offline); docs/policies.md's ran on a GPU machine (DEVICE=cuda LOADERS=12) for SHORT_STEPS
  if [ "$IMAGES" = 1 ]; then
    spawn train act-pl-images pl-images "$SHORT_STEPS" 0 "${ACT[@]}" --policy.pretrained_backbone_weights=null
  fi
  for seed in 0 1; do
    spawn train "act-pln-s$seed" pln "$SHORT_STEPS" "$seed" "${ACT[@]}"
    spawn train "act-hull-s$seed" hull "$SHORT_STEPS" "$seed" "${ACT[@]}"
    spawn train "act-cm-s$seed" cm "$SHORT_STEPS" "$seed" "${ACT[@]}"
  done
  settle
fi
mean() {  # mean RUN FROM TO: averaged/RUN-FROM-TO, the mean of a run's saved weights over a window fixed in advance
  local out="averaged/$1-$2-$3"
  [ -f "$out/model.safetensors" ] || uv run --project "$REPO" --locked python "$REPO/scripts/average_checkpoints.py" \
    "runs/$1" --from "$2" --to "$3" --out "$out" > /dev/null
}
if stage eval; then
  # 1. the weights evaluated that no training saved: means over windows (scripts/average_checkpoints.py): act-pl's
  # last third, both demonstrators' SHORT_STEPS .. STEPS/3 and STEPS/3 .. 2 STEPS/3, each run past STEPS
  MEANS=("act-pl $(( STEPS * 2 / 3 )) $STEPS" "act-pl-s1 $(( STEPS * 2 / 3 )) $STEPS"
         "act-pl-s1 $STEPS $(( STEPS * 4 / 3 ))" "act-pl-s1 $(( STEPS * 4 / 3 )) $(( STEPS * 5 / 3 ))"
         "act-plk-s0 $SHORT_STEPS $(( STEPS / 3 ))" "act-plk-s1 $SHORT_STEPS $(( STEPS / 3 ))"
         "act-plg-s0 $(( STEPS * 2 / 3 )) $STEPS" "act-plg-s1 $(( STEPS * 2 / 3 )) $STEPS")
  for run in act-pl act-pl-s1 act-pla act-plt act-pls-s0 act-pls-s1 act-plg-s0 act-plg-s1; do
    MEANS+=("$run $SHORT_STEPS $(( STEPS / 3 ))" "$run $(( STEPS / 3 )) $(( STEPS * 2 / 3 ))")
  done
  for run in act-plg-s0 act-plg-s1 act-plg-s2 act-plg-s3; do MEANS+=("$run $STEPS $(( STEPS * 4 / 3 ))"); done
  for window in "${MEANS[@]}"; do spawn mean $window; done
  settle
  # ... and copies of saved weights with other chunking at evaluation: act-pl's whole chunk of 20, and one action
  # with temporal ensembling; the gripper frame's actions per prediction (2-20, chosen on the validation split at
  # STEPS: 15), at STEPS, 4/3 STEPS and over the mean of its STEPS .. 4/3 STEPS weights
  later=$(( STEPS * 4 / 3 ))
  chunked "$(checkpoint act-pl "$STEPS")" chunking/act-pl-n20 20
  chunked "$(checkpoint act-pl "$STEPS")" chunking/act-pl-te1 1 0.01
  for run in act-plg-s0 act-plg-s1; do
    for n in 2 5 10 15 20; do chunked "$(checkpoint "$run" "$STEPS")" "chunking/$run-$STEPS-n$n" "$n"; done
    chunked "$(checkpoint "$run" "$later")" "chunking/$run-$later-n15" 15
  done
  for run in act-plg-s0 act-plg-s1 act-plg-s2 act-plg-s3; do
    chunked "averaged/$run-$STEPS-$later" "chunking/$run-mean-$STEPS-$later-n15" 15
  done

  # 2. the evaluations, queued, then run by run_evaluations. The scripted teacher first, in each variants folder: it
  # builds the test episodes' variants there, which the policies' evaluations (JOBS processes) then share
  evaluate strategy:planned planned
  evaluate strategy:planned planned variants-creep
  evaluate strategy:planned planned variants-hull
  run_evaluations
  for step in $(( STEPS / 10 )) $(( STEPS / 3 )) $(( STEPS * 2 / 3 )) "$STEPS"; do
    evaluate "$(checkpoint act-pl "$step")" "act-pl-$step"
    evaluate "$(checkpoint act-pl-s1 "$step")" "act-pl-s1-$step"
  done
  evaluate "$(checkpoint act-pl-quarter $(( STEPS / 3 )))" "act-pl-quarter-$(( STEPS / 3 ))"
  for step in $(( STEPS / 10 )) "$SHORT_STEPS" $(( STEPS / 3 )); do  # rik eval reads its frame from its statistics
    evaluate "$(checkpoint act-plh "$step")" "act-plh-$step"
    evaluate "$(checkpoint act-plah "$step")" "act-plah-$step"
  done
  for step in $(( STEPS / 10 )) "$SHORT_STEPS" $(( STEPS / 3 )) $(( STEPS * 2 / 3 )); do
    evaluate "$(checkpoint act-pla "$step")" "act-pla-$step"
    evaluate "$(checkpoint act-plt "$step")" "act-plt-$step"
    for seed in 0 1; do  # rik eval reads the handle's shape from the policy's input width
      evaluate "$(checkpoint "act-pls-s$seed" "$step")" "act-pls-s$seed-$step"
      evaluate "$(checkpoint "act-plg-s$seed" "$step")" "act-plg-s$seed-$step"  # gripper frame: its input width
    done
  done
  for window in "${MEANS[@]}"; do
    set -- $window
    evaluate "averaged/$1-$2-$3" "$1-mean-$2-$3"
  done
  for step in $(( STEPS * 4 / 3 )) $(( STEPS * 5 / 3 )); do  # act-pl-s1 past STEPS
    evaluate "$(checkpoint act-pl-s1 "$step")" "act-pl-s1-$step"
  done
  for run in act-plk-s0 act-plk-s1; do
    evaluate "$(checkpoint "$run" $(( STEPS / 3 )))" "$run-$(( STEPS / 3 ))"
  done
  # the joint side of the fidelity ablation at STEPS/3: each arm in held joints (the highest fidelity) and creeping ones
  for seed in 0 1; do
    evaluate "$(checkpoint "act-plgc-s$seed" $(( STEPS / 3 )))" "act-plgc-s$seed-$(( STEPS / 3 ))"
    evaluate "$(checkpoint "act-plgc-s$seed" $(( STEPS / 3 )))" "act-plgc-s$seed-$(( STEPS / 3 ))" variants-creep
    evaluate "$(checkpoint "act-plg-s$seed" $(( STEPS / 3 )))" "act-plg-s$seed-$(( STEPS / 3 ))" variants-creep
    evaluate "$(checkpoint "act-plgh-s$seed" $(( STEPS / 3 )))" "act-plgh-s$seed-$(( STEPS / 3 ))"
  done
  for run in act-plg-s2 act-plgc-s2; do evaluate "$(checkpoint "$run" $(( STEPS / 3 )))" "$run-$(( STEPS / 3 ))"; done
  # ... and at 2/3 STEPS, three runs of each arm (act-plg-s0/s1 at 2/3 STEPS are evaluated above)
  for run in act-plg-s2 act-plgc-s0 act-plgc-s1 act-plgc-s2; do
    evaluate "$(checkpoint "$run" $(( STEPS * 2 / 3 )))" "$run-$(( STEPS * 2 / 3 ))"
  done
  for run in act-plg-s0 act-plg-s1; do evaluate "$(checkpoint "$run" "$STEPS")" "$run-$STEPS"; done
  if [ "${DIFFUSION:-0}" = 1 ]; then evaluate "$(checkpoint dp-pl "$STEPS")" "dp-pl-$STEPS"; fi
  if [ "$IMAGES" = 1 ]; then evaluate "runs/act-pl-images/checkpoints/last/pretrained_model" act-pl-images; fi
  evaluate chunking/act-pl-n20 "act-pl-$STEPS-n20"
  evaluate chunking/act-pl-te1 "act-pl-$STEPS-te1"
  for run in act-plg-s0 act-plg-s1; do
    for n in 2 5 10 15 20; do evaluate_val "chunking/$run-$STEPS-n$n" "$run-$STEPS-n$n"; done
    evaluate "chunking/$run-$STEPS-n15" "$run-$STEPS-n15"
    evaluate "chunking/$run-$later-n15" "$run-$later-n15"
  done
  # the recipe (docs/policies.md): four training seeds at 4/3 STEPS, and each one's mean of STEPS .. 4/3 STEPS with 15
  for run in act-plg-s0 act-plg-s1 act-plg-s2 act-plg-s3; do
    evaluate "$(checkpoint "$run" "$later")" "$run-$later"
    evaluate "chunking/$run-mean-$STEPS-$later-n15" "$run-mean-$STEPS-$later-n15"
  done
  evaluate "$(checkpoint act-pl "$SHORT_STEPS")" "act-pl-$SHORT_STEPS"
  for seed in 0 1; do
    for run in pln hull cm; do
      evaluate "runs/act-$run-s$seed/checkpoints/last/pretrained_model" "act-$run-s$seed"
    done
    # the sim-to-sim gap: each ablation arm also in the other collision model
    evaluate "runs/act-hull-s$seed/checkpoints/last/pretrained_model" "act-hull-s$seed" variants-hull
    evaluate "runs/act-cm-s$seed/checkpoints/last/pretrained_model" "act-cm-s$seed" variants-hull
  done
  run_evaluations
fi
if stage report; then
  uv run --project "$REPO" --locked python "$REPO/scripts/policy_curves.py" . --out report
  # the diagnosis: how precisely the policies imitate demonstrations they never saw (test split, teacher-forced)
  [ -d demos-heldout ] || "${RIK[@]}" record --split test --strategy planned --episodes 18 --seed 2000 \
    --out demos-heldout --variants variants --workers "$WORKERS"
  [ -d ds-heldout ] || "${RIK[@]}" export-lerobot demos-heldout --out ds-heldout --repo-id local/rik-heldout \
    --streams none --outcomes S --variants variants
  [ -d ds-heldout-h ] || "${RIK[@]}" export-lerobot demos-heldout --out ds-heldout-h --repo-id local/rik-heldout-h \
    --streams none --outcomes S --variants variants --action-frame handle
  for step in $(( STEPS / 10 )) $(( STEPS / 3 )) "$STEPS"; do
    uv run --project "$REPO" --locked python "$REPO/scripts/policy_precision.py" "$(checkpoint act-pl "$step")" \
      ds-heldout
  done | tee report/precision.txt
  for step in $(( STEPS / 10 )) $(( STEPS / 3 )); do  # the handle-frame run against the same episodes in its frame
    uv run --project "$REPO" --locked python "$REPO/scripts/policy_precision.py" "$(checkpoint act-plh "$step")" \
      ds-heldout-h
  done | tee -a report/precision.txt
fi
