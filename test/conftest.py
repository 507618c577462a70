"""Shared fixtures. The library is installed editable (tools/setup.sh), so no sys.path edits."""
import fcntl
import json
import random
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
VENV = ROOT / ".venv"


def pytest_addoption(parser):
    parser.addoption("--shuffle", type=int, default=None, metavar="SEED",
                     help="run the tests in an order shuffled with SEED: every test must pass "
                          "alone and in any order")


def pytest_collection_modifyitems(config, items):
    """Shuffle (``--shuffle``); then the modules holding a test marked ``slow`` go first.
    tools/run_tests.sh runs each module on one worker (``--dist loadfile``, so its module
    fixtures, the scenario runs, start once) and hands the modules out in this order, so the
    workers finish together instead of one starting a long module at the end."""
    seed = config.getoption("--shuffle")
    if seed is not None:
        random.Random(seed).shuffle(items)
    slow = {item.module for item in items if item.get_closest_marker("slow")}
    items.sort(key=lambda item: item.module not in slow)     # stable: keeps the shuffle


@pytest.fixture
def project_venv():
    """The project's .venv; tests of the set-up skip under another interpreter (e.g. a scratch venv)."""
    if Path(sys.prefix).resolve() != VENV.resolve():
        pytest.skip(f"needs the project venv {VENV} (run tools/run_tests.sh)")
    return VENV


@pytest.fixture(scope="session")
def shared_run(tmp_path_factory, request):
    """``shared_run(name, make)``: the run directory and CompletedProcess of ``make(out)``, made
    once per test session even across xdist workers (modules that only read one scenario run,
    e.g. the 2-link graph's smoke run: test_two_link_graph_scenario.py and test_multi_host.py).

    The first worker to ask makes it under a lock in the session's own temporary directory;
    the others wait for the lock and read it. A run that raised (a timeout) leaves no result,
    so the next one to ask makes it again."""
    base = tmp_path_factory.getbasetemp()
    if hasattr(request.config, "workerinput"):   # an xdist worker: pytest-N/popen-gwK
        base = base.parent                       # pytest-N, this session's, shared by workers
    made = {}

    def get(name, make):
        if name in made:
            return made[name]
        home = base / f"shared-{name}"
        home.mkdir(exist_ok=True)
        done = home / "completed.json"
        with open(home / "lock", "w") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX)     # released when the file closes
            if not done.exists():
                result = make(home / "run")
                done.write_text(json.dumps([result.args, result.returncode, result.stdout,
                                            result.stderr]))
        made[name] = home / "run", subprocess.CompletedProcess(*json.loads(done.read_text()))
        return made[name]
    return get


def pytest_sessionfinish(session, exitstatus):
    """Remove the shared-memory segments of Fast DDS processes the tests killed.

    ``fastdds shm clean`` only removes segments whose owner process is gone, so it never
    disturbs a live ROS graph.
    """
    fastdds = Path(sys.prefix) / "bin" / "fastdds"
    if fastdds.exists():
        subprocess.run([str(fastdds), "shm", "clean"], capture_output=True, timeout=60,
                       check=False)
