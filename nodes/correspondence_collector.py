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

Guided exploration (``program:=goal_babbling``, thesis §6.4.2, Alg. 7): the target
goal-babbles, the source follows (:mod:`lpa_transfer_nodes.guided_exploration`).

Parameters, topics and the details of guided exploration: docs/nodes.md.
"""
import dataclasses
import os
import time

from rclpy.duration import Duration
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node

from lpa_transfer.exploration.babbling import BabblingProgram, box_around
from lpa_transfer.robots.kinematics import robot_kinematics
from lpa_transfer.robots.control import PID, start_servo
from lpa_transfer.exploration.correspondences import (DEFAULT_FEATURES, PairCheck,
                                                      check_features, check_pairing_rule,
                                                      collect_correspondences, pair_check_line)
from lpa_transfer._validation import check_int
from lpa_transfer.robots.params import load_robot_params
from lpa_transfer.transfer.fit_spec import FitSpec
from lpa_transfer_interfaces.msg import CorrespondenceBatch, CorrespondenceSample
from lpa_transfer_interfaces.srv import FitModel, ResetRobot, StepRobot
from lpa_transfer_nodes.calls import call_service, wait_for_services, wait_for_subscribers
from lpa_transfer_nodes.collector_parameters import (BABBLING, FIT, GUIDED, KINEMATICS,
                                                     MAPPING, PAIR_CHECK_FIELDS, PIDS, RESETS,
                                                     ROBOTS, RUN, SIDES, TIME_LAW)
from lpa_transfer_nodes.conversions import sim_stamp, to_matrix
from lpa_transfer_nodes.entry import run_job
from lpa_transfer_nodes.guided_exploration import GuidedExploration
from lpa_transfer_nodes.params import declare_table, describe_use_sim_time
from lpa_transfer_nodes.qos import BATCH_QOS, SAMPLE_QOS
from lpa_transfer_nodes.robot_clients import robot_stepper


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


class CorrespondenceCollector(GuidedExploration, Node):
    def __init__(self, stop):
        super().__init__("correspondence_collector")
        self.stop = stop
        p = declare_table(self, ROBOTS + KINEMATICS + PIDS + BABBLING)
        self.robots = {side: load_robot_params(required_path(p[f"{side}_robot"],
                                                             f"{side}_robot")) for side in SIDES}
        self.kinematics = {side: self.side_kinematics(side, p) for side in SIDES}
        self.pid = {side: PID.from_gains(p[f"{side}_pid"], f"{side}_pid") if p[f"{side}_pid"]
                    else None for side in SIDES}
        self.pairing_rule = check_pairing_rule(p["pairing_rule"])
        self.steps_per_sample = p["steps_per_sample"]
        self.pair_check = PairCheck(**{field: p[name]
                                       for name, field in PAIR_CHECK_FIELDS.items()})
        self.task_offset = p["task_offset"] or None
        self.guided = p["program"] == GUIDED
        if self.guided:
            self.declare_guided(p["seed"], bool(p["features"]))
        else:
            self.program = BabblingProgram(
                p["program"], p["n_segments"], p["samples_per_segment"], p["seed"],
                tuple(p["task_low"]), tuple(p["task_high"]),
                declare_table(self, TIME_LAW)["time_law"])
        self.features = check_features(p["features"] or DEFAULT_FEATURES)
        self.declare_run()
        describe_use_sim_time(self)
        self.sample_pub = self.create_publisher(CorrespondenceSample, "correspondences",
                                                SAMPLE_QOS)
        self.batch_pub = self.create_publisher(CorrespondenceBatch, "correspondence_batch",
                                               BATCH_QOS)
        self.spinner = SingleThreadedExecutor()
        self.spinner.add_node(self)
        self.sim_time = 0.0

    def side_kinematics(self, side, p):
        """A robot's kinematics from its home, with its own task-space box if it has one."""
        kinematics = robot_kinematics(self.robots[side], p[f"{side}_home"] or None)
        return dataclasses.replace(kinematics, task_box=task_box(
            kinematics, p[f"{side}_task_low"], p[f"{side}_task_high"],
            p[f"{side}_task_halfwidth"], side))

    def declare_run(self):
        """What to do with the pairs (save, fit), how long to wait, and the services."""
        run = declare_table(self, RUN + (RESETS if self.guided else ()) + MAPPING)
        self.output = os.path.expanduser(run["output"])
        self.model_id = run["model_id"]
        self.fit_spec = FitSpec(**dict({name: run[name] for name, *_ in FIT},
                                       cluster_dims=tuple(run["cluster_dims"])))
        self.cross_validation_folds = run["cross_validation_folds"]
        if self.cross_validation_folds:
            check_int(self.cross_validation_folds, "cross_validation_folds", 2)
        self.wait_for_subscribers = run["wait_for_subscribers"]
        self.subscribed_topics = run["wait_for_subscribed_topics"]
        self.wait_timeout, self.call_timeout = run["wait_timeout"], run["call_timeout"]
        self.step_clients = {side: self.create_client(StepRobot, run[f"{side}_step"])
                             for side in SIDES}
        self.reset_clients = {side: self.create_client(ResetRobot, run[f"{side}_reset"])
                              for side in SIDES} if self.guided else {}
        self.fit_client = self.create_client(FitModel, run["mapping_service"])

    # -- talking to the robots and the mapping service ---------------------------------------
    def call(self, client, request, **options):
        return call_service(self.spinner, client, request, self.call_timeout, **options)

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
        """The FitModel request, with the robots' names and the columns' names as metadata."""
        source_columns, target_columns = pairs.columns()
        return FitModel.Request(
            model_id=self.model_id, source=to_matrix(pairs.source),
            target=to_matrix(pairs.target), source_robot=pairs.source_robot,
            target_robot=pairs.target_robot, source_features=source_columns,
            target_features=target_columns, **self.fit_spec.request_fields())

    def held_out(self, pairs):
        """The k-fold held-out nMSE of the model the service will fit, and of PA (metadata)."""
        scores = self.fit_spec.held_out_errors(pairs.source, pairs.target,
                                               self.cross_validation_folds)
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

    def run(self):
        clients = list(self.step_clients.values()) + list(self.reset_clients.values()) \
            + ([self.fit_client] if self.model_id else [])
        wait_for_services(clients, self.wait_timeout, self.stop, self.spinner)
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
