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
while [ $# -gt 0 ]; do
    case $1 in
        --config) CONFIG=$(realpath "$2"); shift 2 ;;
        --out) OUT=$(realpath -m "$2"); shift 2 ;;
        *) echo "usage: $0 [--config FILE.yaml] [--out DIR]" >&2; exit 2 ;;
    esac
done

# A run directory holds one run: refuse to clear a directory this script did not make.
if [ -d "$OUT" ] && [ -n "$(ls -A "$OUT")" ] && [ ! -e "$OUT/.two_link_graph_run" ]; then
    echo "error: $OUT exists and is not a run directory of this script" >&2; exit 2
fi
rm -rf "$OUT"; mkdir -p "$OUT/logs"; touch "$OUT/.two_link_graph_run"
source "$ROOT/tools/env.sh"
export ROS_LOG_DIR=$OUT/logs/ros PYTHONUNBUFFERED=1
cd "$ROOT"
PARAMS=(--ros-args --params-file "$CONFIG")

# Every process gets its own session (setsid), so Ctrl-C reaches only this script, which then
# stops them in order: the running step first, then the nodes in reverse start order, the
# recorder last, so the bag holds everything the others published.
PIDS=() NAMES=() CURRENT=""
start() {   # start NAME MODULE ARGS...: a node in the background, its output in logs/NAME.log
    local name=$1 module=$2; shift 2
    setsid python -m "lpa_transfer_nodes.$module" "$@" >"$OUT/logs/$name.log" 2>&1 &
    PIDS+=($!) NAMES+=("$name")
}
FAILED=0
stop_process() {   # stop_process PID NAME: SIGINT (the nodes finalise their files), SIGKILL after 20 s
    local pid=$1 name=$2 waited=0 code=0
    kill -INT "$pid" 2>/dev/null || true
    while kill -0 "$pid" 2>/dev/null && [ $waited -lt 200 ]; do sleep 0.1; waited=$((waited + 1)); done
    if kill -0 "$pid" 2>/dev/null; then
        echo "$name did not stop on SIGINT: killed" >&2; kill -KILL "$pid" 2>/dev/null || true
        FAILED=1
    fi
    wait "$pid" || code=$?
    if [ $code != 0 ]; then echo "$name exited with $code (see $OUT/logs/$name.log)" >&2; FAILED=1; fi
}
stop_all() {
    if [ -n "$CURRENT" ]; then stop_process "$CURRENT" "the running step"; CURRENT=""; fi
    for ((i = ${#PIDS[@]} - 1; i >= 0; i--)); do stop_process "${PIDS[$i]}" "${NAMES[$i]}"; done
    PIDS=() NAMES=()
}
trap stop_all EXIT
trap 'echo "interrupted: stopping the nodes" >&2; stop_all; exit 130' INT TERM

step() {   # step NAME COMMAND...: one step with its own log, waited for (so Ctrl-C interrupts it)
    local name=$1; shift
    echo "[$(date +%T)] $name" >&2
    setsid "$@" >"$OUT/logs/$name.log" 2>&1 &
    CURRENT=$!
    local code=0; wait "$CURRENT" || code=$?
    CURRENT=""
    if [ $code != 0 ]; then
        echo "error: $name failed; its log ($OUT/logs/$name.log) ends with:" >&2
        tail -n 15 "$OUT/logs/$name.log" >&2; exit 1
    fi
}

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
from lpa_transfer.bag import describe
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
