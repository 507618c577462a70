"""The inverse-dynamics learner's parameters as tables
(:func:`~lpa_transfer_nodes.params.declare_table`), in the order it declares them: the robot,
the control timing, the feedback PID, the star task, the regressor, then the robot's services.

Descriptions are what ``~/describe_parameters`` answers; docs/nodes.md explains them at length.
"""
import numpy as np

from lpa_transfer.inverse_dynamics.online_learning import regressors
from lpa_transfer.inverse_dynamics.tasks import TIME_LAWS
from lpa_transfer_nodes.params import DOUBLES

ROBOT = (("robot", "", "the robot parameter file (scenarios/robots/*.toml; required)"),)
TIMING = (
    ("control_rate", 100.0, "control periods a second (Hz), up to 1 / physics_step",
     dict(positive=True, finite=True)),
    ("physics_step", 0.001, "the simulator's physics step (s): each period advances "
     "round(1 / (control_rate * physics_step)) steps", dict(positive=True, finite=True)))
FEEDBACK = (("pid", DOUBLES, "[kp, ki, kd] of the feedback PID (required; thesis: Pincher "
             "[5, 0.01, 0.1], youBot [100, 0.01, 2.0])"),)
TASK = (
    ("centre_pose", DOUBLES, "joint angles (rad) whose end-effector position is the star's "
     "centre; every trial starts there; unset: zero clipped into the joint limits"),
    ("star_radius", 0.05, "the star's radius (m)", dict(positive=True, finite=True)),
    ("star_u", DOUBLES, "first axis of the star's plane (world); unset: x"),
    ("star_v", DOUBLES, "second axis of the star's plane (world); unset: y"),
    ("star_spread", 2 * np.pi, "the angle the star's lines spread over (rad)",
     dict(positive=True, finite=True)),
    ("star_start_angle", 0.0, "the angle of the first line (rad)", dict(finite=True)),
    ("star_time_law", "minimum_jerk", "each 0.6 s leg's time law: minimum_jerk (from rest to "
     "rest) or linear (constant speed)", dict(choices=list(TIME_LAWS))))
REGRESSOR = (
    ("regressor", "lwpr", "the online learner of the feed-forward torque",
     dict(choices=sorted(regressors()))),
    ("regressor_params", "{}", "JSON object of the regressor's hyperparameters, e.g. "
     "{\"init_D\": 30}; LWPR's norm_in defaults to the spread of the task's desired states"))
YIELDING = (
    ("own_w_gen", 0.3, "after a yielding initialisation (InitialiseLearner yielding): the "
     "robot's own samples make a receptive field of their own unless one answers them above "
     "this (LWPR's w_gen for them)", dict(range=(0.0, 1.0), finite=True)),)
SERVICES = (
    ("call_timeout", 30.0, "seconds for each robot call (step or reset)", dict(positive=True)),
    ("wait_timeout", 30.0, "seconds to wait for the robot's services", dict(positive=True)),
    ("step_service", "robot_sim/step", "the robot's StepRobot service (relative: in the "
     "node's namespace)"),
    ("reset_service", "robot_sim/reset", "the robot's ResetRobot service"))
