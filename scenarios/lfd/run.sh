#!/usr/bin/env bash
# Thesis ch. 4 (§4.5.1-4.5.2) over the ROS 2 node graph: the human arm model demonstrates
# letters (demonstration_source), lpa_mapping transfers them onto the PR2 and the Meka M1,
# and each robot's skill_learner fits DMPs on them and executes the reproductions on its
# robot_sim (position mode); the recorder keeps everything. Every node is its own process
# with its own log. Fig. 4-10/4-12 sweeps and Table 4.3 run in process: accuracy.py.
#
# Usage: scenarios/lfd/run.sh [--config FILE.yaml] [--override FILE.yaml]... [--out DIR]
#   defaults: scenarios/lfd/config.yaml, runs/lfd; smoke.yaml shrinks it to the tests' size.
# Leaves in DIR: run.mcap, models/, logs/, results.json, report.txt, fig4_11_13_letters.png.
set -euo pipefail
HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
ROOT=$(cd "$HERE/../.." && pwd)
CONFIG=$HERE/config.yaml
OUT=$ROOT/runs/lfd
SCENARIO=lfd
source "$ROOT/scenarios/lib/graph.sh"

start recorder recorder "${PARAMS[@]}" -p "output:=$OUT/run.mcap"
start lpa_mapping lpa_mapping "${PARAMS[@]}" -p "model_dir:=$OUT/models"
for robot in pr2_right_arm meka_right_arm; do
    start "${robot}_sim" robot_sim "${PARAMS[@]}" -r "__ns:=/$robot"
    start "${robot}_skill_learner" skill_learner "${PARAMS[@]}" -r "__ns:=/$robot" \
        $(sim_time "$robot")
done
start demonstration_source demonstration_source "${PARAMS[@]}"
step experiment python "$HERE/run_experiment.py" "${PARAMS[@]}" -p "output_dir:=$OUT"
stop_all
[ $FAILED = 0 ] || { echo "error: a node did not stop cleanly" >&2; exit 1; }
echo >&2; cat "$OUT/report.txt"; echo "run directory: $OUT" >&2
