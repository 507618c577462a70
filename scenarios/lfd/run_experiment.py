#!/usr/bin/env python3
"""Thesis §4.5.1-4.5.2 over the node graph: letters demonstrated by the human arm model,
transferred by LPA onto the PR2 and the Meka, encoded as DMPs and executed on their simulators.

Part of run.sh, as the ROS node ``experiment`` (parameters: scenarios/lfd/config.yaml).
Running: ``demonstration_source`` (the human's demonstrations on ``demonstrations``),
``lpa_mapping``, per robot a ``robot_sim`` in position mode and a ``skill_learner`` (namespace
= the robot's name in frames.yaml), and the recorder. For every robot:

1. Correspondences (§4.4.2): motor babbling on the robot and the human's IK, in process
   (:func:`lpa_transfer.lfd.experiment.collect_pairs`: forward kinematics, as the thesis'
   "simulated motor babbling"), ``graph_pairs`` of them with seed ``graph_seed``.
2. ``/lpa_mapping/fit``: an LPA (``graph_n_min``, ``c_min``) human -> robot on them.
3. ``/lpa_mapping/transfer``: every demonstration, whole, onto the robot (Alg. 4).
4. ``/<robot>/skill_learner/learn_skill``: per shape, one DMP on its transferred
   demonstrations, the first reproduced and executed on the simulated robot. The same with
   the robot's own IK trajectories: the thesis' "IK method".

Then Table 4.3 (§4.5.3): ``learner`` (the Meka) taught via ``teacher`` (the PR2): an LPA
teacher -> learner in lpa_mapping (the learner babbles, the teacher's IK starts from the
joint map composed through the human), fed the teacher's transferred demonstrations
(unrefined) or its own IK trajectories (refined), and the learner's skill_learner executing
them.

Errors (m, against where the robot's task frame puts the demonstrated points, T_R^H x_H):
mapping (the transferred joints' forward kinematics, every point) and encoding (the executed
reproduction's end effector, each shape's first demonstration). Published for the bag: every
model's correspondences (``correspondence_batch``) and the trajectories each robot learned
from (``/<robot>/skill_demonstrations``). Writes into ``output_dir``:
``results.json``, ``report.txt`` and ``fig4_11_13_letters.png`` (demonstrations, transferred
and reproduced letters in 3-D, like Fig. 4-11/4-13, and the learner's via the teacher, like
Fig. 4-15).
"""
import json
import sys
import time
from pathlib import Path

import matplotlib
matplotlib.use("Agg")
import numpy as np  # noqa: E402
from rclpy.executors import SingleThreadedExecutor  # noqa: E402
from rclpy.node import Node  # noqa: E402

from lpa_transfer.robots import arm_kinematics  # noqa: E402
from lpa_transfer.lfd import (Demonstration, IK_TOLERANCE, between, by_shape,  # noqa: E402
                              collect_pairs, graph_report, load_setup, mean_mapping_error,
                              plot_letters, robot_ik_demonstrations, task_point_residuals)
from lpa_transfer.lfd.skills import CONDITIONS  # noqa: E402
from lpa_transfer_interfaces.msg import CorrespondenceBatch  # noqa: E402
from lpa_transfer_interfaces.msg import Demonstration as DemonstrationMsg  # noqa: E402
from lpa_transfer_interfaces.srv import LearnSkill  # noqa: E402
from lpa_transfer_nodes.calls import ServiceCalls, ServiceTimeout  # noqa: E402
from lpa_transfer_nodes.conversions import from_matrix, to_matrix  # noqa: E402
from lpa_transfer_nodes.entry import run_job  # noqa: E402
from lpa_transfer_nodes.params import declare, describe_use_sim_time  # noqa: E402
from lpa_transfer_nodes.mapping_client import MappingClient  # noqa: E402
from lpa_transfer_nodes.demonstration_source import (demonstration_msg,  # noqa: E402
                                                     demonstration_qos)

METHODS = ("transferred", "ik_method")


