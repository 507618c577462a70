"""Where one chapter 5 control period goes: the youBot tracking Star 1 with LWPR + PID at 100 Hz.

Times one trial (840 periods of 10 ms, 10 physics steps each) five ways, each from a fresh
learner on the same start, and prints the wall time per period and per simulated second:

1. ``graph``: the learner in this process over a ``robot_sim`` node in its own process (the
   StepRobot service round trip per period), as ``inverse_dynamics_learner`` runs it;
2. ``in process``: the same learner over a RobotSimulator in this process (no ROS);
3. the parts alone: a StepRobot round trip with a zero torque, ``LWPR`` predict + update on the
   trial's samples, 10 pybullet steps, and the rest of the learner's period (PID, features,
   bookkeeping) with a dummy regressor.

Usage (repository root, after ``source tools/env.sh``): ``python -m bench.bench_control_period
[--trials N] [--no-tf]``; it starts and stops its own robot_sim on a private ROS domain.
"""
import argparse
import json
import os
import tempfile
import time
from pathlib import Path

import numpy as np
import rclpy
import yaml
from lpa_transfer_nodes.entry import FastExecutor

from lpa_transfer.inverse_dynamics.online_learning import (FeedForwardLearner, input_scale,
                                                           make_regressor)
from lpa_transfer.inverse_dynamics.tasks import star_task
from lpa_transfer.robots.control import PID
from lpa_transfer.robots.kinematics import robot_kinematics
from lpa_transfer.robots.params import load_robot_params
from lpa_transfer.robots.simulator import RobotSimulator, robot_urdf
from lpa_transfer_interfaces.srv import StepRobot
from lpa_transfer_nodes.calls import call_service
from lpa_transfer_nodes.robot_clients import robot_stepper
from bench.ros_harness import NodeProcess, ros_params, unique_domain_id, wait_until

ROOT = Path(__file__).resolve().parents[1]
CONFIG = ROOT / "scenarios" / "inverse_dynamics" / "config.yaml"


def settings():
    config = yaml.safe_load(CONFIG.read_text())
    sim, learner = config["/youbot/robot_sim"]["ros__parameters"], \
        config["/youbot/star1"]["ros__parameters"]
    robot = load_robot_params(ROOT / learner["robot"])
    kinematics = robot_kinematics(robot, learner["centre_pose"])
    trajectory = star_task(kinematics, learner["star_radius"], 0.01, [], [], 2 * np.pi,
                           learner["star_start_angle"])
    hyper = json.loads(learner["regressor_params"])
    hyper["norm_in"] = input_scale(*trajectory[:3])
    return robot, sim, learner, kinematics.home, trajectory, hyper


def learner_for(learner, hyper, regressor="lwpr"):
    model = make_regressor("lwpr", **hyper) if regressor == "lwpr" else _Zero()
    return FeedForwardLearner(model, PID.from_gains(learner["pid"]))


class _Zero:
    """A regressor that predicts zero and learns nothing: the learner's own overhead."""

    def predict(self, X):
        return np.zeros((len(X), 5))

    def partial_fit(self, X, Y):
        return self


def run(step, start_state, learner, trajectory, n_trials):
    start = time.perf_counter()
    state = start_state
    for _ in range(n_trials):
        state = learner.run_trial(step, state, *trajectory, 10, 0.01).end_state
    return (time.perf_counter() - start) / (n_trials * len(trajectory[0]))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--trials", type=int, default=2)
    parser.add_argument("--no-tf", action="store_true",
                        help="robot_sim without its /tf (publish_tf false): what TF costs")
    args = parser.parse_args()
    robot, sim_params, learner, home, trajectory, hyper = settings()
    rows = []

    with RobotSimulator(robot_urdf(robot), "torque", 0.001) as sim:
        def local_step(command, n_steps):
            sim.step(command, n_steps)
            return sim.state()
        sim.reset(home)
        rows.append(("in process: learner + pybullet, no ROS",
                     run(local_step, sim.state(), learner_for(learner, hyper), trajectory,
                         args.trials)))
        sim.reset(home)
        rows.append(("  learner without LWPR (PID, features) + pybullet",
                     run(local_step, sim.state(), learner_for(learner, hyper, "zero"),
                         trajectory, args.trials)))
        sim.reset(home)
        zero = np.zeros(robot.n_joints)
        start = time.perf_counter()
        for _ in range(2000):
            sim.step(zero, 10)
            sim.state()
        rows.append(("  pybullet: 10 steps + state read", (time.perf_counter() - start) / 2000))
        sim.reset(home)
        samples = learner_for(learner, hyper, "zero")
        trial = samples.run_trial(local_step, sim.state(), *trajectory, 10, 0.01)
    lwpr = make_regressor("lwpr", **hyper)
    X, Y = trial.samples[:, :15], trial.samples[:, 15:]
    lwpr.partial_fit(X[:1], Y[:1])      # predicting needs a fitted model
    start = time.perf_counter()
    for _ in range(args.trials):
        for x, y in zip(X, Y):
            lwpr.predict(x[None])
            lwpr.partial_fit(x[None], y[None])
    rows.append(("  LWPR predict + update (15 in, 5 out)",
                 (time.perf_counter() - start) / (args.trials * len(X))))

    domain_id = unique_domain_id()
    os.environ["ROS_DOMAIN_ID"] = str(domain_id)
    with tempfile.TemporaryDirectory() as logs:
        params = ros_params(robot=str(ROOT / sim_params["robot"]), control_mode="torque",
                            physics_step=0.001, publish_tf=not args.no_tf)
        node_args = params + ["-p", "initial_positions:=" + str([float(q) for q in home])]
        with NodeProcess("robot_sim", domain_id, logs, node_args):
            rclpy.init()
            node = rclpy.create_node("bench_control_period")
            executor = FastExecutor()
            executor.add_node(node)
            client = node.create_client(StepRobot, "/robot_sim/step")
            wait_until(lambda: client.wait_for_service(timeout_sec=0.1), 30, what="robot_sim")

            def call(client_, request):
                return call_service(executor, client_, request, 30.0)
            step = robot_stepper(call, client, robot.name)
            state = step(np.zeros(robot.n_joints), 1)
            rows.insert(0, ("graph: learner + StepRobot round trip + robot_sim",
                            run(step, state, learner_for(learner, hyper), trajectory,
                                args.trials)))
            request = StepRobot.Request(command=[0.0] * robot.n_joints, n_steps=10)
            times = []
            for _ in range(2000):
                start = time.perf_counter()
                call(client, request)
                times.append(time.perf_counter() - start)
            rows.append(("  StepRobot round trip (10 steps, zero torque)", float(np.median(times))))
            node.destroy_node()
            rclpy.shutdown()

    print(f"chapter 5 control period, youBot Star 1, {args.trials} trial(s) of 840 periods, "
          f"{os.cpu_count()} cores, load {os.getloadavg()[0]:.2f}")
    print(f"{'part':56s} {'ms / period':>11s} {'sim s / wall s':>14s}")
    for name, seconds in rows:
        print(f"{name:56s} {1e3 * seconds:11.3f} {0.01 / seconds:14.2f}")


if __name__ == "__main__":
    main()
