#!/usr/bin/env bash
# Issue 48, item 3: the paper's task at 5, 10, 20 and 30 joints, with and without initialisation by
# imitation, one training run at a time on both cores (wall times mean nothing with two at once).
# Each argument is LABEL:JOINTS:SEEDS[:TIMESTEPS]: LABEL "anchor" (paper-init-10.yaml as it is: the
# init, then PPO anchored to the controller), "init" (the same without the anchor: init.anchor=0,
# PPO alone after the init, bit for bit) or "tuned" (paper-tuned-10.yaml: the same learner at its own
# learning rate, no init), TIMESTEPS by default the config's.
#   bash experiments/sine-init/train_seeds.sh init:10:1,2,3,4,5 tuned:20:1,2:524288
# Runs go to runs/sine-init/LABEL-JOINTS-sSEED; a finished run (model.safetensors) is skipped.
# THREADS (default 2): the training threads of each run.
set -euo pipefail
cd "$(dirname "$0")/../.."
CLI=${CLI:-target/release/snake-cli}
for spec in "$@"; do
  IFS=: read -r label joints seeds timesteps <<<"$spec"
  extra=()
  case $label in
    anchor) config=snake-py/configs/paper-init-10.yaml ;;
    init) config=snake-py/configs/paper-init-10.yaml extra=(--set init.anchor=0) ;;
    tuned) config=snake-py/configs/paper-tuned-10.yaml ;;
    *) echo "unknown label $label (anchor, init or tuned)" >&2; exit 2 ;;
  esac
  budget=("${extra[@]}")
  if [[ -n ${timesteps:-} ]]; then budget+=(--timesteps "$timesteps"); fi
  for seed in ${seeds//,/ }; do
    dir=runs/sine-init/$label-$joints-s$seed
    if [[ -f $dir/model.safetensors ]]; then continue; fi
    rm -rf "$dir"
    echo "$(date -u +%T) $dir"
    "$CLI" train --config "$config" --set joints="$joints" --seed "$seed" "${budget[@]}" \
      --threads "${THREADS:-2}" --no-progress --run-dir "$dir"
  done
done
