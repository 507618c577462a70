"""Regression models the robots learn with: LWPR (online, chapter 5), locally weighted
regression (the §3.6 forward-kinematics example) and the k-NN sensorimotor models of chapter 6.
"""
from lpa_transfer._lazy import lazy_names

#: Imported on first use: LWPR's users need not import the k-NN regression.
_LAZY = {"LWPR": "lpa_transfer.learners.lwpr",
         "LocallyWeightedRegression": "lpa_transfer.learners.locally_weighted"}
__all__ = list(_LAZY)
__getattr__, __dir__ = lazy_names(__name__, _LAZY, globals())
