"""The correspondence collector's parameters as tables
(:func:`~lpa_transfer_nodes.params.declare_table`), in the order it declares them: the robots, babbling and pairing, guided exploration, then the
run (output, the fit, waits and services).

Descriptions are what ``~/describe_parameters`` answers; docs/nodes.md explains them at length.
"""
from dataclasses import fields

from lpa_transfer.exploration.babbling import PROGRAMS, TIME_LAWS
from lpa_transfer.exploration.correspondences import (BAD_PAIR_ACTIONS, DEFAULT_FEATURES,
                                                      FEATURES, PAIRING_RULES, PairCheck)
from lpa_transfer.exploration.guided import SOURCE_FOLLOWS, TARGET_RANGES
from lpa_transfer.transfer.fit_spec import FitSpec
from lpa_transfer_nodes.params import DOUBLES, INTEGERS, STRINGS

SIDES = ("source", "target")
GUIDED = "goal_babbling"          # the program of guided exploration (§6.4.2, Alg. 7)


def sided(rows):
    """``rows`` for the source, then for the target: ``{side}`` in their texts filled in."""
    return tuple(tuple(item.format(side=side) if isinstance(item, str) else item
                       for item in row) for side in SIDES for row in rows)


ROBOTS = sided((
    ("{side}_robot", "", "the {side} robot's parameter file (joint limits and kinematics, for "
     "the babbling program and inverse kinematics); its name labels the pairs; required"),))
KINEMATICS = sided((
    ("{side}_home", DOUBLES, "the {side} robot's pose babbling starts from (rad); unset: zero "
     "clipped into the joint limits", dict(additional_constraints="one value per joint")),
    ("{side}_task_low", DOUBLES, "task_lines: the low corner of the {side} robot's own waypoint "
     "box (m); unset: the program's box (task_low/task_high)"),
    ("{side}_task_high", DOUBLES, "task_lines: the high corner of the {side} robot's own "
     "waypoint box (m); unset: the program's box (task_low/task_high)"),
    ("{side}_task_halfwidth", DOUBLES, "task_lines: instead of {side}_task_low/high, the "
     "half-width (m) of the box around the {side} end effector at {side}_home",
     dict(additional_constraints="one value >= 0 per task coordinate"))))
PIDS = sided((
    ("{side}_pid", DOUBLES, "[kp, ki, kd] for a {side} robot_sim in torque mode: the robot "
     "tracks the babbling commands with this PID; unset: position mode",
     dict(additional_constraints="3 values")),))
_CHECK = PairCheck()
#: PairCheck's fields by parameter name.
PAIR_CHECK_FIELDS = dict(max_settle_steps="max_settle_steps", settle_check_steps="check_steps",
                         settle_velocity_tol="velocity_tol", settle_position_tol="position_tol",
                         pair_tolerance="tolerance", on_bad_pair="on_bad_pair",
                         max_bad_share="max_bad_share")
BABBLING = (
    ("pairing_rule", "same_command", "how samples of the two robots are paired",
     dict(choices=PAIRING_RULES)),
    ("program", "joint_lines", f"the babbling program; {GUIDED}: guided exploration (thesis "
     "§6.4.2, Alg. 7)", dict(choices=PROGRAMS + (GUIDED,))),
    ("seed", 0, f"seeds the babbling program ({GUIDED}: the GoalBabbling)", dict(range=(0, None))),
    ("n_segments", 20, "joint_lines/task_lines: lines per run", dict(range=(1, None))),
    ("samples_per_segment", 5, "joint_lines/task_lines: samples per line",
     dict(range=(1, None))),
    ("task_low", DOUBLES, "task_lines: the low corner of the waypoint box (m)"),
    ("task_high", DOUBLES, "task_lines: the high corner of the waypoint box (m)"),
    # the minimum a sample; settling by state and the pairing check (PairCheck) go on
    ("steps_per_sample", 400, "physics steps between samples, the minimum when the robots "
     f"settle; {GUIDED}: the physics steps of one movement step", dict(range=(1, None))),
    ("max_settle_steps", _CHECK.max_settle_steps, "at most this many physics steps a sample "
     "while the robots settle; 0: exactly steps_per_sample, no settling", dict(range=(0, None))),
    ("settle_check_steps", _CHECK.check_steps, "physics steps between two looks at a settling "
     "robot", dict(range=(1, None))),
    ("settle_velocity_tol", _CHECK.velocity_tol, "settled when no joint moves faster (rad/s or "
     "m/s) ...", dict(range=(0.0, None))),
    ("settle_position_tol", _CHECK.position_tol, "... and none moved more over the last look "
     "(rad or m)", dict(range=(0.0, None))),
    ("pair_tolerance", _CHECK.tolerance, "a pair is true when its residual is at most this: "
     "same_command the largest difference of the common joint angles (rad), same_task_point "
     "the target's end effector from the source's point plus task_offset (m); .inf: no check",
     dict(range=(0.0, None))),
    ("on_bad_pair", _CHECK.on_bad_pair, "drop: count a failing pair and go on; retry: settle "
     "both robots once more, check again, then drop", dict(choices=BAD_PAIR_ACTIONS)),
    ("max_bad_share", _CHECK.max_bad_share, "the run fails once more than this share of the "
     "planned pairs failed", dict(range=(0.0, 1.0))),
    ("task_offset", DOUBLES, "same_task_point: the target's task frame relative to the "
     "source's (m)"),
    ("features", STRINGS, f"the columns of a sample; unset: {list(DEFAULT_FEATURES)}",
     dict(additional_constraints="distinct names from " + ", ".join(FEATURES))))
