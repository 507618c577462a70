"""Shared fixtures. The library is installed editable (tools/setup.sh), so no sys.path edits."""
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
VENV = ROOT / ".venv"


@pytest.fixture
def project_venv():
    """The project's .venv; tests of the set-up skip under another interpreter (e.g. a scratch venv)."""
    if Path(sys.prefix).resolve() != VENV.resolve():
        pytest.skip(f"needs the project venv {VENV} (run tools/run_tests.sh)")
    return VENV
