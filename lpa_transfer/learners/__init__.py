"""Regression models the robots learn with: LWPR (online, chapter 5), locally weighted
regression (the §3.6 forward-kinematics example) and the k-NN sensorimotor models of chapter 6.
"""
from lpa_transfer.learners.locally_weighted import LocallyWeightedRegression
from lpa_transfer.learners.lwpr import LWPR

__all__ = ["LWPR", "LocallyWeightedRegression"]
