"""Sensorimotor models of a learning robot (thesis ch. 6, §6.3 and §6.3.2).

The forward model L(q) = x predicts where a joint command q puts the end effector; the inverse
model L⁻¹(x) = q predicts the command that reaches a task point x (§6.3). The thesis learns
both with k-nearest-neighbour regression, K = 3 (§6.5); the RobMech 2019 paper calls it a
weighted nearest-neighbour inverse model. :class:`KNNRegressor` is that regressor, learning
online: goal babbling (Alg. 6, :mod:`lpa_transfer.goal_babbling.goal_babbling`) adds one sample and asks one
query at every step, over up to ~10⁵ samples, so the inputs are indexed in a KD-tree
(:class:`scipy.spatial.cKDTree`) that is rebuilt lazily, and the recent samples not yet in the
tree are searched by brute force.

Every sample carries a weight (default 1), so that data transferred from another robot
(§6.4) can count less than the robot's own experience.
"""
import numbers

import numpy as np
from scipy.spatial import cKDTree

from lpa_transfer import _validation as check
from lpa_transfer._estimator import Estimator

#: Never rebuild the tree for fewer unindexed samples than this (brute force is cheap).
_MIN_TAIL = 256
#: Rebuild the tree before a query batch whose brute-force part would exceed this many
#: distances (e.g. an evaluation on thousands of test points).
_BRUTE_BUDGET = 1 << 18
WEIGHTINGS = ("distance", "uniform")
_TINY = np.finfo(np.float64).tiny


def _check_weights(sample_weight, n_rows):
    """``sample_weight`` as an (n_rows,) float array of finite positive values (None: ones)."""
    if sample_weight is None:
        return np.ones(n_rows)
    weights = np.asarray(sample_weight, dtype=np.float64)
    if weights.shape != (n_rows,):
        raise ValueError(f"sample_weight must have shape ({n_rows},) (one weight per sample), "
                         f"got shape {weights.shape}")
    if not (np.isfinite(weights).all() and (weights > 0).all()):
        raise ValueError("sample_weight must hold finite values > 0")
    return weights


