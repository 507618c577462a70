"""FROZEN REFERENCE: the pure-numpy LWPR as it was before its update and prediction moved into
compiled kernels (lpa_transfer/learners/_lwpr_kernels.py). Test code, not library code: kept
verbatim (only this paragraph added) as the oracle of the equality tests in test/test_lwpr.py
and the yardstick of bench/bench_lwpr.py; the tests require the library's LWPR to reproduce it to
1e-9 relative. Do not edit or optimise it; the library's docstring is the maintained one.

Locally Weighted Projection Regression (LWPR): incremental online nonlinear regression.

Reference: S. Vijayakumar, A. D'Souza and S. Schaal, "Incremental Online Learning in High
Dimensions", Neural Computation 17(12):2602-2634, 2005 ("the paper"; Table 3: incremental
locally weighted PLS of one receptive field, Table 4: derivatives for the distance-metric
update, Table 5: the complete algorithm). The thesis (ch. 5, §5.5.2) learns robot inverse
dynamics online with LWPR, predicting the feed-forward torque and then updating the model at
100 Hz (init_D = 30; init_alpha 1.1 / 0.01 / 0.001). Defaults and numerical safety
heuristics follow the authors' reference library (Klanke, Vijayakumar & Schaal, JMLR 9,
2008), whose parameter names this module uses.

Model
-----
Each output dimension has its own, independent set of receptive fields (RFs). RF k has a
centre c, a distance metric D = Mᵀ M (M upper triangular) and the Gaussian activation

    w(x) = exp(-½ (x - c)ᵀ D (x - c)).

Its local model is a partial-least-squares regression on R projections (prediction part of
Table 3): z_1 = x - x0, s_r = u_rᵀ z_r, z_{r+1} = z_r - s_r p_r, ŷ = β0 + Σ_r β_r s_r. The
recursion is linear, s = T (x - x0) with T = (I + L)⁻¹ U, L_rq = u_r·p_q (q < r), so each RF
caches T and its effective slope g = Tᵀ β: predicting is one affine map per RF. The model
predicts the activation-weighted mean ŷ(x) = Σ_k w_k ŷ_k(x) / Σ_k w_k over the trustworthy RFs
with w_k > cutoff.

Learning one sample (x, y) (the complete algorithm, Table 5)
-------------------------------------------------------------
1. Every RF with w > 0.001 updates its local PLS model (Table 3): with forgetting factor λ,
   W ← λW + w, x0 ← (λW x0 + w x)/W, β0 likewise; then, for r = 1..R with residual input z_r
   and residual target res_r: u_r ∝ λ u_r + w z_r res_r, SS_r ← λ SS_r + w s_r²,
   SR_r ← λ SR_r + w s_r res_r, SZ_r ← λ SZ_r + w z_r s_r, β_r = SR_r / SS_r,
   p_r = SZ_r / SS_r, and MSE_r ← λ MSE_r + w res_{r+1}² (errors of the model before this
   update, i.e. leave-one-out errors). λ is annealed per update: λ ← τ λ + (1 - τ) λ_final.
2. ``update_D``: one gradient step M ← M - α ∂J/∂M on the penalised leave-one-out cost
   J = (1/W) Σ_i w_i (y_i - ŷ_i,-i)² / (1 - w_i h_i)² + (γ/d) Σ_ij D_ij²,
   with the incremental approximation of ∂J/∂w (memory traces E, H, R) and the chain rule
   ∂w/∂M, ∂J2/∂M of Table 4. ``meta`` adapts α element-wise by incremental delta-bar-delta
   using the second derivatives of Table 4.
3. A PLS projection is added when MSE_R / MSE_{R-1} < ``add_threshold`` (the last projection
   still cut the error a lot), up to ``max_projections``. RFs start with 2 projections.
4. No RF of an output activated above ``w_gen`` → a new RF centred at x. Two RFs of an output
   both activated above ``w_prune`` → one is removed.

Simplifications and choices (vs. the paper / reference library)
---------------------------------------------------------------
* Only the Gaussian kernel. Inputs are divided by ``norm_in`` and outputs by ``norm_out``
  before learning; c, D, x0 and β live in these normalised units.
* Pruning removes the RF with the larger det D (the narrower one; the reference library
  compares trace D); equal metrics (e.g. ``update_D=False``) are decided by the larger
  leave-one-out MSE.
* A new RF copies the metric and learning rates of the most active RF of its output if that
  one is trustworthy and activated above 0.1 w_gen (as the reference library), else init_D.
* Safety heuristics of the reference library are kept: statistics start at 1e-10, the
  statistics of u_r forget more slowly (0.9 + 0.1 λ instead of λ), the last projection is
  ignored in predictions until it has seen 2 d samples, an RF predicts only
  once it has seen 2 d samples ("trustworthy"), metric updates start after 0.1 / (1 - λ)
  samples and are damped by the transient multiplier min(1, (Σe² / Σe_cv²)⁴), a metric step
  larger than 0.1 max|M| is skipped and its rate halved. Here the step test uses |ΔM|, and
  the leverage w sᵀ P s in the 1 / (1 - h) factors is capped at 1 - 1e-6.
* When no trustworthy RF is active for a query, the output is β0 (the mean output) of the RF
  with the smallest Mahalanobis distance, or 0 if the output has no RF yet (the reference
  library returns 0).

Speed: all RFs of all outputs live in stacked arrays. The distances of an input to the RFs
are computed in two stages, a lower bound from 4 inputs for all RFs (one small matrix-vector
product) and the exact value for the few RFs that pass it; the updates run vectorised over
the active RFs of all outputs at once. bench/bench_lwpr.py measures the online cycle.
"""
import numbers

