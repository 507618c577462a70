"""rclpy helpers shared by the nodes (no ``main``: not a console script)."""
import array
import importlib
import math
import signal
import threading
import time
import traceback
import weakref

import numpy as np
import rclpy
from rclpy.duration import Duration
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.experimental import EventsExecutor
from rclpy.exceptions import (InvalidParameterTypeException, InvalidParameterValueException,
                              ParameterUninitializedException)
from rclpy.parameter import Parameter
from rclpy.qos import (DurabilityPolicy, HistoryPolicy, LivelinessPolicy, QoSProfile,
                       ReliabilityPolicy)
from rclpy.signals import SignalHandlerOptions

from builtin_interfaces.msg import Time
from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor

from lpa_transfer.recording.bag import split_type_name
from lpa_transfer.robots.simulator import SimState
from lpa_transfer_interfaces.msg import Matrix
from lpa_transfer_interfaces.srv import ResetRobot, StepRobot


#: The executor of the lock-step control loop's two ends (robot_sim's step service and the
#: learners' robot clients): rclpy's C++ events executor, which dispatches a service request
#: or response with far less Python work per call than SingleThreadedExecutor
#: (bench/bench_control_period.py).
FastExecutor = EventsExecutor

#: The frame of every pose and point the nodes publish (robot_sim's bases stand at its origin).
WORLD_FRAME = "world"

#: Correspondence topics: every sample must arrive (reliable, deep queue); the batch is
#: latched (transient local) so that a subscriber that joins late still gets the last one.
SAMPLE_QOS = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
BATCH_QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                       durability=DurabilityPolicy.TRANSIENT_LOCAL)
#: /clock (rosgraph_msgs/Clock) from robot_sim and the player: what rclpy's TimeSource
#: subscribes with (best effort, only the latest time matters).
CLOCK_QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT)
#: robot_description and /tf_static: latched (reliable, transient local, depth 1), as
#: robot_state_publisher and tf2's static broadcaster offer them.
LATCHED_QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                         durability=DurabilityPolicy.TRANSIENT_LOCAL)
#: task_markers: latched as above, but the last MARKERS_DEPTH arrays stay with the writer
#: until acknowledged, so a recorder that lags behind a few trials still records every array
#: (with depth 1, an array not yet acknowledged is dropped when the next one is published); a
#: late viewer replays them in order, each clearing the one before.
MARKERS_DEPTH = 10
MARKERS_QOS = QoSProfile(depth=MARKERS_DEPTH, reliability=ReliabilityPolicy.RELIABLE,
                         durability=DurabilityPolicy.TRANSIENT_LOCAL)
#: /tf: as tf2's TransformBroadcaster offers it (reliable, volatile, depth 100).
TF_QOS = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)


def to_matrix(values):
    """A Matrix message of a 2-D float64 array: one buffer copy into the ``array.array`` that
    rclpy takes without converting element by element (see the ROS notes)."""
    values = np.ascontiguousarray(values, dtype=np.float64)   # no copy when it already is
    data = array.array("d")
    data.frombytes(memoryview(values.reshape(-1)).cast("B"))
    return Matrix(rows=values.shape[0], cols=values.shape[1], data=data)


def from_matrix(msg, name):
    """The (rows, cols) array of a Matrix message; ValueError if rows*cols != len(data)."""
    return matrix_from_rows(msg.rows, msg.cols, msg.data, name)


