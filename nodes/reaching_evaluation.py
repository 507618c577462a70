"""The goal-babbling learner's progress as in thesis §6.5, mixed into the learner node: the
reachable test points, the reaching error and rate of its inverse model on them (on the
analytic kinematics: the robot never moves for it), published as a ReachingEvaluation and as
green (reached) and red (missed) test points on task_markers.
"""
import math

import numpy as np
from rclpy.qos import QoSProfile, ReliabilityPolicy

from lpa_transfer._validation import check_x_bounds
from lpa_transfer.goal_babbling.negative_transfer import GuardedModel
from lpa_transfer.goal_babbling.reaching import (evaluation_points, reaching_errors,
                                                 reaching_rate)
from lpa_transfer.goal_babbling.yielding import YieldingModel
from lpa_transfer_interfaces.msg import ReachingEvaluation
from lpa_transfer_nodes.conversions import sim_stamp
from lpa_transfer_nodes.markers import MISSED, REACHED, marker_array, sphere_list

#: Every evaluation should reach its subscribers, even many in one babble call.
EVALUATION_QOS = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)


class ReachingEvaluator:
    """Evaluation of the learner's ``model`` on its test ``points`` (see the module)."""

    def test_points(self, p):
        """The reachable points of the test grid over the evaluation box (§6.5)."""
        eval_bounds = tuple(p[f"eval_{end}"] or bound
                            for end, bound in zip(("low", "high"), self.x_bounds))
        points = evaluation_points(self.kinematics, check_x_bounds(eval_bounds, self.n_task),
                                   spacing=p["eval_spacing"],
                                   n_joint_samples=p["eval_joint_samples"])
        if not len(points):
            raise ValueError(f"no test points: no point of the grid of {p['eval_spacing']:g} m "
                             f"over the box {np.round(eval_bounds, 6).tolist()} is reachable "
                             f"(check eval_low/eval_high, x_low/x_high and eval_spacing)")
        return points

    def counts(self):
        """(own samples, active transferred samples) in the inverse model."""
        if isinstance(self.model, (GuardedModel, YieldingModel)):
            own = getattr(self.model.model.inverse, "n_samples_", 0)
            return own, self.model.n_active_
        total = getattr(self.model.inverse, "n_samples_", 0)
        return total - self.n_transferred, self.n_transferred

    def evaluate(self):
        """Evaluate L⁻¹ on the test points (analytic kinematics) and publish the result."""
        n_own, n_transferred = self.counts()
        if n_own + n_transferred:
            errors = reaching_errors(self.model.inverse, self.kinematics, self.points)
            mean_error, rate = float(errors.mean()), reaching_rate(errors, self.threshold)
        else:   # nothing learned yet: no command to evaluate
            errors, mean_error, rate = np.full(len(self.points), np.inf), math.nan, 0.0
        msg = ReachingEvaluation(
            robot=self.robot.name, learning_time=float(self.clock), mean_error=float(mean_error),
            reaching_rate=float(rate), reaching_threshold=self.threshold,
            n_test_points=len(self.points), n_own_samples=int(n_own),
            n_transferred_samples=int(n_transferred))
        msg.header.stamp, msg.header.frame_id = sim_stamp(self.sim_time), "world"
        self.evaluation_pub.publish(msg)
        # the test points on task_markers: green reached within the threshold, red not
        # (task coordinates are the first of world x, y, z: a planar chain's z is 0)
        points = np.zeros((len(self.points), 3))
        points[:, :self.n_task] = self.points
        colours = np.where((errors <= self.threshold)[:, None], REACHED, MISSED)
        self.marker_pub.publish(marker_array(sphere_list(
            f"{self.get_name()}/test_points", 0, points, colours, msg.header.stamp,
            diameter=0.4 * self.eval_spacing)))
        self.get_logger().info(f"t = {self.clock:g} s: " + self.describe(msg))
        return msg

    @staticmethod
    def describe(evaluation):
        return (f"mean reaching error {1e3 * evaluation.mean_error:.1f} mm, reaching rate "
                f"{100 * evaluation.reaching_rate:.1f} % ({evaluation.n_own_samples} own, "
                f"{evaluation.n_transferred_samples} transferred samples)")
