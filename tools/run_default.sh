#!/usr/bin/env bash
# `make demo`: set up (quick when nothing changed), then the default demo over the ROS 2 node
# graph: the youBot learns a star tracking task (thesis ch. 5) from scratch and with the
# Pincher's experience transferred through the mapping service (scenarios/inverse_dynamics/
# demo.yaml on config.yaml). Progress and a summary table in the terminal; figure, report and
# bag in runs/demo/. Extra args (--override FILE, --out DIR) go to the scenario script.
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
bash "$ROOT/tools/setup.sh"
exec bash "$ROOT/scenarios/inverse_dynamics/run.sh" --progress \
    --override "$ROOT/scenarios/inverse_dynamics/demo.yaml" --out "$ROOT/runs/demo" "$@"
