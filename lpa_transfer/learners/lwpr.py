"""Locally Weighted Projection Regression (LWPR): incremental online nonlinear regression.

The thesis (ch. 5, §5.5.2) learns robot inverse dynamics online with LWPR, predicting the
feed-forward torque and then updating the model at 100 Hz (init_D = 30; init_alpha 1.1 / 0.01
/ 0.001). The algorithm is that of S. Vijayakumar, A. D'Souza and S. Schaal, "Incremental
Online Learning in High Dimensions", Neural Computation 17(12):2602-2634, 2005 (Table 3:
incremental locally weighted PLS of one receptive field, Table 4: derivatives for the
distance-metric update, Table 5: the complete algorithm). Defaults, parameter names and
numerical safety heuristics follow the authors' reference library (Klanke, Vijayakumar &
Schaal, JMLR 9, 2008).

Each output dimension has its own receptive fields (RFs), each a Gaussian activation and a
local PLS model; the model predicts the activation-weighted mean of its trustworthy RFs.
Learning a sample updates the active RFs' statistics and distance metrics, adds projections
and creates or prunes RFs. The update equations, and where this implementation departs from
the paper and the reference library: docs/library.md, "LWPR". The RFs live in preallocated
arrays that compiled kernels (:mod:`lpa_transfer.learners._lwpr_kernels`) update in place;
this class keeps the API, the checks and the growing of the arrays.
"""
import numbers

import numpy as np
from scipy.sparse import issparse
from sklearn.base import BaseEstimator, RegressorMixin
from sklearn.utils.validation import check_is_fitted

from lpa_transfer._validation import as_matrix, check_float, check_int, check_unit
from lpa_transfer.learners import _lwpr_kernels as _kernels

#: Only RFs activated above this are updated (reference library).
UPDATE_CUTOFF = _kernels.UPDATE_CUTOFF
#: Initial sufficient statistics of a new RF (reference library).
_TINY = _kernels.TINY

# RF state, grouped by shape (the kernels' index constants follow these orders).
#: Per projection r: (n_rfs, 9, R).
_PROJ_STATS = ("beta", "SSs2", "SSY", "H", "r", "sum_w", "n_data", "lam", "sum_ecv2")
#: Per projection r, vectors in input space: (n_rfs, 5, R, d). T maps z_1 to s (s = T z_1).
_PROJ_AXES = ("U", "P", "SXY", "SSX", "T")
#: Vectors in input space: (n_rfs, 2, d).
_POINTS = ("c", "x0")
#: Distance-metric parameters: (n_rfs, 4, L), L = d (diagonal of M, ...) or d·d (row-major).
_METRIC = ("M", "alpha", "b", "hm")
#: Scalars: (n_rfs, 3).
_SCALARS = ("beta0", "sum_e2", "SSp")
_GROUPS = (("proj_stats", _PROJ_STATS), ("proj_axes", _PROJ_AXES), ("points", _POINTS),
           ("metric", _METRIC), ("scalars", _SCALARS))


