"""tools/setup.sh on an already set-up checkout must do nothing (how fast is bench's business)."""
import subprocess

from conftest import ROOT


def snapshot(venv):
    """(path, mtime_ns) of every stamp, of the venv's site-packages entries and of its bin/."""
    paths = [*sorted((venv / ".stamps").iterdir()), *sorted((venv / "bin").iterdir()),
             *sorted(next((venv / "lib").glob("python3*/site-packages")).iterdir())]
    return [(path.name, path.lstat().st_mtime_ns) for path in paths]


def test_second_setup_does_nothing(project_venv):
    before = snapshot(project_venv)
    run = subprocess.run(["bash", str(ROOT / "tools" / "setup.sh")],
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    assert run.stdout.strip() == f"setup: up to date ({project_venv})", run.stdout
    assert snapshot(project_venv) == before      # nothing installed, rebuilt or re-stamped