TIME_LAW = (("time_law", "linear", "how the samples are spaced along each line",
             dict(choices=TIME_LAWS)),)
GUIDED_EXPLORATION = (
    ("guided_seconds", 60.0, "T_guided: the target's goal-babbling time (simulated s)",
     dict(range=(0.0, None), finite=True)),
    *((name, DOUBLES, f"X_bounds' {end} corner: the box of the target's goals in its task "
       "space (m); required", dict(additional_constraints="one value per task coordinate"))
      for name, end in (("x_low", "low"), ("x_high", "high")))) + sided((
        ("{side}_joints", INTEGERS, "the {side} robot's shared joints (source_joints[i] is "
         "target_joints[i]); unset: the first min(n_s, n_t) joints",
         dict(additional_constraints="distinct joint indices")),))
#: GoalBabbling's hyperparameters.
GOAL_BABBLING = (
    ("n_subtargets", 10, f"{GUIDED}: GoalBabbling's T, sub-targets per goal",
     dict(range=(1, None))),
    ("sigma", 0.1, f"{GUIDED}: GoalBabbling's exploration noise",
     dict(range=(0.0, None), finite=True)),
    ("drift", 0.01, f"{GUIDED}: drift of the exploration noise",
     dict(range=(0.0, None), finite=True)),
    ("p_home", 0.1, f"{GUIDED}: probability of returning home", dict(range=(0.0, 1.0))),
    ("steps_per_second", 10.0, f"{GUIDED}: movement steps a simulated second",
     dict(positive=True, finite=True)))
GUIDED_PAIRING = (
    ("target_range", "shared", "shared: the target explores within both robots' ranges of the "
     "shared joints; own: within its own, and only the commands the source could follow are "
     "pairs", dict(choices=TARGET_RANGES)),
    ("source_follows", "reached", "reached: the source takes the posture the target reached in "
     "each movement and settles there (max_settle_steps), so both rows of a pair are at the "
     "same shared joints; command: it is sent the target's command for steps_per_sample steps "
     "and lags it its own way", dict(choices=SOURCE_FOLLOWS)))
#: The fit the mapping service is asked for: FitSpec's fields.
FIT = tuple((field.name, INTEGERS if field.name == "cluster_dims" else field.default,
             field.metadata["description"], field.metadata["constraints"])
            for field in fields(FitSpec))
RUN = (
    ("output", "", "the .npz to save the correspondences to; empty: do not save"),
    ("model_id", "", "fit a model under this id in the mapping service when done (only after "
     "a complete run); empty: do not fit"),
    *FIT,
    # k-fold held-out error of the model (and of PA) on the pairs, before the fit; 0: off
    ("cross_validation_folds", 5, "with model_id: before the fit, log the k-fold held-out nMSE "
     "of the model and of PA; 0: off", dict(range=(0, None),
                                           additional_constraints="0 (off) or >= 2")),
    ("wait_for_subscribers", 0, "babble only once correspondences has this many subscribers "
     "(e.g. 2: a recorder and lpa_mapping)", dict(range=(0, None))),
    ("wait_for_subscribed_topics", STRINGS, "also wait until each of these topics has a "
     "subscriber (e.g. the robots' joint_states, so that a recorder records from the first "
     "step)"),
    ("wait_timeout", 30.0, "s to wait for each service and the subscribers, and at the end for "
     "the subscribers to acknowledge the published pairs",
     dict(range=(0.0, None), finite=True)),
    ("call_timeout", 120.0, "s a single service call may take (a fit on many points)",
     dict(range=(0.0, None)))) + sided((
        ("{side}_step", "/{side}/robot_sim/step", "the {side} robot's StepRobot service"),))
RESETS = sided((("{side}_reset", "/{side}/robot_sim/reset",
                 f"{GUIDED} only: the {{side}} robot's ResetRobot service"),))
MAPPING = (("mapping_service", "/lpa_mapping/fit", "the mapping service's FitModel service"),)