import numpy as np
from scipy.sparse import issparse
from sklearn.base import BaseEstimator, RegressorMixin
from sklearn.utils.validation import check_is_fitted

from lpa_transfer._validation import as_matrix, check_float, check_int

#: Only RFs activated above this are updated (reference library).
UPDATE_CUTOFF = 1e-3
#: Initial sufficient statistics of a new RF (reference library).
_TINY = 1e-10
#: Inputs used by the cheap first stage of the distance computation (``activations``).
_SCREEN_DIMS = 4
#: Queries per block in ``predict``, bounding the (block, n_rfs) work arrays.
_QUERY_BLOCK = 128

# RF state, grouped by shape so that an update gathers and scatters each group once.
#: Per projection r: (n_rfs, 9, R).
_PROJ_STATS = ("beta", "SSs2", "SSY", "H", "r", "sum_w", "n_data", "lam", "sum_ecv2")
#: Per projection r, vectors in input space: (n_rfs, 5, R, d). T maps z_1 to s (s = T z_1).
_PROJ_AXES = ("U", "P", "SXY", "SSX", "T")
#: Vectors in input space: (n_rfs, 2, d).
_POINTS = ("c", "x0")
#: Distance-metric parameters: (n_rfs, 4, d) (diagonal of M, ...) or (n_rfs, 4, d, d).
_METRIC = ("M", "alpha", "b", "hm")
#: Scalars: (n_rfs, 3).
_SCALARS = ("beta0", "sum_e2", "SSp")
_GROUPS = (("proj_stats", _PROJ_STATS), ("proj_axes", _PROJ_AXES), ("points", _POINTS),
           ("metric", _METRIC), ("scalars", _SCALARS))