class KNNRegressor(Estimator):
    """Weighted k-nearest-neighbour regression, learning incrementally (§6.3.2, §6.5).

    The prediction for a query x is the weighted mean of the outputs of its K nearest
    training inputs x_j (Euclidean distance d_j = ‖x_j − x‖)::

        ŷ(x) = Σ_j w_j y_j / Σ_j w_j,   w_j = s_j · κ(d_j)

    where s_j is the sample's weight (``sample_weight``, default 1) and κ(d) = 1/d for
    ``weights="distance"`` or κ(d) = 1 for ``weights="uniform"``. With ``"distance"``, if any
    of the K neighbours coincides with the query (d_j = 0) only those coinciding samples count
    (w_j = s_j, the others 0), so a training input is mapped to its own output (the weighted
    mean of its duplicates). Among samples tied in distance, which ones are among the K is
    unspecified (but the same for the same samples and queries).

    Parameters
    ----------
    n_neighbors : int
        K, the neighbours averaged (3 in the thesis, §6.5); fewer while fewer samples exist.
    weights : {"distance", "uniform"}
        κ above.
    rebuild_fraction : float
        The KD-tree indexes the first samples; the later ones are searched by brute force
        until they outnumber ``rebuild_fraction`` × the indexed ones (and at least
        ``_MIN_TAIL``), when the next query rebuilds the tree over all. Amortised, a sample
        costs O(log N / rebuild_fraction) to index and a query O(log N + tail).

    Learned attributes: ``n_features_in_``, ``n_outputs_``, ``n_samples_``, and the samples
    ``X_``, ``Y_``, ``sample_weight_`` (read-only views of the first ``n_samples_`` rows).
    Before any data, ``predict`` raises :class:`sklearn.exceptions.NotFittedError`.
    """

    def __init__(self, n_neighbors=3, weights="distance", rebuild_fraction=0.05):
        self.n_neighbors = n_neighbors
        self.weights = weights
        self.rebuild_fraction = rebuild_fraction

    def _check_hyperparameters(self):
        check.check_int(self.n_neighbors, "n_neighbors", 1)
        if self.weights not in WEIGHTINGS:
            raise ValueError(f"weights must be one of {WEIGHTINGS}, got {self.weights!r}")
        if (isinstance(self.rebuild_fraction, bool)
                or not isinstance(self.rebuild_fraction, numbers.Real)
                or not 0 < self.rebuild_fraction <= 1):
            raise ValueError(f"rebuild_fraction must be a number in (0, 1], got "
                             f"{self.rebuild_fraction!r}")

    # -- learning ------------------------------------------------------------------------------
    def fit(self, X, Y, sample_weight=None):
        """Forget all samples, then learn inputs X (N, d) -> outputs Y (N, m) or (N,)."""
        for attribute in ("n_features_in_", "n_outputs_", "n_samples_"):
            self.__dict__.pop(attribute, None)
        return self.partial_fit(X, Y, sample_weight)

    def partial_fit(self, X, Y, sample_weight=None):
        """Append samples X (N, d) -> Y (N, m) or (N,), each with weight ``sample_weight``
        (N,) > 0 (default 1). The widths must match the earlier samples'."""
        self._check_hyperparameters()
        X, y_1d = check.as_matrix(X, "X"), np.ndim(Y) == 1
        Y = check.as_matrix(np.reshape(Y, (-1, 1)) if y_1d else Y, "Y")
        if len(X) != len(Y):
            raise ValueError(f"X and Y must have the same number of rows (one per sample), "
                             f"got {len(X)} and {len(Y)}")
        if not len(X):
            raise ValueError("X and Y hold no samples (0 rows)")
        weights = _check_weights(sample_weight, len(X))
        if not hasattr(self, "n_samples_"):
            self._start(X.shape[1], Y.shape[1])
            self._y_was_1d = y_1d
        for array, width, name in ((X, self.n_features_in_, "X"), (Y, self.n_outputs_, "Y")):
            if array.shape[1] != width:
                raise ValueError(f"{name} has {array.shape[1]} columns but the model was fitted "
                                 f"on {width}")
        n, end = self.n_samples_, self.n_samples_ + len(X)
        if end > len(self._X):
            self._grow(end)
        self._X[n:end], self._Y[n:end], self._w[n:end] = X, Y, weights
        self.n_samples_ = end
        return self

    def _start(self, n_features, n_outputs, capacity=1024):
        self.n_features_in_, self.n_outputs_, self.n_samples_ = n_features, n_outputs, 0
        self._X = np.empty((capacity, n_features))
        self._Y = np.empty((capacity, n_outputs))
        self._w = np.empty(capacity)
        self._tree, self._n_indexed = None, 0

    def _grow(self, needed):
        """Double the sample buffers (amortised O(1) appends; the tree keeps its own copy)."""
        capacity = max(needed, 2 * len(self._X))
        for name in ("_X", "_Y", "_w"):
            old = getattr(self, name)
            new = np.empty((capacity,) + old.shape[1:])
            new[:self.n_samples_] = old[:self.n_samples_]
            setattr(self, name, new)

    @property
    def X_(self):
        return self._view("_X")

    @property
    def Y_(self):
        return self._view("_Y")

    @property
    def sample_weight_(self):
        return self._view("_w")

    def _check_fitted(self):
        if not hasattr(self, "n_samples_"):
            raise check.not_fitted(f"this {type(self).__name__} has no samples yet: call "
                                   "fit or partial_fit first")

    def _view(self, buffer):
        self._check_fitted()
        view = getattr(self, buffer)[:self.n_samples_]
        view.flags.writeable = False
        return view

    # -- prediction ----------------------------------------------------------------------------
    def _check_queries(self, X):
        self._check_fitted()
        X = check.as_matrix(X, "X")
        if X.shape[1] != self.n_features_in_:
            raise ValueError(f"X has {X.shape[1]} columns but the model was fitted on "
                             f"{self.n_features_in_}")
        return X

    def kneighbors(self, X):
        """(distances, indices), each (M, k) sorted by distance, of the k = min(K, N) nearest
        samples to each query row of X (M, d)."""
        X = self._check_queries(X)
        tail = self.n_samples_ - self._n_indexed
        if tail > max(_MIN_TAIL, self.rebuild_fraction * self._n_indexed) \
                or len(X) * tail > _BRUTE_BUDGET:
            self._tree = cKDTree(self._X[:self.n_samples_].copy())
            self._n_indexed, tail = self.n_samples_, 0
        k = min(self.n_neighbors, self.n_samples_)
        parts = []
        if self._n_indexed:
            distances, indices = self._tree.query(X, k=min(k, self._n_indexed))
            parts.append((distances.reshape(len(X), -1), indices.reshape(len(X), -1)))
        if tail:
            parts.append(self._tail_neighbors(X, k))
        if len(parts) == 1 and tail == 0:   # the tree's answer is sorted already
            return parts[0]
        distances = np.hstack([part[0] for part in parts])
        indices = np.hstack([part[1] for part in parts])
        order = np.lexsort((indices, distances))[:, :k]   # by distance, then index
        rows = np.arange(len(X))[:, None]
        return distances[rows, order], indices[rows, order]

    def _tail_neighbors(self, X, k):
        """The k nearest among the unindexed samples, by brute force (unsorted)."""
        tail = self._X[self._n_indexed:self.n_samples_]
        distances = np.sqrt(((X[:, None, :] - tail[None, :, :]) ** 2).sum(axis=2))
        nearest = np.broadcast_to(np.arange(len(tail)), distances.shape)
        if len(tail) > k:
            nearest = np.argpartition(distances, k - 1, axis=1)[:, :k]
            distances = distances[np.arange(len(X))[:, None], nearest]
        return distances, nearest + self._n_indexed

    def predict(self, X):
        """ŷ for queries X (M, d): the weighted neighbour mean (class docstring), (M, m), or
        (M,) when the first samples' Y was 1-D."""
        distances, indices = self.kneighbors(X)
        weights = self._w[indices]
        if self.weights == "distance":
            exact = distances <= _TINY
            on_sample = exact[:, 0]   # distances are sorted: the nearest coincides
            with np.errstate(divide="ignore", invalid="ignore"):
                kernel = distances[:, :1] / distances   # 1/d_j scaled by d_1 (cancels): <= 1
            kernel[on_sample] = exact[on_sample]
            weights = weights * kernel
        weights /= weights.sum(axis=1, keepdims=True)
        predictions = np.einsum("mk,mko->mo", weights, self._Y[indices])
        return predictions[:, 0] if self._y_was_1d else predictions


