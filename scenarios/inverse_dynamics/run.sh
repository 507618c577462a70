#!/usr/bin/env bash
# Thesis ch. 5 over the ROS 2 node graph: two robots (torque-controlled robot_sim nodes; a
# youBot and a Pincher arm in config.yaml, the youBot and a 3-DoF or 2-link arm in
# youbot_three_dof.yaml / youbot_two_link.yaml) learn two 'star' tracking tasks online (one
# inverse_dynamics_learner per robot and star), with and without transfer of the other
# robot's experience through lpa_mapping. Every node is its own process with its own log;
# everything is recorded. The robots and stars are the experiment node's parameters.
#
# Usage: scenarios/inverse_dynamics/run.sh [--config FILE.yaml] [--override FILE.yaml]...
#                                          [--out DIR] [--progress]
#   defaults: scenarios/inverse_dynamics/config.yaml, runs/inverse_dynamics; an override file
#   changes some parameters (e.g. experiment seeds: [3, 4] to run a share of the seeds;
#   merge_results.py joins the shares' results).
# Leaves in DIR: run.mcap, pairs_<seed>_<star>.npz, models/, logs/, results.json,
# learning_curves.csv, the figures and report.txt.
set -euo pipefail
HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
ROOT=$(cd "$HERE/../.." && pwd)
CONFIG=$HERE/config.yaml
OUT=$ROOT/runs/inverse_dynamics
SCENARIO=inverse_dynamics
source "$ROOT/scenarios/lib/graph.sh"

SEEDS=$(experiment_list seeds)
STARS=$(experiment_list stars)
START=$(date +%s.%N)
start recorder recorder "${PARAMS[@]}" -p "output:=$OUT/run.mcap"
start lpa_mapping lpa_mapping "${PARAMS[@]}" -p "model_dir:=$OUT/models"
for robot in $(experiment_list robots); do
    start "${robot}_sim" robot_sim "${PARAMS[@]}" -r "__ns:=/$robot"
    for star in $STARS; do
        start "${robot}_${star}" inverse_dynamics_learner "${PARAMS[@]}" -r "__ns:=/$robot" \
            -r "__node:=$star" $(sim_time "$robot")
    done
done
PAIRS=()
for seed in $SEEDS; do     # babbling in the vicinity of each star (config: /babbling/*)
    k=0
    for star in $STARS; do
        step "babbling_seed${seed}_$star" python -m lpa_transfer_nodes.correspondence_collector \
            "${PARAMS[@]}" -r __ns:=/babbling -r "__node:=$star" \
            -r correspondences:=/correspondences -r correspondence_batch:=/correspondence_batch \
            -p "seed:=$((10 * seed + k))" -p "output:=$OUT/pairs_${seed}_$star.npz"
        PAIRS+=("$OUT/pairs_${seed}_$star.npz")
        k=$((k + 1))
    done
done
step experiment python "$HERE/run_experiment.py" "${PAIRS[@]}" "${PARAMS[@]}" \
    -p "output_dir:=$OUT"
stop_all
[ $FAILED = 0 ] || { echo "error: a node did not stop cleanly" >&2; exit 1; }
WALL=$(python -c "import time; print(f'{time.time() - $START:.0f}')")
python -m lpa_transfer.recording.bag "$OUT/run.mcap" >>"$OUT/report.txt"
# the robots at their last state, drawn from the bag's robot_description and /tf
python -m lpa_transfer.recording.scene "$OUT/run.mcap" "$OUT/robots.png" >/dev/null
echo "whole run (nodes' start-up included): $WALL s of wall time" >>"$OUT/report.txt"
if [ $PROGRESS = 1 ]; then   # the summary table went by; say where everything is
    echo "done in $WALL s. Written to $OUT:"
    echo "  figure  $OUT/fig5_7_5_8_learning_curves.png"
    echo "  report  $OUT/report.txt"
    echo "  bag     $OUT/run.mcap   (python -m lpa_transfer.recording.bag $OUT/run.mcap)"
    echo "  robots  $OUT/robots.png   (from the bag's /tf; Foxglove: docs/nodes.md, robot_sim)"
    echo "  models  $OUT/models/   logs  $OUT/logs/"
else
    cat "$OUT/report.txt"; echo "run directory: $OUT" >&2
fi
