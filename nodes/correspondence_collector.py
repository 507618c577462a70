"""correspondence_collector: babble two simulated robots, pair their samples, fit a mapping.

Run (with two robot_sim nodes in lock-step mode under the namespaces ``/source`` and
``/target``, and lpa_mapping): ``correspondence_collector --ros-args -p
source_robot:=scenarios/robots/two_link_source.toml -p target_robot:=... -p output:=pairs.npz``.

What it does (:func:`lpa_transfer.exploration.correspondences.collect_correspondences`): drives
both robots through one seeded babbling program over their ``StepRobot`` services, pairs their
samples by ``pairing_rule``, publishes every pair as it is made, saves the set, asks the
mapping service to fit a model on it, and exits (0 on success). Pairs are made true for any
robot pair: a commanded robot is stepped until it has settled (by its state, at least
``steps_per_sample`` steps) and every pair is checked under its rule
(:class:`~lpa_transfer.exploration.correspondences.PairCheck`); failing pairs are dropped or
retried, and a set with too many ends the run with one FATAL line naming the robots, the rule
and the residual. Before the fit it logs the model's k-fold held-out error beside PA's. SIGINT/SIGTERM stop the
babbling early: the pairs made so far are published and saved (``complete = False`` in the
file) and no model is fitted. Because the robots are stepped in lock-step, a run takes as
long as the computation, and the same parameters give the same pairs, bit for bit.

Guided exploration (``program:=goal_babbling``, thesis §6.4.2, Alg. 7,
:func:`lpa_transfer.exploration.correspondences.collect_guided_correspondences`): the target
goal-babbles (Alg. 6) on the joints it shares with the source, then the source executes the
same commands; pair i is each robot's observed (q̄, x) for command i (``same_command``).

Parameters, topics and the details of guided exploration: docs/nodes.md.
"""
import dataclasses
import os
import time

import numpy as np
from rclpy.duration import Duration
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter

from lpa_transfer.exploration.babbling import BabblingProgram, box_around
from lpa_transfer.robots.kinematics import robot_kinematics
from lpa_transfer.robots.control import PID, start_servo
from lpa_transfer.exploration.correspondences import (DEFAULT_FEATURES, PairCheck,
                                                      check_features, pair_check_line,
                                                      check_guided_exploration, check_pairing_rule,
                                                      collect_correspondences,
                                                      collect_guided_correspondences)
from lpa_transfer.goal_babbling.goal_babbling import GoalBabbling
from lpa_transfer._validation import check_int, check_x_bounds
from lpa_transfer.robots.environment import stepped_environment
from lpa_transfer.robots.params import load_robot_params
from lpa_transfer.transfer import LocalProcrustesAnalysis, ProcrustesAnalysis
from lpa_transfer.transfer.cross_validation import held_out_nmse
from lpa_transfer_interfaces.msg import CorrespondenceBatch, CorrespondenceSample
from lpa_transfer_interfaces.srv import FitModel, ResetRobot, StepRobot
from lpa_transfer_nodes.lpa_mapping import fit_hyperparameters
from lpa_transfer_nodes._ros_util import (BATCH_QOS, SAMPLE_QOS, array_parameter, call_service,
                                          robot_resetter, robot_stepper, run_job, sim_stamp,
                                          to_matrix, wait_for_services, wait_for_subscribers)

FIT_FIELDS = {"method": "lpa", "latent_dim": 0, "n_min": 0, "c_min": 0.0, "k_max": 0,
              "n_init": 0}
GUIDED = "goal_babbling"          # the program of guided exploration (§6.4.2, Alg. 7)
GOAL_BABBLING_FIELDS = {"n_subtargets": 10, "sigma": 0.1, "drift": 0.01, "p_home": 0.1,
                        "steps_per_second": 10.0}


def required_path(value, name):
    if not value:
        raise ValueError(f"set the parameter {name!r} (a robot parameter file)")
    return os.path.expanduser(value)


def task_box(kinematics, low, high, halfwidth, side):
    """A robot's own task-space babbling box, or None (then the program's box is used)."""
    if halfwidth and (low or high):
        raise ValueError(f"give {side}_task_halfwidth or {side}_task_low/high, not both")
    if halfwidth:
        return box_around(kinematics, halfwidth)
    return (tuple(low), tuple(high)) if low or high else None


