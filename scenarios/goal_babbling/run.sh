#!/usr/bin/env bash
# Thesis ch. 6, experiment 1 (§6.5.1) over the ROS 2 node graph: a 2-link target arm learns
# its inverse kinematics by goal babbling, from scratch or after guided exploration and
# transfer of a 2-link source arm's experience (PA, LPA; plain, behind the guard against
# negative transfer, or yielding to the own samples). Two robot_sim nodes in position mode,
# four goal_babbling_learner nodes,
# the correspondence collector in guided-exploration mode, lpa_mapping and the recorder; every
# node is its own process with its own log; everything is recorded.
#
# Usage: scenarios/goal_babbling/run.sh [--config FILE.yaml] [--override FILE.yaml]...
#                                       [--out DIR]
#   defaults: scenarios/goal_babbling/config.yaml, runs/goal_babbling; smoke.yaml shrinks it
#   to the test suite's size; an override with experiment seeds runs a share of the seeds.
# Leaves in DIR: run.mcap, guided_<seed>.npz, models/, logs/, results.json,
# learning_curves.csv, the figures and report.txt.
set -euo pipefail
HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
ROOT=$(cd "$HERE/../.." && pwd)
CONFIG=$HERE/config.yaml
OUT=$ROOT/runs/goal_babbling
SCENARIO=goal_babbling
source "$ROOT/scenarios/lib/graph.sh"

SEEDS=$(experiment_list seeds)
LONGEST=$(python -c "import sys; print(max(map(float, sys.argv[1:])))" \
          $(experiment_list guided_seconds))
start recorder recorder "${PARAMS[@]}" -p "output:=$OUT/run.mcap"
start lpa_mapping lpa_mapping "${PARAMS[@]}" -p "model_dir:=$OUT/models"
for side in source target; do
    start "${side}_sim" robot_sim "${PARAMS[@]}" -r "__ns:=/$side"
done
start source_learner goal_babbling_learner "${PARAMS[@]}" -r __ns:=/source -r __node:=learner \
    $(sim_time source)
start target_learner goal_babbling_learner "${PARAMS[@]}" -r __ns:=/target -r __node:=learner \
    $(sim_time target)
for variant in guarded yielding; do
    start "target_${variant}_learner" goal_babbling_learner "${PARAMS[@]}" -r __ns:=/target \
        -r "__node:=${variant}_learner" $(sim_time target)
done
PAIRS=()
for seed in $SEEDS; do   # guided exploration with the target's babbling seed of this run
    target_seed=$(python -c "from lpa_transfer.goal_babbling import derived_seeds
print(derived_seeds($seed)[1])")
    step "guided_exploration_seed$seed" python -m lpa_transfer_nodes.correspondence_collector \
        "${PARAMS[@]}" -r __node:=guided_exploration -p "seed:=$target_seed" \
        -p "guided_seconds:=$LONGEST" -p "output:=$OUT/guided_$seed.npz"
    PAIRS+=("$OUT/guided_$seed.npz")
done
step experiment python "$HERE/run_experiment.py" "${PAIRS[@]}" "${PARAMS[@]}" \
    -p "output_dir:=$OUT"
stop_all
[ $FAILED = 0 ] || { echo "error: a node did not stop cleanly" >&2; exit 1; }
echo >&2; cat "$OUT/report.txt"; echo "run directory: $OUT" >&2
