"""Thesis chapter 5: online inverse-dynamics learning of star tracking tasks, with and
without transferred experience: the tasks, the feed-forward learner and the analysis of its
learning curves (trials to convergence, training time saved).
"""
from lpa_transfer._lazy import lazy_names

#: The public names and their modules, imported on first use (PEP 562): a node that learns
#: online imports no analysis of the learning curves.
_LAZY = {
    **dict.fromkeys(["convergence_table", "per_seed_savings", "trials_to_convergence"],
                    "lpa_transfer.inverse_dynamics.analysis"),
    **dict.fromkeys(["BABBLING_SECONDS", "SETUPS", "load", "set_up"],
                    "lpa_transfer.inverse_dynamics.in_process"),
    **dict.fromkeys(["INTERPOLATIONS", "interpolated"],
                    "lpa_transfer.inverse_dynamics.interpolation"),
    **dict.fromkeys(["FeedForwardLearner", "input_scale", "make_regressor", "regressors"],
                    "lpa_transfer.inverse_dynamics.online_learning"),
    **dict.fromkeys(["final_error_lines", "paired_lines", "read_run", "summary_lines"],
                    "lpa_transfer.inverse_dynamics.report"),
    **dict.fromkeys(["CONFIG", "babble", "StarRobot"], "lpa_transfer.inverse_dynamics.star_robot"),
    **dict.fromkeys(["star_task"], "lpa_transfer.inverse_dynamics.tasks"),
}
__all__ = list(_LAZY)
__getattr__, __dir__ = lazy_names(__name__, _LAZY, globals())
