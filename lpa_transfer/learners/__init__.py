"""Regression models the robots learn with: LWPR (online, chapter 5), locally weighted
regression (the §3.6 forward-kinematics example) and the k-NN sensorimotor models of chapter 6.
"""
from lpa_transfer._lazy import lazy_names

#: The public names and their modules, imported on first use (PEP 562): LWPR's users need not
#: import the k-NN regression.
_LAZY = {
    **dict.fromkeys(["LocallyWeightedRegression"], "lpa_transfer.learners.locally_weighted"),
    **dict.fromkeys(["LWPR"], "lpa_transfer.learners.lwpr"),
    **dict.fromkeys(["make_sensorimotor_model"], "lpa_transfer.learners.sensorimotor"),
}
__all__ = list(_LAZY)
__getattr__, __dir__ = lazy_names(__name__, _LAZY, globals())
