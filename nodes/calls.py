"""Calling services and actions from a node: waiting for servers and subscribers, blocking
calls and goals with timeouts, stopped by SIGINT/SIGTERM.

``spin_once`` loops rather than ``spin_until_future_complete``, which slows down with every
call in rclpy 7.1.
"""
import math
import time
import weakref


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
