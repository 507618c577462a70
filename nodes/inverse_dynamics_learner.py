"""inverse_dynamics_learner: online inverse-dynamics learning for torque tracking (thesis ch. 5).

Run (next to a robot_sim in torque mode, lock-step, in the same namespace):
``inverse_dynamics_learner --ros-args -r __ns:=/pincher
-p robot:=scenarios/robots/pincher_arm.toml -p centre_pose:=[0.0,0.6,0.9,0.6]
-p star_radius:=0.05 -p pid:=[5.0,0.01,0.1]``.

The node runs the control loop of Fig. 5-1
(:class:`lpa_transfer.inverse_dynamics.online_learning.FeedForwardLearner`) on its robot
through the robot's StepRobot service: at every control period the learned feed-forward
torque τ_ff(q_d, q̇_d, q̈_d) plus PID feedback, then one online update from the observed
(q, q̇, q̈, τ). The task is a 'star' (§5.5.1, :mod:`lpa_transfer.inverse_dynamics.tasks`)
around the end-effector position of ``centre_pose``, tracked in trials of 8.4 s.

``~/initialise`` (InitialiseLearner) learns offline from (q, q̇, q̈, τ) samples, e.g. another
robot's experience transferred through the mapping service; the action ``~/run_trials``
(RunTrials) runs trials from rest at ``centre_pose``, with feedback after each trial and
cancel between trials, each trial also published on ``trial_result``.

Parameters, topics and services: docs/nodes.md.
"""
import json
import os
import threading

import numpy as np
from rclpy.executors import MultiThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter

from lpa_transfer.robots.kinematics import robot_kinematics
from lpa_transfer.robots.control import PID
from lpa_transfer.robots.kinematics import home_pose
from lpa_transfer.inverse_dynamics.online_learning import (FeedForwardLearner, input_scale,
                                                           make_regressor, regressors)
from lpa_transfer.robots.params import load_robot_params
from lpa_transfer.inverse_dynamics.tasks import TIME_LAWS, star_task
from lpa_transfer_interfaces.msg import TrialResult
from lpa_transfer_interfaces.action import RunTrials
from lpa_transfer_interfaces.srv import InitialiseLearner
from lpa_transfer_nodes.calls import call_service, wait_for_services
from lpa_transfer_nodes.conversions import from_matrix, sim_stamp, to_matrix
from lpa_transfer_nodes.entry import serve
from lpa_transfer_nodes.params import declare, declare_array, describe_use_sim_time
from lpa_transfer_nodes.robot_clients import RobotClients, robot_resetter, robot_stepper
from lpa_transfer_nodes.servers import JobCancelled, answering, long_job, unless_busy
from lpa_transfer_nodes.markers import (ACTUAL, DESIRED, line_strip, marker_array,
                                        task_marker_publisher)


