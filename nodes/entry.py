"""The ``main()`` of a node: start it, spin it until SIGINT/SIGTERM, then drain what is
queued, deliver what was published and shut down; a node that cannot start says why in one
FATAL line and exits 1.
"""
import signal
import threading
import time

import rclpy
from rclpy.duration import Duration
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.experimental import EventsExecutor
from rclpy.signals import SignalHandlerOptions

#: The executor of the lock-step control loop's two ends (robot_sim's step service and the
#: learners' robot clients): rclpy's C++ events executor, which dispatches a service request
#: or response with far less Python work per call than SingleThreadedExecutor
#: (bench/bench_control_period.py).
FastExecutor = EventsExecutor


def init_with_stop_event(args=None):
    """``rclpy.init`` without rclpy's signal handlers; SIGINT/SIGTERM set the returned event.

    The nodes then leave their ``spin_once`` loop themselves, drain what is queued and close
    their files before shutting rclpy down (rclpy's own handler would shut the context first).
    """
    rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
    stop = threading.Event()
    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, lambda *_: stop.set())
    return stop


def spin_until_stopped(node, stop, executor_class=SingleThreadedExecutor):
    """Serve ``node`` until SIGINT/SIGTERM sets ``stop``, then clean up and shut rclpy down.

    A ``spin_once`` loop, not ``rclpy.spin`` (which can ignore signals in rclpy 7.1).
    ``executor_class``: :class:`FastExecutor` for a node whose callbacks are a control loop's
    critical path (robot_sim's step service).
    """
    executor = executor_class()
    executor.add_node(node)
    busy = getattr(node, "busy", None)      # held while a long job runs (long_job)
    try:
        while rclpy.ok() and not stop.is_set():
            executor.spin_once(timeout_sec=0.2)
            if busy is not None and busy.locked():
                # rclpy's executors hand a running job's task back at once, so this loop
                # would spin hot and starve the job's thread of the GIL (bench/README.md,
                # "run_trials as an action"): poll every 10 ms instead (cancels, parameters)
                stop.wait(0.01)
        _drain(node, executor)
        _deliver(node)
    except ExternalShutdownException:
        pass
    finally:
        executor.shutdown()
        node.destroy_node()
        rclpy.try_shutdown()


def _drain(node, executor, timeout=5.0):
    """After SIGINT/SIGTERM: a long job (:func:`long_job`, its ``node.busy`` lock held) sees
    the stop at its next step and ends; spin until it has and its result has gone out, so
    its client gets the answer "stopped" rather than nothing (at most ``timeout`` s)."""
    busy = getattr(node, "busy", None)
    if busy is None:
        return
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if busy.acquire(blocking=False):
            busy.release()
            flush = time.monotonic() + 0.3         # the result response, then stop
            while time.monotonic() < flush:
                executor.spin_once(timeout_sec=0.05)
            return
        executor.spin_once(timeout_sec=0.05)


def _deliver(node, timeout=1.0):
    """Before the node goes: wait (at most ``timeout`` s in all) until its subscribers have
    acknowledged what its reliable publishers sent, so that a message published just before
    SIGINT (a learner's last trial_result and task_markers) reaches the recorder rather than
    dying with the process while DDS would still have resent it. Nothing to wait for once
    the context is shut down."""
    if not rclpy.ok():
        return
    deadline = time.monotonic() + timeout
    for publisher in node.publishers:
        left = deadline - time.monotonic()
        if left <= 0 or not publisher.wait_for_all_acked(Duration(seconds=left)):
            return


def _describe(exc):
    """An error for the log: the message of an expected failure (bad parameter or request,
    missing file or service), the type too for anything else."""
    if isinstance(exc, (ValueError, RuntimeError, OSError)):
        return str(exc)
    return f"{type(exc).__name__}: {exc}"


def serve(name, make_node, args=None, executor_class=SingleThreadedExecutor):
    """main() of a serving node: ``make_node(stop)`` then spin until SIGINT/SIGTERM (with an
    ``executor_class``, see :func:`spin_until_stopped`); a node that cannot start logs why
    and exits 1."""
    stop = init_with_stop_event(args)
    try:
        node = make_node(stop)
    except Exception as exc:  # a bad parameter or file: say what, exit 1
        rclpy.logging.get_logger(name).fatal(f"cannot start: {_describe(exc)}")
        rclpy.try_shutdown()
        raise SystemExit(1) from None
    spin_until_stopped(node, stop, executor_class)


def run_job(name, make_node, job, args=None):
    """main() of a node with one job (a collector, an experiment client): ``make_node(stop)``,
    then ``job(node)``, then everything shut down (the node's ``spinner`` executor too).
    Returns ``(node, job's result)``; any error is logged as fatal and exits 1."""
    stop = init_with_stop_event(args)
    node = None
    try:
        node = make_node(stop)
        return node, job(node)
    except Exception as exc:  # a bad parameter, a refused call, a missing service: say what
        rclpy.logging.get_logger(name).fatal(_describe(exc))
        raise SystemExit(1) from None
    finally:
        if node is not None:
            if getattr(node, "spinner", None) is not None:
                node.spinner.shutdown()
            node.destroy_node()
        rclpy.try_shutdown()