class SensorimotorModel:
    """The pair L⁻¹ (inverse: x -> q) and L (forward: q -> x) a robot learns (§6.3).

    ``inverse`` and ``forward`` are online regressors (``partial_fit``/``predict``, e.g.
    :class:`KNNRegressor`); ``forward`` may be None when only L⁻¹ is learned (goal babbling
    needs only L⁻¹, §6.3.1). Both learn every sample (q, x) given to :meth:`update`.
    """

    def __init__(self, inverse, forward=None):
        self.inverse, self.forward = inverse, forward

    def update(self, q, x, sample_weight=None):
        """Learn samples: commands q (N, d) executed and the task points x (N, m) reached."""
        self.inverse.partial_fit(x, q, sample_weight)
        if self.forward is not None:
            self.forward.partial_fit(q, x, sample_weight)
        return self

    def infer_command(self, x):
        """L⁻¹: commands (N, d) predicted to reach task points x (N, m)."""
        return self.inverse.predict(x)

    def predict_point(self, q):
        """L: task points (N, m) predicted for commands q (N, d); needs a forward model."""
        if self.forward is None:
            raise ValueError("this sensorimotor model learns no forward model (forward=None)")
        return self.forward.predict(q)


#: Sensorimotor regressors by the name a configuration uses (the model is a parameter).
MODELS = {"knn": KNNRegressor}


def make_model(name, **hyperparameters):
    """A fresh regressor ``MODELS[name]`` with its hyperparameters; ValueError if unknown."""
    if name not in MODELS:
        raise ValueError(f"unknown sensorimotor model {name!r}; available: {sorted(MODELS)}")
    return MODELS[name](**hyperparameters)


def make_sensorimotor_model(name="knn", forward=True, **hyperparameters):
    """A :class:`SensorimotorModel` whose inverse (and, if ``forward``, forward) model are
    fresh regressors ``name`` with the same hyperparameters."""
    return SensorimotorModel(make_model(name, **hyperparameters),
                             make_model(name, **hyperparameters) if forward else None)
