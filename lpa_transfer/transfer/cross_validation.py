"""Held-out error of a domain mapping on its own correspondences (k-fold cross-validation).

A mapping fitted on pairs that are not true correspondences, or too few for its clusters,
can look fine on its training data; the error on pairs it did not see shows it at collection
time. The score is the normalised mean squared error of the transferred target points,
averaged over the target's columns (each column's MSE divided by its variance), so that
columns in different units (rad, m) weigh alike: 0 is a perfect mapping, 1 is as good as
predicting each column's mean.
"""
import numpy as np

from lpa_transfer._estimator import clone
from lpa_transfer._validation import check_int


def held_out_nmse(estimator, source, target, n_folds=5, random_state=0):
    """Mean nMSE of ``clone(estimator)`` fitted on k-1 folds, scored on the k-th.

    Folds are a seeded permutation of the pairs; columns of ``target`` with zero variance are
    left out of the average. ValueError when there are fewer pairs than folds.
    """
    source, target = np.asarray(source, dtype=np.float64), np.asarray(target, dtype=np.float64)
    check_int(n_folds, "n_folds", 2)
    if len(source) != len(target) or len(source) < n_folds:
        raise ValueError(f"cross-validation needs as many source as target rows and at least "
                         f"{n_folds} of them, got {len(source)} and {len(target)}")
    variance = target.var(axis=0)
    columns = variance > 0
    if not columns.any():
        raise ValueError("every target column is constant: nothing to score")
    order = np.random.default_rng(random_state).permutation(len(source))
    errors = []
    for fold in np.array_split(order, n_folds):
        train = np.setdiff1d(order, fold)
        model = clone(estimator).fit(source[train], target[train])
        residual = model.transfer(source[fold]) - target[fold]
        errors.append(np.mean(residual[:, columns] ** 2, axis=0) / variance[columns])
    return float(np.mean(errors))
