#!/usr/bin/env python3
"""Transfer the source robot's experience through the mapping service and score it (§3.6).

Part of run.sh: runs after correspondence_collector has fitted the model, as the ROS node
``transfer_evaluation`` (parameters from the scenario's YAML). It is also an example of a
user's own node calling the mapping service.

1. The source robot babbles on its own (its "experience": joint-space lines, a seed of its
   own) over its robot_sim StepRobot service: domain points z_s = (q, x, y).
2. The experience goes through ``/lpa_mapping/transfer`` into the target's domain, and a
   forward-kinematics model (q -> x, y; the locally weighted regression of the §3.6
   scenario, standing in for LWPR) is trained on it.
3. Scores against the target's true kinematics (its parameter file) on uniform target test
   joints: that model; the target's own correspondence samples alone ("no transfer", what
   the target learns from the pairs without the source's experience); and the target babbling
   as long as the source did ("own babbling", what transfer saves). The mapping error: uniform
   source test points transferred through the service against the target's true end effector
   at the same joint angles (Fig. 3-6a).

Writes ``evaluation.json`` and ``report.txt`` into ``output_dir``.
"""
import json
import sys
import time
from pathlib import Path

import numpy as np
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node

from lpa_transfer.exploration import (BabblingProgram, DEFAULT_FEATURES, load_correspondences,
                                      run_commands)
from lpa_transfer.robots import (domain_data, end_effector_rmse, load_robot_params,
                                 planar_forward_kinematics, planar_kinematics,
                                 sample_joint_uniform)
from lpa_transfer.learners import LocallyWeightedRegression
from lpa_transfer_interfaces.srv import StepRobot, TransferPoints
from lpa_transfer_nodes.calls import call_service, wait_for_services
from lpa_transfer_nodes.conversions import from_matrix, to_matrix
from lpa_transfer_nodes.entry import run_job
from lpa_transfer_nodes.params import declare, describe_use_sim_time
from lpa_transfer_nodes.robot_clients import robot_stepper


