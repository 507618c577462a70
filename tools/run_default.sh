#!/usr/bin/env bash
# Set up (quick when nothing changed), then run the default scenario: the thesis' 2-link
# example (§3.6) over the ROS 2 node graph. Writes into runs/two_link_graph/; extra args
# (--config FILE, --out DIR) go to the scenario script.
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
bash "$ROOT/tools/setup.sh"
exec bash "$ROOT/scenarios/two_link_graph/run.sh" "$@"