class InverseDynamicsLearner(Node):
    def __init__(self, stop):
        super().__init__("inverse_dynamics_learner")
        d = lambda *args, **kwargs: declare(self, *args, **kwargs)  # noqa: E731
        doubles = lambda name, text: declare_array(  # noqa: E731
            self, name, Parameter.Type.DOUBLE_ARRAY, text)
        self.stop = stop
        describe_use_sim_time(self)
        self.robot = load_robot_params(os.path.expanduser(
            d("robot", "", "the robot parameter file (scenarios/robots/*.toml; required)")))
        control_rate = float(d("control_rate", 100.0, "control periods a second (Hz), up to "
                               "1 / physics_step", positive=True, finite=True))
        physics_step = float(d("physics_step", 0.001, "the simulator's physics step (s): each "
                               "period advances round(1 / (control_rate * physics_step)) steps",
                               positive=True, finite=True))
        if not 0 < control_rate <= 1.0 / physics_step:
            raise ValueError(f"the parameter control_rate must be in (0, {1 / physics_step:g}] "
                             f"Hz (1 / physics_step), got {control_rate}")
        self.dt = 1.0 / control_rate
        self.n_steps = max(1, round(self.dt / physics_step))
        pid = PID.from_gains(doubles("pid", "[kp, ki, kd] of the feedback PID (required; "
                                     "thesis: Pincher [5, 0.01, 0.1], youBot [100, 0.01, 2.0])"))
        self.trajectory = self.task(d, doubles)
        self.regressor_spec = (
            d("regressor", "lwpr", "the online learner of the feed-forward torque",
              choices=sorted(regressors())),
            json.loads(d("regressor_params", "{}", "JSON object of the regressor's "
                         "hyperparameters, e.g. {\"init_D\": 30}; LWPR's norm_in defaults to "
                         "the spread of the task's desired states")))
        if self.regressor_spec[0] == "lwpr":
            self.regressor_spec[1].setdefault("norm_in", input_scale(*self.trajectory[:3]))
        self.own_w_gen = float(d("own_w_gen", 0.3, "after a yielding initialisation "
                                 "(InitialiseLearner yielding): the robot's own samples make "
                                 "a receptive field of their own unless one answers them above "
                                 "this (LWPR's w_gen for them)", range=(0.0, 1.0), finite=True))
        self.learner = self.fresh_learner(pid)
        self.call_timeout = float(d("call_timeout", 30.0, "seconds for each robot call (step "
                                    "or reset)", positive=True))
        self.wait_timeout = float(d("wait_timeout", 30.0, "seconds to wait for the robot's "
                                    "services", positive=True))
        self.robot_clients = RobotClients(
            self, d("step_service", "robot_sim/step", "the robot's StepRobot service (relative: "
                    "in the node's namespace)"),
            d("reset_service", "robot_sim/reset", "the robot's ResetRobot service"))
        self.step = robot_stepper(self.call, self.robot_clients.step, self.robot.name)
        self.reset_robot_to = robot_resetter(self.call, self.robot_clients.reset,
                                             self.robot.name)
        self.trial = 0
        self.result_pub = self.create_publisher(TrialResult, "trial_result", 10)
        self.marker_pub = task_marker_publisher(self)
        self.publish_markers(sim_stamp(0.0))
        self.busy = threading.Lock()   # held while a run_trials goal runs
        self.create_service(InitialiseLearner, "~/initialise",
                            answering(self, "initialise",
                                      unless_busy(self.busy, "run_trials", self.initialise)))
        self.run_trials_server = long_job(self, RunTrials, "~/run_trials", self.run_trials,
                                          self.busy)
        self.get_logger().info(
            f"{self.robot.name}: star of {len(self.trajectory[0])} periods at "
            f"{control_rate:g} Hz ({self.n_steps} physics steps each), "
            f"regressor {self.regressor_spec[0]}")

    def task(self, d, doubles):
        """The star's desired (q, q̇, q̈, x) around the end effector of ``centre_pose``."""
        kinematics = robot_kinematics(self.robot, doubles(
            "centre_pose", "joint angles (rad) whose end-effector position is the star's centre; "
            "every trial starts there; unset: zero clipped into the joint limits") or None)
        self.centre_pose = kinematics.home
        return star_task(
            kinematics, d("star_radius", 0.05, "the star's radius (m)", positive=True,
                          finite=True), self.dt,
            doubles("star_u", "first axis of the star's plane (world); unset: x"),
            doubles("star_v", "second axis of the star's plane (world); unset: y"),
            d("star_spread", 2 * np.pi, "the angle the star's lines spread over (rad)",
              positive=True, finite=True),
            d("star_start_angle", 0.0, "the angle of the first line (rad)", finite=True),
            time_law=d("star_time_law", "minimum_jerk", "each 0.6 s leg's time law: "
                       "minimum_jerk (from rest to rest) or linear (constant speed)",
                       choices=list(TIME_LAWS)))

    def publish_markers(self, stamp, actual=None):
        """The star's desired end-effector path and, after a trial, the path it tracked, on
        the latched ``task_markers`` (frame world)."""
        name = self.get_name()
        markers = [line_strip(f"{name}/desired", 0, self.trajectory[3], DESIRED, stamp)]
        if actual is not None:
            markers.append(line_strip(f"{name}/actual", 0, actual, ACTUAL, stamp))
        self.marker_pub.publish(marker_array(*markers))

    def fresh_learner(self, pid, yielding=False):
        """A learner that knows nothing yet: a new regressor of the configured kind (whose
        initial data become a yielding prior if ``yielding``)."""
        name, hyperparameters = self.regressor_spec
        return FeedForwardLearner(make_regressor(name, **hyperparameters), pid,
                                  yielding=yielding, own_w_gen=self.own_w_gen)

    def call(self, client, request, **options):
        return call_service(self.robot_clients.executor, client, request, self.call_timeout,
                            **options)

    def initialise(self, request, response):
        samples = from_matrix(request.samples, "samples")
        if samples.shape[1] != 4 * self.robot.n_joints:
            raise ValueError(f"samples need 4 x {self.robot.n_joints} columns (q, q_dot, "
                             f"q_ddot, tau), got {samples.shape[1]}")
        if request.reset:
            self.learner = self.fresh_learner(self.learner.pid, request.yielding)
            self.trial = 0
        elif request.yielding != self.learner.yielding:
            raise ValueError("yielding differs from the learner's: set reset to start a "
                             f"{'yielding' if request.yielding else 'plain'} learner")
        rejected_before = self.learner.n_rejected_
        response.n_learned = self.learner.initialise(samples)
        response.n_rejected = self.learner.n_rejected_ - rejected_before
        return f"learned {response.n_learned} samples, rejected {response.n_rejected}"

    def run_trials(self, goal, result, feedback, cancelled):
        """The RunTrials action: ``goal.n_trials`` trials, feedback after each; a cancel or
        SIGINT stops before the next trial."""
        wait_for_services([self.robot_clients.step, self.robot_clients.reset], self.wait_timeout,
                          self.stop)
        state = self.reset_robot_to(self.start_pose(goal.start_offset))
        self.learner.learn = not goal.frozen
        errors, experience = [], []

        def fill():       # the result of the trials run so far (all, or those before a cancel)
            result.tracking_errors = errors
            result.experience = to_matrix(np.vstack(experience) if experience
                                          else np.zeros((0, 4 * self.robot.n_joints)))
            result.sim_time = state.time

        for _ in range(goal.n_trials):
            if self.stop.is_set():
                raise ValueError(f"stopped (SIGINT/SIGTERM) after {len(errors)} trials")
            if cancelled():
                fill()
                raise JobCancelled(f"after {len(errors)} of {goal.n_trials} trials (they stay "
                                   "learned)")
            learned, rejected = self.learner.n_learned_, self.learner.n_rejected_
            trial = self.learner.run_trial(self.step, state, *self.trajectory,
                                           self.n_steps, self.dt)
            state, self.trial = trial.end_state, self.trial + 1
            errors.append(trial.tracking_error)
            experience.append(trial.samples)
            self.publish(trial, self.learner.n_learned_ - learned,
                         self.learner.n_rejected_ - rejected)
            feedback(trial=len(errors), n_trials=goal.n_trials,
                     tracking_error=trial.tracking_error, sim_time=state.time)
        fill()
        return (f"{goal.n_trials} trials, tracking error "
                + ", ".join(f"{1e3 * e:.1f}" for e in errors) + " mm")

    def start_pose(self, offset):
        """The centre pose plus ``offset`` (empty: none); ValueError unless that is one finite
        value per joint inside the joint limits."""
        if len(offset) == 0:
            return self.centre_pose
        offset = np.asarray(offset, dtype=np.float64)
        if offset.shape != self.centre_pose.shape:     # home_pose checks the rest
            raise ValueError(f"start_offset needs {len(self.centre_pose)} finite joint values "
                             f"(or none), got {offset.tolist()}")
        return home_pose(self.robot.joint_limits, self.centre_pose + offset,
                         name="the centre pose plus start_offset")

    def publish(self, trial, n_learned, n_rejected):
        msg = TrialResult(robot=self.robot.name, task=self.get_name(), trial=self.trial,
                          tracking_error=trial.tracking_error, n_learned=n_learned,
                          n_rejected=n_rejected, desired=to_matrix(trial.desired),
                          actual=to_matrix(trial.actual))
        msg.header.stamp, msg.header.frame_id = sim_stamp(trial.end_state.time), "world"
        self.result_pub.publish(msg)
        self.publish_markers(msg.header.stamp, trial.actual)
        self.get_logger().info(f"trial {self.trial}: tracking error "
                               f"{1e3 * trial.tracking_error:.2f} mm")

    def destroy_node(self):
        self.robot_clients.destroy()
        super().destroy_node()


def main(args=None):
    # multi-threaded: a cancel of the run_trials goal is heard while the trials run
    serve("inverse_dynamics_learner", InverseDynamicsLearner, args,
          executor_class=MultiThreadedExecutor)


if __name__ == "__main__":
    main()