def sim_stamp(seconds):
    """A builtin_interfaces/Time of a simulated time in seconds."""
    nanoseconds = int(round(seconds * 1e9))
    return Time(sec=nanoseconds // 1_000_000_000, nanosec=nanoseconds % 1_000_000_000)


def message_class(type_name):
    """The Python class of ``pkg/msg/Type`` (rosidl_runtime_py is not available as a wheel)."""
    package, name = split_type_name(type_name)
    return getattr(importlib.import_module(f"{package}.msg"), name)


def array_parameter(node, name, parameter_type=Parameter.Type.STRING_ARRAY):
    """Declare an array parameter without default (rclpy cannot infer the type of ``[]``);
    unset means ``[]``."""
    node.declare_parameter(name, parameter_type)
    try:
        return list(node.get_parameter(name).value or [])
    except ParameterUninitializedException:
        return []


#: The ends of an integer range open on that side (rcl_interfaces' IntegerRange is int64).
INT64_MIN, INT64_MAX = -2 ** 63, 2 ** 63 - 1

_TYPE_TEXT = {Parameter.Type.BOOL: "a bool", Parameter.Type.INTEGER: "an integer",
              Parameter.Type.DOUBLE: "a number", Parameter.Type.STRING: "a string",
              Parameter.Type.BOOL_ARRAY: "a list of bools",
              Parameter.Type.INTEGER_ARRAY: "a list of integers",
              Parameter.Type.DOUBLE_ARRAY: "a list of numbers",
              Parameter.Type.STRING_ARRAY: "a list of strings"}


def _number(value):
    return f"{value:g}" if isinstance(value, float) else str(value)


def allowed_text(parameter_type, range=None, positive=False, finite=False, choices=None):
    """What a parameter accepts, as the descriptor's constraints and the errors say it:
    "an integer >= 1", "a finite number > 0", "a number in [0, 1]", "one of 'a', 'b'"."""
    if choices:
        return "one of " + ", ".join(repr(choice) for choice in choices)
    text = _TYPE_TEXT[parameter_type]
    if parameter_type == Parameter.Type.DOUBLE and finite:
        text = "a finite number"
    low, high = range if range is not None else (None, None)
    if positive:
        low = None if low is not None and low <= 0 else low
        return f"{text} > 0" + (f" and <= {_number(high)}" if high is not None else "")
    if low is not None and high is not None:
        return f"{text} in [{_number(low)}, {_number(high)}]"
    if low is not None:
        return f"{text} >= {_number(low)}"
    if high is not None:
        return f"{text} <= {_number(high)}"
    return text


def parameter_descriptor(parameter_type, description, *, read_only=True, range=None,
                         positive=False, finite=False, choices=None, additional_constraints=""):
    """An rcl_interfaces ParameterDescriptor: ``description`` (what it is, its unit),
    ``read_only`` (a change at run time would not take effect), ``range`` = (low, high), both
    inclusive, None for an open side, as an IntegerRange or FloatingPointRange (rclpy then
    refuses values outside it), and in ``additional_constraints`` what values are allowed
    (:func:`allowed_text`) followed by ``additional_constraints``."""
    descriptor = ParameterDescriptor(description=description, type=parameter_type.value,
                                     read_only=read_only)
    if positive:
        range = (0, None if range is None else range[1])
    if range is not None:
        low, high = range
        if parameter_type == Parameter.Type.INTEGER:
            descriptor.integer_range = [IntegerRange(
                from_value=INT64_MIN if low is None else int(low),
                to_value=INT64_MAX if high is None else int(high), step=0)]
        elif parameter_type == Parameter.Type.DOUBLE:
            descriptor.floating_point_range = [FloatingPointRange(
                from_value=-math.inf if low is None else float(low),
                to_value=math.inf if high is None else float(high), step=0.0)]
        else:
            raise ValueError(f"a range needs an integer or double parameter, not "
                             f"{parameter_type.name}")
    constraints = []
    if range is not None or positive or finite or choices:
        constraints.append(allowed_text(parameter_type, range, positive, finite, choices))
    if additional_constraints:
        constraints.append(additional_constraints)
    descriptor.additional_constraints = "; ".join(constraints)
    return descriptor


def declare(node, name, default, description, *, read_only=True, range=None, positive=False,
            finite=False, choices=None, additional_constraints=""):
    """Declare the parameter ``name`` with its default and a descriptor
    (:func:`parameter_descriptor`; the type is the default's) and return its value.

    ``range`` = (low, high), inclusive, None for an open side: rclpy refuses values outside
    it, at start and at run time. ``positive`` (> 0), ``finite`` (no inf/NaN) and ``choices``
    (the allowed values) are checked here, at start. Read-only parameters (the default: the
    nodes read their parameters once, at start) are refused at run time by rclpy. A value
    that breaks any of this raises ValueError "the parameter NAME must be ALLOWED, got VALUE"
    (one FATAL line with :func:`serve` and :func:`run_job`), also for a value of the wrong
    type.
    """
    parameter_type = Parameter.Type.from_parameter_value(default)
    descriptor = parameter_descriptor(
        parameter_type, description, read_only=read_only, range=range, positive=positive,
        finite=finite, choices=choices, additional_constraints=additional_constraints)
    allowed = allowed_text(parameter_type, range, positive, finite, choices)
    value = _declared(node, name, default, descriptor, allowed)
    bad = ((choices and value not in choices)
           or (positive and not value > 0)
           or (finite and not math.isfinite(value)))
    if bad:
        raise ValueError(f"the parameter {name} must be {allowed}, got {value!r}")
    return value


def declare_array(node, name, parameter_type, description, *, read_only=True,
                  additional_constraints=""):
    """Declare an array parameter without default (rclpy cannot infer the type of ``[]``),
    with a descriptor as :func:`declare`; unset means ``[]``. Returns a list."""
    descriptor = parameter_descriptor(parameter_type, description, read_only=read_only,
                                      additional_constraints=additional_constraints)
    value = _declared(node, name, parameter_type, descriptor, _TYPE_TEXT[parameter_type])
    return list(value or [])


def _declared(node, name, default, descriptor, allowed):
    """``node.declare_parameter`` whose refusal of the given value (out of range, wrong type)
    is a ValueError naming the parameter and what it accepts."""
    try:
        parameter = node.declare_parameter(name, default, descriptor)
    except (InvalidParameterValueException, InvalidParameterTypeException):
        given = getattr(node, "_parameter_overrides", {}).get(name)
        raise ValueError(f"the parameter {name} must be {allowed}, got "
                         f"{given.value if given is not None else '?'!r}") from None
    try:
        return parameter.value
    except ParameterUninitializedException:
        return None


def describe_use_sim_time(node):
    """Give rclpy's own ``use_sim_time`` parameter a description (it has none); it stays
    writable: rclpy's time source follows it at run time."""
    if node.has_parameter("use_sim_time"):
        descriptor = node.describe_parameter("use_sim_time")
        if not descriptor.description:
            descriptor.description = ("take this node's ROS clock from the /clock topic "
                                      "(standard ROS parameter, handled by rclpy)")
            node.set_descriptor("use_sim_time", descriptor)


def answering(node, name, handler):
    """A service callback around ``handler(request, response) -> message``.

    Fills ``success`` and ``message``: the handler's message, or ``success=false`` with the
    ValueError's text (a bad request), or with "internal error" for anything else, whose
    traceback is logged. Either way the node keeps serving.
    """
    def callback(request, response):
        start = time.perf_counter()
        try:
            response.message = handler(request, response)
            response.success = True
        except ValueError as exc:
            response.success, response.message = False, str(exc)
        except Exception as exc:  # keep serving whatever happens; the log has the trace
            node.get_logger().error(f"{name} failed:\n{traceback.format_exc()}")
            response.success, response.message = False, f"internal error: {exc!r}"
        node.get_logger().debug(f"{name} handled in {1000 * (time.perf_counter() - start):.2f} ms")
        return response
    return callback


class JobCancelled(Exception):
    """Raised by a long job's handler when its client cancelled the goal (:func:`long_job`)."""


def long_job(node, action_type, name, handler, busy):
    """An action server ``name`` (e.g. ``~/run_trials``) for a job that runs for minutes,
    around ``handler(goal, result, feedback, cancelled) -> message``.

    ``feedback(**fields)`` publishes the action's Feedback; ``cancelled()`` is True once the
    client asked to cancel, and the handler then raises :class:`JobCancelled` at its next
    step (the goal ends canceled). ``success`` and ``message`` of the Result are filled as
    :func:`answering` fills a response: the handler's message; a ValueError's text (the goal
    aborted, e.g. a bad goal); "internal error" for anything else (traceback logged). One goal
    at a time: ``busy`` (a threading.Lock the node's other state-changing services also take)
    is held while a goal runs, and a goal that arrives meanwhile is rejected. The server is
    in its own reentrant callback group, so with a multi-threaded executor a cancel is heard
    while the job runs.
    """
    from rclpy.action import ActionServer, CancelResponse, GoalResponse
    from rclpy.callback_groups import ReentrantCallbackGroup

    def on_goal(goal):
        if busy.acquire(blocking=False):
            return GoalResponse.ACCEPT
        node.get_logger().warning(f"{name}: goal rejected, a job is running")
        return GoalResponse.REJECT

    def execute(goal_handle):
        result, start = action_type.Result(), time.perf_counter()
        try:
            result.message = handler(
                goal_handle.request, result,
                lambda **fields: goal_handle.publish_feedback(action_type.Feedback(**fields)),
                lambda: goal_handle.is_cancel_requested)
            result.success = True
            goal_handle.succeed()
        except JobCancelled as exc:
            result.success, result.message = False, f"cancelled: {exc}"
            goal_handle.canceled()
        except ValueError as exc:
            result.success, result.message = False, str(exc)
            goal_handle.abort()
        except Exception as exc:  # keep serving whatever happens; the log has the trace
            node.get_logger().error(f"{name} failed:\n{traceback.format_exc()}")
            result.success, result.message = False, f"internal error: {exc!r}"
            goal_handle.abort()
        finally:
            busy.release()
        node.get_logger().info(f"{name}: {result.message} "
                               f"({time.perf_counter() - start:.1f} s)")
        return result

    return ActionServer(node, action_type, name, execute, goal_callback=on_goal,
                        cancel_callback=lambda goal_handle: CancelResponse.ACCEPT,
                        callback_group=ReentrantCallbackGroup())


def unless_busy(busy, job, handler):
    """``handler(request, response)`` for a service that changes what a long job (``job``,
    e.g. "run_trials") works on: refused with a ValueError while ``busy`` (the job's lock,
    :func:`long_job`) is held, else run holding it. Wrap it in :func:`answering`."""
    def guarded(request, response):
        if not busy.acquire(blocking=False):
            raise ValueError(f"a {job} goal is running: call again after it (or cancel it)")
        try:
            return handler(request, response)
        finally:
            busy.release()
    return guarded


def run_action(executor, client, goal, timeout, stop=None, on_feedback=None):
    """Send ``goal`` to an action server and spin ``executor`` until its result arrives;
    returns the Result. ``on_feedback(feedback)`` sees each Feedback. After ``timeout`` s, or
    once ``stop`` (SIGINT/SIGTERM) is set, the goal is cancelled and ServiceTimeout raised;
    RuntimeError if the server rejects the goal."""
    return run_actions(executor, [(client, goal, on_feedback)], timeout, stop)[0]


def run_actions(executor, goals, timeout, stop=None):
    """:func:`run_action` for several goals at once, each ``(client, goal, on_feedback)`` on
    its own action server: all are sent, then ``executor`` spins until every result is in
    (the servers work in parallel); the Results in that order. On a timeout, a stop or a
    rejected goal every goal still running is cancelled before the error is raised."""
    deadline = time.monotonic() + timeout

    def wait(futures):
        while not all(future.done() for future in futures):
            stopped = stop is not None and stop.is_set()
            if stopped or time.monotonic() > deadline:
                return "stopped" if stopped else "timeout"
            executor.spin_once(timeout_sec=0.05)
        return None

    def cancel(handles):
        cancels = [handle.cancel_goal_async() for handle in handles]
        until = time.monotonic() + 5.0
        while not all(c.done() for c in cancels) and time.monotonic() < until:
            executor.spin_once(timeout_sec=0.05)

    names = [client._action_name for client, _, _ in goals]
    sent = [client.send_goal_async(
        goal, feedback_callback=None if on_feedback is None
        else lambda message, f=on_feedback: f(message.feedback))
        for client, goal, on_feedback in goals]
    if (why := wait(sent)) is not None:
        cancel([f.result() for f in sent if f.done() and f.result().accepted])
        raise ServiceTimeout(f"{why} while action(s) {', '.join(names)} took the goal")
    handles = [future.result() for future in sent]
    refused = [name for name, handle in zip(names, handles) if not handle.accepted]
    if refused:
        cancel([handle for handle in handles if handle.accepted])
        raise RuntimeError(f"action {refused[0]} rejected the goal (it runs one goal at a time)")
    answers = [handle.get_result_async() for handle in handles]
    if (why := wait(answers)) is not None:
        cancel([h for h, a in zip(handles, answers) if not a.done()])
        late = [n for n, a in zip(names, answers) if not a.done()]
        raise ServiceTimeout(f"stopped while waiting for action {', '.join(late)} (goal "
                             "cancelled)" if why == "stopped" else
                             f"action {', '.join(late)} did not finish within {timeout:g} s "
                             "(goal cancelled)")
    return [answer.result().result for answer in answers]


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


def qos_to_dict(qos):
    """A QoS profile as the lower-case dict ``lpa_transfer.recording.bag.qos_profiles_yaml`` writes."""
    return {"history": qos.history.name.lower(), "depth": qos.depth,
            "reliability": qos.reliability.name.lower(),
            "durability": qos.durability.name.lower(), "liveliness": qos.liveliness.name.lower()}


def qos_from_offered(offered, depth):
    """A keep-last QoS of ``depth`` compatible with every offered profile (dicts or QoSProfiles).

    As rosbag2 does: best effort if any publisher offers only that, transient-local only if
    every publisher offers it; with nothing offered, reliable and volatile.
    """
    profiles = [qos_to_dict(p) if isinstance(p, QoSProfile) else p for p in offered]
    reliable = all(p.get("reliability") == "reliable" for p in profiles)
    transient_local = bool(profiles) and all(
        p.get("durability") == "transient_local" for p in profiles)
    return QoSProfile(
        history=HistoryPolicy.KEEP_LAST, depth=depth,
        reliability=ReliabilityPolicy.RELIABLE if reliable else ReliabilityPolicy.BEST_EFFORT,
        durability=(DurabilityPolicy.TRANSIENT_LOCAL if transient_local
                    else DurabilityPolicy.VOLATILE),
        liveliness=LivelinessPolicy.AUTOMATIC)


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


class ServiceTimeout(RuntimeError):
    """A service did not appear or answer in time."""


#: Clients whose first wait has let discovery settle (see :func:`wait_for_services`).
_SETTLED = weakref.WeakSet()
#: How long a client's first wait lets discovery settle once its service is available (s).
SETTLE_SECONDS = 0.5


def wait_for_services(clients, timeout, stop, executor=None):
    """Wait until every client's service (or action server, for an ActionClient) is
    available; ServiceTimeout after ``timeout`` s.

    With an ``executor`` (a job node's own), it spins while it waits, so that the node
    answers meanwhile, e.g. its parameter services (``~/describe_parameters``).

    The first wait of a client then lets DDS discovery settle for ``SETTLE_SECONDS``: Fast
    DDS reports a service available once the client has matched the server, which may not
    yet have matched the client's response reader; a request sent in that window is
    answered into the void (the server logs "failed to send response (timeout)") and the
    call times out. Seen once in CI, on a test's first StepRobot call.
    """
    deadline = time.monotonic() + timeout
    def available(client):
        action = hasattr(client, "server_is_ready")      # an rclpy ActionClient
        if executor is None:
            return (client.wait_for_server if action else client.wait_for_service)(
                timeout_sec=0.2)
        executor.spin_once(timeout_sec=0.1)
        return client.server_is_ready() if action else client.service_is_ready()

    for client in clients:
        name = getattr(client, "srv_name", None) or f"action {client._action_name}"
        while not available(client):
            if stop.is_set():
                raise ServiceTimeout(f"stopped (SIGINT/SIGTERM) while waiting for {name}")
            if time.monotonic() > deadline:
                raise ServiceTimeout(f"service {name} is not available after "
                                     f"{timeout:g} s (is its node running, in this ROS domain?)")
    fresh = [client for client in clients if client not in _SETTLED]
    if fresh and not stop.wait(SETTLE_SECONDS):
        _SETTLED.update(fresh)


def wait_for_subscribers(node, topic, count, timeout, stop):
    """Wait until ``topic`` has ``count`` subscribers; ServiceTimeout after ``timeout`` s."""
    deadline = time.monotonic() + timeout
    while node.count_subscribers(topic) < count and not stop.is_set():
        if time.monotonic() > deadline:
            raise ServiceTimeout(f"{topic} has {node.count_subscribers(topic)} subscribers "
                                 f"after {timeout:g} s, waited for {count}")
        time.sleep(0.05)


def call_service(executor, client, request, timeout, stop=None, resend_every=None):
    """Call a service and wait for the answer with a ``spin_once`` loop (rclpy 7.1's
    ``spin_until_future_complete`` slows down with every call); ServiceTimeout after
    ``timeout`` s, or as soon as the ``stop`` event (SIGINT/SIGTERM) is set.

    ``resend_every`` (s), for idempotent requests only: a request not answered by then is
    sent again (the earlier one's late answer is dropped). A request sent before discovery
    has fully settled can be answered into the void (see :func:`wait_for_services`); seen in
    CI on a learner's first reset under load, after the settle time.
    """
    deadline = time.monotonic() + timeout
    while True:
        future = client.call_async(request)
        resend = time.monotonic() + resend_every if resend_every else math.inf
        while not future.done() and time.monotonic() < resend:
            stopped = stop is not None and stop.is_set()
            if stopped or time.monotonic() > deadline:
                client.remove_pending_request(future)
                raise ServiceTimeout(f"stopped while waiting for {client.srv_name}" if stopped
                                     else f"service {client.srv_name} did not answer within "
                                          f"{timeout:g} s")
            executor.spin_once(timeout_sec=0.05)
        if future.done():
            return future.result()
        client.remove_pending_request(future)


def robot_stepper(call, client, name):
    """``step(command, n_steps) -> SimState`` over a robot_sim's StepRobot service.

    ``call(client, request, **options)`` makes the blocking call (e.g. :func:`call_service`
    bound to an executor); a refused step raises RuntimeError with the simulator's message.
    """
    def step(command, n_steps):
        response = call(client, StepRobot.Request(command=[float(c) for c in command],
                                                  n_steps=int(n_steps)))
        if not response.success:
            raise RuntimeError(f"the {name} robot refused a step: {response.message}")
        return sim_state(response)
    return step


#: A reset not answered within this is sent again (a reset is idempotent: the same positions,
#: the clock kept), see :func:`call_service`.
RESET_RESEND_SECONDS = 3.0


def robot_resetter(call, client, name):
    """``reset(positions) -> SimState`` over a robot_sim's ResetRobot service: the robot at rest
    at ``positions``; a refused reset raises RuntimeError with the simulator's message."""
    def reset(positions):
        response = call(client, ResetRobot.Request(positions=[float(q) for q in positions]),
                        resend_every=RESET_RESEND_SECONDS)
        if not response.success:
            raise RuntimeError(f"the {name} robot refused a reset: {response.message}")
        return sim_state(response)
    return reset


class RobotClients:
    """A robot_sim's StepRobot and ResetRobot clients for calls made inside a node's service
    callbacks: on a client node of their own (``<node>_robot_client``, no command-line
    remaps, which would rename it), spun by their own ``executor``, so that a callback never
    re-enters its node's executor. ``destroy()`` with the node."""

    def __init__(self, node, step_service, reset_service):
        self.node = rclpy.create_node(f"{node.get_name()}_robot_client",
                                      namespace=node.get_namespace(), use_global_arguments=False)
        self.executor = FastExecutor()
        self.executor.add_node(self.node)
        self.step = self.node.create_client(StepRobot, step_service)
        self.reset = self.node.create_client(ResetRobot, reset_service)

    def destroy(self):
        self.executor.shutdown()
        self.node.destroy_node()


def sim_state(response):
    """The SimState of a StepRobot or ResetRobot answer."""
    state, point = response.joint_state, response.end_effector
    return SimState(response.sim_time, np.array(state.position), np.array(state.velocity),
                    np.array(state.effort), np.array([point.x, point.y, point.z]))


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


class ServiceCalls:
    """Blocking service calls and action goals of a job node (an experiment client): one
    client per name, made on first use; ``call(srv_type, name, **request_fields)`` returns
    the answer, ``run(action_type, name, **goal_fields)`` the result; both raise RuntimeError
    when it says ``success = false``."""

    def __init__(self, node, executor, timeout, stop):
        self.node, self.executor, self.timeout, self.stop = node, executor, timeout, stop
        self.clients = {}

    def client(self, srv_type, name):
        if name not in self.clients:
            self.clients[name] = self.node.create_client(srv_type, name)
        return self.clients[name]

    def call(self, srv_type, name, **fields):
        answer = call_service(self.executor, self.client(srv_type, name),
                              srv_type.Request(**fields), self.timeout, self.stop)
        if not answer.success:
            raise RuntimeError(f"{name} failed: {answer.message}")
        return answer

    def action_client(self, action_type, name):
        from rclpy.action import ActionClient

        if name not in self.clients:
            self.clients[name] = ActionClient(self.node, action_type, name)
        return self.clients[name]

    def run(self, action_type, name, on_feedback=None, **fields):
        """Run the goal ``fields`` on the action ``name`` (:func:`run_action`); its Result,
        RuntimeError when it says ``success = false``."""
        return self.run_many(action_type, [(name, on_feedback, fields)])[0]

    def run_many(self, action_type, goals):
        """Run goals ``(name, on_feedback, fields)`` on different servers of ``action_type``
        at once (:func:`run_actions`); their Results, RuntimeError when one says
        ``success = false``."""
        results = run_actions(self.executor, [
            (self.action_client(action_type, name), action_type.Goal(**fields), on_feedback)
            for name, on_feedback, fields in goals], self.timeout, self.stop)
        for (name, _, _), result in zip(goals, results):
            if not result.success:
                raise RuntimeError(f"{name} failed: {result.message}")
        return results


def matrix_from_rows(rows, cols, data, name):
    """A (rows, cols) float64 view of row-major ``data``; ValueError if the sizes disagree."""
    if rows * cols != len(data):
        raise ValueError(f"{name}: rows*cols = {rows}*{cols} = {rows * cols} does not match "
                         f"the {len(data)} values in data")
    if isinstance(data, array.array) and data.typecode == "d":
        return np.frombuffer(data, dtype=np.float64).reshape(rows, cols)   # no copy
    return np.asarray(data, dtype=np.float64).reshape(rows, cols)
