#!/usr/bin/env bash
# Thesis ch. 5 over the ROS 2 node graph: a youBot and a Pincher arm (torque-controlled
# robot_sim nodes) learn two 'star' tracking tasks online (one inverse_dynamics_learner per
# robot and star), with and without transfer of the other robot's experience through
# lpa_mapping. Every node is its own process with its own log; everything is recorded.
#
# Usage: scenarios/inverse_dynamics/run.sh [--config FILE.yaml] [--out DIR]
#   defaults: scenarios/inverse_dynamics/config.yaml, runs/inverse_dynamics
# Leaves in DIR: run.mcap, pairs_<seed>.npz, models/, logs/, results.json,
# learning_curves.csv, the figures and report.txt.
set -euo pipefail
HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
ROOT=$(cd "$HERE/../.." && pwd)
CONFIG=$HERE/config.yaml
OUT=$ROOT/runs/inverse_dynamics
SCENARIO=inverse_dynamics
source "$ROOT/scenarios/lib/graph.sh"

SEEDS=$(python -c "import sys, yaml
print(*yaml.safe_load(open(sys.argv[1]))['experiment']['ros__parameters']['seeds'])" "$CONFIG")
START=$(date +%s.%N)
start recorder recorder "${PARAMS[@]}" -p "output:=$OUT/run.mcap"
start lpa_mapping lpa_mapping "${PARAMS[@]}" -p "model_dir:=$OUT/models"
for robot in youbot pincher; do
    start "${robot}_sim" robot_sim "${PARAMS[@]}" -r "__ns:=/$robot"
    for star in star1 star2; do
        start "${robot}_${star}" inverse_dynamics_learner "${PARAMS[@]}" -r "__ns:=/$robot" \
            -r "__node:=$star"
    done
done
PAIRS=()
for seed in $SEEDS; do
    step "correspondence_collector_seed$seed" python -m lpa_transfer_nodes.correspondence_collector \
        "${PARAMS[@]}" -p "seed:=$seed" -p "output:=$OUT/pairs_$seed.npz"
    PAIRS+=("$OUT/pairs_$seed.npz")
done
step experiment python "$HERE/run_experiment.py" "${PAIRS[@]}" "${PARAMS[@]}" \
    -p "output_dir:=$OUT"
stop_all
[ $FAILED = 0 ] || { echo "error: a node did not stop cleanly" >&2; exit 1; }
WALL=$(python -c "import time; print(f'{time.time() - $START:.0f}')")
python -m lpa_transfer.bag "$OUT/run.mcap" >>"$OUT/report.txt"
echo "whole run (nodes' start-up included): $WALL s of wall time" >>"$OUT/report.txt"
cat "$OUT/report.txt"; echo "run directory: $OUT" >&2
