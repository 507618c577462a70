#!/usr/bin/env bash
# lpa_mapping's discovery time and round trip as a user's node sees them (bench/mapping_round_trip.py):
# the service and the client as two processes of one graph. On one host:
#   bash bench/mapping_round_trip.sh [--out DIR]
# across network hosts (root): scenarios/multi_host/run.sh --scenario mapping_round_trip
# [--out DIR] puts the service on the mapping host and the client on the learners' host.
# Prints the client's figures; logs in DIR/logs (default runs/mapping_round_trip).
set -euo pipefail
HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
ROOT=$(cd "$HERE/.." && pwd)
CONFIG=$ROOT/scenarios/two_link_graph/smoke.yaml   # no lpa_mapping entry: its defaults
OUT=$ROOT/runs/mapping_round_trip
SCENARIO=mapping_round_trip
source "$ROOT/scenarios/lib/graph.sh"

start lpa_mapping lpa_mapping "${PARAMS[@]}" -p "model_dir:=$OUT/models"
step mapping_round_trip python -m bench.mapping_round_trip
stop_all
[ $FAILED = 0 ] || { echo "error: a node did not stop cleanly" >&2; exit 1; }
cat "$OUT/logs/mapping_round_trip.log"
