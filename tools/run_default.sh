#!/usr/bin/env bash
# Set up (quick when nothing changed), then run the default scenario: the thesis' 2-link
# example (§3.6). Writes into runs/two_link_fk/; extra args go to the scenario script.
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
bash "$ROOT/tools/setup.sh"
source "$ROOT/tools/env.sh"
cd "$ROOT"
exec python scenarios/two_link_fk/run_two_link_fk.py "$@"
