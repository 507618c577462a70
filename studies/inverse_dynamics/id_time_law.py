"""Chapter 5 set-up factors 1, 3 and 6: learning from scratch with the star legs'
time law minimum-jerk (today's default) against constant speed ("linear"), in process, with
today's LWPR settings or others (``--lwpr``: JSON of LWPR hyperparameters replacing the
config's, e.g. the thesis' init_D 30 without normalisation and the reference library's
empty prediction: '{"init_D": 30, "norm_in": 1, "empty_prediction": "zero"}').

    nice -n 10 python -m studies.inverse_dynamics.id_time_law [--trials 15]
        [--targets youbot pincher]
        [--time-laws minimum_jerk linear] [--lwpr JSON] [--actuator velocity_motor]

For each robot and star of scenarios/inverse_dynamics/config.yaml, a learner from scratch
(uninitialised, today's LWPR settings) tracks the star for ``--trials`` trials from rest at
its centre (inverse_dynamics.star_robot.StarRobot: the same simulator, PID and LWPR as the
graph). Printed: first and last trial's tracking error (mm), the trial from which the curve
stays within 10 % of its own last trial (the scenario's convergence rule, with the learner's
own final error as the reference), the share of control periods in which some joint's torque
is at its effort limit (first and last trial), and the largest |τ| the first trial applied
per joint.
"""
import argparse
import json

import numpy as np
import yaml

from lpa_transfer.inverse_dynamics import CONFIG, StarRobot, trials_to_convergence
from lpa_transfer.inverse_dynamics.tasks import TIME_LAWS


def scratch(config, name, star, time_law, n_trials, lwpr=None, actuator="torque"):
    robot = StarRobot(config, name, star, actuator).configure(config, name, star, time_law,
                                                              lwpr)
    learner = robot.learner()
    errors, experience = robot.trials(learner, n_trials)
    n = robot.params.n_joints
    torque = np.abs(experience[:, 3 * n:]).reshape(n_trials, -1, n)
    saturated = (torque >= robot.sim.effort_limits * (1 - 1e-9)).any(axis=2).mean(axis=1)
    robot.sim.close()
    return np.array(errors), torque[0].max(axis=0), saturated


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=15)
    parser.add_argument("--targets", nargs="+", default=["youbot", "pincher"])
    parser.add_argument("--stars", nargs="+", default=["star1", "star2"])
    parser.add_argument("--time-laws", nargs="+", default=list(TIME_LAWS))
    parser.add_argument("--lwpr", type=json.loads, default=None)
    parser.add_argument("--actuator", default="torque",
                        help="torque (default) or velocity_motor (V-REP's torque mode)")
    args = parser.parse_args(argv)
    config = yaml.safe_load(CONFIG.read_text())
    print(f"{'robot/star':<16} {'time law':<13} {'trial 1':>8} {'last':>7} {'converged':>9} "
          f"{'sat 1':>6} {'sat last':>8}  max |tau| in trial 1 (N m, per joint)")
    for name in args.targets:
        for star in args.stars:
            for time_law in args.time_laws:
                errors, torque, saturated = scratch(config, name, star, time_law,
                                                    args.trials, args.lwpr, args.actuator)
                converged = trials_to_convergence(errors, errors[-1], 0.1)
                print(f"{name + '/' + star:<16} {time_law:<13} {1e3 * errors[0]:8.2f} "
                      f"{1e3 * errors[-1]:7.2f} {converged:9d} {100 * saturated[0]:5.1f}% "
                      f"{100 * saturated[-1]:7.1f}%  "
                      + " ".join(f"{t:6.2f}" for t in torque), flush=True)


if __name__ == "__main__":
    main()
