#!/usr/bin/env bash
# Issue 48, item 3: the runs of train_seeds.sh on the 100 unseen episodes (seed 900000): each final
# policy, each fitted policy alone (checkpoints/model_0_steps, the runs with init), and the two
# controllers the init imitates on the same episodes per snake length; JSON in runs/sine-init/eval,
# two evaluations at a time (one core each). An evaluation already written is skipped.
#   bash experiments/sine-init/evaluate_runs.sh [JOINTS ...]   (default 10 20 30 5)
# ALONE_SEEDS (default 1 2 3 4 5): the seeds whose fitted policy alone is evaluated (runs labelled
# init or anchor); FINALS (default 1; 0: the final policies
# are skipped); CONTROLLERS (default "steered_sine sine"); PARALLEL (default 2): evaluations at a
# time.
set -euo pipefail
cd "$(dirname "$0")/../.."
SNAKESIM=${SNAKESIM:-.venv/bin/snakesim}
out=runs/sine-init/eval
mkdir -p "$out"
jobs=()
add() { # OUT.json SOURCE [evaluate flags]
  local json=$1
  shift
  [[ -f $json ]] || jobs+=("$SNAKESIM evaluate $* --episodes 100 --seed 900000 --json $json")
}
lengths=("$@")
[[ ${#lengths[@]} -gt 0 ]] || lengths=(10 20 30 5)
for joints in "${lengths[@]}"; do
  for run in runs/sine-init/*-"$joints"-s*/; do
    name=$(basename "$run")
    [[ -f $run/model.safetensors ]] || continue
    [[ ${FINALS:-1} == 0 ]] || add "$out/$name.json" "$run/model.safetensors"
    # An anchor run's fitted policy is its init run's (the same bits): one file for both.
    if [[ $name == init-* || $name == anchor-* ]] && [[ " ${ALONE_SEEDS:-1 2 3 4 5} " == *" ${name##*-s} "* ]]; then
      add "$out/${name/#anchor-/init-}-alone.json" "$run/checkpoints/model_0_steps.safetensors"
    fi
  done
  for controller in ${CONTROLLERS-steered_sine sine}; do
    add "$out/$controller-$joints.json" "baseline:$controller" --env paper --joints "$joints" \
      --preset snakebot-gym
  done
done
printf '%s\n' "${jobs[@]}" | xargs -P "${PARALLEL:-2}" -I{} sh -c '{} >/dev/null'