class TransferEvaluation(Node):
    def __init__(self, stop):
        super().__init__("transfer_evaluation")
        self.stop = stop
        self.robots = {side: load_robot_params(declare(
            self, f"{side}_robot", "", f"the {side} robot's parameter file; required"))
            for side in ("source", "target")}
        self.model_id = declare(self, "model_id", "", "the mapping service's model that "
                                "transfers the source's experience")
        self.correspondence_file = declare(self, "correspondence_file", "", "the collector's "
                                           "correspondences (.npz): the target's samples are "
                                           "the no-transfer baseline")
        self.output_dir = Path(declare(self, "output_dir", ".", "where evaluation.json and "
                                       "report.txt go"))
        self.experience = BabblingProgram(
            "joint_lines",
            declare(self, "n_segments", 200, "the source's own experience: joint-space lines",
                    range=(1, None)),
            declare(self, "samples_per_segment", 5, "samples per line", range=(1, None)),
            declare(self, "seed", 1, "seed of the experience's babbling", range=(0, None)))
        self.steps_per_sample = declare(self, "steps_per_sample", 400, "physics steps between "
                                        "samples", range=(1, None))
        self.n_test = declare(self, "n_test", 10000, "uniform test joints (and source test "
                              "points for the mapping error)", range=(1, None))
        self.test_seed = declare(self, "test_seed", 2, "seed of the test points",
                                 range=(0, None))
        self.n_neighbors = declare(self, "n_neighbors", 10, "neighbours of the target's "
                                   "forward-kinematics learner (locally weighted regression)",
                                   range=(1, None))
        self.timeout = declare(self, "wait_timeout", 30.0, "s to wait for the services, and "
                               "for each call", range=(0.0, None))
        describe_use_sim_time(self)
        self.step_clients = {side: self.create_client(StepRobot, f"/{side}/robot_sim/step")
                             for side in ("source", "target")}
        self.transfer_client = self.create_client(TransferPoints, declare(
            self, "transfer_service", "/lpa_mapping/transfer", "the mapping service's "
            "TransferPoints service"))
        self.spinner = SingleThreadedExecutor()
        self.spinner.add_node(self)

    def call(self, client, request):
        return call_service(self.spinner, client, request, self.timeout)

    def transfer(self, points):
        answer = self.call(self.transfer_client, TransferPoints.Request(
            model_id=self.model_id, source=to_matrix(points)))
        if not answer.success:
            raise RuntimeError(f"transfer through {self.model_id!r} failed: {answer.message}")
        return from_matrix(answer.target, "target")

    def babble(self, side):
        """The robot's own experience over its simulator: (samples, simulated seconds)."""
        kinematics = planar_kinematics(self.robots[side])
        return run_commands(self.experience.commands(kinematics),
                            robot_stepper(self.call, self.step_clients[side], side),
                            self.steps_per_sample, DEFAULT_FEATURES, kinematics.home,
                            self.stop.is_set)

    def model_error(self, data, test_q):
        n = self.robots["target"].n_joints
        model = LocallyWeightedRegression(n_neighbors=self.n_neighbors).fit(data[:, :n],
                                                                             data[:, n:])
        truth = planar_forward_kinematics(test_q, self.robots["target"].link_lengths)
        return end_effector_rmse(model.predict(test_q), truth)

    def run(self):
        wait_for_services([*self.step_clients.values(), self.transfer_client], self.timeout,
                          self.stop, self.spinner)
        start = time.perf_counter()
        source, target = self.robots["source"], self.robots["target"]
        experience, source_seconds = self.babble("source")
        transferred = self.transfer(experience)
        own, target_seconds = self.babble("target")
        _, pairs_target = load_correspondences(self.correspondence_file)
        rng = np.random.default_rng(self.test_seed)
        test_q = sample_joint_uniform(self.n_test, target.joint_limits, rng)
        source_test_q = sample_joint_uniform(self.n_test, source.joint_limits, rng)
        mapped = self.transfer(domain_data(source_test_q, source.link_lengths))
        n = target.n_joints
        return dict(
            model_id=self.model_id, n_correspondences=len(pairs_target),
            n_experience=len(experience), experience_sim_s=source_seconds,
            own_babbling_sim_s=target_seconds, n_test=self.n_test,
            mapping_rmse_m=end_effector_rmse(
                mapped[:, n:], planar_forward_kinematics(source_test_q, target.link_lengths)),
            model_rmse_m={"transferred experience": self.model_error(transferred, test_q),
                          "no transfer (target's correspondence samples)":
                              self.model_error(pairs_target, test_q),
                          "own babbling (target, same length)": self.model_error(own, test_q)},
            wall_s=time.perf_counter() - start)


def report_text(result):
    lines = [f"Transfer of the source robot's experience through model {result['model_id']!r}",
             f"  correspondences: {result['n_correspondences']}; source experience: "
             f"{result['n_experience']} samples ({result['experience_sim_s']:.1f} s simulated)",
             f"  mapping RMSE (uniform source test points, {result['n_test']}): "
             f"{1e3 * result['mapping_rmse_m']:.2f} mm",
             "  target forward-kinematics model RMSE against the true kinematics:"]
    lines += [f"    {name:<48} {1e3 * value:8.2f} mm"
              for name, value in result["model_rmse_m"].items()]
    return "\n".join(lines) + "\n"


def main(args=None):
    node, result = run_job("transfer_evaluation", TransferEvaluation, lambda n: n.run(), args)
    node.output_dir.mkdir(parents=True, exist_ok=True)
    (node.output_dir / "evaluation.json").write_text(json.dumps(result, indent=2) + "\n")
    text = report_text(result)
    (node.output_dir / "report.txt").write_text(text)
    print(text, end="")
    return 0


if __name__ == "__main__":
    sys.exit(main())
