"""Sweeps on Dask (lpa_transfer/sweeps.py), library and command line: a failing task is run
once more and then named, and nothing is merged. The graph sweeps (one machine, and a
two-node cluster in two network namespaces) are in test_inverse_dynamics_variants.py, beside
the sequential run they must equal bit for bit."""
import subprocess
import sys

import pytest

from conftest import ROOT
from lpa_transfer import sweeps

pytestmark = [pytest.mark.timeout(300)]


def test_a_failing_task_runs_once_more_then_is_named(tmp_path):
    """Library level: a task failing once succeeds on its second run; one failing every time
    is named with the end of its log after two runs."""
    count_flaky, count_broken = tmp_path / "flaky", tmp_path / "broken"
    flaky = sweeps.Task("flaky", ("bash", "-c", f"echo x >>{count_flaky}; "
                                  f"[ $(wc -l <{count_flaky}) -ge 2 ]"),
                        str(tmp_path), str(tmp_path / "flaky.log"))
    broken = sweeps.Task("broken", ("bash", "-c", f"echo x >>{count_broken}; "
                                    "echo the cause; exit 3"),
                         str(tmp_path), str(tmp_path / "broken.log"))
    said = []
    client, cluster = sweeps.connect(workers=2)
    try:
        results, failed = sweeps.run_sweep([flaky, broken], client, say=said.append)
    finally:
        client.close()
        cluster.close()
    assert list(results) == ["flaky"]
    assert count_flaky.read_text().count("x") == 2 and count_broken.read_text().count("x") == 2
    (name, text), = failed
    assert name == "broken" and "exit 3" in text and "the cause" in text
    assert any(line.startswith("task broken failed (") and "running it again" in line
               for line in said)
    assert any(line.startswith("task broken failed again") for line in said)


def test_the_cli_names_a_task_that_failed_twice_and_merges_nothing(tmp_path):
    result = subprocess.run([sys.executable, "-m", "lpa_transfer.sweeps", "inprocess",
                             "--setups", "no_such_setup", "--seeds", "0", "--workers", "1",
                             "--out", str(tmp_path / "sweep")],
                            capture_output=True, text=True, timeout=120, cwd=ROOT)
    assert result.returncode == 1, result.stdout + result.stderr
    assert result.stdout.count("task no_such_setup seed 0 failed") == 2
    assert "error: task no_such_setup seed 0 failed twice: TaskFailed: exit 2" in result.stderr
    assert not (tmp_path / "sweep" / "report.txt").exists()
