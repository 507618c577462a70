"""Thesis chapter 6: goal babbling of inverse kinematics (Alg. 6), transfer of experience
after guided exploration, the guard against negative transfer, reaching evaluation, experiment 1
and the analysis of its reaching curves.
"""
from lpa_transfer._lazy import lazy_names

#: The public names and their modules, imported on first use (PEP 562): a node that runs goal
#: babbling imports no reaching analysis.
_LAZY = {
    **dict.fromkeys(["Experiment1", "run_condition"], "lpa_transfer.goal_babbling.experiment"),
    **dict.fromkeys(["GoalBabbling"], "lpa_transfer.goal_babbling.goal_babbling"),
    **dict.fromkeys(["ACTIVE", "COVERED", "DISAGREED", "chain_lipschitz", "GuardedModel"],
                    "lpa_transfer.goal_babbling.negative_transfer"),
    **dict.fromkeys(["coverage", "evaluate_reaching", "evaluation_points", "grid",
                     "reachable_share", "reaching_errors", "reaching_rate"],
                    "lpa_transfer.goal_babbling.reaching"),
    **dict.fromkeys(["derived_seeds"], "lpa_transfer.goal_babbling.seeds"),
    **dict.fromkeys(["finite_experience", "initialise_with_transfer", "inverse_knn_model",
                     "padded_rows", "transfer_experience"], "lpa_transfer.goal_babbling.transfer"),
    **dict.fromkeys(["YieldingModel"], "lpa_transfer.goal_babbling.yielding"),
}
__all__ = list(_LAZY)
__getattr__, __dir__ = lazy_names(__name__, _LAZY, globals())
