"""lpa_transfer: transfer learning between differently built robots with (Local) Procrustes
Analysis — the pure library (the ROS 2 nodes are ``lpa_transfer_nodes``).

Thesis: Makondo, "Accelerating robot learning of motor skills with knowledge transfer".
Models follow scikit-learn conventions: constructor arguments are hyperparameters,
``fit(source, target)`` learns from correspondences, learned attributes end in ``_``, and
``transfer(source)`` maps new source points into the target domain.

Subpackages by role: ``transfer`` (PA, LPA, model files), ``robots``, ``learners``,
``exploration``, ``evaluation``, ``recording``, and one per thesis chapter: ``lfd`` (ch. 4),
``inverse_dynamics`` (ch. 5), ``goal_babbling`` (ch. 6).
"""
from lpa_transfer._lazy import lazy_names

#: The top-level names and their modules, imported on first use, so that a node that needs
#: only ``lpa_transfer.robots`` does not import the learners and scikit-learn.
_LAZY = {"ProcrustesAnalysis": "lpa_transfer.transfer",
         "LocalProcrustesAnalysis": "lpa_transfer.transfer",
         "load_model": "lpa_transfer.transfer", "LWPR": "lpa_transfer.learners.lwpr"}
__all__ = list(_LAZY)
__getattr__, __dir__ = lazy_names(__name__, _LAZY, globals())
