#!/usr/bin/env bash
# Set up (quick when nothing changed), then run the test suite; extra args go to pytest.
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
bash "$ROOT/tools/setup.sh"
source "$ROOT/tools/env.sh"
cd "$ROOT"
# setup.cfg sets testpaths = test, so with no arguments the whole suite runs, and prints the
# 15 slowest tests. Three workers on the 2 cores, because many tests wait (DDS discovery,
# nodes' start-up, signals), so a third fills the idle CPU (docs/history.md has the times).
# TEST_WORKERS=0 runs in this process. Each test file stays on
# one worker, which starts its module fixtures (the scenario runs) once; the modules with slow
# tests first, in the order test/conftest.py puts them (not xdist's: most tests first).
exec python -m pytest -n "${TEST_WORKERS:-3}" --dist loadfile --no-loadscope-reorder "$@"
