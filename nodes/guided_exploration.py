"""The correspondence collector's guided exploration (``program:=goal_babbling``, thesis
§6.4.2, Alg. 7, :func:`lpa_transfer.exploration.correspondences.collect_guided_correspondences`):
its parameters and its run, mixed into the collector node.

The target goal-babbles (Alg. 6) on the joints it shares with the source, then the source
takes the posture the target reached in each movement (``source_follows``), settling by its
state; pair i is each robot's observed (q̄, x) for movement i, checked as a ``same_command``
pair.
"""
import dataclasses

from lpa_transfer._validation import check_x_bounds
from lpa_transfer.exploration.correspondences import (SettlingStep, check_guided_exploration,
                                                      collect_guided_correspondences,
                                                      pair_check_line)
from lpa_transfer.goal_babbling.goal_babbling import GoalBabbling
from lpa_transfer.robots.environment import stepped_environment
from lpa_transfer_nodes.collector_parameters import (GOAL_BABBLING, GUIDED, GUIDED_EXPLORATION,
                                                     GUIDED_PAIRING, SIDES)
from lpa_transfer_nodes.params import declare_table
from lpa_transfer_nodes.robot_clients import robot_resetter


class GuidedExploration:
    """The collector's guided exploration: the target goal-babbles, the source follows."""

    def declare_guided(self, seed, features_given):
        """The goal_babbling parameters, checked on the robots' kinematics before any step."""
        if self.pairing_rule != "same_command":
            raise ValueError(f"program {GUIDED} pairs the robots by same_command (guided "
                             f"exploration, §6.4.2), not by pairing_rule "
                             f"{self.pairing_rule!r}")
        if any(pid is not None for pid in self.pid.values()):
            raise ValueError(f"program {GUIDED} runs the robots in position mode: leave "
                             f"source_pid and target_pid empty")
        if features_given:
            self.get_logger().warning(f"program {GUIDED}: the features parameter is ignored "
                                      "(rows are (shared joint positions, task point))")
        g = declare_table(self, GUIDED_EXPLORATION + GOAL_BABBLING + GUIDED_PAIRING)
        x_bounds = [g["x_low"], g["x_high"]]
        if not all(x_bounds):
            raise ValueError(f"program {GUIDED} needs x_low and x_high (the box of the "
                             "target's goals in its task space)")
        try:
            check_x_bounds(x_bounds)
        except ValueError as exc:
            raise ValueError(f"x_low/x_high: {exc}") from None
        n_shared = min(robot.n_joints for robot in self.robots.values())
        self.joints = {side: g[f"{side}_joints"] or list(range(n_shared)) for side in SIDES}
        self.babbling = GoalBabbling(tuple(tuple(bound) for bound in x_bounds), seed=seed,
                                     **{name: g[name] for name, *_ in GOAL_BABBLING})
        self.guided_seconds = g["guided_seconds"]
        self.target_range, self.source_follows = g["target_range"], g["source_follows"]
        check_guided_exploration(self.babbling, self.kinematics["source"],
                                 self.kinematics["target"], self.joints["source"],
                                 self.joints["target"], self.guided_seconds, self.target_range)

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
