"""lpa_transfer: transfer learning between differently built robots with (Local) Procrustes
Analysis — the pure library (no rclpy).

Thesis: Makondo, "Accelerating robot learning of motor skills with knowledge transfer"
(../shared/seeds). Models follow scikit-learn conventions: constructor arguments are
hyperparameters, ``fit(source, target)`` learns from correspondences, learned attributes end
in ``_``, and ``transfer(source)`` maps new source points into the target domain.
"""
from .local_procrustes import LocalProcrustesAnalysis
from .model_io import load_model
from .procrustes import ProcrustesAnalysis

__all__ = ["ProcrustesAnalysis", "LocalProcrustesAnalysis", "load_model"]
