#!/usr/bin/env bash
# Set up (quick when nothing changed), then run the default scenario: thesis chapter 5, online
# inverse-dynamics learning of two 'star' tasks by a youBot and a Pincher arm with and without
# transfer, over the ROS 2 node graph, for babbling seed 0 (one_seed.yaml; drop that override
# for all 10 seeds). Writes into runs/inverse_dynamics/; extra args (--config FILE,
# --override FILE, --out DIR) go to the scenario script.
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
bash "$ROOT/tools/setup.sh"
exec bash "$ROOT/scenarios/inverse_dynamics/run.sh" \
    --override "$ROOT/scenarios/inverse_dynamics/one_seed.yaml" "$@"
