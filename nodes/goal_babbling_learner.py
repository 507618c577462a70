"""goal_babbling_learner: online goal babbling of one robot (thesis ch. 6, Alg. 6, §6.4, §6.5).

Run (next to a robot_sim in position mode, lock-step, in the same namespace):
``goal_babbling_learner --ros-args -r __ns:=/target
-p robot:=scenarios/robots/goal_babbling_target.toml -p home:=[-0.785398,1.65]
-p x_low:=[0.1,-1.1] -p x_high:=[1.1,0.4]``.

One learner of :func:`lpa_transfer.goal_babbling.experiment.run_condition`: goal babbling
(Alg. 6) on the robot through its StepRobot service into a K-NN inverse model. ``~/initialise``
adds own samples and experience transferred from another robot (§6.4), learned like own data,
behind the guard (``guard``, §6.6) or yielding to the own samples (``yielding``); ``~/babble``
goal-babbles for some simulated seconds. Progress as in §6.5: reaching error and rate of L⁻¹
on reachable test points, on the analytic kinematics (the robot never moves for it).

Parameters, topics, services and the learner's clock: docs/nodes.md.
"""
import math
import os
import threading

import numpy as np
from rclpy.executors import MultiThreadedExecutor
from rclpy.node import Node

from lpa_transfer.robots.kinematics import hold_at_home, robot_kinematics
from lpa_transfer.goal_babbling.goal_babbling import GoalBabbling
from lpa_transfer._validation import check_x_bounds
from lpa_transfer.goal_babbling.negative_transfer import chain_lipschitz
from lpa_transfer.goal_babbling.transfer import (finite_experience, initialise_with_transfer,
                                                 inverse_knn_model)
from lpa_transfer.robots.environment import stepped_environment, task_dims
from lpa_transfer.robots.params import load_robot_params
from lpa_transfer_interfaces.msg import ReachingEvaluation
from lpa_transfer_interfaces.action import GoalBabble
from lpa_transfer_interfaces.srv import InitialiseSensorimotor
from lpa_transfer_nodes.conversions import from_matrix, to_matrix
from lpa_transfer_nodes.entry import serve
from lpa_transfer_nodes.goal_babbling_parameters import (EVALUATION, GOAL_BABBLING, LEARNING,
                                                         ROBOT, guard_params)
from lpa_transfer_nodes.markers import task_marker_publisher
from lpa_transfer_nodes.params import declare_table, describe_use_sim_time
from lpa_transfer_nodes.reaching_evaluation import EVALUATION_QOS, ReachingEvaluator
from lpa_transfer_nodes.robot_clients import RobotCalls, RobotClients, Stopped, robot_stepper
from lpa_transfer_nodes.servers import JobCancelled, answering, long_job, unless_busy


