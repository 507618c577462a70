"""skill_learner: learn a skill (joint-space DMP), execute it on a robot (thesis §4.4.4, §4.5.2).

Run (next to a robot_sim in position mode, lock-step, in the same namespace):
``skill_learner --ros-args -r __ns:=/meka -p robot:=scenarios/robots/meka_right_arm.toml``
(or ``python -m lpa_transfer_nodes.skill_learner ...``).

Each LearnSkill call (``~/learn_skill``) fits one :class:`lpa_transfer.lfd.dmp.JointDMP`
(eq. 4.1-4.5) on a shape's demonstrations in this robot's joint space (transferred by LPA, or
traced by its own IK), reproduces the first demonstration with it (§4.5.2: "reproduce the
first demonstration") and executes that reproduction on the robot's simulator: a reset to its
first pose, then each sample commanded in position mode for the physics steps of its time
interval. Poses are clipped into the joint limits first (as position mode clips its targets;
a reset outside them would be refused), so a reproduction that leaves the limits shows in the
reported distance. Each learned skill is also published on ``skill_reproduction``.

Parameters, topics and services: docs/nodes.md.
"""
import os

import numpy as np
from rclpy.node import Node

from lpa_transfer.lfd.dmp import JointDMP
from lpa_transfer.robots.kinematics import pad_transferred
from lpa_transfer.robots.kinematics import home_pose
from lpa_transfer.robots.kinematics import arm_kinematics
from lpa_transfer.robots.params import load_robot_params
from lpa_transfer_interfaces.msg import SkillReproduction
from lpa_transfer_interfaces.srv import LearnSkill
from lpa_transfer_nodes.calls import call_service, wait_for_services
from lpa_transfer_nodes.conversions import from_matrix, sim_stamp, to_matrix
from lpa_transfer_nodes.entry import serve
from lpa_transfer_nodes.params import declare_table, describe_use_sim_time
from lpa_transfer_nodes.robot_clients import RobotClients, robot_resetter, robot_stepper
from lpa_transfer_nodes.servers import answering
from lpa_transfer_nodes.markers import ACTUAL, line_strip, marker_array, task_marker_publisher


ROBOT = (
    ("robot", "", "the robot parameter file; required"),
    ("n_joints", 4, "the DMP drives the robot's first n joints; the others are held at the "
     "robot's home (zero clipped into the limits)", dict(range=(1, None))))
EXECUTION = (
    ("dmp_weights_per_joint", 30, "the DMP's N, basis functions per joint",
     dict(range=(2, None))),
    ("dmp_alpha_z", 25.0, "the DMP's alpha_z (beta_z = alpha_z / 4)",
     dict(positive=True, finite=True)),
    ("physics_step", 0.001, "the simulator's physics step (s): sample k is commanded for "
     "round((t_k - t_k-1) / physics_step) + settle_steps physics steps",
     dict(positive=True, finite=True)),
    ("settle_steps", 0, "extra physics steps after each command before the end effector is "
     "read", dict(range=(0, None))),
    ("call_timeout", 30.0, "s for each robot call", dict(range=(0.0, None))),
    ("wait_timeout", 30.0, "s to wait for the robot's services", dict(range=(0.0, None))),
    ("step_service", "robot_sim/step", "the robot's StepRobot service, resolved in the node's "
     "namespace"),
    ("reset_service", "robot_sim/reset", "the robot's ResetRobot service, resolved in the "
     "node's namespace"))