class _ReceptiveFields:
    """All RFs of a model (every output dimension) in stacked arrays, row k = RF k.

    Learning state lives in the groups of ``_GROUPS``; projections are padded to ``n_slots``
    slots (one more than the largest n_reg, up to ``n_proj_max``; widened on demand), and
    slots r >= ``n_reg[k]`` keep their initial values (U = P = 0: they contribute nothing).

    Prediction uses cached coefficients: ``q_coef`` with q = φ(x)·q_coef (φ(x) = (x², x, 1),
    or (x⊗x, x, 1) for full metrics), ``screen_t`` the same (transposed) for the last
    ``n_screen`` inputs only (a lower bound of q, see ``activations``), and ``lin_coef`` the RF's
    affine prediction ŷ = (x, 1)·lin_coef.
    """

    def __init__(self, cfg, n_outputs, capacity=64):
        d, R = cfg.n_in, min(3, cfg.n_proj_max)
        self.cfg, self.n, self.n_outputs, self.n_slots = cfg, 0, n_outputs, R
        self.n_screen = s = min(d, _SCREEN_DIMS)
        m_shape = (d,) if cfg.diag_only else (d, d)
        self._shapes = dict(
            proj_stats=((len(_PROJ_STATS), R), float), proj_axes=((len(_PROJ_AXES), R, d), float),
            points=((2, d), float), metric=((4,) + m_shape, float), scalars=((3,), float),
            out=((), np.intp), n_reg=((), np.intp), trust=((), bool),
            onehot=((n_outputs,), float), lin_coef=((d + 1,), float),
            q_coef=((len(_features(np.zeros((1, d)), cfg.diag_only)[0]),), float))
        for name, (shape, dtype) in self._shapes.items():
            setattr(self, name, np.zeros((capacity,) + shape, dtype))
        # transposed, (features, capacity): scanning all RFs is then a faster product
        self.screen_t = np.zeros((len(_features(np.zeros((1, s)), cfg.diag_only)[0]), capacity))

    def field(self, group, name, rows=slice(None)):
        """Rows of one named field, e.g. ``field("metric", "M")``."""
        names = dict(_GROUPS)[group]
        return getattr(self, group)[rows, names.index(name)]

    # ----------------------------------------------------------------- bookkeeping
    def _grow(self):
        for name in self._shapes:
            old = getattr(self, name)
            new = np.zeros((2 * len(old),) + old.shape[1:], old.dtype)
            new[:self.n] = old[:self.n]
            setattr(self, name, new)
        screen = np.zeros((len(self.screen_t), 2 * self.screen_t.shape[1]))
        screen[:, :self.n] = self.screen_t[:, :self.n]
        self.screen_t = screen

    def _widen(self):
        """Double the projection slots (at most n_proj_max); new slots get initial values."""
        old = self.n_slots
        self.n_slots = min(2 * old, self.cfg.n_proj_max)
        for group, fresh in zip(("proj_stats", "proj_axes"), self._fresh_projections()):
            array = getattr(self, group)
            wider = np.empty(array.shape[:2] + fresh.shape[1:])
            wider[:, :, :old], wider[:, :, old:] = array, fresh[:, old:]
            setattr(self, group, wider)

    def _fresh_projections(self):
        """Projection state of a new RF: (stats (9, n_slots), axes (5, n_slots, d)).

        Statistics start at init_S2 / 1e-10, λ at init_lambda; the first two projections
        (U = P = T = unit vectors) are in use.
        """
        cfg, n_reg = self.cfg, min(2, self.cfg.n_proj_max)
        stats = np.zeros((len(_PROJ_STATS), self.n_slots))
        for name, value in (("SSs2", cfg.init_S2), ("lam", cfg.init_lambda), ("sum_w", _TINY)):
            stats[_PROJ_STATS.index(name)] = value
        stats[_PROJ_STATS.index("n_data"), :n_reg] = _TINY
        axes = np.zeros((len(_PROJ_AXES), self.n_slots, cfg.n_in))
        for name in ("U", "P", "T"):
            axes[_PROJ_AXES.index(name), range(n_reg), range(n_reg)] = 1.0
        return stats, axes

    def add(self, outs, centre, y0, M, alpha):
        """Append one RF per output in ``outs``, centred at ``centre``, offsets β0 = ``y0``.

        ``M`` and ``alpha`` (one row per new RF) are its metric factor and learning rates.
        """
        while self.n + len(outs) > len(self.out):
            self._grow()
        k, cfg = np.arange(self.n, self.n + len(outs)), self.cfg
        self.n += len(outs)
        self.out[k], self.n_reg[k], self.trust[k] = outs, min(2, cfg.n_proj_max), False
        self.onehot[k] = 0.0
        self.onehot[k, outs] = 1.0
        self.points[k] = centre
        self.scalars[k] = self.lin_coef[k] = 0.0
        self.scalars[k, 0] = self.lin_coef[k, -1] = y0
        b = np.where(cfg.metric_mask, np.log(alpha + _TINY), 0.0)
        self.metric[k] = np.stack((M, alpha, b, np.zeros_like(M)), axis=1)
        self.proj_stats[k], self.proj_axes[k] = self._fresh_projections()
        self._refresh_distances(k, M, self.points[k, 0])

    def _refresh_distances(self, idx, M, c):
        """Recompute ``q_coef`` and ``screen_t`` of the RFs ``idx`` (metrics M, centres c).

        The screen uses the last s inputs: with M upper triangular, the last s rows of M x
        depend on them only, so |M_SS x_S|² (M_SS the lower-right s×s block) <= |M x|² = q.
        """
        s, diag = self.n_screen, self.cfg.diag_only
        self.q_coef[idx] = _distance_coefficients(M, c, diag)
        self.screen_t[:, idx] = _distance_coefficients(
            M[:, -s:] if diag else M[:, -s:, -s:], c[:, -s:], diag).T

    def remove(self, k):
        """Delete RF k by moving the last RF into its row."""
        last = self.n - 1
        for name in self._shapes:
            array = getattr(self, name)
            array[k] = array[last]
        self.screen_t[:, k] = self.screen_t[:, last]
        self.n = last

    def log_det_D(self, idx):
        M = self.field("metric", "M", idx)
        diag = M if self.cfg.diag_only else np.diagonal(M, axis1=1, axis2=2)
        return 2.0 * np.log(np.abs(diag)).sum(axis=1)

    def loo_mse(self, idx):
        last = self.n_reg[idx] - 1
        return (self.field("proj_stats", "sum_ecv2", idx)[np.arange(len(idx)), last]
                / self.field("proj_stats", "sum_w", idx)[np.arange(len(idx)), last])

    def metrics(self, idx):
        """Distance metrics D = Mᵀ M of the RFs ``idx``, (len(idx), d, d)."""
        M = self.field("metric", "M", idx)
        return (np.einsum("ki,ij->kij", M * M, np.eye(self.cfg.n_in)) if self.cfg.diag_only
                else M.transpose(0, 2, 1) @ M)

    # ----------------------------------------------------------------- prediction
    def activations(self, X, w_min):
        """Pairs (row i of X, RF k) with activation w_ik > w_min: (rows, rfs, w).

        Two stages, to read little memory per RF: the lower bound of q on the last s inputs
        (``screen_t``) discards most RFs, then q is computed exactly for the rest.
        """
        n, s = self.n, self.n_screen
        q_max = -2.0 * np.log(w_min) if w_min > 0 else np.inf      # w > w_min <=> q < q_max
        bound = _features(X[:, -s:], self.cfg.diag_only) @ self.screen_t[:, :n]
        hits = np.flatnonzero(bound < q_max * (1 + 1e-9) + 1e-9)    # slack for rounding
        rows, rfs = np.divmod(hits, n) if n else (hits, hits)
        q = np.einsum("ij,ij->i", _features(X, self.cfg.diag_only)[rows], self.q_coef[rfs])
        keep = q < q_max
        rows, rfs = rows[keep], rfs[keep]
        return rows, rfs, np.exp(-0.5 * np.maximum(q[keep], 0.0))

    def combine(self, X, pairs, cutoff):
        """Activation-weighted mean of the RF predictions, (N, n_outputs) (normalised units).

        ``pairs`` from ``activations``; only trustworthy RFs with w > cutoff contribute.
        """
        rows, rfs, w = pairs
        keep = (w > cutoff) & self.trust[rfs]
        rows, rfs, w = rows[keep], rfs[keep], w[keep]
        d, shape = self.cfg.n_in, (len(X), self.n_outputs)
        local = np.einsum("ij,ij->i", X[rows], self.lin_coef[rfs, :d]) + self.lin_coef[rfs, d]
        key = rows * self.n_outputs + self.out[rfs]
        weight = np.bincount(key, w, minlength=len(X) * self.n_outputs).reshape(shape)
        total = np.bincount(key, w * local, minlength=len(X) * self.n_outputs).reshape(shape)
        missing = weight <= 0.0
        Y = np.divide(total, weight, out=np.zeros(shape), where=~missing)
        if missing.any():
            self._fallback(Y, X, pairs, missing)
        return Y

    def _fallback(self, Y, X, pairs, missing):
        """No trustworthy RF active: β0 of the nearest RF (Mahalanobis), or 0 without RFs.

        The nearest RF is looked for among the ``pairs`` first, then among all RFs.
        """
        rows, rfs, w = pairs
        key = rows * self.n_outputs + self.out[rfs]
        order = np.lexsort((-w, key))                     # per (row, output), nearest first
        key, nearest = key[order], rfs[order]
        first = np.r_[True, key[1:] != key[:-1]] if key.size else key.astype(bool)
        key, nearest = key[first], nearest[first]
        hit = missing.ravel()[key]
        Y.ravel()[key[hit]] = self.scalars[nearest[hit], 0]
        missing.ravel()[key[hit]] = False
        for j in np.flatnonzero(missing.any(axis=0)):
            rows, rfs = np.flatnonzero(missing[:, j]), np.flatnonzero(self.out[:self.n] == j)
            if rfs.size:
                q = _features(X[rows], self.cfg.diag_only) @ self.q_coef[rfs].T
                Y[rows, j] = self.scalars[rfs[np.argmin(q, axis=1)], 0]

    def confidence(self, x, pairs, cutoff):
        """Predictive standard deviation per output for one input (normalised units)."""
        _, act, w = pairs
        keep = (w > cutoff) & self.trust[act]
        act, w = act[keep], w[keep]
        b = _Batch(self, act, all_slots=True)
        s = (b.T @ (x - b.x0)[:, :, None])[:, :, 0] * _usable(b, self.cfg)
        rows, last = np.arange(len(act)), b.n_reg - 1
        dof = np.maximum(b.sum_w[rows, last] - b.SSp, _TINY)
        sigma2 = b.sum_ecv2[rows, last] / dof * (1 + w * (s * s / b.SSs2).sum(axis=1))
        local = self.lin_coef[act, :-1] @ x + self.lin_coef[act, -1]
        sw, swy, sws2, swyy = (np.bincount(self.out[act], weights=v, minlength=self.n_outputs)
                               for v in (w, w * local, w * sigma2, w * local * local))
        with np.errstate(divide="ignore", invalid="ignore"):
            conf = np.sqrt(np.abs(sws2 + swyy - swy * swy / sw)) / sw
        return np.where(sw > 0, conf, np.inf)

    # ----------------------------------------------------------------- learning
    def learn(self, idx, w, x, y):
        """Update the RFs ``idx`` (activations ``w``) with the normalised sample (x, y)."""
        cfg = self.cfg
        b = _Batch(self, idx)
        z0, yz = _update_means(b, w, x, y[self.out[idx]])
        s, e_cv, e = _update_pls(b, w, z0, yz, cfg)
        if cfg.update_D:
            _update_metric(b, w, x, s, e_cv, e, cfg)
            self._refresh_distances(idx, b.M, b.c)
        _add_projections(b, cfg)
        _update_counts(b, w, cfg)
        b.write_back(self)
        if b.top == self.n_slots and self.n_slots < cfg.n_proj_max:   # keep a spare slot
            self._widen()
        slope = np.einsum("kr,krd->kd", b.beta * _usable(b, cfg), b.T)
        self.lin_coef[idx, :-1] = slope
        self.lin_coef[idx, -1] = b.beta0 - (slope * b.x0).sum(axis=1)


