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
goal-babbles (Alg. 6) on the joints it shares with the source, then the source takes the
posture the target reached in each movement (``source_follows``), settling by its state; pair
i is each robot's observed (q̄, x) for movement i, checked as a ``same_command`` pair.

Parameters, topics and the details of guided exploration: docs/nodes.md.
"""
import dataclasses
import os
import time

from rclpy.duration import Duration
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter

from lpa_transfer.exploration.babbling import PROGRAMS, TIME_LAWS, BabblingProgram, box_around
from lpa_transfer.robots.kinematics import robot_kinematics
from lpa_transfer.robots.control import PID, start_servo
from lpa_transfer.exploration.correspondences import (BAD_PAIR_ACTIONS, DEFAULT_FEATURES,
                                                      FEATURES, PAIRING_RULES, PairCheck,
                                                      SettlingStep,
                                                      check_features, pair_check_line,
                                                      check_guided_exploration, check_pairing_rule,
                                                      collect_correspondences,
                                                      collect_guided_correspondences)
from lpa_transfer.exploration.guided import SOURCE_FOLLOWS, TARGET_RANGES
from lpa_transfer.goal_babbling.goal_babbling import GoalBabbling
from lpa_transfer._validation import check_int, check_x_bounds
from lpa_transfer.robots.environment import stepped_environment
from lpa_transfer.robots.params import load_robot_params
from lpa_transfer.transfer import LocalProcrustesAnalysis, ProcrustesAnalysis
from lpa_transfer.transfer.cross_validation import held_out_nmse
from lpa_transfer.transfer.model_store import METHODS
from lpa_transfer_interfaces.msg import CorrespondenceBatch, CorrespondenceSample
from lpa_transfer_interfaces.srv import FitModel, ResetRobot, StepRobot
from lpa_transfer_nodes.lpa_mapping import feature_columns, fit_hyperparameters
from lpa_transfer_nodes.calls import call_service, wait_for_services, wait_for_subscribers
from lpa_transfer_nodes.conversions import sim_stamp, to_matrix
from lpa_transfer_nodes.entry import run_job
from lpa_transfer_nodes.params import declare, declare_array, describe_use_sim_time
from lpa_transfer_nodes.qos import BATCH_QOS, SAMPLE_QOS
from lpa_transfer_nodes.robot_clients import robot_resetter, robot_stepper

#: FitModel's fields as parameters: (default, description, constraints).
FIT_FIELDS = {
    "method": ("lpa", "as in FitModel.srv: pa or lpa", dict(choices=tuple(METHODS))),
    "latent_dim": (0, "as in FitModel.srv; 0: the service's default (no limit)",
                   dict(range=(0, None))),
    "n_min": (0, "as in FitModel.srv: LPA's N_min; 0: the service's default",
              dict(range=(0, None))),
    "c_min": (0.0, "as in FitModel.srv: LPA's c_min (0: always split)",
              dict(range=(0.0, None))),
    "k_max": (0, "as in FitModel.srv: LPA's most clusters; 0: no limit", dict(range=(0, None))),
    "n_init": (0, "as in FitModel.srv: LPA's k-means restarts; 0: the service's default",
               dict(range=(0, None)))}
GUIDED = "goal_babbling"          # the program of guided exploration (§6.4.2, Alg. 7)
#: GoalBabbling's hyperparameters as parameters: (default, description, constraints).
GOAL_BABBLING_FIELDS = {
    "n_subtargets": (10, f"{GUIDED}: GoalBabbling's T, sub-targets per goal",
                     dict(range=(1, None))),
    "sigma": (0.1, f"{GUIDED}: GoalBabbling's exploration noise",
              dict(range=(0.0, None), finite=True)),
    "drift": (0.01, f"{GUIDED}: drift of the exploration noise",
              dict(range=(0.0, None), finite=True)),
    "p_home": (0.1, f"{GUIDED}: probability of returning home", dict(range=(0.0, 1.0))),
    "steps_per_second": (10.0, f"{GUIDED}: movement steps a simulated second",
                         dict(positive=True, finite=True))}


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
        def doubles(name, description, constraints=""):
            return declare_array(self, name, Parameter.Type.DOUBLE_ARRAY, description,
                                 additional_constraints=constraints)

        self.robots = {side: load_robot_params(required_path(declare(
            self, f"{side}_robot", "", f"the {side} robot's parameter file (joint limits and "
            f"kinematics, for the babbling program and inverse kinematics); its name labels "
            f"the pairs; required"), f"{side}_robot")) for side in ("source", "target")}
        self.kinematics = {}
        for side, robot in self.robots.items():
            home = doubles(f"{side}_home", f"the {side} robot's pose babbling starts from "
                           f"(rad); unset: zero clipped into the joint limits",
                           "one value per joint")
            kinematics = robot_kinematics(robot, home or None)
            box = [doubles(f"{side}_task_{end}", f"task_lines: the {end} corner of the {side} "
                           f"robot's own waypoint box (m); unset: the program's box "
                           f"(task_low/task_high)") for end in ("low", "high")]
            halfwidth = doubles(f"{side}_task_halfwidth", f"task_lines: instead of "
                                f"{side}_task_low/high, the half-width (m) of the box around "
                                f"the {side} end effector at {side}_home",
                                "one value >= 0 per task coordinate")
            self.kinematics[side] = dataclasses.replace(kinematics, task_box=task_box(
                kinematics, *box, halfwidth, side))
        gains = {side: doubles(f"{side}_pid", f"[kp, ki, kd] for a {side} robot_sim in torque "
                               f"mode: the robot tracks the babbling commands with this PID; "
                               f"unset: position mode", "3 values")
                 for side in self.robots}
        self.pid = {side: PID.from_gains(gains[side], f"{side}_pid") if gains[side] else None
                    for side in self.robots}
        self.pairing_rule = check_pairing_rule(declare(
            self, "pairing_rule", "same_command", "how samples of the two robots are paired",
            choices=PAIRING_RULES))
        program = declare(self, "program", "joint_lines", "the babbling program; "
                          f"{GUIDED}: guided exploration (thesis §6.4.2, Alg. 7)",
                          choices=PROGRAMS + (GUIDED,))
        seed = declare(self, "seed", 0, f"seeds the babbling program ({GUIDED}: the "
                       "GoalBabbling)", range=(0, None))
        n_segments = declare(self, "n_segments", 20, "joint_lines/task_lines: lines per run",
                             range=(1, None))
        samples_per_segment = declare(self, "samples_per_segment", 5,
                                      "joint_lines/task_lines: samples per line",
                                      range=(1, None))
        task_low, task_high = (tuple(doubles(f"task_{end}", f"task_lines: the {end} corner "
                                             f"of the waypoint box (m)"))
                               for end in ("low", "high"))
        # the minimum a sample; settling by state and the pairing check (PairCheck) go on
        self.steps_per_sample = declare(
            self, "steps_per_sample", 400, "physics steps between samples, the minimum when "
            f"the robots settle; {GUIDED}: the physics steps of one movement step",
            range=(1, None))
        defaults = PairCheck()
        self.pair_check = PairCheck(
            max_settle_steps=declare(
                self, "max_settle_steps", defaults.max_settle_steps, "at most this many "
                "physics steps a sample while the robots settle; 0: exactly steps_per_sample, "
                "no settling", range=(0, None)),
            check_steps=declare(self, "settle_check_steps", defaults.check_steps,
                                "physics steps between two looks at a settling robot",
                                range=(1, None)),
            velocity_tol=declare(self, "settle_velocity_tol", defaults.velocity_tol,
                                 "settled when no joint moves faster (rad/s or m/s) ...",
                                 range=(0.0, None)),
            position_tol=declare(self, "settle_position_tol", defaults.position_tol,
                                 "... and none moved more over the last look (rad or m)",
                                 range=(0.0, None)),
            tolerance=declare(self, "pair_tolerance", defaults.tolerance,
                              "a pair is true when its residual is at most this: same_command "
                              "the largest difference of the common joint angles (rad), "
                              "same_task_point the target's end effector from the source's "
                              "point plus task_offset (m); .inf: no check", range=(0.0, None)),
            on_bad_pair=declare(self, "on_bad_pair", defaults.on_bad_pair,
                                "drop: count a failing pair and go on; retry: settle both "
                                "robots once more, check again, then drop",
                                choices=BAD_PAIR_ACTIONS),
            max_bad_share=declare(self, "max_bad_share", defaults.max_bad_share,
                                  "the run fails once more than this share of the planned "
                                  "pairs failed", range=(0.0, 1.0)))
        self.task_offset = doubles("task_offset", "same_task_point: the target's task frame "
                                   "relative to the source's (m)") or None
        features = declare_array(self, "features", Parameter.Type.STRING_ARRAY,
                                 "the columns of a sample; unset: "
                                 f"{list(DEFAULT_FEATURES)}",
                                 additional_constraints="distinct names from "
                                 + ", ".join(FEATURES))
        self.guided = program == GUIDED
        if self.guided:
            self.declare_guided(seed, gains, bool(features))
        else:
            self.program = BabblingProgram(
                program, n_segments, samples_per_segment, seed, task_low, task_high,
                declare(self, "time_law", "linear", "how the samples are spaced along each "
                        "line", choices=TIME_LAWS))
        self.features = check_features(features or DEFAULT_FEATURES)
        self.output = os.path.expanduser(declare(
            self, "output", "", "the .npz to save the correspondences to; empty: do not save"))
        self.model_id = declare(self, "model_id", "", "fit a model under this id in the "
                                "mapping service when done (only after a complete run); "
                                "empty: do not fit")
        self.fit_fields = {name: declare(self, name, default, description, **constraints)
                           for name, (default, description, constraints) in FIT_FIELDS.items()}
        self.fit_fields["cluster_dims"] = declare_array(
            self, "cluster_dims", Parameter.Type.INTEGER_ARRAY, "as in FitModel.srv: the "
            "source columns LPA clusters in; unset: all source dimensions")
        self.fit_fields["random_state"] = declare(self, "random_state", 0,
                                                  "the fit's seed (also the folds')",
                                                  range=(0, None))
        # k-fold held-out error of the model (and of PA) on the pairs, before the fit; 0: off
        self.cross_validation_folds = declare(
            self, "cross_validation_folds", 5, "with model_id: before the fit, log the k-fold "
            "held-out nMSE of the model and of PA; 0: off", range=(0, None),
            additional_constraints="0 (off) or >= 2")
        if self.cross_validation_folds:
            check_int(self.cross_validation_folds, "cross_validation_folds", 2)
        self.wait_for_subscribers = declare(
            self, "wait_for_subscribers", 0, "babble only once correspondences has this many "
            "subscribers (e.g. 2: a recorder and lpa_mapping)", range=(0, None))
        self.subscribed_topics = declare_array(
            self, "wait_for_subscribed_topics", Parameter.Type.STRING_ARRAY,
            "also wait until each of these topics has a subscriber (e.g. the robots' "
            "joint_states, so that a recorder records from the first step)")
        self.wait_timeout = declare(self, "wait_timeout", 30.0, "s to wait for each service "
                                    "and the subscribers, and at the end for the subscribers "
                                    "to acknowledge the published pairs", range=(0.0, None),
                                    finite=True)
        self.call_timeout = declare(self, "call_timeout", 120.0, "s a single service call "
                                    "may take (a fit on many points)", range=(0.0, None))
        self.step_clients = {side: self.create_client(StepRobot, declare(
            self, f"{side}_step", f"/{side}/robot_sim/step",
            f"the {side} robot's StepRobot service")) for side in ("source", "target")}
        self.reset_clients = {side: self.create_client(ResetRobot, declare(
            self, f"{side}_reset", f"/{side}/robot_sim/reset",
            f"{GUIDED} only: the {side} robot's ResetRobot service"))
            for side in ("source", "target")} if self.guided else {}
        self.fit_client = self.create_client(FitModel, declare(
            self, "mapping_service", "/lpa_mapping/fit", "the mapping service's FitModel "
            "service"))
        describe_use_sim_time(self)
        self.sample_pub = self.create_publisher(CorrespondenceSample, "correspondences",
                                                SAMPLE_QOS)
        self.batch_pub = self.create_publisher(CorrespondenceBatch, "correspondence_batch",
                                               BATCH_QOS)
        self.spinner = SingleThreadedExecutor()
        self.spinner.add_node(self)
        self.sim_time = 0.0

    def declare_guided(self, seed, gains, features_given):
        """The goal_babbling parameters, checked on the robots' kinematics before any step."""
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
        self.guided_seconds = declare(self, "guided_seconds", 60.0, "T_guided: the target's "
                                      "goal-babbling time (simulated s)", range=(0.0, None),
                                      finite=True)
        x_bounds = [declare_array(self, name, Parameter.Type.DOUBLE_ARRAY,
                                  f"X_bounds' {end} corner: the box of the target's goals in "
                                  f"its task space (m); required", additional_constraints=
                                  "one value per task coordinate")
                    for name, end in (("x_low", "low"), ("x_high", "high"))]
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
            given = declare_array(self, f"{side}_joints", Parameter.Type.INTEGER_ARRAY,
                                  f"the {side} robot's shared joints (source_joints[i] is "
                                  f"target_joints[i]); unset: the first min(n_s, n_t) joints",
                                  additional_constraints="distinct joint indices")
            self.joints[side] = given or list(range(n_shared))
        self.babbling = GoalBabbling(
            tuple(tuple(bound) for bound in x_bounds), seed=seed,
            **{name: declare(self, name, default, description, **constraints)
               for name, (default, description, constraints) in GOAL_BABBLING_FIELDS.items()})
        self.target_range = declare(self, "target_range", "shared", "shared: the target "
                                    "explores within both robots' ranges of the shared joints; "
                                    "own: within its own, and only the commands the source "
                                    "could follow are pairs", choices=TARGET_RANGES)
        self.source_follows = declare(
            self, "source_follows", "reached", "reached: the source takes the posture the "
            "target reached in each movement and settles there (max_settle_steps), so both rows "
            "of a pair are at the same shared joints; command: it is sent the target's command "
            "for steps_per_sample steps and lags it its own way", choices=SOURCE_FOLLOWS)
        check_guided_exploration(self.babbling, self.kinematics["source"],
                                 self.kinematics["target"], self.joints["source"],
                                 self.joints["target"], self.guided_seconds, self.target_range)

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
        return FitModel.Request(
            model_id=self.model_id, source=to_matrix(pairs.source),
            target=to_matrix(pairs.target), source_robot=pairs.source_robot,
            target_robot=pairs.target_robot,
            source_features=feature_columns(pairs.features, pairs.source.shape[1]),
            target_features=feature_columns(pairs.features, pairs.target.shape[1]),
            **self.fit_fields)

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
        settling = SettlingStep(self.stepper("source"), self.pair_check
                                if self.source_follows == "reached"
                                else dataclasses.replace(self.pair_check, max_settle_steps=0))
        pairs = collect_guided_correspondences(
            babbling, stepped_environment(self.kinematics["source"], settling,
                                          self.steps_per_sample),
            stepped_environment(self.kinematics["target"], self.stepper("target"),
                                self.steps_per_sample),
            self.joints["source"], self.joints["target"], self.guided_seconds,
            on_pair=self.publish_pair, should_stop=self.stop.is_set,
            target_range=self.target_range, source_follows=self.source_follows,
            pair_check=self.pair_check, source_settling=settling,
            names=(self.robots["source"].name, self.robots["target"].name))
        self.get_logger().info(f"pairing check: {pair_check_line(pairs.metadata)}, median "
                               f"{pairs.metadata['median_residual']:.3g} rad")
        pairs.metadata.update(program=GUIDED)
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