class SkillLearner(Node):
    def __init__(self, stop):
        super().__init__("skill_learner")
        self.stop = stop
        p = declare_table(self, ROBOT)
        self.robot = load_robot_params(os.path.expanduser(p["robot"]))
        self.n_joints = p["n_joints"]
        self.kinematics = arm_kinematics(self.robot, self.n_joints, name=self.robot.name)
        self.home = home_pose(self.robot.joint_limits)
        p = declare_table(self, EXECUTION)
        self.dmp = JointDMP(n_weights_per_dim=p["dmp_weights_per_joint"],
                            alpha_z=p["dmp_alpha_z"])
        self.physics_step, self.settle_steps = p["physics_step"], p["settle_steps"]
        self.call_timeout, self.wait_timeout = p["call_timeout"], p["wait_timeout"]
        self.robot_clients = RobotClients(self, p["step_service"], p["reset_service"])
        describe_use_sim_time(self)
        self.step = robot_stepper(self.call, self.robot_clients.step, self.robot.name)
        self.reset_robot_to = robot_resetter(self.call, self.robot_clients.reset,
                                             self.robot.name)
        self.publisher = self.create_publisher(SkillReproduction, "skill_reproduction", 10)
        self.marker_pub, self.executed = task_marker_publisher(self), {}
        self.create_service(LearnSkill, "~/learn_skill",
                            answering(self, "learn_skill", self.learn_skill))
        step_service = self.robot_clients.node.resolve_service_name(
            self.robot_clients.step.srv_name)
        self.get_logger().info(
            f"{self.robot.name}: DMP (N={self.dmp.n_weights_per_dim}, alpha_z="
            f"{self.dmp.alpha_z:g}) on joints 0..{self.n_joints - 1}, the other "
            f"{self.robot.n_joints - self.n_joints} held at {self.home[self.n_joints:].tolist()}; "
            f"executed on {step_service} (settle_steps {self.settle_steps})")

    def call(self, client, request, **options):
        return call_service(self.robot_clients.executor, client, request, self.call_timeout,
                            **options)

    def demonstrations(self, request):
        """The requests' (times list, joints list), the column count checked."""
        if not request.demonstrations:
            raise ValueError("no demonstrations: LearnSkill needs at least one")
        times, joints = [], []
        for k, demo in enumerate(request.demonstrations):
            q = from_matrix(demo.joints, f"demonstrations[{k}].joints")
            if q.shape[1] != self.n_joints:
                raise ValueError(f"demonstrations[{k}].joints has {q.shape[1]} columns, the "
                                 f"{self.robot.name} learner drives {self.n_joints} joints")
            times.append(np.array(demo.times))
            joints.append(q)
        return times, joints

    def learn_skill(self, request, response):
        times, joints = self.demonstrations(request)
        self.dmp.fit_many(times, joints)
        reproduced, t = self.dmp.reproduce(), self.dmp.times_
        wait_for_services([self.robot_clients.step, self.robot_clients.reset],
                          self.wait_timeout, self.stop)
        limits = np.asarray(self.robot.joint_limits, dtype=np.float64)
        commands = np.clip(pad_transferred(reproduced, self.home, np.arange(self.n_joints)),
                           limits[:, 0], limits[:, 1])
        state = self.reset_robot_to(commands[0])
        points = [state.end_effector]
        for k in range(1, len(t)):
            n_steps = max(1, round((t[k] - t[k - 1]) / self.physics_step) + self.settle_steps)
            state = self.step(commands[k], n_steps)
            points.append(state.end_effector)
        points = np.array(points, dtype=np.float64)
        msg = SkillReproduction(robot=self.robot.name, shape=request.shape,
                                n_demonstrations=len(joints), times=[float(x) for x in t],
                                reproduced_joints=to_matrix(reproduced),
                                executed_points=to_matrix(points))
        msg.header.stamp, msg.header.frame_id = sim_stamp(state.time), "world"
        self.publisher.publish(msg)
        # every shape executed so far, on task_markers (frame world)
        self.executed[request.shape] = points
        self.marker_pub.publish(marker_array(*(
            line_strip(f"{self.get_name()}/{shape}", 0, path, ACTUAL, msg.header.stamp)
            for shape, path in sorted(self.executed.items()))))
        response.reproduction = msg
        distance = np.linalg.norm(points - self.kinematics.forward(reproduced), axis=1).mean()
        return (f"{request.shape}: DMP on {len(joints)} demonstrations, executed {len(t)} "
                f"samples, mean distance to the reproduction's FK {1e3 * distance:.1f} mm")

    def destroy_node(self):
        self.robot_clients.destroy()
        super().destroy_node()


def main(args=None):
    serve("skill_learner", SkillLearner, args)


if __name__ == "__main__":
    main()