class _Batch:
    """Copies of the state of the RFs ``idx``, with one attribute per named field (views).

    Update functions write into the fields in place; ``write_back`` scatters them. Only the
    projection slots up to max(n_reg) + 1 are copied (one spare slot for a new projection).
    """

    def __init__(self, rfs, idx, all_slots=False):
        self.idx, self.n_reg, self.trust = idx, rfs.n_reg[idx], rfs.trust[idx]
        R = rfs.n_slots
        self.R = R if all_slots or not len(idx) else min(int(self.n_reg.max()) + 1, R)
        for group, names in _GROUPS:
            array = getattr(rfs, group)
            copy = array[idx, :, :self.R] if group.startswith("proj") else array[idx]
            setattr(self, group, copy)
            for i, name in enumerate(names):
                setattr(self, name, copy[:, i])
        self.index_slots()

    def index_slots(self):
        """Cache the mask of used projection slots and the index of each RF's last one."""
        n_reg = self.n_reg
        self.used = np.arange(self.R) < n_reg[:, None]
        self.top = int(n_reg.max()) if len(n_reg) else 0
        if len(n_reg) and (n_reg == self.top).all():       # common case: basic indexing
            self.last = (slice(None), self.top - 1)
        else:
            self.last = (np.arange(len(n_reg)), n_reg - 1)

    def at_last(self, array):
        """Each RF's entry of (n, R, ...) ``array`` at its last used projection."""
        return array[self.last]

    def write_back(self, rfs):
        for group, _ in _GROUPS:
            if group.startswith("proj"):
                getattr(rfs, group)[self.idx, :, :self.R] = getattr(self, group)
            else:
                getattr(rfs, group)[self.idx] = getattr(self, group)
        rfs.n_reg[self.idx], rfs.trust[self.idx] = self.n_reg, self.trust


