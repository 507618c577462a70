"""The servers of a node: service callbacks that answer every request, and actions for jobs
that run for minutes (feedback, cancel, one goal at a time).

A bad request is answered with ``success = false`` and the reason; the node keeps serving.
"""
import time
import traceback

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
