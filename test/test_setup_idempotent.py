"""tools/setup.sh on an already set-up checkout must do nothing, quickly."""
import subprocess
import time

from conftest import ROOT


def test_second_setup_does_nothing(project_venv):
    start = time.monotonic()
    run = subprocess.run(["bash", str(ROOT / "tools" / "setup.sh")],
                         capture_output=True, text=True, timeout=120)
    elapsed = time.monotonic() - start
    assert run.returncode == 0, run.stderr
    assert run.stdout.strip() == f"setup: up to date ({project_venv})", run.stdout
    assert elapsed < 5, f"took {elapsed:.1f} s"
