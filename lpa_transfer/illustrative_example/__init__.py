"""Thesis chapter 3, §3.6: the illustrative example. Two planar 2-link arms (Table 3.1), PA
and LPA mappings learned from N correspondences, scored by the mapping error and by the error
of the target's forward-kinematics model trained on transferred experience (Fig. 3-6), over
training sizes (experiment 1) and target link lengths (experiment 2, Fig. 3-8).
"""
from lpa_transfer._lazy import lazy_names

#: The public names and their modules, imported on first use (PEP 562), like every
#: subpackage's, so that importing the package stays cheap.
_LAZY = {
    **dict.fromkeys(["LEARNER_KINDS", "LINK_FIELDS", "SCRATCH_FIELDS", "SIZE_FIELDS",
                     "build_tasks", "make_learner", "run_all"],
                    "lpa_transfer.illustrative_example.experiment"),
    **dict.fromkeys(["plot_link_sweep", "plot_scratch_sweep", "plot_size_sweep", "summary_text",
                     "write_csv"], "lpa_transfer.illustrative_example.report"),
}
__all__ = list(_LAZY)
__getattr__, __dir__ = lazy_names(__name__, _LAZY, globals())