class CorrespondenceCollector(Node):
    def __init__(self, stop):
        super().__init__("correspondence_collector")
        self.stop = stop
        declare = lambda name, default: self.declare_parameter(name, default).value  # noqa: E731
        doubles = lambda name: array_parameter(self, name, Parameter.Type.DOUBLE_ARRAY)  # noqa: E731,E501
        self.robots = {side: load_robot_params(required_path(declare(f"{side}_robot", ""),
                                                             f"{side}_robot"))
                       for side in ("source", "target")}
        self.kinematics = {}
        for side, robot in self.robots.items():
            kinematics = robot_kinematics(robot, doubles(f"{side}_home") or None)
            self.kinematics[side] = dataclasses.replace(kinematics, task_box=task_box(
                kinematics, doubles(f"{side}_task_low"), doubles(f"{side}_task_high"),
                doubles(f"{side}_task_halfwidth"), side))
        gains = {side: doubles(f"{side}_pid") for side in self.robots}
        self.pid = {side: PID.from_gains(gains[side], f"{side}_pid") if gains[side] else None
                    for side in self.robots}
        self.pairing_rule = check_pairing_rule(declare("pairing_rule", "same_command"))
        program, seed = declare("program", "joint_lines"), declare("seed", 0)
        n_segments, samples_per_segment = (declare("n_segments", 20),
                                           declare("samples_per_segment", 5))
        task_low, task_high = tuple(doubles("task_low")), tuple(doubles("task_high"))
        # the minimum a sample; settling by state and the pairing check (PairCheck) go on
        self.steps_per_sample = declare("steps_per_sample", 400)
        defaults = PairCheck()
        self.pair_check = PairCheck(
            max_settle_steps=declare("max_settle_steps", defaults.max_settle_steps),
            check_steps=declare("settle_check_steps", defaults.check_steps),
            velocity_tol=float(declare("settle_velocity_tol", defaults.velocity_tol)),
            position_tol=float(declare("settle_position_tol", defaults.position_tol)),
            tolerance=float(declare("pair_tolerance", defaults.tolerance)),
            on_bad_pair=declare("on_bad_pair", defaults.on_bad_pair),
            max_bad_share=float(declare("max_bad_share", defaults.max_bad_share)))
        self.task_offset = doubles("task_offset") or None
        features = array_parameter(self, "features")
        self.guided = program == GUIDED
        if self.guided:
            self.declare_guided(seed, gains, bool(features))
        else:
            self.program = BabblingProgram(program, n_segments, samples_per_segment, seed,
                                           task_low, task_high, declare("time_law", "linear"))
        self.features = check_features(features or DEFAULT_FEATURES)
        self.output = os.path.expanduser(declare("output", ""))
        self.model_id = declare("model_id", "")
        self.fit_fields = {name: declare(name, default) for name, default in FIT_FIELDS.items()}
        self.fit_fields["cluster_dims"] = array_parameter(self, "cluster_dims",
                                                          Parameter.Type.INTEGER_ARRAY)
        self.fit_fields["random_state"] = declare("random_state", 0)
        # k-fold held-out error of the model (and of PA) on the pairs, before the fit; 0: off
        self.cross_validation_folds = declare("cross_validation_folds", 5)
        if self.cross_validation_folds:
            check_int(self.cross_validation_folds, "cross_validation_folds", 2)
        self.wait_for_subscribers = declare("wait_for_subscribers", 0)
        self.subscribed_topics = array_parameter(self, "wait_for_subscribed_topics")
        self.wait_timeout = float(declare("wait_timeout", 30.0))
        self.call_timeout = float(declare("call_timeout", 120.0))
        self.step_clients = {side: self.create_client(
            StepRobot, declare(f"{side}_step", f"/{side}/robot_sim/step"))
            for side in ("source", "target")}
        self.reset_clients = {side: self.create_client(
            ResetRobot, declare(f"{side}_reset", f"/{side}/robot_sim/reset"))
            for side in ("source", "target")} if self.guided else {}
        self.fit_client = self.create_client(FitModel, declare("mapping_service",
                                                               "/lpa_mapping/fit"))
        self.sample_pub = self.create_publisher(CorrespondenceSample, "correspondences",
                                                SAMPLE_QOS)
        self.batch_pub = self.create_publisher(CorrespondenceBatch, "correspondence_batch",
                                               BATCH_QOS)
        self.spinner = SingleThreadedExecutor()
        self.spinner.add_node(self)
        self.sim_time = 0.0

    def declare_guided(self, seed, gains, features_given):
        """The goal_babbling parameters, checked on the robots' kinematics before any step."""
        declare = lambda name, default: self.declare_parameter(name, default).value  # noqa: E731
        if self.pairing_rule != "same_command":
            raise ValueError(f"program {GUIDED} pairs the robots by same_command (guided "
                             f"exploration, §6.4.2), not by pairing_rule "
                             f"{self.pairing_rule!r}")
        if any(gains.values()):
            raise ValueError(f"program {GUIDED} runs the robots in position mode: leave "
                             f"source_pid and target_pid empty")
        if features_given:
            self.get_logger().warning(f"program {GUIDED}: the features parameter is ignored "
                                      "(rows are (shared joint positions, task point))")
        self.guided_seconds = float(declare("guided_seconds", 60.0))
        if not (np.isfinite(self.guided_seconds) and self.guided_seconds >= 0):
            raise ValueError(f"guided_seconds must be a finite number >= 0, got "
                             f"{self.guided_seconds!r}")
        x_bounds = [array_parameter(self, name, Parameter.Type.DOUBLE_ARRAY)
                    for name in ("x_low", "x_high")]
        if not all(x_bounds):
            raise ValueError(f"program {GUIDED} needs x_low and x_high (the box of the "
                             "target's goals in its task space)")
        try:
            check_x_bounds(x_bounds)
        except ValueError as exc:
            raise ValueError(f"x_low/x_high: {exc}") from None
        n_shared = min(robot.n_joints for robot in self.robots.values())
        self.joints = {}
        for side in self.robots:
            given = array_parameter(self, f"{side}_joints", Parameter.Type.INTEGER_ARRAY)
            self.joints[side] = given or list(range(n_shared))
        self.babbling = GoalBabbling(
            tuple(tuple(bound) for bound in x_bounds), seed=seed,
            **{name: declare(name, default) for name, default in GOAL_BABBLING_FIELDS.items()})
        self.target_range = declare("target_range", "shared")
        check_guided_exploration(self.babbling, self.kinematics["source"],
                                 self.kinematics["target"], self.joints["source"],
                                 self.joints["target"], self.guided_seconds, self.target_range)

    # -- talking to the robots and the mapping service ---------------------------------------
    def call(self, client, request):
        return call_service(self.spinner, client, request, self.call_timeout)

    def stepper(self, side):
        step = robot_stepper(self.call, self.step_clients[side], side)
        if self.pid[side] is not None:          # a torque-mode robot tracking the commands
            step = start_servo(step, self.robots[side].n_joints, self.pid[side]).step
        if side == "target":
            return step

        def step_source(command, n_steps):      # remembers the clock for the pairs' stamps
            state = step(command, n_steps)
            self.sim_time = state.time
            return state
        return step_source

    def publish_pair(self, index, source, target):
        msg = CorrespondenceSample(source_robot=self.robots["source"].name,
                                   target_robot=self.robots["target"].name, index=index,
                                   source=source.tolist(), target=target.tolist())
        msg.header.stamp = sim_stamp(self.sim_time)
        self.sample_pub.publish(msg)

    def publish_batch(self, pairs):
        msg = CorrespondenceBatch(source_robot=pairs.source_robot,
                                  target_robot=pairs.target_robot,
                                  pairing_rule=pairs.pairing_rule,
                                  source=to_matrix(pairs.source), target=to_matrix(pairs.target))
        meta = pairs.metadata
        if "pairs_checked" in meta:
            msg.pairs_checked, msg.pairs_dropped = meta["pairs_checked"], meta["pairs_dropped"]
            msg.worst_residual = float(meta["worst_residual"])
            msg.pair_tolerance = float(meta["pair_tolerance"])
            msg.residual_unit = meta["residual_unit"]
        msg.header.stamp = sim_stamp(self.sim_time)
        self.batch_pub.publish(msg)

    def fit_request(self, pairs):
        return FitModel.Request(model_id=self.model_id, source=to_matrix(pairs.source),
                                target=to_matrix(pairs.target), **self.fit_fields)

    def held_out(self, pairs):
        """The k-fold held-out nMSE of the model the service will fit, and of PA (metadata)."""
        hyperparameters = fit_hyperparameters(self.fit_request(pairs))
        estimators = {"pa": ProcrustesAnalysis(latent_dim=hyperparameters["latent_dim"])}
        if self.fit_fields["method"] == "lpa":
            estimators["lpa"] = LocalProcrustesAnalysis(**hyperparameters)
        scores = {name: held_out_nmse(estimator, pairs.source, pairs.target,
                                      self.cross_validation_folds,
                                      self.fit_fields["random_state"])
                  for name, estimator in estimators.items()}
        self.get_logger().info(
            f"held-out error ({self.cross_validation_folds}-fold, nMSE of the target "
            f"columns): " + ", ".join(f"{name.upper()} {score:.4g}"
                                      for name, score in scores.items()))
        return {f"held_out_nmse_{name}": score for name, score in scores.items()}

    def fit(self, pairs):
        request = self.fit_request(pairs)
        response = self.call(self.fit_client, request)
        if not response.success:
            raise RuntimeError(f"the mapping service could not fit {self.model_id!r}: "
                               f"{response.message}")
        self.get_logger().info(f"{response.message} (training RMSE "
                               f"{response.training_rmse:.6g})")

    # -- the run ----------------------------------------------------------------------------
    def collect(self):
        """Babbling programs (joint_lines, task_lines) under one of the pairing rules."""
        self.get_logger().info(
            f"babbling {self.robots['source'].name} -> {self.robots['target'].name}: "
            f"{self.program.program}, {self.program.n_samples} samples, {self.pairing_rule}, "
            f"seed {self.program.seed}")
        pairs = collect_correspondences(
            self.program, self.pairing_rule, self.kinematics["source"],
            self.kinematics["target"], self.stepper("source"), self.stepper("target"),
            self.steps_per_sample, self.features, self.task_offset, on_pair=self.publish_pair,
            should_stop=self.stop.is_set, pair_check=self.pair_check,
            names=(self.robots["source"].name, self.robots["target"].name))
        self.get_logger().info(f"pairing check: {pair_check_line(pairs.metadata)}")
        pairs.metadata.update(seed=self.program.seed, program=self.program.program)
        return pairs

    def collect_guided(self):
        """Guided exploration (§6.4.2, Alg. 7): the target goal-babbles, the source follows."""
        babbling = self.babbling
        self.get_logger().info(
            f"goal babbling {self.robots['target'].name} for {self.guided_seconds:g} s "
            f"({round(self.guided_seconds * babbling.steps_per_second)} steps, joints "
            f"{self.joints['target']}), then {self.robots['source'].name} (joints "
            f"{self.joints['source']}): same_command, seed {babbling.seed}")
        for side, client in self.reset_clients.items():   # same seed, same start, same pairs
            robot_resetter(self.call, client, side)(self.kinematics[side].home)
        environments = {side: stepped_environment(self.kinematics[side], self.stepper(side),
                                                  self.steps_per_sample)
                        for side in self.robots}
        pairs = collect_guided_correspondences(
            babbling, environments["source"], environments["target"], self.joints["source"],
            self.joints["target"], self.guided_seconds, on_pair=self.publish_pair,
            should_stop=self.stop.is_set, target_range=self.target_range)
        self.get_logger().info(f"pairing check (reported, not enforced: each row is what its "
                               f"robot reached): {pair_check_line(pairs.metadata)}, median "
                               f"{pairs.metadata['median_residual']:.3g} rad")
        pairs.metadata.update(program=GUIDED)
        return pairs

    def run(self):
        clients = list(self.step_clients.values()) + list(self.reset_clients.values()) \
            + ([self.fit_client] if self.model_id else [])
        wait_for_services(clients, self.wait_timeout, self.stop)
        for topic, count in ((self.sample_pub.topic_name, self.wait_for_subscribers),
                             *((topic, 1) for topic in self.subscribed_topics)):
            wait_for_subscribers(self, topic, count, self.wait_timeout, self.stop)
        source, target = self.robots["source"], self.robots["target"]
        start = time.perf_counter()
        pairs = self.collect_guided() if self.guided else self.collect()
        pairs.source_robot, pairs.target_robot = source.name, target.name
        pairs.metadata.update(steps_per_sample=self.steps_per_sample)
        wall = time.perf_counter() - start
        self.get_logger().info(
            f"collected {len(pairs)} pairs over {pairs.sim_time:.3f} s of simulated time in "
            f"{wall:.3f} s ({pairs.sim_time / wall:.1f}x real time)"
            + ("" if pairs.complete else " (stopped early)"))
        if self.model_id and pairs.complete and self.cross_validation_folds:
            pairs.metadata.update(self.held_out(pairs))
        self.publish_batch(pairs)
        if self.output:
            pairs.save(self.output)
            self.get_logger().info(f"saved the correspondences to {self.output}")
        if self.model_id and pairs.complete:
            self.fit(pairs)
        for publisher in (self.sample_pub, self.batch_pub):   # deliver before exiting
            if not publisher.wait_for_all_acked(Duration(seconds=self.wait_timeout)):
                self.get_logger().warning(f"{publisher.topic_name}: not all acknowledged")
        return pairs


def main(args=None):
    run_job("correspondence_collector", CorrespondenceCollector, lambda node: node.run(), args)


if __name__ == "__main__":
    main()