def _features(X, diag_only):
    """φ(x) = (x², x, 1), or (x⊗x, x, 1) for full metrics, per row of X."""
    quadratic = X * X if diag_only else np.einsum("ni,nj->nij", X, X).reshape(len(X), -1)
    return np.hstack((quadratic, X, np.ones((len(X), 1))))


def _distance_coefficients(M, c, diag_only):
    """Rows of ``q_coef``: (D, -2 D c, cᵀ D c) so that q = (x², x, 1)·row for D = Mᵀ M."""
    if diag_only:
        D = M * M
        Dc = D * c
    else:
        D = M.transpose(0, 2, 1) @ M
        Dc = (D @ c[:, :, None])[:, :, 0]
    return np.hstack((D.reshape(len(M), -1), -2.0 * Dc, (Dc * c).sum(axis=1)[:, None]))


def _update_means(b, w, x, y):
    """Forgetting-factor weighted means x0 and β0 (Table 3, step 1); returns x - x0, y - β0."""
    share = w / (b.sum_w[:, 0] * b.lam[:, 0] + w)        # w / W_new
    b.x0 += share[:, None] * (x - b.x0)
    b.beta0 += share * (y - b.beta0)
    return x - b.x0, y - b.beta0


def _update_pls(b, w, z0, yz, cfg):
    """Incremental locally weighted PLS (Table 3, step 2) of the batch's RFs.

    Returns the projections s of the updated model (as used for predicting), the
    leave-one-out error e_cv (model before this update) and the error e after it, per RF.
    """
    lam = np.where(b.used, b.lam, 1.0)                          # unused slots stay as they are
    s = (b.T @ z0[:, :, None])[:, :, 0]                        # projections, old model
    shift = s[:, :, None] * b.P
    z = np.empty_like(shift)                                    # residual inputs z_r
    z[:, 0] = z0
    for r in range(1, b.R):
        np.subtract(z[:, r - 1], shift[:, r - 1], out=z[:, r])
    fitted = b.beta * s
    res = yz[:, None] - np.cumsum(fitted, axis=1)               # residual after stage r
    ww = w[:, None] * b.used
    w_res, w_s = ww * (res + fitted), ww * s                    # res + fitted: before stage r
    b.SXY *= (0.9 + 0.1 * lam)[:, :, None]                      # slower forgetting for u_r
    b.SXY += w_res[:, :, None] * z
    norm = np.sqrt(np.einsum("krd,krd->kr", b.SXY, b.SXY))[:, :, None]
    np.divide(b.SXY, norm, out=b.U, where=norm > 1e-12)
    b.SSs2 *= lam
    b.SSs2 += w_s * s
    b.SSY *= lam
    b.SSY += w_res * s
    b.SSX *= lam[:, :, None]
    b.SSX += w_s[:, :, None] * z
    np.divide(b.SSY, b.SSs2, out=b.beta)
    np.divide(b.SSX, b.SSs2[:, :, None], out=b.P)
    b.SSp[:] = b.at_last(lam) * b.SSp + w * (w_s * s / b.SSs2).sum(axis=1)
    b.T[:] = _projection_operator(b.U, b.P, b.top)
    s = (b.T @ z0[:, :, None])[:, :, 0] * _usable(b, cfg)      # projections, new model
    e = yz - (b.beta * s).sum(axis=1)
    _update_errors(b, w, ww * res * res, e, lam)
    b.trust |= b.n_data[:, 0] > 2 * cfg.n_in
    return s, b.at_last(res), e


