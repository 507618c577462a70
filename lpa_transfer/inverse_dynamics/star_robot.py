"""One robot of chapter 5's scenario on one star, in process: its simulator, star task, PID and
learner settings as scenarios/inverse_dynamics/config.yaml gives them (:class:`StarRobot`), and
a seed's babbling near a star paired as the graph's collector pairs it (:func:`babble`).

The in-process experiment (:mod:`lpa_transfer.inverse_dynamics.in_process`) and the chapter 5
studies build on these; with the same simulator, PID and LWPR as the graph's nodes they give
the graph's curves.
"""
import dataclasses
import json
from pathlib import Path

import numpy as np

from lpa_transfer.exploration.babbling import BabblingProgram, box_around
from lpa_transfer.robots.kinematics import robot_kinematics
from lpa_transfer.robots.control import PID, start_servo
from lpa_transfer.exploration.correspondences import collect_correspondences
from lpa_transfer.inverse_dynamics.online_learning import (FeedForwardLearner, input_scale,
                                                           make_regressor)
from lpa_transfer.robots.params import load_robot_params
from lpa_transfer.robots.simulator import RobotSimulator, robot_urdf
from lpa_transfer.inverse_dynamics.tasks import star_task

#: The scenario's configuration, relative to the repository root.
CONFIG = Path("scenarios/inverse_dynamics/config.yaml")


class StarRobot:
    """One robot of the scenario on one star: its simulator, task and learner settings.
    ``actuator``: the simulator's (``"torque"`` or ``"velocity_motor"``, V-REP's torque mode;
    lpa_transfer.robots.simulator), the set-ups' actuator switch."""

    def __init__(self, config, name, star, actuator="torque"):
        node = config[f"/{name}/{star}"]["ros__parameters"]
        self.params = load_robot_params(node["robot"])
        self.kinematics = robot_kinematics(self.params, node["centre_pose"])
        self.dt = 1.0 / node["control_rate"]
        physics_step = config[f"/{name}/robot_sim"]["ros__parameters"]["physics_step"]
        self.n_steps = max(1, round(self.dt / physics_step))
        self.trajectory = star_task(self.kinematics, node["star_radius"], self.dt,
                                    start_angle=node["star_start_angle"])
        self.pid_gains = node["pid"]
        self.regressor = (node["regressor"], dict(json.loads(node["regressor_params"]),
                                                  norm_in=input_scale(*self.trajectory[:3])))
        self.sim = RobotSimulator(robot_urdf(self.params), "torque", physics_step,
                                  initial_positions=self.kinematics.home, actuator=actuator)

    def configure(self, config, name, star, time_law=None, lwpr=None):
        """The set-ups' switches: the star legs' time law and LWPR hyperparameters replacing
        the config's (``lwpr``, a dict)."""
        node = config[f"/{name}/{star}"]["ros__parameters"]
        if time_law is not None:
            self.trajectory = star_task(self.kinematics, node["star_radius"], self.dt,
                                        start_angle=node["star_start_angle"], time_law=time_law)
        if lwpr:
            self.regressor = (self.regressor[0], {**self.regressor[1], **lwpr})
        return self

    def learner(self, samples=None, **yielding):
        """A fresh learner initialised with ``samples`` (as its own data, or so that they
        yield to its own experience: FeedForwardLearner's ``yielding`` and its settings)."""
        learner = FeedForwardLearner(make_regressor(self.regressor[0], **self.regressor[1]),
                                     PID.from_gains(self.pid_gains), **yielding)
        if samples is not None:
            learner.initialise(samples)
        return learner

    def trials(self, learner, n_trials, start=None, after_trial=None):
        """Tracking errors (m) and the experience of ``n_trials`` trials from rest at the centre
        (or at the joint positions ``start``); ``after_trial(learner, errors)``, if given, is
        called after each trial (to look at the learner as it learns)."""
        self.sim.reset(self.kinematics.home if start is None else start)
        state, errors, experience = self.sim.state(), [], []
        for _ in range(n_trials):
            trial = learner.run_trial(self.sim.step, state, *self.trajectory, self.n_steps,
                                      self.dt)
            state = trial.end_state
            errors.append(trial.tracking_error)
            experience.append(trial.samples)
            if after_trial is not None:
                after_trial(learner, errors)
        return errors, np.vstack(experience)


def babble(config, robots, star, seed, reset=True):
    """The seed's correspondences near ``star``: (source rows, target rows) as the graph's
    collector /babbling/<star> makes them (source = the config's source robot). ``reset``:
    the robots start at rest at the star's centre (else where their simulators are)."""
    common = config["/babbling/*"]["ros__parameters"]
    own = config[f"/babbling/{star}"]["ros__parameters"]
    k = config["experiment"]["ros__parameters"]["stars"].index(star)
    program = BabblingProgram(common["program"], common["n_segments"],
                              common["samples_per_segment"], 10 * seed + k,
                              time_law=common.get("time_law", "linear"))
    kinematics, steps = [], []
    for side, robot in zip(("source", "target"), robots):
        kinematics.append(dataclasses.replace(robot.kinematics, task_box=box_around(
            robot.kinematics, own[f"{side}_task_halfwidth"])))
        if reset:
            robot.sim.reset(robot.kinematics.home)
        steps.append(start_servo(robot.sim.step, robot.params.n_joints,
                                 PID.from_gains(common[f"{side}_pid"])).step)
    pairs = collect_correspondences(program, common["pairing_rule"], *kinematics, *steps,
                                    common["steps_per_sample"], tuple(common["features"]))
    return pairs.source, pairs.target