class _ReceptiveFields:
    """All RFs of a model (every output dimension) in preallocated arrays, row k = RF k.

    The arrays (layout: lpa_transfer/learners/_lwpr_kernels.py) are updated in place by the
    compiled kernels; this class allocates them, doubles the rows when full (``_grow``) and
    the projection slots when an RF uses the last one (``_widen``: ``n_slots`` is one more
    than the largest n_reg, up to ``n_proj_max``). Slots r >= ``n_reg[k]`` keep their initial
    values (U = P = 0: they contribute nothing). ``lin_coef`` caches each RF's affine
    prediction ŷ = (x, 1)·lin_coef.
    """

    def __init__(self, cfg, n_outputs, capacity=2 * _kernels.BLOCK):
        d, S = cfg.n_in, min(3, cfg.n_proj_max)
        self.cfg, self.n, self.n_outputs, self.n_slots = cfg, 0, n_outputs, S
        self.m_shape = (d,) if cfg.diag_only else (d, d)
        L = int(np.prod(self.m_shape))
        self._shapes = dict(
            proj_stats=((len(_PROJ_STATS), S), float), proj_axes=((len(_PROJ_AXES), S, d), float),
            points=((2, d), float), metric=((4, L), float), scalars=((3,), float),
            lin_coef=((d + 1,), float), out=((), np.int64), n_reg=((), np.int64),
            trust=((), bool), near=((), np.int64), act=((), float))
        for name, (shape, dtype) in self._shapes.items():
            setattr(self, name, np.zeros((capacity,) + shape, dtype))
        self.boxes = np.zeros((capacity // _kernels.BLOCK, 3, d))
        k = _kernels
        params = np.zeros(k.N_PARAMS)
        for index, value in ((k.P_W_GEN, cfg.w_gen), (k.P_W_PRUNE, cfg.w_prune),
                             (k.P_INIT_LAMBDA, cfg.init_lambda),
                             (k.P_FINAL_LAMBDA, cfg.final_lambda),
                             (k.P_TAU_LAMBDA, cfg.tau_lambda), (k.P_GAMMA, cfg.gamma),
                             (k.P_META_RATE, cfg.meta_rate),
                             (k.P_ADD_THRESHOLD, cfg.add_threshold), (k.P_INIT_S2, cfg.init_S2),
                             (k.P_UPDATE_D, cfg.update_D), (k.P_META, cfg.meta),
                             (k.P_DIAG, cfg.diag_only), (k.P_N_PROJ_MAX, cfg.n_proj_max),
                             (k.P_ZERO_EMPTY, cfg.zero_empty)):
            params[index] = value
        self.params = params
        self.init = np.stack((cfg.init_M.ravel(), cfg.init_alpha.ravel(),
                              cfg.metric_mask.ravel().astype(float)))[None]

    def __getstate__(self):
        state = self.__dict__.copy()
        del state["near"], state["act"]                  # scratch of the kernels
        return state

    def __setstate__(self, state):
        # Unpickled arrays can be read-only memory maps (joblib); the kernels write in place
        # and take plain C-contiguous arrays.
        for key, value in state.items():
            if isinstance(value, np.ndarray) and (type(value) is not np.ndarray
                                                  or not value.flags.writeable
                                                  or not value.flags.c_contiguous):
                state[key] = np.array(value)
        self.__dict__.update(state)
        self.near = np.zeros(len(self.out), np.int64)
        self.act = np.zeros(len(self.out))

    def field(self, group, name, rows=slice(None)):
        """Rows of one named field, e.g. ``field("metric", "M")``; metrics in their shape
        (k, d) or (k, d, d)."""
        names = dict(_GROUPS)[group]
        values = getattr(self, group)[rows, names.index(name)]
        return values.reshape(values.shape[:-1] + self.m_shape) if group == "metric" else values

    def _state(self):
        """The arrays as the kernels take them."""
        return (self.proj_stats, self.proj_axes, self.points, self.metric, self.scalars,
                self.lin_coef, self.out, self.n_reg, self.trust, self.boxes)

    # ----------------------------------------------------------------- bookkeeping
    def _grow(self):
        for name in list(self._shapes) + ["boxes"]:
            old = getattr(self, name)
            new = np.zeros((2 * len(old),) + old.shape[1:], old.dtype)
            new[:len(old)] = old
            setattr(self, name, new)

    def _widen(self):
        """Double the projection slots (at most n_proj_max); new slots get initial values:
        statistics SS = init_S2, λ = init_lambda, Σw = 1e-10, all else 0 (reference library)."""
        old, cfg = self.n_slots, self.cfg
        self.n_slots = min(2 * old, cfg.n_proj_max)
        for group in ("proj_stats", "proj_axes"):
            array = getattr(self, group)
            wider = np.zeros(array.shape[:2] + (self.n_slots,) + array.shape[3:])
            wider[:, :, :old] = array
            setattr(self, group, wider)
        for name, value in (("SSs2", cfg.init_S2), ("lam", cfg.init_lambda), ("sum_w", _TINY)):
            self.proj_stats[:, _PROJ_STATS.index(name), old:] = value

    def metrics(self, idx):
        """Distance metrics D = Mᵀ M of the RFs ``idx``, (len(idx), d, d)."""
        M = self.field("metric", "M", idx)
        return (np.einsum("ki,ij->kij", M * M, np.eye(self.cfg.n_in)) if self.cfg.diag_only
                else M.transpose(0, 2, 1) @ M)

    # ----------------------------------------------------------------- kernels
    def learn(self, X, Y, before, n_pruned, cutoff):
        """Learn the normalised samples in order; ``before`` gets the predictions made before
        each (kernel ``lwpr_learn``, which returns whenever the arrays must grow)."""
        i = 0
        while i < len(X):
            while self.n + self.n_outputs > len(self.out):
                self._grow()
            i, self.n, widen = _kernels.lwpr_learn(
                X, Y, i, before, self.n, float(cutoff), *self._state(), n_pruned, self.near,
                self.act, self.params, self.init)
            if widen:
                self._widen()

    def predict(self, X, cutoff):
        """Activation-weighted mean of the RF predictions, (N, n_outputs) (normalised units):
        the trustworthy RFs with w > cutoff; without one, β0 of the nearest RF (or 0)."""
        Y = np.empty((len(X), self.n_outputs))
        _kernels.lwpr_predict(X, self.n, float(cutoff), self.points, self.metric,
                              self.scalars, self.lin_coef, self.out, self.trust, self.boxes,
                              self.near, self.act, self.cfg.diag_only, Y,
                              getattr(self.cfg, "zero_empty", False))
        return Y

    def activations(self, x, w_min):
        """The RFs activated above w_min by one input x: (rows, activations)."""
        near, act = np.empty(self.n, np.int64), np.empty(self.n)     # own scratch: no race
        count = _kernels.lwpr_activations(x, self.n, float(w_min), self.points, self.metric,
                                          self.boxes, self.cfg.diag_only, near, act)
        return near[:count], act[:count]

    def answering(self, x, cutoff):
        """The RFs a prediction for one input x averages over: the trustworthy ones activated
        above ``cutoff``, (rows, activations)."""
        act, w = self.activations(x, cutoff)
        keep = (w > cutoff) & self.trust[act]
        return act[keep], w[keep]

    def confidence(self, x, cutoff):
        """Predictive standard deviation per output for one input (normalised units)."""
        act, w = self.answering(x, cutoff)
        n_reg, rows = self.n_reg[act], np.arange(len(act))
        last = n_reg - 1
        stat = {name: self.proj_stats[act, i] for i, name in enumerate(_PROJ_STATS)}
        T = self.proj_axes[act, _PROJ_AXES.index("T")]
        usable = np.arange(self.n_slots) < n_reg[:, None]
        usable[rows, last] = stat["n_data"][rows, last] > 2 * self.cfg.n_in
        x0 = self.points[act, _POINTS.index("x0")]
        s = (T @ (x - x0)[:, :, None])[:, :, 0] * usable
        SSp = self.scalars[act, _SCALARS.index("SSp")]
        dof = np.maximum(stat["sum_w"][rows, last] - SSp, _TINY)
        sigma2 = (stat["sum_ecv2"][rows, last] / dof
                  * (1 + w * (s * s / stat["SSs2"]).sum(axis=1)))
        local = self.lin_coef[act, :-1] @ x + self.lin_coef[act, -1]
        sw, swy, sws2, swyy = (np.bincount(self.out[act], weights=v, minlength=self.n_outputs)
                               for v in (w, w * local, w * sigma2, w * local * local))
        with np.errstate(divide="ignore", invalid="ignore"):
            conf = np.sqrt(np.abs(sws2 + swyy - swy * swy / sw)) / sw
        return np.where(sw > 0, conf, np.inf)


class _Settings:
    """Hyperparameters resolved for an input dimensionality (read-only bag of values)."""

    def __init__(self, **values):
        self.__dict__.update(values)


class LWPR(RegressorMixin, BaseEstimator):
    """Locally Weighted Projection Regression (Vijayakumar, D'Souza & Schaal 2005).

    An incremental, online learner: ``partial_fit`` / ``update`` learn one sample after the
    other (docs/library.md, "LWPR", explains the algorithm and its simplifications). One
    independent set of receptive fields is learned per output dimension.

    Parameters (names and defaults as in the reference LWPR library)
    ----------
    init_D : float, (d,) array or (d, d) array
        Distance metric of new receptive fields in normalised input units: a scalar r means
        r·I, a vector a diagonal metric, a matrix must be symmetric positive definite (and
        diagonal when ``diag_only``). Larger values give narrower RFs.
    init_alpha : float or (d, d) array
        Learning rate(s) of the gradient step on M (element-wise).
    w_gen : float
        A sample activating no RF of an output above ``w_gen`` creates a new RF there.
    w_prune : float
        Two RFs of an output both activated above ``w_prune`` → one is pruned (1.0: never).
    init_lambda, final_lambda, tau_lambda : float
        Forgetting factor λ, annealed per update as λ ← τ λ + (1 - τ) λ_final.
    penalty : float
        γ of the smoothness penalty (γ / d) Σ D_ij² in the distance-metric cost.
    update_D : bool
        Learn the distance metrics by gradient descent on the leave-one-out cost.
    meta, meta_rate : bool, float
        Adapt the learning rates by incremental delta-bar-delta, with this meta rate.
    diag_only : bool
        Keep the distance metrics diagonal (faster; the reference library's default).
    max_projections : int or None
        Upper limit on PLS projections per RF; None: the input dimensionality d.
    add_threshold : float
        A projection is added when MSE_R / MSE_{R-1} < add_threshold.
    init_S2 : float
        Initial variance statistic SS of a new projection.
    norm_in, norm_out : None, float or array
        Inputs are divided by ``norm_in`` (d,) and outputs by ``norm_out`` (m,) before
        learning. None: the column standard deviations of the first batch given to
        ``fit``/``partial_fit`` if it has at least 2 rows (columns with zero spread: 1),
        else 1 (the reference library's default is 1). init_D is in units of the normalised
        inputs, and the metric learning rates act on normalised output errors.
    kernel : {"gaussian"}
        Activation function; only the Gaussian is implemented.
    cutoff : float
        RFs activated at or below ``cutoff`` do not contribute to predictions (0: all RFs,
        but then every RF is evaluated for every query, which is slow for many RFs).
    empty_prediction : {"nearest", "zero"}
        The prediction of an output where no trustworthy RF is active above ``cutoff``:
        ``"nearest"``, β0 of the most active (else the nearest) RF; ``"zero"``, 0, as the
        authors' reference library (C and MATLAB) answers, so that until the model covers
        an input nothing is predicted there (thesis ch. 5: the PID alone acts).
    n_epochs : int
        Passes over the data in ``fit`` (same order every pass).

    Learned attributes: ``n_features_in_``, ``n_outputs_``, ``n_data_`` (samples learned),
    ``norm_in_``, ``norm_out_``, ``n_pruned_`` (per output), ``n_receptive_fields_`` (per
    output), ``receptive_fields_`` (per output: dict of arrays in normalised units).
    """

    def __init__(self, init_D=25.0, init_alpha=50.0, w_gen=0.1, w_prune=1.0,
                 init_lambda=0.999, final_lambda=0.99999, tau_lambda=0.9999, penalty=1e-6,
                 update_D=True, meta=False, meta_rate=250.0, diag_only=True,
                 max_projections=None, add_threshold=0.5, init_S2=1e-10, norm_in=None,
                 norm_out=None, kernel="gaussian", cutoff=1e-3, n_epochs=1,
                 empty_prediction="nearest"):
        self.init_D = init_D
        self.init_alpha = init_alpha
        self.w_gen = w_gen
        self.w_prune = w_prune
        self.init_lambda = init_lambda
        self.final_lambda = final_lambda
        self.tau_lambda = tau_lambda
        self.penalty = penalty
        self.update_D = update_D
        self.meta = meta
        self.meta_rate = meta_rate
        self.diag_only = diag_only
        self.max_projections = max_projections
        self.add_threshold = add_threshold
        self.init_S2 = init_S2
        self.norm_in = norm_in
        self.norm_out = norm_out
        self.kernel = kernel
        self.cutoff = cutoff
        self.n_epochs = n_epochs
        self.empty_prediction = empty_prediction

    # ----------------------------------------------------------------- public API
    def fit(self, X, Y):
        """Learn a fresh model from X (n, d) -> Y (n, m) or (n,), sample by sample in row order."""
        check_int(self.n_epochs, "n_epochs", minimum=1)
        X, Y, y_1d = _as_samples(X, Y, allow_single=False)
        self._reset(X, Y, y_1d)
        for _ in range(self.n_epochs):
            self._learn(X, Y)
        return self

    def partial_fit(self, X, Y):
        """Online update with the samples in row order (X (n, d) or (d,), Y (n, m) or (m,)).

        The whole batch is validated before any sample is learned.
        """
        self._learn(*self._start_or_check(*_as_samples(X, Y, allow_single=True)))
        return self

    def update(self, x, y):
        """Learn one sample and return the prediction for x made *before* learning it.

        This is the online control-loop step (predict the feed-forward torque, then learn).
        Returns an (m,) array, or a float if the model was fitted with a 1-D Y.
        """
        X, Y, y_1d = _as_samples(x, y, allow_single=True)
        if len(X) != 1:
            raise ValueError(f"update takes a single sample, got {len(X)} rows")
        prediction = self._learn(*self._start_or_check(X, Y, y_1d))[0] * self.norm_out_
        return float(prediction[0]) if self._y_1d else prediction

    def predict(self, X):
        """Predicted outputs (n, m), or (n,) if fitted with a 1-D Y, for inputs X (n, d)."""
        Xn = self._check_queries(X)
        Y = self._rfs.predict(Xn, self.cutoff) * self.norm_out_
        return Y[:, 0] if self._y_1d else Y

    def predict_with_confidence(self, X):
        """Predictions and their confidence bounds (predictive standard deviations).

        Per output, with the activations w_k, RF predictions ŷ_k, the RFs' leave-one-out
        variances σ_k² (inflated by the leverage of x) and ŷ = Σ w_k ŷ_k / Σ w_k:
        conf = sqrt(Σ w_k (σ_k² + (ŷ_k - ŷ)²)) / Σ w_k (inf where no RF is active).
        """
        Xn = self._check_queries(X)
        Y = self.predict(X).reshape(len(Xn), -1)
        rfs = self._rfs
        conf = np.array([rfs.confidence(x, self.cutoff) for x in Xn]) * self.norm_out_
        return (Y[:, 0], conf[:, 0]) if self._y_1d else (Y, conf)

    def set_w_gen(self, w_gen):
        """From now on a sample makes a new receptive field unless one answers it above
        ``w_gen`` (in [0, 1]); what the model has learned is kept. A yielding transfer
        (FeedForwardLearner's ``yielding``) raises it after the transferred data, so that the
        robot's own samples make fields of their own on its task where the transferred data's
        fields answer them only weakly. Returns self."""
        check_is_fitted(self, "n_data_")
        check_unit(w_gen, "w_gen")
        self.w_gen = w_gen
        self._settings.w_gen = float(w_gen)
        self._rfs.params[_kernels.P_W_GEN] = float(w_gen)
        return self

    @property
    def n_receptive_fields_(self):
        check_is_fitted(self, "n_data_")
        return np.bincount(self._rfs.out[:self._rfs.n], minlength=self.n_outputs_)

    @property
    def receptive_fields_(self):
        """Per output dimension, a dict of the RFs' arrays (normalised units; copies).

        Keys: ``c`` centres, ``x0`` input means, ``D`` metrics (k, d, d), ``M`` their factors
        (diagonals if ``diag_only``), ``beta0``, ``beta``, ``U``, ``P`` (padded projection
        slots), ``n_projections``, ``n_data`` (discounted sample counts), ``trustworthy``.
        """
        check_is_fitted(self, "n_data_")
        rfs = self._rfs
        fields = []
        for j in range(self.n_outputs_):
            k = np.flatnonzero(rfs.out[:rfs.n] == j)
            fields.append(dict(
                c=rfs.field("points", "c", k), x0=rfs.field("points", "x0", k),
                D=rfs.metrics(k), M=rfs.field("metric", "M", k),
                beta0=rfs.field("scalars", "beta0", k), beta=rfs.field("proj_stats", "beta", k),
                U=rfs.field("proj_axes", "U", k), P=rfs.field("proj_axes", "P", k),
                n_projections=rfs.n_reg[k], n_data=rfs.field("proj_stats", "n_data", k)[:, 0],
                trustworthy=rfs.trust[k]))
        return fields

    # ----------------------------------------------------------------- internals
    def _learn(self, X, Y):
        """Learn the rows in order; returns the normalised predictions made before each."""
        Xn, Yn = X / self.norm_in_, Y / self.norm_out_
        before = np.empty_like(Yn)
        self._rfs.learn(Xn, Yn, before, self.n_pruned_, self.cutoff)
        self.n_data_ += len(X)
        return before

    def _reset(self, X, Y, y_1d):
        """Start a fresh model sized by the first batch (X, Y)."""
        d, m = X.shape[1], Y.shape[1]
        self._settings = self._resolve(d)
        self.norm_in_ = _normaliser(self.norm_in, X, "norm_in")
        self.norm_out_ = _normaliser(self.norm_out, Y, "norm_out")
        self.n_features_in_, self.n_outputs_, self._y_1d = d, m, y_1d
        self.n_data_ = 0
        self.n_pruned_ = np.zeros(m, dtype=int)
        self._rfs = _ReceptiveFields(self._settings, m)

    def _resolve(self, d):
        """Validate the hyperparameters for d inputs; return them as ``_Settings``."""
        for name in ("init_lambda", "final_lambda", "tau_lambda"):
            _check_open_unit(getattr(self, name), name)
        for name in ("w_gen", "w_prune"):
            check_unit(getattr(self, name), name)
        for name in ("penalty", "meta_rate", "add_threshold", "init_S2"):
            check_float(getattr(self, name), name, minimum=0)
        check_float(self.cutoff, "cutoff", minimum=0)
        for name in ("update_D", "meta", "diag_only"):
            if not isinstance(getattr(self, name), (bool, np.bool_)):
                raise ValueError(f"{name} must be a bool, got {getattr(self, name)!r}")
        if str(self.kernel).lower() != "gaussian":
            raise ValueError(f"kernel must be 'gaussian' (the only kernel implemented), got "
                             f"{self.kernel!r}")
        if self.empty_prediction not in ("nearest", "zero"):
            raise ValueError(f"empty_prediction must be 'nearest' or 'zero', got "
                             f"{self.empty_prediction!r}")
        if self.max_projections is not None:
            check_int(self.max_projections, "max_projections", minimum=1)
        n_proj = d if self.max_projections is None else min(int(self.max_projections), d)
        M = _cholesky_metric(self.init_D, d, self.diag_only)
        alpha = _learning_rates(self.init_alpha, d)
        if self.diag_only:      # diagonal metrics are stored as their diagonals
            mask, M, alpha = np.ones(d, dtype=bool), np.diag(M).copy(), np.diag(alpha).copy()
        else:
            mask = np.triu(np.ones((d, d), dtype=bool))
        return _Settings(
            n_in=d, n_proj_max=n_proj, diag_only=bool(self.diag_only), metric_mask=mask,
            init_M=M, init_alpha=alpha, w_gen=float(self.w_gen),
            w_prune=float(self.w_prune), init_lambda=float(self.init_lambda),
            final_lambda=float(self.final_lambda), tau_lambda=float(self.tau_lambda),
            gamma=float(self.penalty) / d, update_D=bool(self.update_D),
            meta=bool(self.meta), meta_rate=float(self.meta_rate),
            add_threshold=float(self.add_threshold), init_S2=max(float(self.init_S2), 1e-300),
            zero_empty=self.empty_prediction == "zero")

    def _start_or_check(self, X, Y, y_1d):
        """Start a model on the first batch; later batches must match its widths."""
        if not hasattr(self, "_rfs"):
            self._reset(X, Y, y_1d)
        self._check_width(X)
        if Y.shape[1] != self.n_outputs_:
            raise ValueError(f"Y has {Y.shape[1]} columns, but LWPR was fitted on "
                             f"{self.n_outputs_} outputs")
        return X, Y

    def _check_queries(self, X):
        check_is_fitted(self, "n_data_")
        X, _ = _as_inputs(X, allow_single=False)
        self._check_width(X)
        return X / self.norm_in_

    def _check_width(self, X):
        if X.shape[1] != self.n_features_in_:
            raise ValueError(f"X has {X.shape[1]} features, but LWPR is expecting "
                             f"{self.n_features_in_} features as input")


# --------------------------------------------------------------------- input helpers
def _as_inputs(X, allow_single):
    """X as a checked (n, d) array, and whether it was one sample given as (d,).

    A 1-D X is one sample where ``allow_single`` (partial_fit, update) and an error in fit
    and predict (the scikit-learn convention).
    """
    X = _as_real_array(X, "X")
    single = X.ndim == 1
    if single and not allow_single:
        raise ValueError(f"X must be 2-D (n_samples, n_features), got shape {X.shape}. Reshape "
                         "your data: pass one sample as X[None] (partial_fit and update take "
                         "it as it is)")
    if X.ndim == 2 and X.shape[1] == 0:
        raise ValueError(f"X has 0 feature(s) (shape={X.shape}) while a minimum of 1 is "
                         "required.")
    X = as_matrix(X.reshape(1, -1) if single else X, "X")
    if len(X) == 0:
        raise ValueError("X is empty (no rows)")
    return X, single


def _as_samples(X, Y, allow_single):
    """Checked (X (n, d), Y (n, m), whether Y is a 1-D target of a single-output model).

    A 1-D X is one sample; with it a 1-D Y holds its m outputs. With a 2-D X, a 1-D Y holds
    one output per row. A scalar Y is one sample of one output.
    """
    X, single = _as_inputs(X, allow_single)
    if Y is None:
        raise ValueError("LWPR requires y to be passed, but the target y is None")
    Y = _as_real_array(Y, "Y")
    y_1d = Y.ndim == 0 or (Y.ndim == 1 and not single)
    if Y.ndim == 0 or (Y.ndim == 1 and single):
        Y = Y.reshape(1, -1)
    elif Y.ndim == 1:
        Y = Y.reshape(-1, 1)
    Y = as_matrix(Y, "Y")
    if len(Y) != len(X):
        raise ValueError(f"X and Y must have the same number of rows (one per sample), got "
                         f"{len(X)} and {len(Y)}")
    return X, Y, y_1d


def _as_real_array(values, name):
    """``values`` as an array; sparse matrices and complex numbers are refused."""
    if issparse(values):
        raise ValueError(f"{name} is a sparse matrix; LWPR needs dense input (sparse input is "
                         "not supported)")
    try:
        values = np.asarray(values)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be a numeric array: {exc}") from None
    if np.iscomplexobj(values):
        raise ValueError(f"Complex data not supported: {name} has complex values")
    return values


def _normaliser(value, data, name):
    """The normalisation factors of ``data``'s columns (see ``norm_in``)."""
    width = data.shape[1]
    if value is None:
        if len(data) < 2:
            return np.ones(width)
        spread = data.std(axis=0)
        return np.where(spread > 0, spread, 1.0)
    try:
        factors = np.broadcast_to(np.asarray(value, dtype=float), (width,)).copy()
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be None, a number or {width} numbers, got "
                         f"{value!r}") from None
    if not (np.isfinite(factors).all() and (factors > 0).all()):
        raise ValueError(f"{name} must be finite and positive, got {value!r}")
    return factors


def _cholesky_metric(init_D, d, diag_only):
    """Upper-triangular M with Mᵀ M = init_D (scalar, (d,) diagonal or (d, d) matrix)."""
    try:
        D = np.asarray(init_D, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"init_D must be numeric, got {init_D!r}") from None
    if D.ndim == 0 or D.shape == (d,):
        D = np.diag(np.broadcast_to(D, (d,)))
    if D.shape != (d, d) or not np.isfinite(D).all():
        raise ValueError(f"init_D must be a number, {d} numbers or a ({d}, {d}) matrix, got "
                         f"shape {np.shape(init_D)}")
    if not np.allclose(D, D.T):
        raise ValueError("init_D must be symmetric")
    if diag_only and np.any(D[~np.eye(d, dtype=bool)] != 0):
        raise ValueError("init_D has off-diagonal entries but diag_only=True")
    try:
        return np.linalg.cholesky(D).T
    except np.linalg.LinAlgError:
        raise ValueError("init_D must be positive definite") from None


def _learning_rates(init_alpha, d):
    try:
        alpha = np.broadcast_to(np.asarray(init_alpha, dtype=float), (d, d)).copy()
    except (TypeError, ValueError):
        raise ValueError(f"init_alpha must be a number or a ({d}, {d}) matrix, got "
                         f"{init_alpha!r}") from None
    if not (np.isfinite(alpha).all() and (alpha > 0).all()):
        raise ValueError(f"init_alpha must be finite and positive, got {init_alpha!r}")
    return alpha


def _check_open_unit(value, name):
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not 0 < value < 1:
        raise ValueError(f"{name} must be a number in (0, 1), got {value!r}")