def _projection_operator(U, P, n_used):
    """T with s = T z_1: forward substitution T_r = u_r - Σ_{q<r} (u_r·p_q) T_q."""
    T = U.copy()
    for r in range(1, n_used):
        coupling = P[:, :r] @ U[:, r, :, None]                  # (n, r, 1): u_r·p_q
        T[:, r] -= (coupling.transpose(0, 2, 1) @ T[:, :r])[:, 0]
    return T


def _usable(b, cfg):
    """Projections used for predicting: the last one only after 2 d samples (reference lib)."""
    usable = b.used.copy()
    usable[b.last] = b.at_last(b.n_data) > 2 * cfg.n_in
    return usable


def _update_errors(b, w, w_e_cv2, e, lam):
    """Accumulate the leave-one-out MSE per PLS stage and the fitted MSE (after some data)."""
    ready = b.n_data[:, 0] * (1 - b.lam[:, 0]) > 0.1
    sum_ecv2 = lam * b.sum_ecv2 + w_e_cv2
    sum_e2 = b.at_last(lam) * b.sum_e2 + w * e * e
    if not ready.all():
        sum_ecv2 = np.where(ready[:, None], sum_ecv2, b.sum_ecv2)
        sum_e2 = np.where(ready, sum_e2, b.sum_e2)
    b.sum_ecv2[:], b.sum_e2[:] = sum_ecv2, sum_e2


def _update_metric(b, w, x, s, e_cv, e, cfg):
    """One gradient step on M of the penalised leave-one-out cost J (Table 4).

    RFs whose first projection has seen fewer than 0.1 / (1 - λ) samples are left unchanged
    (their transient multiplier is set to 0).
    """
    lam = b.lam
    ok = b.used & (b.n_data > 0.1 / (1 - lam))
    ok &= ok[:, :1]
    Ps = np.where(ok, s / b.SSs2, 0.0)
    h = np.minimum(w * (Ps * s).sum(axis=1), 1 - 1e-6)
    W = b.sum_w[:, 0] * lam[:, 0] + w
    E = b.at_last(b.sum_ecv2)
    tm = np.minimum(1.0, (b.sum_e2 / (E + _TINY)) ** 4) * ok[:, 0]   # transient multiplier
    dJ1dw = ((e_cv * e_cv - 2 * e * (Ps * b.H).sum(axis=1) - 2 * (Ps * Ps * b.r).sum(axis=1)) / W
             - E / (W * W))
    x_c = x - b.c
    dq, dJ2 = _metric_gradients(b.M, x_c, cfg)
    col = _broadcaster(b.M)
    dwdM = col(-0.5 * w) * dq
    dJdM = dwdM * col(dJ1dw) + col(w / W) * dJ2
    if cfg.meta:
        terms = dict(w=w, W=W, E=E, e=e, e_cv=e_cv, h=h, s=s, Ps=Ps, dJ1dw=dJ1dw)
        d2JdM2 = _second_derivative(b, terms, dq, dwdM, x_c, cfg)
        _meta_rates(b, dJdM, d2JdM2, col(tm), cfg)
    step = b.alpha * dJdM * col(tm)
    too_big = np.abs(step) > col(0.1 * np.abs(b.M).reshape(len(w), -1).max(axis=1))
    if too_big.any():
        b.alpha[too_big] /= 2
        step[too_big] = 0.0
    b.M -= step
    trace = (w / (1 - h) * tm)[:, None] * s
    b.H[:] = np.where(ok, lam * b.H + trace * e_cv[:, None], b.H)
    b.r[:] = np.where(ok, lam * b.r + trace * s * (w * e_cv * e_cv)[:, None], b.r)


def _broadcaster(M):
    """Reshape an (n,) vector to broadcast against metric-shaped arrays (n, d[, d])."""
    shape = (-1,) + (1,) * (M.ndim - 1)
    return lambda v: np.reshape(v, shape)


def _metric_gradients(M, x_c, cfg):
    """dq/dM and dJ2/dM for q = |M x_c|² and the penalty J2 = γ Σ D_ij², D = Mᵀ M."""
    if cfg.diag_only:
        return 2.0 * M * x_c * x_c, 4.0 * cfg.gamma * M * M * M
    Mx = (M @ x_c[:, :, None])[:, :, 0]
    dq = 2.0 * Mx[:, :, None] * x_c[:, None, :] * cfg.metric_mask
    return dq, 4.0 * cfg.gamma * (M @ (M.transpose(0, 2, 1) @ M)) * cfg.metric_mask