class Experiment(Node):
    def __init__(self, stop):
        super().__init__("experiment")
        self.stop = stop
        self.setup = load_setup(declare(self, "frames", "", "the scenario's frames file "
                                        "(demonstrator, robots, joint maps, task frames); "
                                        "required"), Path.cwd())
        self.n_expected = len(declare(self, "shapes", ["LShape"], "the shapes "
                                      "demonstration_source demonstrates (as its parameter)")) \
            * declare(self, "n_demos", 5, "demonstrations per shape (as demonstration_source's "
                      "parameter)", range=(1, None))
        self.pairs = declare(self, "graph_pairs", 20000, "correspondences collected per "
                             "mapping (babbling the robot, the demonstrator's IK)",
                             range=(1, None))
        self.seed = declare(self, "graph_seed", 0, "seed of the correspondences' babbling",
                            range=(0, None))
        self.fit = dict(method="lpa",
                        n_min=declare(self, "graph_n_min", 12, "LPA's N_min of every mapping "
                                      "(0: the service's default)", range=(0, None)),
                        c_min=declare(self, "c_min", 1e-7, "LPA's c_min of every mapping",
                                      range=(0.0, None)),
                        latent_dim=0, random_state=0)
        self.teacher = declare(self, "teacher", "pr2_right_arm", "Table 4.3: the robot that "
                               "teaches the learner (a robot of the frames file)")
        self.learner = declare(self, "learner", "meka_right_arm", "Table 4.3: the robot "
                               "taught via the teacher (a robot of the frames file)")
        self.output_dir = Path(declare(self, "output_dir", ".", "where results.json, "
                                       "report.txt and the figure go"))
        self.wait_timeout = declare(self, "wait_timeout", 120.0, "s to wait for every "
                                    "demonstration to arrive", range=(0.0, None))
        call_timeout = declare(self, "call_timeout", 600.0, "s a single service call may "
                               "take", range=(0.0, None))
        describe_use_sim_time(self)
        self.received = {}
        self.create_subscription(DemonstrationMsg, "demonstrations", self.on_demonstration,
                                 demonstration_qos(self.n_expected))
        # for the bag: the correspondences of every model and the trajectories each robot
        # learned from (latched, so the recorder gets them whatever its discovery lag)
        self.batch_pub = self.create_publisher(CorrespondenceBatch, "correspondence_batch",
                                               demonstration_qos(10))
        self.skill_demo_pubs = {name: self.create_publisher(
            DemonstrationMsg, f"/{name}/skill_demonstrations", demonstration_qos(1000))
            for name in self.setup.learners}
        self.spinner = SingleThreadedExecutor()
        self.spinner.add_node(self)
        self.calls = ServiceCalls(self, self.spinner, call_timeout, stop)
        self.mapping = MappingClient(self, timeout=call_timeout, executor=self.spinner,
                                     stop=stop)

    def on_demonstration(self, msg):
        self.received[(msg.shape, msg.index)] = Demonstration(
            msg.shape, np.array(msg.times), from_matrix(msg.joints, "joints"),
            from_matrix(msg.points, "points"))

    def demonstrations(self):
        """Every demonstration, in the source's order (shape by shape), once all arrived."""
        deadline = time.monotonic() + self.wait_timeout
        while len(self.received) < self.n_expected:
            if self.stop.is_set() or time.monotonic() > deadline:
                raise ServiceTimeout(f"received {len(self.received)} of {self.n_expected} "
                                     f"demonstrations (is demonstration_source running?)")
            self.spinner.spin_once(timeout_sec=0.1)
        shapes = list(dict.fromkeys(shape for shape, _ in self.received))   # arrival order
        return [self.received[key] for key in
                sorted(self.received, key=lambda key: (shapes.index(key[0]), key[1]))]

    def learn_skills(self, name, demos, joints):
        """Per shape: the skill node's DMP on these joint trajectories, executed. Returns
        {shape: executed end-effector points (T, 3) of its first demonstration}."""
        executed = {}
        for shape, members in by_shape(demos).items():
            request = [demonstration_msg(name, Demonstration(shape, demos[i].times, joints[i],
                                                             demos[i].x), k, len(members),
                                         self.get_clock().now().to_msg())
                       for k, i in enumerate(members)]
            for msg in request:
                self.skill_demo_pubs[name].publish(msg)
            answer = self.calls.call(LearnSkill, f"/{name}/skill_learner/learn_skill",
                                     shape=shape, demonstrations=request)
            executed[shape] = from_matrix(answer.reproduction.executed_points, "points")
        return executed

    def fit_model(self, model_id, learner, body):
        """Correspondences body -> learner (babbling on the learner) and an LPA on them in
        lpa_mapping: (poses babbled, clusters)."""
        source, target, tried = collect_pairs(learner, body, self.pairs, self.seed)
        residuals = task_point_residuals(body, source, learner.joint_map.n_joints)
        batch = CorrespondenceBatch(source_robot=body.name, target_robot=learner.robot.name,
                                    pairing_rule="same_task_point", source=to_matrix(source),
                                    target=to_matrix(target), pairs_checked=tried,
                                    pairs_dropped=tried - len(source),
                                    worst_residual=float(residuals.max()),
                                    pair_tolerance=IK_TOLERANCE, residual_unit="m")
        self.get_logger().info(
            f"{body.name} -> {learner.robot.name}: pairing check: {tried} poses babbled, "
            f"{len(source)} pairs kept (the rest out of {body.name}'s reach by more than "
            f"{IK_TOLERANCE:g} m, or past the count); worst kept residual "
            f"{residuals.max():.3g} m")
        batch.header.stamp, batch.header.frame_id = self.get_clock().now().to_msg(), "world"
        self.batch_pub.publish(batch)
        fitted = self.mapping.fit(model_id, source, target, source_robot=body.name,
                                  target_robot=learner.robot.name, **self.fit)
        return tried, fitted.n_clusters

    def transfer(self, model_id, trajectories):
        """Each trajectory's rows (T, D_s), whole, through lpa_mapping: the mapped rows."""
        return [self.mapping.transfer(model_id, rows) for rows in trajectories]

    def encoding(self, name, demos, joints, targets):
        """Skills of these joint trajectories executed on robot ``name``: ({shape: error},
        {shape: executed points}) against ``targets`` {shape: T_R^H x_H of its first}."""
        executed = self.learn_skills(name, demos, joints)
        return ({shape: float(np.linalg.norm(executed[shape] - x, axis=1).mean())
                 for shape, x in targets.items()}, executed)

    def robot(self, name, demos):
        learner = self.setup.learners[name]
        started = time.perf_counter()
        model_id = f"{self.setup.demonstrator.name}->{name}"
        tried, clusters = self.fit_model(model_id, learner, self.setup.demonstrator)
        mapped = self.transfer(model_id, [d.rows for d in demos])
        n = learner.joint_map.n_joints
        joints = {"transferred": [m[:, :n] for m in mapped],
                  "ik_method": [d.q for d in robot_ik_demonstrations(learner, demos)]}
        result = {"pairs": self.pairs, "babbled": tried, "clusters": clusters,
                  "mapping_error": mean_mapping_error(learner, demos, np.vstack(mapped))}
        firsts = {shape: members[0] for shape, members in by_shape(demos).items()}
        forward = arm_kinematics(learner.robot, n).forward
        traces = {"demonstrated": {s: learner.task_frame.to_robot(demos[i].x)
                                   for s, i in firsts.items()},
                  "mapped": {s: forward(joints["transferred"][i]) for s, i in firsts.items()}}
        for method in METHODS:
            errors, traces[method] = self.encoding(name, demos, joints[method],
                                                   traces["demonstrated"])
            result[f"{method}_encoding_error"] = float(np.mean(list(errors.values())))
            result[f"{method}_encoding_by_shape"] = errors
        self.get_logger().info(
            f"{name}: mapping {result['mapping_error'] * 1e3:.1f} mm, encoding "
            f"{result['transferred_encoding_error'] * 1e3:.1f} mm (IK method "
            f"{result['ik_method_encoding_error'] * 1e3:.1f} mm), "
            f"{time.perf_counter() - started:.0f} s")
        return result, traces

    def multi_robot(self, demos, results, direct_traces):
        """Table 4.3 over the graph: the learner taught via the teacher, whose skills are
        unrefined (human -> teacher -> learner through lpa_mapping) or refined (the teacher's
        own IK trajectories -> learner); "direct" is the learner's own run (its
        ``direct_traces``). Returns (table, executed traces for the picture)."""
        names = self.teacher, self.learner
        teacher, learner = (self.setup.learners[name] for name in names)
        relay_id = f"{names[0]}->{names[1]}"
        self.fit_model(relay_id, between(teacher, learner), teacher.robot)
        via = {"unrefined": self.transfer(
                   relay_id, self.transfer(f"{self.setup.demonstrator.name}->{names[0]}",
                                           [d.rows for d in demos])),
               "refined": self.transfer(relay_id, [d.rows for d in
                                                   robot_ik_demonstrations(teacher, demos)])}
        targets = {shape: learner.task_frame.to_robot(demos[members[0]].x)
                   for shape, members in by_shape(demos).items()}
        direct = results[names[1]]
        table = {"direct": {"mapping_error": direct["mapping_error"],
                            "encoding_error": direct["transferred_encoding_error"]}}
        traces = {"demonstrated": targets, "transferred": direct_traces["transferred"]}
        for condition, mapped in via.items():
            errors, traces[condition] = self.encoding(
                names[1], demos, [m[:, :learner.joint_map.n_joints] for m in mapped], targets)
            table[condition] = {"mapping_error": mean_mapping_error(learner, demos, np.vstack(mapped)),
                                "encoding_error": float(np.mean(list(errors.values())))}
        return {condition: table[condition] for condition in CONDITIONS}, traces

    def run(self):
        demos = self.demonstrations()
        results, traces = {}, {}
        for name in self.setup.learners:
            results[name], traces[name] = self.robot(name, demos)
        table, traces[f"{self.learner} via {self.teacher}"] = self.multi_robot(
            demos, results, traces[self.learner])
        self.output_dir.mkdir(parents=True, exist_ok=True)
        (self.output_dir / "results.json").write_text(json.dumps(
            {"robots": results, "multi_robot": table}, indent=1))
        (self.output_dir / "report.txt").write_text(graph_report(
            results, table, len(demos), self.teacher, self.learner))
        plot_letters(self.output_dir / "fig4_11_13_letters.png", traces)
        return results


def main(args=None):
    _, results = run_job("experiment", Experiment, lambda node: node.run(), args)
    print(json.dumps(results, indent=1))


if __name__ == "__main__":
    sys.exit(main())
