"""Start real ROS 2 nodes as separate processes for integration tests, and stop them cleanly.

Each test gets its own ``ROS_DOMAIN_ID`` (so tests never see each other's traffic), discovery
stays on this host, and every node writes its own log file. ``stop()`` sends SIGINT first
(nodes must finalise their files on it) and falls back to SIGKILL, because rclpy 7.1 can
ignore signals while blocked in a wait set.
"""
import ctypes
import itertools
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

_DOMAINS = itertools.count()
_PR_SET_PDEATHSIG = 1


def _terminate_with_parent():
    """Child side of Popen: get SIGTERM when the test process dies, even if pytest itself is
    killed before its fixtures can stop the node (the node then finalises and exits)."""
    ctypes.CDLL(None, use_errno=True).prctl(_PR_SET_PDEATHSIG, signal.SIGTERM)


STOP_SECONDS = 240   # a scenario script's own shutdown: at most 20 s a node (graph.sh)
INTERACTIVE_DOMAIN_ID = 42   # tools/env.sh's default: scenario runs started by hand use it


def unique_domain_id():
    """A ROS domain id unlikely to clash with other test processes on this host, and never the
    interactive default, so tests do not talk to a scenario running meanwhile.

    Under pytest-xdist each worker (``PYTEST_XDIST_WORKER`` = gw0, gw1, ...) draws from its own
    band of 1..200, so two workers never share a domain; otherwise the id mixes in the pid.
    """
    worker = os.environ.get("PYTEST_XDIST_WORKER", "")
    while True:
        if worker.startswith("gw"):
            count = max(1, int(os.environ.get("PYTEST_XDIST_WORKER_COUNT", "1")))
            band = 200 // count
            domain_id = 1 + int(worker[2:]) % count * band + next(_DOMAINS) % band
        else:
            domain_id = 1 + (os.getpid() * 7 + next(_DOMAINS)) % 100
        if domain_id != INTERACTIVE_DOMAIN_ID:
            return domain_id


def ros_env(domain_id, log_dir):
    env = dict(os.environ)
    env.update(ROS_DOMAIN_ID=str(domain_id), ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST",
               ROS_LOG_DIR=str(log_dir), PYTHONUNBUFFERED="1")
    return env


def ros_params(**params):
    """``--ros-args -p name:=value ...`` for a node's command line."""
    args = ["--ros-args"]
    for name, value in params.items():
        if isinstance(value, bool):
            value = str(value).lower()
        args += ["-p", f"{name}:={value}"]
    return args


class NodeProcess:
    """One node (``python -m lpa_transfer_nodes.<module>``) in its own process group."""

    def __init__(self, module, domain_id, log_dir, args=(), name=None):
        self.module, self.log_dir = module, Path(log_dir)
        self.log_dir.mkdir(parents=True, exist_ok=True)
        self.log_path = self.log_dir / f"{name or module}.log"
        self._log = open(self.log_path, "ab")
        self.process = subprocess.Popen(
            [sys.executable, "-m", f"lpa_transfer_nodes.{module}", *args],
            env=ros_env(domain_id, self.log_dir), stdout=self._log, stderr=subprocess.STDOUT,
            start_new_session=True, preexec_fn=_terminate_with_parent)

    def log(self):
        return self.log_path.read_text(errors="replace")

    def alive(self):
        return self.process.poll() is None

    def stop(self, sig=signal.SIGINT, timeout=15.0):
        """Signal the node, wait up to ``timeout`` s, then SIGKILL; returns the exit code."""
        if self.alive():
            os.killpg(self.process.pid, sig)
            try:
                self.process.wait(timeout)
            except subprocess.TimeoutExpired:
                os.killpg(self.process.pid, signal.SIGKILL)
                self.process.wait()
        self._log.close()
        return self.process.returncode

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.stop()


