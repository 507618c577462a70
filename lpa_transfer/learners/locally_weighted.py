"""A memory-based locally weighted affine regression.

The thesis learns its models with LWPR (Locally Weighted Projection Regression [146]; §3.6,
§5), and so do chapter 3's example and chapter 5's online learner
(:class:`lpa_transfer.learners.lwpr.LWPR`). :class:`LocallyWeightedRegression` is a different
learner (no incremental receptive fields, no projection regression), kept as an option of the
§3.6 example (scenarios/two_link_fk, learner ``locally_weighted``) and of the 2-link graph's
evaluation: on noise-free 2-link kinematics it is markedly more accurate than the LWPR ground
truth the thesis reports (RMSE 0.0061 m).
"""
import numbers

import numpy as np
from sklearn.base import BaseEstimator, RegressorMixin
from sklearn.neighbors import NearestNeighbors
from sklearn.utils.validation import check_is_fitted

#: Queries per block in ``predict``, bounding the (block, k, d + 1) work arrays.
_QUERY_BLOCK = 1 << 15


def _finite_array(values, name, ndims):
    try:
        values = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be numeric: {exc}") from None
    if values.ndim not in ndims or values.size == 0:
        raise ValueError(f"{name} must be a non-empty array with ndim in {ndims}, got shape "
                         f"{values.shape}")
    if not np.isfinite(values).all():
        raise ValueError(f"{name} contains NaN or infinite values")
    return values


class LocallyWeightedRegression(RegressorMixin, BaseEstimator):
    """Locally weighted affine regression on the k nearest training inputs.

    For a query x the ``n_neighbors`` nearest training inputs x_j get Gaussian weights
    w_j = exp(-||x_j - x||² / (2 h²)) and an affine model y ≈ b + W (x_j - x) is fitted by
    weighted least squares; the prediction is b. The normal equations of all queries,
    (M, d + 1, d + 1), are built and solved in one batched ``np.linalg.solve``.

    Parameters
    ----------
    n_neighbors : int
        k, the training points each local model uses (clipped to the training-set size).
        At least d + 1 are needed for a well-posed affine fit; more smooth out noise.
    bandwidth : float or None
        Fixed Gaussian width h in input units. ``None`` (default) adapts it per query:
        h = (distance to the k-th neighbour) / 2, so the farthest neighbour keeps weight
        e^-2 ≈ 0.14 and dense and sparse regions are treated alike (a k-NN bandwidth, as in
        LOESS). Weights are computed relative to the nearest neighbour, so they never all
        underflow for queries far from the data.
    ridge : float
        Added to the slope entries of each normal-equation matrix (not the intercept), so a
        degenerate neighbourhood falls back to the weighted mean of its outputs.

    Learned attributes: ``n_neighbors_``, ``n_features_in_``, ``n_outputs_``, ``X_fit_``,
    ``Y_fit_``, ``neighbors_`` (the fitted :class:`sklearn.neighbors.NearestNeighbors`).
    """

    def __init__(self, n_neighbors=10, bandwidth=None, ridge=1e-8):
        self.n_neighbors = n_neighbors
        self.bandwidth = bandwidth
        self.ridge = ridge

    def _check_hyperparameters(self):
        if (isinstance(self.n_neighbors, bool) or not isinstance(self.n_neighbors, numbers.Integral)
                or self.n_neighbors < 1):
            raise ValueError(f"n_neighbors must be an integer >= 1, got {self.n_neighbors!r}")
        if self.bandwidth is not None and not (isinstance(self.bandwidth, numbers.Real)
                                               and np.isfinite(self.bandwidth)
                                               and self.bandwidth > 0):
            raise ValueError(f"bandwidth must be None or a positive number, got "
                             f"{self.bandwidth!r}")
        if not (isinstance(self.ridge, numbers.Real) and np.isfinite(self.ridge)
                and self.ridge >= 0):
            raise ValueError(f"ridge must be a non-negative number, got {self.ridge!r}")

    def fit(self, X, Y):
        """Store the training set X (N, d) -> Y (N, m) or (N,) and index its inputs."""
        self._check_hyperparameters()
        X = _finite_array(X, "X", (2,))
        Y = _finite_array(Y, "Y", (1, 2))
        if len(Y) != len(X):
            raise ValueError(f"X and Y must have the same number of rows, got {len(X)} and "
                             f"{len(Y)}")
        self.n_neighbors_ = min(int(self.n_neighbors), len(X))
        self.n_features_in_ = X.shape[1]
        self.n_outputs_ = 1 if Y.ndim == 1 else Y.shape[1]
        self.X_fit_, self.Y_fit_ = X, Y.reshape(len(Y), self.n_outputs_)
        self.neighbors_ = NearestNeighbors(n_neighbors=self.n_neighbors_).fit(X)
        self._y_was_1d = Y.ndim == 1
        return self

    def predict(self, X):
        """Predict outputs (M, m) (or (M,) if fitted on a 1-D Y) for queries X (M, d)."""
        check_is_fitted(self, "neighbors_")
        X = _finite_array(X, "X", (2,))
        if X.shape[1] != self.n_features_in_:
            raise ValueError(f"X has {X.shape[1]} columns but the model was fitted on "
                             f"{self.n_features_in_}")
        out = np.vstack([self._predict_block(X[start:start + _QUERY_BLOCK])
                         for start in range(0, len(X), _QUERY_BLOCK)])
        return out[:, 0] if self._y_was_1d else out

    def _predict_block(self, queries):
        distances, index = self.neighbors_.kneighbors(queries)
        if self.bandwidth is None:
            width = np.maximum(distances[:, -1:] / 2.0, np.finfo(float).tiny)
        else:
            width = float(self.bandwidth)
        weights = np.exp(-0.5 * (distances ** 2 - distances[:, :1] ** 2) / width ** 2)
        local = self.X_fit_[index] - queries[:, None, :]                # (M, k, d)
        design = np.concatenate((np.ones(local.shape[:2] + (1,)), local), axis=2)
        weighted = design * weights[:, :, None]
        normal = np.einsum("mki,mkj->mij", weighted, design)              # (M, d+1, d+1)
        normal[:, 1:, 1:] += self.ridge * np.eye(self.n_features_in_)
        rhs = np.einsum("mki,mko->mio", weighted, self.Y_fit_[index])     # (M, d+1, m)
        return np.linalg.solve(normal, rhs)[:, 0, :]
