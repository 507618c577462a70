#!/usr/bin/env bash
# Set up (quick when nothing changed), then run the test suite; extra args go to pytest.
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
bash "$ROOT/tools/setup.sh"
source "$ROOT/tools/env.sh"
cd "$ROOT"
# setup.cfg sets testpaths = test, so with no arguments the whole suite runs.
exec python -m pytest "$@"
