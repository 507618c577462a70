#!/usr/bin/env python3
"""PID-only star tracking with the thesis gains, with and without the joints' drives.

Thesis §5.5.2: torque control at 100 Hz with PID gains Pincher K_p 5, K_d 0.1, K_i 0.01 and
youBot K_p 100, K_d 2.0, K_i 0.01, effort limits 2.5 / 100 N·m (§5.5.1). This runs one trial
of a 'star' (7 lines, 0.6 s out and 0.6 s back, ``lpa_transfer.inverse_dynamics.tasks``) with the feedback
alone (no learned feed-forward: the first trial of learning), the torque held for the whole
control period over 1 ms physics steps, at 100 Hz (thesis) and 1 kHz control, for each robot
file as it is and with its joint drives (armature, damping) set to zero, and prints:

* error: mean (and max) task-space distance to the desired point, mm (§5.5.2's measure);
* τ range: per joint, N·m;
* sat %: share of control periods in which some joint is at its effort limit;
* flips: control periods whose torque jumps from one limit to the opposite one (chatter).

Usage: python -m studies.inverse_dynamics.pid_stability [--robots youbot_arm pincher_arm]
                                     [--rates 100 1000]
                                     [--drives file none armature]
(``armature``: the file's armature without its damping). About a minute for everything;
most of it is inverse kinematics of the desired paths.
"""
import argparse
import dataclasses
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]

from lpa_transfer.robots import (PID, RobotSimulator, load_robot_params,  # noqa: E402
                                 robot_kinematics, robot_urdf)
from lpa_transfer.learners import LWPR  # noqa: E402
from lpa_transfer.inverse_dynamics import FeedForwardLearner, star_task  # noqa: E402

PHYSICS_STEP = 1e-3
#: robot file stem: (PID kp, ki, kd of §5.5.2, star centre pose q_c, star radius m): Star 1
#: of scenarios/inverse_dynamics/config.yaml (every point reachable)
ROBOTS = {"pincher_arm": ((5.0, 0.01, 0.1), [0.0, 0.3, 1.0, 0.8], 0.05),
          "youbot_arm": ((100.0, 0.01, 2.0), [0.0, 0.0, 1.2, 0.8, 0.0], 0.10)}
#: the star's plane (world x-y: the arms' vertical plane, gravity along -y)
PLANE_U, PLANE_V = [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]


def with_drives(robot, drives):
    """The robot with its joint drives as in the file, none, or the armature alone."""
    zeros = np.zeros(robot.n_joints)
    if drives == "file":
        return robot
    if drives == "none":
        return dataclasses.replace(robot, joint_armature=zeros, joint_damping=zeros)
    if drives == "armature":
        return dataclasses.replace(robot, joint_damping=zeros)
    raise ValueError(f"unknown drives {drives!r}")


def desired(robot, q_centre, radius, dt):
    """Desired task points (T, 3) and joint trajectory (q, q̇, q̈) of one star trial."""
    q, qd, qdd, x_d = star_task(robot_kinematics(robot, q_centre), radius, dt, PLANE_U,
                                PLANE_V, tolerance=1e-6)
    return x_d, q, qd, qdd


def pid_trial(robot, gains, trajectory, dt):
    """One PID-only trial; returns the Trial (lpa_transfer.inverse_dynamics.online_learning)."""
    x_d, q, qd, qdd = trajectory
    with RobotSimulator(robot_urdf(robot), control_mode="torque", physics_step=PHYSICS_STEP,
                        initial_positions=q[0]) as sim:
        state = sim.step(np.zeros(robot.n_joints), 1)
        learner = FeedForwardLearner(LWPR(), PID(*gains), learn=False)
        return learner.run_trial(sim.step, state, q, qd, qdd, x_d,
                                 int(round(dt / PHYSICS_STEP)), dt)


def summary(robot, trial):
    """(error mm, max error mm, τ min, τ max, saturated share, limit-to-limit flips)."""
    n, limits = robot.n_joints, robot.effort_limits
    tau = trial.samples[:, 3 * n:]
    error = np.linalg.norm(trial.desired - trial.actual, axis=1)
    at_limit = np.sign(tau) * (np.abs(tau) >= limits * (1 - 1e-9))   # +1 / -1 / 0
    flips = int((at_limit[1:] * at_limit[:-1] < 0).any(axis=1).sum())
    return (1e3 * error.mean(), 1e3 * error.max(), tau.min(axis=0), tau.max(axis=0),
            float((at_limit != 0).any(axis=1).mean()), flips)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--robots", nargs="+", default=list(ROBOTS), choices=list(ROBOTS))
    parser.add_argument("--rates", nargs="+", type=float, default=[100.0, 1000.0])
    parser.add_argument("--drives", nargs="+", default=["none", "armature", "file"],
                        choices=["none", "armature", "file"])
    args = parser.parse_args()
    print(f"{'robot':<12} {'Hz':>5} {'drives':<9} {'error mm':>9} {'max mm':>8} {'sat %':>6} "
          f"{'flips':>5}  τ range per joint, N·m")
    for stem in args.robots:
        gains, q_centre, radius = ROBOTS[stem]
        robot = load_robot_params(ROOT / "scenarios" / "robots" / f"{stem}.toml")
        for rate in args.rates:
            dt = 1.0 / rate
            trajectory = desired(robot, q_centre, radius, dt)
            for drives in args.drives:
                start = time.perf_counter()
                trial = pid_trial(with_drives(robot, drives), gains, trajectory, dt)
                mean, worst, low, high, saturated, flips = summary(robot, trial)
                ranges = " ".join(f"[{a:+.2f},{b:+.2f}]" for a, b in zip(low, high))
                print(f"{stem:<12} {rate:>5.0f} {drives:<9} {mean:>9.1f} {worst:>8.1f} "
                      f"{100 * saturated:>6.1f} {flips:>5d}  {ranges}   "
                      f"({time.perf_counter() - start:.1f} s)", flush=True)


if __name__ == "__main__":
    main()