def _second_derivative(b, v, dq, dwdM, x_c, cfg):
    """∂²J/∂M² (element-wise) for meta learning (Table 4)."""
    w, W, e, e_cv, Ps = v["w"], v["W"], v["e"], v["e_cv"], v["Ps"]
    Pse = Ps * e[:, None]
    sPse = (v["s"] * Pse).sum(axis=1)
    d2J1dw2 = (-e_cv ** 2 / W ** 2
               - 2 / W * ((-Pse / W[:, None] - 2 * Ps * sPse[:, None]) * b.H).sum(axis=1)
               + 2 / W * e ** 2 * v["h"] / w
               - (e_cv ** 2 - 2 * (Pse * b.H).sum(axis=1)) / W ** 2 + v["E"] / W ** 3)
    M, col = b.M, _broadcaster(b.M)
    if cfg.diag_only:
        d2q, d2J2 = 2.0 * x_c * x_c, 12.0 * cfg.gamma * M * M
    else:
        D = M.transpose(0, 2, 1) @ M
        d2q = 2.0 * (x_c * x_c)[:, None, :] * cfg.metric_mask
        d2J2 = 4.0 * cfg.gamma * (np.diagonal(D, axis1=1, axis2=2)[:, None, :]
                                  + (M * M).sum(axis=2)[:, :, None] + M * M) * cfg.metric_mask
    d2wdM2 = col(0.25 * w) * dq * dq - col(0.5 * w) * d2q
    return (d2wdM2 * col(v["dJ1dw"]) + dwdM * dwdM * col(d2J1dw2) + col(w / W) * d2J2)


def _meta_rates(b, dJdM, d2JdM2, tm, cfg):
    """Incremental delta-bar-delta on the learning rates α = exp(b) (Table 4, meta)."""
    b.b[:] = np.clip(b.b - np.clip(cfg.meta_rate * tm * dJdM * b.hm, -0.1, 0.1), -10.0, 10.0)
    b.alpha[:] = np.exp(b.b)
    b.hm[:] = b.hm * np.maximum(0.0, 1 - b.alpha * d2JdM2 * tm) - b.alpha * dJdM * tm


def _add_projections(b, cfg):
    """Add a PLS projection where MSE_R / MSE_{R-1} < add_threshold (with enough data)."""
    if b.top < 2:
        return
    before = (b.last[0], b.last[1] - 1)                     # the second to last projection
    n_last = b.at_last(b.n_data)
    mse_ratio = ((b.at_last(b.sum_ecv2) / b.at_last(b.sum_w) + _TINY)
                 / (b.sum_ecv2[before] / b.sum_w[before] + _TINY))
    add = ((b.n_reg >= 2) & (b.n_reg < cfg.n_proj_max) & (mse_ratio < cfg.add_threshold)
           & (n_last / b.n_data[:, 0] > 0.99) & (n_last * (1 - b.at_last(b.lam)) > 0.5))
    if add.any():
        rows = np.flatnonzero(add)
        R = b.n_reg[rows]
        b.U[rows, R, R] = b.P[rows, R, R] = 1.0       # the new slot keeps its initial stats
        b.SSp[rows] = 0.0
        b.n_reg[rows] += 1
        b.index_slots()
        b.T[:] = _projection_operator(b.U, b.P, b.top)


def _update_counts(b, w, cfg):
    """Discounted activation sums and data counts; anneal the forgetting factors λ."""
    used = b.used
    lam = np.where(used, b.lam, 1.0)
    b.sum_w *= lam
    b.sum_w += w[:, None] * used
    b.n_data *= lam
    b.n_data += used
    b.lam += used * ((cfg.tau_lambda - 1) * b.lam + cfg.final_lambda * (1 - cfg.tau_lambda))


class _Settings:
    """Hyperparameters resolved for an input dimensionality (read-only bag of values)."""

    def __init__(self, **values):
        self.__dict__.update(values)


