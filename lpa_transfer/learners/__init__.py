"""Regression models the robots learn with: LWPR (online, chapter 5), locally weighted
regression (the §3.6 forward-kinematics example) and the k-NN sensorimotor models of chapter 6.
"""
import importlib

#: Imported on first use (PEP 562): LWPR's users need not import the k-NN regression.
_LAZY = {"LWPR": "lpa_transfer.learners.lwpr",
         "LocallyWeightedRegression": "lpa_transfer.learners.locally_weighted"}
__all__ = list(_LAZY)


def __getattr__(name):
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'lpa_transfer.learners' has no attribute {name!r}")


def __dir__():
    return sorted(list(globals()) + __all__)
