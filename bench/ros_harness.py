"""The tests' ROS harness (test/ros_harness.py: nodes as processes on their own ROS domain)
for the benchmarks that start nodes.

test/ is no package (pytest puts it on the path), so the benchmarks load the harness from its
file; ``from bench.ros_harness import NodeProcess`` then works as in a test.
"""
import importlib.util
import sys
from pathlib import Path

_PATH = Path(__file__).resolve().parents[1] / "test" / "ros_harness.py"


def _load():
    if "ros_harness" not in sys.modules:     # one module, shared with tests in this process
        spec = importlib.util.spec_from_file_location("ros_harness", _PATH)
        module = importlib.util.module_from_spec(spec)
        sys.modules["ros_harness"] = module
        spec.loader.exec_module(module)
    return sys.modules["ros_harness"]


_harness = _load()


def __getattr__(name):
    return getattr(_harness, name)
