"""A simulated or real robot behind the environment interface of goal babbling.

:mod:`lpa_transfer.goal_babbling.goal_babbling` (like explauto) separates the environment from the
sensorimotor model and the exploration strategy; the environment is a
:class:`lpa_transfer.robots.kinematics.Kinematics` whose ``forward(Q) -> X`` *executes* the commands.
With the robot's analytic forward kinematics that is a kinematic simulation;
:func:`stepped_environment` puts a robot behind it instead — a pybullet
:class:`lpa_transfer.robots.simulator.RobotSimulator` or a robot_sim node's StepRobot service,
anything with ``step(command, n_steps) -> SimState`` — so that every command is sent to the
robot in position mode, the physics runs ``n_steps`` steps, and the observed end-effector
position is what the model learns (Alg. 6 l. 11-12).
"""
import dataclasses

import numpy as np

from lpa_transfer import _validation as check


def task_dims(kinematics):
    """m, the number of task coordinates of ``kinematics`` (2 for a planar chain's (x, y),
    3 for a serial chain's world (x, y, z)): the first m of a SimState's end effector."""
    return np.asarray(kinematics.forward(np.asarray(kinematics.home)[None])).shape[1]


def stepped_environment(kinematics, step, n_steps, on_sample=None):
    """``kinematics`` (a Kinematics) with ``execute`` (and ``forward``) running each command
    on a robot.

    ``step(command, n_steps) -> SimState`` moves the robot (position mode) for ``n_steps``
    physics steps; observed are the state's joint positions, which may lag the command, and
    x, the first m coordinates of its end effector (:func:`task_dims`). ``on_sample(command, state)``, if given, sees every execution (e.g.
    to publish it). Joint limits, home and task box stay those of ``kinematics``.
    """
    check.check_int(n_steps, "n_steps", 1)
    n_task = task_dims(kinematics)

    def run(commands):
        commands = np.atleast_2d(np.asarray(commands, dtype=np.float64))
        positions = np.empty(commands.shape)
        reached = np.empty((len(commands), n_task))
        for i, command in enumerate(commands):
            state = step(command, n_steps)
            positions[i] = state.positions
            reached[i] = np.asarray(state.end_effector, dtype=np.float64)[:n_task]
            if on_sample is not None:
                on_sample(command, state)
        return positions, reached

    return dataclasses.replace(kinematics, forward=lambda commands: run(commands)[1],
                               execute=run)