class LWPR(RegressorMixin, BaseEstimator):
    """Locally Weighted Projection Regression (Vijayakumar, D'Souza & Schaal 2005).

    An incremental, online learner: ``partial_fit`` / ``update`` learn one sample after the
    other (the module docstring explains the algorithm and its simplifications). One
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
                 norm_out=None, kernel="gaussian", cutoff=1e-3, n_epochs=1):
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
        Y = np.vstack([self._predict_block(block) for block in _blocks(Xn)]) * self.norm_out_
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
        conf = np.array([rfs.confidence(x, rfs.activations(x[None], self.cutoff), self.cutoff)
                         for x in Xn]) * self.norm_out_
        return (Y[:, 0], conf[:, 0]) if self._y_1d else (Y, conf)

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
            b = _Batch(rfs, k, all_slots=True)
            fields.append(dict(c=b.c, x0=b.x0, D=rfs.metrics(k), M=b.M, beta0=b.beta0,
                               beta=b.beta, U=b.U, P=b.P, n_projections=b.n_reg,
                               n_data=b.n_data[:, 0], trustworthy=b.trust))
        return fields

    # ----------------------------------------------------------------- internals
    def _learn(self, X, Y):
        """Learn the rows in order; returns the normalised predictions made before each."""
        Xn, Yn = X / self.norm_in_, Y / self.norm_out_
        before = np.empty_like(Yn)
        for i, (x, y) in enumerate(zip(Xn, Yn)):
            before[i] = self._learn_one(x, y)
        self.n_data_ += len(X)
        return before

    def _predict_block(self, X):
        return self._rfs.combine(X, self._rfs.activations(X, self.cutoff), self.cutoff)

    def _learn_one(self, x, y):
        """Learn one normalised sample; returns the prediction made before learning it."""
        rfs, cfg = self._rfs, self._settings
        pairs = rfs.activations(x[None], min(self.cutoff, UPDATE_CUTOFF, cfg.w_gen))
        prediction = rfs.combine(x[None], pairs, self.cutoff)[0]
        _, near, w = pairs
        active = w > UPDATE_CUTOFF
        if active.any():
            rfs.learn(near[active], w[active], x, y)
        self._create_and_prune(near, w, x, y)
        return prediction

    def _create_and_prune(self, near, w, x, y):
        """New RF for outputs without activation above w_gen; prune pairs above w_prune.

        ``near``: the RFs activated above min(w_gen, 0.001) and their activations ``w``.
        """
        rfs, cfg = self._rfs, self._settings
        out = rfs.out[near]
        covered = np.bincount(out[w > cfg.w_gen], minlength=self.n_outputs_)
        if covered.all() and (np.bincount(out[w > cfg.w_prune]) < 2).all():
            return                                           # the common case: nothing to do
        order = np.lexsort((-w, out))                        # by output, most active first
        near, w, out = near[order], w[order], out[order]
        first = np.flatnonzero(np.r_[True, out[1:] != out[:-1]]) if near.size else near
        self._create(near[first], w[first], out[first], x, y)
        first = first[first + 1 < len(out)]
        pairs = first[(out[first + 1] == out[first]) & (w[first + 1] > cfg.w_prune)]
        victims = [self._victim(near[i], near[i + 1]) for i in pairs]
        for k in sorted(victims, reverse=True):              # highest row first: rows stay valid
            self.n_pruned_[rfs.out[k]] += 1
            rfs.remove(k)

    def _create(self, best, best_w, best_out, x, y):
        """A new RF at x for every output whose most active RF (``best``) is below w_gen.

        The new RF copies M and α of that RF if it is trustworthy and activated above
        0.1 w_gen (reference library), else starts from init_D and init_alpha.
        """
        rfs, cfg = self._rfs, self._settings
        top_w, top = np.zeros(self.n_outputs_), np.full(self.n_outputs_, -1)
        top_w[best_out], top[best_out] = best_w, best
        outs = np.flatnonzero(top_w <= cfg.w_gen)
        if not outs.size:
            return
        k = top[outs]
        copy = (k >= 0) & (top_w[outs] > 0.1 * cfg.w_gen) & rfs.trust[k]
        start = np.stack((cfg.init_M, cfg.init_alpha))
        copy = copy.reshape((-1,) + (1,) * start.ndim)
        M, alpha = np.where(copy, rfs.metric[k, :2], start).swapaxes(0, 1)
        rfs.add(outs, x, y[outs], M, alpha)

    def _victim(self, k1, k2):
        """Of two overlapping RFs, the narrower one (larger det D), else the worse one."""
        ld = self._rfs.log_det_D(np.array([k1, k2]))
        if abs(ld[0] - ld[1]) > 1e-9 * max(1.0, abs(ld[0])):
            return k1 if ld[0] > ld[1] else k2
        mse = self._rfs.loo_mse(np.array([k1, k2]))
        return k1 if mse[0] > mse[1] else k2

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
            _check_unit(getattr(self, name), name)
        for name in ("penalty", "meta_rate", "add_threshold", "init_S2"):
            check_float(getattr(self, name), name, minimum=0)
        check_float(self.cutoff, "cutoff", minimum=0)
        for name in ("update_D", "meta", "diag_only"):
            if not isinstance(getattr(self, name), (bool, np.bool_)):
                raise ValueError(f"{name} must be a bool, got {getattr(self, name)!r}")
        if str(self.kernel).lower() != "gaussian":
            raise ValueError(f"kernel must be 'gaussian' (the only kernel implemented), got "
                             f"{self.kernel!r}")
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
            add_threshold=float(self.add_threshold), init_S2=max(float(self.init_S2), 1e-300))

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


def _blocks(X):
    return [X[i:i + _QUERY_BLOCK] for i in range(0, len(X), _QUERY_BLOCK)]


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


def _check_unit(value, name):
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not 0 < value <= 1:
        raise ValueError(f"{name} must be a number in (0, 1], got {value!r}")


def _check_open_unit(value, name):
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not 0 < value < 1:
        raise ValueError(f"{name} must be a number in (0, 1), got {value!r}")
