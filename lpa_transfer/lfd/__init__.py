"""Thesis chapter 4: learning from demonstration with transfer. A demonstrator's letters
(LASA), demonstrator-robot correspondences, joint-space DMPs and the chapter's experiments.
"""
from lpa_transfer._lazy import lazy_names

#: The public names and their modules, imported on first use (PEP 562): a node that loads the
#: LASA letters imports no DMP or skill sweep.
_LAZY = {
    **dict.fromkeys(["accuracy_report", "plot_accuracy", "read_csvs", "write_csvs"],
                    "lpa_transfer.lfd.accuracy"),
    **dict.fromkeys(["IK_TOLERANCE", "babbling_limits", "collect_demonstrator_correspondences",
                     "task_point_residuals"], "lpa_transfer.lfd.correspondences"),
    **dict.fromkeys(["LASA_DEMOS_PER_SHAPE", "lasa_shape_names"],
                    "lpa_transfer.lfd.demonstrations"),
    **dict.fromkeys(["JointDMP"], "lpa_transfer.lfd.dmp"),
    **dict.fromkeys(["MAX_BATCHES", "collect_pairs", "Demonstration", "load_setup",
                     "RememberedPairs"], "lpa_transfer.lfd.experiment"),
    **dict.fromkeys(["graph_report", "plot_letters"], "lpa_transfer.lfd.report"),
    **dict.fromkeys(["accuracy_sweep", "between", "by_shape", "ik_method_errors",
                     "mean_mapping_error", "multi_robot_transfer", "robot_ik_demonstrations"],
                    "lpa_transfer.lfd.skills"),
}
__all__ = list(_LAZY)
__getattr__, __dir__ = lazy_names(__name__, _LAZY, globals())