class GoalBabblingLearner(ReachingEvaluator, RobotCalls, Node):
    def __init__(self, stop):
        super().__init__("goal_babbling_learner")
        self.stop = stop
        p = declare_table(self, ROBOT)
        if not p["robot"]:
            raise ValueError("the parameter 'robot' (a robot .toml file) is required")
        self.robot = load_robot_params(os.path.expanduser(p["robot"]))
        self.kinematics = robot_kinematics(self.robot, p["home"] or None)
        if p["active_joints"]:   # the other joints held at home (their ranges shrink to it)
            self.kinematics = hold_at_home(self.kinematics, p["active_joints"])
        self.n_task = task_dims(self.kinematics)
        if not p["x_low"] or not p["x_high"]:
            raise ValueError("the parameters 'x_low' and 'x_high' (X_bounds, the task box goals "
                             "are drawn from) are required")
        self.x_bounds = check_x_bounds((p["x_low"], p["x_high"]), self.n_task)
        learning = declare_table(self, LEARNING)
        self.babbling_params = {name: learning[name] for name, *_ in GOAL_BABBLING}
        self.steps_per_sample = learning["steps_per_sample"]
        self.n_neighbors = learning["n_neighbors"]
        self.guard = self.guard_spec(learning["guard"], learning["guard_params"])
        self.yielding = learning["yielding"]
        p = declare_table(self, EVALUATION)
        self.eval_spacing, self.threshold = p["eval_spacing"], p["reaching_threshold"]
        self.call_timeout, self.wait_timeout = p["call_timeout"], p["wait_timeout"]
        describe_use_sim_time(self)
        self.check_hyperparameters(learning["physics_step"])
        self.points = self.test_points(p)
        self.robot_clients = RobotClients(self, p["step_service"], p["reset_service"])
        self.environment = stepped_environment(
            self.kinematics, robot_stepper(self.call, self.robot_clients.step, self.robot.name),
            self.steps_per_sample, on_sample=self.on_sample)
        self.sim_time = 0.0
        self.start_afresh()
        self.serve()

    def serve(self):
        """Publish the evaluations and offer ~/initialise and the ~/babble action."""
        self.marker_pub = task_marker_publisher(self)
        self.evaluation_pub = self.create_publisher(ReachingEvaluation, "reaching_evaluation",
                                                    EVALUATION_QOS)
        self.busy = threading.Lock()   # held while a babble goal runs
        self.create_service(InitialiseSensorimotor, "~/initialise",
                            answering(self, "initialise",
                                      unless_busy(self.busy, "babble", self.initialise)))
        self.babble_server = long_job(self, GoalBabble, "~/babble", self.babble, self.busy)
        self.get_logger().info(
            f"{self.robot.name}: goal babbling in X_bounds {self.x_bounds[0].tolist()} .. "
            f"{self.x_bounds[1].tolist()} from home {self.kinematics.home.tolist()}, "
            f"{len(self.points)} test points, "
            + ("guarded " if self.guard is not None else "yielding " if self.yielding else "")
            + f"{self.n_neighbors}-NN model")

    # -- configuration -------------------------------------------------------------------------
    def guard_spec(self, guard, text):
        """GuardedModel's hyperparameters when ``guard`` is set (None otherwise)."""
        params = guard_params(text)
        if not guard:
            if params:
                self.get_logger().warning("guard_params are ignored: guard is false")
            return None
        params.setdefault("lipschitz", chain_lipschitz(self.robot.link_lengths))
        return params

    def check_hyperparameters(self, physics_step):
        """Fail at start-up, not at the first call, on bad hyperparameters (the parameters'
        ranges are checked as they are declared): build a model and start a GoalBabbling on
        the analytic kinematics (no robot involved)."""
        GoalBabbling(self.x_bounds, home=self.kinematics.home, **self.babbling_params).start(
            self.kinematics, self.fresh_model())
        step_seconds = self.steps_per_sample * physics_step
        per_second = self.babbling_params["steps_per_second"]
        if not math.isclose(step_seconds * per_second, 1.0, rel_tol=1e-9):
            self.get_logger().warning(
                f"a babbling step runs {self.steps_per_sample} physics steps of {physics_step:g} "
                f"s = {step_seconds:g} s on the robot, but the learner's clock counts "
                f"1 / steps_per_second = {1 / per_second:g} s per step")

    def babbler(self):
        """A fresh GoalBabbling with the node's hyperparameters."""
        return GoalBabbling(self.x_bounds, home=self.kinematics.home,
                            **dict(self.babbling_params, seed=self.seed))

    def fresh_model(self):
        """A sensorimotor model knowing nothing yet (inverse K-NN; guarded, yielding or plain)."""
        return inverse_knn_model(self.n_neighbors, self.guard, self.yielding, self.threshold)

    def start_afresh(self, seed=-1):
        """A new model, the clock at 0, babbling (with ``seed``; -1: the seed parameter) to be
        started by the next babble call."""
        self.seed = self.babbling_params["seed"] if seed == -1 else seed
        self.model, self.babbling = self.fresh_model(), None
        self.clock_offset = 0.0   # learner's clock = clock_offset + babbling time
        self.n_transferred = 0    # transferred samples learned like own data (unguarded)

    # -- services --------------------------------------------------------------------------------
    @property
    def clock(self):
        """The learner's clock (s)."""
        return self.clock_offset + (self.babbling.time_ if self.babbling is not None else 0.0)

    def rows(self, matrix, name):
        """(finite rows (N, d + m), number of rejected rows) of a Matrix; ValueError for a
        wrong number of columns (a matrix without rows may have any)."""
        return finite_experience(from_matrix(matrix, name), self.robot.n_joints, self.n_task,
                                 name)

    def initialise(self, request, response):
        own, rejected_own = self.rows(request.own, "own")
        transferred, rejected_transferred = self.rows(request.transferred, "transferred")
        elapsed = request.elapsed
        if not (math.isfinite(elapsed) and elapsed >= 0):
            raise ValueError(f"elapsed must be a finite number >= 0 (s), got {elapsed}")
        if request.seed < -1:
            raise ValueError(f"seed must be >= 0, or -1 for the seed parameter, got "
                             f"{request.seed}")
        if request.reset:
            self.wait_for_robot()
            self.reset_robot()
            self.start_afresh(request.seed)
        d = self.robot.n_joints
        if len(own):
            self.model.update(own[:, :d], own[:, d:])
        if len(transferred):   # kept apart, or like own data with weight 1 (§6.4, §6.5.1)
            initialise_with_transfer(self.model, transferred[:, :d], transferred[:, d:])
            if not hasattr(self.model, "transfer"):
                self.n_transferred += len(transferred)
        self.clock_offset += elapsed
        response.n_own, response.n_transferred = len(own), len(transferred)
        response.n_rejected = rejected_own + rejected_transferred
        response.evaluation = self.evaluate()
        return (f"learned {len(own)} own and {len(transferred)} transferred samples, rejected "
                f"{response.n_rejected}; " + self.describe(response.evaluation))

    def babble(self, goal, result, feedback, cancelled):
        """The GoalBabble action: ``goal.seconds`` of goal babbling, feedback at every
        evaluation; a cancel or SIGINT stops at the next step (the steps done stay learned)."""
        seconds, interval = goal.seconds, goal.evaluation_interval
        for name, value in (("seconds", seconds), ("evaluation_interval", interval)):
            if not (math.isfinite(value) and value >= 0):
                raise ValueError(f"{name} must be a finite number >= 0 (s), got {value}")
        self.wait_for_robot()
        if self.babbling is None:
            self.reset_robot()
            self.babbling = self.babbler().start(self.environment, self.model)
        per_second = self.babbling.steps_per_second
        n_steps = int(round(seconds * per_second))   # as GoalBabbling.run_for
        evaluations, done = [], [0]

        def multiples(clock):   # of the interval reached by the clock (float-safe)
            return math.floor(clock / interval + 1e-9) if interval > 0 else 0

        last = [multiples(self.clock)]

        def evaluated():
            evaluations.append(self.evaluate())
            feedback(evaluation=evaluations[-1], steps_done=done[0], n_steps=n_steps)

        def after_step(babbling):   # the learner's clock, not the babbler's, sets the times
            done[0] += 1
            if self.stop.is_set():
                raise Stopped()
            reached = multiples(self.clock)
            if reached > last[0]:
                last[0] = reached
                evaluated()
            elif done[0] == n_steps:
                evaluated()
            if cancelled() and done[0] < n_steps:
                raise JobCancelled()

        try:
            positions, points = self.babbling.run(n_steps, after_step, 1)
        except Stopped:   # between two steps or waiting for the robot's answer
            raise Stopped(f"stopped (SIGINT/SIGTERM) after {done[0]} of {n_steps} steps; "
                          f"they stay learned") from None
        except JobCancelled:
            result.evaluations, result.sim_time = evaluations, self.sim_time
            raise JobCancelled(f"after {done[0]} of {n_steps} steps, at t = {self.clock:g} s "
                               "(they stay learned)") from None
        if not n_steps:
            evaluated()
        result.evaluations = evaluations
        result.experience = to_matrix(np.hstack((positions, points)))
        result.sim_time = self.sim_time
        return (f"babbled {n_steps} steps to t = {self.clock:g} s; "
                + self.describe(evaluations[-1]))

    def destroy_node(self):
        self.robot_clients.destroy()
        super().destroy_node()


def main(args=None):
    # multi-threaded: a cancel of the babble goal is heard while the babbling runs
    serve("goal_babbling_learner", GoalBabblingLearner, args,
          executor_class=MultiThreadedExecutor)


if __name__ == "__main__":
    main()
