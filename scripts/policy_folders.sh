# Helpers over saved LeRobot policies and training runs, sourced by scripts/policy_experiment.sh,
# scripts/joints_ablation.sh and scripts/image_policy.sh (each runs them inside its work folder, where
# runs/<run>/checkpoints/ lie), and the message of a failed step.
chunked() {  # chunked POLICY FOLDER N_ACTION_STEPS [ENSEMBLE_COEFF]: a copy of a policy run with other chunking
  [ -d "$2" ] && return
  mkdir -p "$2.tmp"; cp -r "$1"/. "$2.tmp"/
  python3 - "$2.tmp/config.json" "$3" "${4:-}" <<'PY'
import json, sys
path, steps, coeff = sys.argv[1], int(sys.argv[2]), sys.argv[3]
config = json.load(open(path))
config["n_action_steps"], config["temporal_ensemble_coeff"] = steps, (float(coeff) if coeff else None)
json.dump(config, open(path, "w"), indent=4)
PY
  mv "$2.tmp" "$2"
}
checkpoint() {  # checkpoint RUN STEP: the folder of a saved step (the nearest saved one at or below STEP)
  local saved
  saved=$(ls "runs/$1/checkpoints" | grep -E '^[0-9]+$' | awk -v s="$2" '$1 + 0 <= s + 0' | sort -n | tail -n 1)
  echo "runs/$1/checkpoints/$saved/pretrained_model"
}
failed() {  # failed LOG: say which step failed (the sourcing script's name) and its log's last line, then stop
  echo "$(basename "$0"): a step failed ($PWD/$1): $(tail -n 1 "$1")" >&2
  exit 1
}
