#!/usr/bin/env bash
# Thesis §3.6 over the ROS 2 node graph: two simulated 2-link arms, correspondences collected
# by babbling, an LPA model fitted by the mapping service, the source robot's experience
# transferred through it, and a target forward-kinematics model scored against the target's
# true kinematics. Every node is its own process with its own log; everything is recorded.
#
# Usage: scenarios/two_link_graph/run.sh [--config FILE.yaml] [--out DIR]
#   defaults: scenarios/two_link_graph/config.yaml, runs/two_link_graph
# Leaves in DIR: run.mcap (every topic), correspondences.npz, models/, logs/, evaluation.json,
# report.txt. Exit status 0 only if every step succeeded and every node stopped cleanly.
set -euo pipefail
HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
ROOT=$(cd "$HERE/../.." && pwd)
CONFIG=$HERE/config.yaml
OUT=$ROOT/runs/two_link_graph
SCENARIO=two_link_graph
source "$ROOT/scenarios/lib/graph.sh"

START=$(date +%s.%N)
start recorder recorder "${PARAMS[@]}" -p "output:=$OUT/run.mcap"
start lpa_mapping lpa_mapping "${PARAMS[@]}" -p "model_dir:=$OUT/models"
start source_sim robot_sim "${PARAMS[@]}" -r __ns:=/source
start target_sim robot_sim "${PARAMS[@]}" -r __ns:=/target
step correspondence_collector python -m lpa_transfer_nodes.correspondence_collector \
    "${PARAMS[@]}" -p "output:=$OUT/correspondences.npz"
step transfer_evaluation python "$HERE/evaluate_transfer.py" "${PARAMS[@]}" \
    -p "output_dir:=$OUT" -p "correspondence_file:=$OUT/correspondences.npz"
stop_all
[ $FAILED = 0 ] || { echo "error: a node did not stop cleanly" >&2; exit 1; }
WALL=$(python -c "import time; print(f'{time.time() - $START:.1f}')")

python - "$OUT" "$WALL" >>"$OUT/report.txt" <<'PY'
import json, sys
from pathlib import Path
import numpy as np
from lpa_transfer.recording import describe
out, wall = Path(sys.argv[1]), float(sys.argv[2])
evaluation = json.loads((out / "evaluation.json").read_text())
with np.load(out / "correspondences.npz") as pairs:
    collection_s = float(pairs["sim_time"])
simulated = collection_s + evaluation["experience_sim_s"] + evaluation["own_babbling_sim_s"]
print(f"\nsimulated time {simulated:.1f} s (collection {collection_s:.1f} s) in {wall:.1f} s of "
      f"wall time, nodes' start-up included: {simulated / wall:.1f}x faster than real time")
print(describe(out / "run.mcap"), end="")
PY
echo >&2; cat "$OUT/report.txt"; echo "run directory: $OUT" >&2
