"""A robot_sim's StepRobot and ResetRobot services as ``step`` and ``reset`` functions, the
simulated robot interface of the library's learners and explorers; :class:`RobotCalls`, a
node's blocking calls to them that SIGINT/SIGTERM stops.
"""
import rclpy

from lpa_transfer_interfaces.srv import ResetRobot, StepRobot
from lpa_transfer_nodes.calls import ServiceTimeout, call_service, wait_for_services
from lpa_transfer_nodes.conversions import sim_state
from lpa_transfer_nodes.entry import FastExecutor


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


class Stopped(ValueError):
    """SIGINT/SIGTERM arrived during a call (answered as a failed request)."""


class RobotCalls:
    """A node's calls to its robot's ``robot_clients`` (:class:`RobotClients`) within
    ``call_timeout`` and ``wait_timeout`` s, stopped by the event ``stop``; mixed into a node
    with ``robot`` (its name) and ``kinematics`` (its home); the robot's time in ``sim_time``."""

    def call(self, client, request, **options):
        try:
            return call_service(self.robot_clients.executor, client, request, self.call_timeout,
                                self.stop, **options)
        except ServiceTimeout:
            if self.stop.is_set():
                raise Stopped("stopped (SIGINT/SIGTERM) while waiting for the robot's "
                              "answer") from None
            raise

    def on_sample(self, command, state):
        self.sim_time = state.time

    def wait_for_robot(self):
        try:
            wait_for_services([self.robot_clients.step, self.robot_clients.reset],
                              self.wait_timeout, self.stop)
        except ServiceTimeout:
            if not self.stop.is_set():
                raise
        if self.stop.is_set():
            raise Stopped("stopped (SIGINT/SIGTERM) while waiting for the robot")

    def reset_robot(self):
        """Put the robot at rest at q_home."""
        reset = robot_resetter(self.call, self.robot_clients.reset, self.robot.name)
        self.sim_time = reset(self.kinematics.home).time
