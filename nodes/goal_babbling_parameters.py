"""The goal-babbling learner's parameters as tables
(:func:`~lpa_transfer_nodes.params.declare_table`), in the order it declares them: the robot
and its task box, learning (GoalBabbling, the model, the guard), then evaluation and the
robot's services; and the check of the guard's JSON hyperparameters.

Descriptions are what ``~/describe_parameters`` answers; docs/nodes.md explains them at length.
"""
import json

from lpa_transfer_nodes.params import DOUBLES, INTEGERS

GUARD_KEYS = ("transferred_weight", "coverage_radius", "coverage_count",
              "disagreement_threshold", "lipschitz", "n_checked")
ROBOT = (
    ("robot", "", "the robot parameter file (joint limits and analytic kinematics); required"),
    ("home", DOUBLES, "q_home (rad), where babbling starts and returns to; unset: zero clipped "
     "into the joint limits", dict(additional_constraints="one value per joint")),
    ("active_joints", INTEGERS, "babble with these joints only, the others held at home; "
     "unset: all", dict(additional_constraints="distinct joint indices")),
    *((f"x_{end}", DOUBLES, f"X_bounds' {end} corner: the task box goals are drawn from (m); "
       "required", dict(additional_constraints="one value per task coordinate"))
      for end in ("low", "high")))
#: GoalBabbling's hyperparameters.
GOAL_BABBLING = (
    ("n_subtargets", 10, "GoalBabbling's T, sub-targets per goal", dict(range=(1, None))),
    ("sigma", 0.1, "GoalBabbling's exploration noise", dict(range=(0.0, None), finite=True)),
    ("drift", 0.01, "drift of the exploration noise", dict(range=(0.0, None), finite=True)),
    ("p_home", 0.1, "probability of returning home", dict(range=(0.0, 1.0))),
    ("steps_per_second", 10.0, "babbling steps a simulated second (the learner's clock)",
     dict(positive=True, finite=True)),
    ("seed", 0, "GoalBabbling's seed (unless an initialise with reset gives one)",
     dict(range=(0, None))))
LEARNING = GOAL_BABBLING + (
    ("steps_per_sample", 100, "physics steps per babbling step", dict(range=(1, None))),
    ("physics_step", 0.001, "the simulator's physics step (s)",
     dict(positive=True, finite=True)),
    ("n_neighbors", 3, "K of the K-nearest-neighbour inverse model", dict(range=(1, None))),
    ("guard", False, "take transferred samples into a GuardedModel (lower weight, retired once "
     "covered or contradicted by own data) instead of learning them like own data"),
    ("guard_params", "{}", "JSON object of GuardedModel's hyperparameters; lipschitz defaults "
     "to the robot's chain_lipschitz; ignored when guard is false",
     dict(additional_constraints="keys from " + ", ".join(GUARD_KEYS))),
    ("yielding", False, "take transferred samples into a YieldingModel: the own samples alone "
     "answer within reaching_threshold of a query and steer exploration (not with guard)"))
EVALUATION = (
    *((f"eval_{end}", DOUBLES, f"the {end} corner of the test points' box (m); unset: "
       f"X_bounds' {end} corner") for end in ("low", "high")),
    ("eval_spacing", 0.05, "the test points' grid spacing (m)",
     dict(positive=True, finite=True)),
    ("eval_joint_samples", 20000, "the joint samples that find the reachable grid points "
     "(once, at start-up)", dict(range=(1, None))),
    ("reaching_threshold", 0.01, "a test point counts as reached within this distance (m)",
     dict(range=(0.0, None), finite=True)),
    ("call_timeout", 30.0, "s for each robot call", dict(range=(0.0, None), finite=True)),
    ("wait_timeout", 30.0, "s to wait for the robot's services",
     dict(range=(0.0, None), finite=True)),
    ("step_service", "robot_sim/step", "the robot's StepRobot service, resolved in the node's "
     "namespace"),
    ("reset_service", "robot_sim/reset", "the robot's ResetRobot service, resolved in the "
     "node's namespace"))


def guard_params(text):
    """The guard_params parameter: GuardedModel's hyperparameters as a dict of GUARD_KEYS."""
    try:
        params = json.loads(text)
    except json.JSONDecodeError as exc:
        raise ValueError(f"guard_params must be a JSON object: {exc}") from None
    if not isinstance(params, dict):
        raise ValueError(f"guard_params must be a JSON object, got {text!r}")
    unknown = sorted(set(params) - set(GUARD_KEYS))
    if unknown:
        raise ValueError(f"guard_params: unknown {unknown}; known: {list(GUARD_KEYS)}")
    return params