def wait_until(predicate, timeout=20.0, period=0.05, what="condition"):
    """Poll ``predicate`` until it returns truthy; raise TimeoutError naming ``what``."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        value = predicate()
        if value:
            return value
        time.sleep(period)
    raise TimeoutError(f"timed out after {timeout} s waiting for {what}")


def call_service(executor, client, request, timeout=20.0):
    """Wait for the service, call it and spin until the answer arrives (the nodes' own
    helpers: not spin_until_future_complete, which slows down with every call in rclpy 7.1)."""
    from lpa_transfer_nodes.calls import call_service as call, wait_for_services

    wait_for_services([client], timeout, threading.Event())
    return call(executor, client, request, timeout)


class ClientNode:
    """An rclpy node in the test process, on its own context and domain, with its executor.

    Tests build their publishers, subscriptions and clients on ``.node`` and spin with
    :meth:`spin_for` / :meth:`spin_until` / :meth:`call`; :meth:`close` shuts it all down.
    """

    def __init__(self, domain_id, name):
        import rclpy
        from rclpy.executors import SingleThreadedExecutor

        self._rclpy = rclpy
        self.context = rclpy.Context()
        rclpy.init(context=self.context, domain_id=domain_id)
        self.node = rclpy.create_node(name, context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)

    def spin_for(self, seconds):
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline:
            self.executor.spin_once(timeout_sec=0.02)

    def spin_until(self, predicate, timeout=5.0, what="condition"):
        def spun():
            self.executor.spin_once(timeout_sec=0.05)
            return predicate()
        return wait_until(spun, timeout=timeout, period=0, what=what)

    def call(self, client, request, timeout=20.0):
        return call_service(self.executor, client, request, timeout)

    def action_client(self, action_type, name):
        """An rclpy ActionClient on this node."""
        from rclpy.action import ActionClient

        return ActionClient(self.node, action_type, name)

    def run(self, client, goal, timeout=20.0, on_feedback=None):
        """Send ``goal`` on the ActionClient ``client`` (waiting for its server first) and
        spin until the result: the Result (``success``/``message`` as a service's answer)."""
        from lpa_transfer_nodes.calls import run_action, wait_for_services

        wait_for_services([client], timeout, threading.Event(), self.executor)
        return run_action(self.executor, client, goal, timeout, on_feedback=on_feedback)

    def close(self):
        self.executor.shutdown()
        self.node.destroy_node()
        self._rclpy.try_shutdown(context=self.context)


class PairListener(ClientNode):
    """Collects the CorrespondenceSample messages on ``/correspondences`` in the test
    process."""

    def __init__(self, domain_id):
        from lpa_transfer_interfaces.msg import CorrespondenceSample
        from lpa_transfer_nodes.qos import SAMPLE_QOS

        super().__init__(domain_id, "pair_listener")
        self.samples = []
        self.node.create_subscription(CorrespondenceSample, "/correspondences",
                                      self.samples.append, SAMPLE_QOS)

    def matrices(self):
        """(source, target) arrays of the samples in index order."""
        import numpy as np

        ordered = sorted(self.samples, key=lambda msg: msg.index)
        return (np.array([msg.source for msg in ordered]),
                np.array([msg.target for msg in ordered]))


def start_robot_sims(domain_id, log_dir, robots, **params):
    """A robot_sim process per side of ``robots`` ({side: robot file}), in namespace
    ``/<side>``, with ``params`` (e.g. initial_positions)."""
    return [NodeProcess("robot_sim", domain_id, log_dir, name=f"{side}_sim",
                        args=ros_params(robot=robot, **params) + ["-r", f"__ns:=/{side}"])
            for side, robot in robots.items()]


def run_to_end(process, timeout=60):
    """Wait for a node with one job to exit; its exit code (after ``stop()``)."""
    process.process.wait(timeout)
    return process.stop()


def run_scenario(scenario_dir, out, config="smoke.yaml", timeout=300, overrides=(),
                 extra_args=()):
    """Run ``<scenario_dir>/run.sh --config <config> [--override <file>]... --out <out>
    [extra_args]`` on
    its own ROS domain (files relative to the scenario); the CompletedProcess (text output
    captured). Past ``timeout`` the script gets SIGTERM, which its trap turns into stopping
    every node in order (each runs in its own session, out of reach of a kill of the script
    alone; graph.sh), then subprocess.TimeoutExpired is raised."""
    env = dict(os.environ, ROS_DOMAIN_ID=str(unique_domain_id()))
    args = ["--config", str(Path(scenario_dir) / config)]
    for override in overrides:
        args += ["--override", str(Path(scenario_dir) / override)]
    command = ["bash", str(Path(scenario_dir) / "run.sh"), *args, "--out", str(out),
               *extra_args]
    with subprocess.Popen(command, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                          text=True) as script:
        try:
            stdout, stderr = script.communicate(timeout=timeout)
        except subprocess.TimeoutExpired:
            script.terminate()
            try:
                stdout, stderr = script.communicate(timeout=STOP_SECONDS)
            except subprocess.TimeoutExpired:
                script.kill()
                stdout, stderr = script.communicate()
            raise subprocess.TimeoutExpired(command, timeout, stdout, stderr) from None
    return subprocess.CompletedProcess(command, script.returncode, stdout, stderr)
