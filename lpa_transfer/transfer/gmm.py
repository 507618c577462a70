"""Gaussian mixture in the source input space (thesis §3.4, eq. 3.8-3.9, 3.11).

Plain functions over stacked parameter arrays, vectorised across all K components (no Python
loop over components), because LPA fits mixtures with hundreds of components (one per local
linear map). Parameters follow scikit-learn's ``GaussianMixture(covariance_type="full")``:
``weights`` (K,), ``means`` (K, d), ``covariances`` (K, d, d) and the upper-triangular
``precisions_cholesky`` P with Σ⁻¹ = P Pᵀ.
"""
import numpy as np

from lpa_transfer.transfer import _em_kernels, _transfer_kernels
from lpa_transfer.transfer.procrustes import grouped_moments

_LOG_2PI = np.log(2.0 * np.pi)
_LOG_FLOOR = -700.0
_EXP_FLOOR = np.exp(np.full(1, _LOG_FLOOR))[0]
#: The compiled E-step leaves out responsibilities below e^_PRUNE of their row's largest
#: (see _em_iteration).
_PRUNE = -50.0
#: Work-array size per block of rows: small enough to stay in cache.
_BLOCK_ELEMENTS = 1 << 17


def precisions_cholesky(covariances):
    """Upper-triangular P_k with Σ_k⁻¹ = P_k P_kᵀ, for a stack of covariances."""
    try:
        lower = np.linalg.cholesky(covariances)
    except np.linalg.LinAlgError:
        raise ValueError("a mixture component has a singular covariance; increase reg_covar "
                         "or n_min") from None
    return np.swapaxes(np.linalg.inv(lower), 1, 2)


def from_partition(X, labels, n_components, reg_covar):
    """Mixture parameters of a hard partition (Alg. 5 line 17): weights, means, covariances."""
    counts, means, covariances = grouped_moments(X, labels, n_components)
    covariances += reg_covar * np.eye(X.shape[1])
    return counts / len(X), means, covariances


def row_blocks(n_rows, row_elements):
    """Row slices whose (rows, row_elements) work arrays hold about ``_BLOCK_ELEMENTS``."""
    step = max(1, _BLOCK_ELEMENTS // row_elements)
    return [slice(start, start + step) for start in range(0, n_rows, step)]


def quadratic_features(X, centre=None):
    """[x_i x_j for i <= j, x]: the (N, d(d+1)/2 + d) features of a quadratic form, of the
    rows of X less ``centre`` if given (the same bits as of ``X - centre``).

    Returned column-major (a transposed view), built one contiguous column per product.
    """
    if centre is None:
        centre = np.zeros(X.shape[1])
    return _transfer_kernels.quadratic_feature_rows(X, np.asarray(centre, dtype=float)).T


def _simd_exp():
    """Whether numpy's float64 exp is SIMD code here: on x86-64 only with AVX512F, which
    tools/env.sh masks for reproducible results. Otherwise numpy calls the C library's exp
    element by element, which is slower still for large negative arguments."""
    try:
        from numpy._core._multiarray_umath import __cpu_features__
    except ImportError:                                   # numpy < 2
        try:
            from numpy.core._multiarray_umath import __cpu_features__
        except ImportError:
            return False
    return bool(__cpu_features__.get("AVX512F"))


_SIMD_EXP = _simd_exp()


def _floored_exp(log_values):
    """exp(max(v, -700)) in place, for the log-ratios v ≤ 0 of eq. 3.9 to their row's peak.

    e^-700 ≈ 1e-304 is already negligible next to the peak's 1; clamping keeps exp out of
    the denormal range, where it is much slower (docs/history.md). Far from its component a
    point's entries sit at the floor; with a scalar exp (see :func:`_simd_exp`), when fewer
    than half of the entries are above the floor, exp runs on those only (gathered by index)
    and the others are set to e^-700. Both ways give the same bits: each entry is the same
    exp of the same value.
    """
    if _SIMD_EXP or not log_values.flags.c_contiguous:
        live = None
    else:
        live = log_values > _LOG_FLOOR
    if live is None or 2 * np.count_nonzero(live) >= log_values.size:
        np.maximum(log_values, _LOG_FLOOR, out=log_values)
        return np.exp(log_values, out=log_values)
    flat = log_values.reshape(-1)                                # a view (contiguous)
    index = np.flatnonzero(live)
    values = np.exp(flat.take(index))
    flat.fill(_EXP_FLOOR)
    flat.put(index, values)
    return log_values


class Responsibilities:
    """Evaluates γ_k(x) (eq. 3.9/3.11) and log p(x) (eq. 3.8) for blocks of rows.

    The Mahalanobis term is expanded, (x−μ)ᵀΛ(x−μ) = Σ_{i≤j} c_ij x_i x_j − 2 xᵀΛμ + μᵀΛμ,
    so that log π_k N(x | μ_k, Σ_k) for all K components is one matrix product of
    :func:`quadratic_features` with a (d(d+1)/2 + d, K) coefficient matrix. Rows are
    expressed relative to ``centre`` (default: the mixture's mean) to limit cancellation.
    """

    def __init__(self, weights, means, precisions_chol, centre=None):
        dim = means.shape[1]
        self.means, self.precisions_chol = means, precisions_chol
        self.centre = weights @ means if centre is None else centre
        means = means - self.centre
        precision = precisions_chol @ np.swapaxes(precisions_chol, 1, 2)      # Λ_k = P Pᵀ
        linear = np.einsum("kij,kj->ki", precision, means)
        upper = np.triu_indices(dim)
        quadratic = np.where(upper[0] == upper[1], -0.5, -1.0) * precision[:, upper[0], upper[1]]
        self.coefficients = np.vstack((quadratic.T, linear.T))
        self.constant = (np.log(weights) - 0.5 * dim * _LOG_2PI
                         + np.log(np.diagonal(precisions_chol, axis1=1, axis2=2)).sum(axis=1)
                         - 0.5 * np.einsum("ki,ki->k", means, linear))

    def blocks(self, X, features=None):
        """Yield ``(rows, γ (R, K), log p(x) (R,))`` for consecutive blocks of rows of X.

        ``features`` may hold precomputed :func:`quadratic_features` of the centred X. The
        log-densities are one BLAS product per block; the rest of eq. 3.9 runs in compiled
        code (:func:`_transfer_kernels.block_responsibilities`), or in numpy where numpy's exp
        is SIMD code (:func:`_simd_exp`), whose bits the C library's exp would not match.
        """
        width = max(len(self.constant), len(self.coefficients))
        for rows in row_blocks(len(X), width):
            with np.errstate(over="ignore", invalid="ignore"):   # far points: handled below
                block = (quadratic_features(X[rows], self.centre) if features is None
                         else features[rows])
                weighted = block @ self.coefficients
            if _SIMD_EXP:
                resp, log_norm, far = self._numpy_block(weighted)
            else:
                far, peak, total = _transfer_kernels.block_responsibilities(
                    weighted, self.constant, _LOG_FLOOR, _EXP_FLOOR)
                resp, log_norm = weighted, peak + np.log(total)
            if far.any():
                start = rows.start if isinstance(rows, slice) else 0
                resp[far], log_norm[far] = self._far(X[start + np.flatnonzero(far)])
            yield rows, resp, log_norm

    def _numpy_block(self, weighted):
        """γ, log p(x) and the far rows of a block from its log-densities less the constant,
        in numpy: what :func:`_transfer_kernels.block_responsibilities` computes."""
        weighted += self.constant
        far = ~np.isfinite(weighted).all(axis=1)
        if far.any():
            weighted[far] = 0.0               # set by the caller, from the rescaled distances
        peak = weighted.max(axis=1, keepdims=True)
        weighted -= peak
        resp = _floored_exp(weighted)
        total = resp.sum(axis=1, keepdims=True)
        resp /= total
        return resp, peak[:, 0] + np.log(total[:, 0]), far

    def _far(self, X):
        """γ and log p(x) of finite points so far from the mixture that the expanded quadratic
        overflows (|x| beyond ~1e154): all of γ on the component nearest in Mahalanobis
        distance, computed on rows rescaled by their largest offset (the weights' and
        normalisers' differences vanish at that distance); log p(x) is -inf."""
        offsets = X[:, None, :] - self.means[None]                          # (R, K, d)
        scale = np.abs(offsets).max(axis=2, keepdims=True)
        scale[scale == 0] = 1.0
        whitened = np.einsum("rki,kij->rkj", offsets / scale, self.precisions_chol)
        log_distance = np.log(scale[..., 0]) + 0.5 * np.log(
            np.einsum("rkj,rkj->rk", whitened, whitened))
        resp = np.zeros(log_distance.shape)
        resp[np.arange(len(X)), np.argmin(log_distance, axis=1)] = 1.0
        return resp, np.full(len(X), -np.inf)


def log_likelihoods(X, weights, means, precisions_chol):
    """log p(x) (eq. 3.8) for every row of X."""
    out = np.empty(len(X))
    for rows, _, log_norm in Responsibilities(weights, means, precisions_chol).blocks(X):
        out[rows] = log_norm
    return out


def responsibilities(X, weights, means, precisions_chol):
    """γ_k(x) (eq. 3.9/3.11) of every row of X for every component: (N, K)."""
    out = np.empty((len(X), len(weights)))
    for rows, resp, _ in Responsibilities(weights, means, precisions_chol).blocks(X):
        out[rows] = resp
    return out


def mean_log_likelihood(X, weights, means, covariances):
    """Average log-likelihood of X under the mixture; used to rank initEM runs (§3.5).

    Computed as the EM's compiled E-step computes it (:func:`_em_iteration`, without the
    M-step's sums): it leaves out entries below e^_PRUNE of a row's peak, which changes the
    row's total by less than K·e^_PRUNE relative, within the rounding of its log. Points so
    far away that the expanded quadratic overflows take the numpy path.
    """
    precisions_chol = precisions_cholesky(covariances)
    centre = X.mean(axis=0)
    features = np.ascontiguousarray(quadratic_features(X - centre))
    centred = Responsibilities(weights, means - centre, precisions_chol, np.zeros(X.shape[1]))
    log_likelihood, _, _, far = _compiled_sums(features, centred, _PRUNE, with_sums=False)
    if np.any(far):
        return log_likelihoods(X, weights, means, precisions_chol).mean()
    return log_likelihood / len(X)


def _em_iteration(X, features, weights, means, precisions_chol, reg_covar, compiled=True):
    """One E-step fused with the M-step's sums (full covariances).

    ``X`` is centred (the EM works relative to the data mean) and ``features`` holds its
    :func:`quadratic_features`. Returns the mean log-likelihood under the old parameters
    and the new weights, means and covariances. The sums run in compiled code
    (:mod:`._em_kernels`) point by point; the numpy path (block by block, also taken when a
    point is so far away that its quadratic overflows) computes the same to rounding.

    The compiled sums leave out the responsibilities below e^_PRUNE (2e-22) of their row's
    largest, most of a point's entries when hundreds of components lie in a low-dimensional
    space. Left out, they change a row's total (at least 1) by less than K·e^_PRUNE, and a
    component's n_k by less than N·e^_PRUNE, which is within rounding unless n_k itself is
    below N·e^_PRUNE/ε; then the iteration runs again without the cut.
    """
    dim = X.shape[1]
    responsibilities = Responsibilities(weights, means, precisions_chol, np.zeros(dim))
    far = True
    if compiled:
        log_likelihood, n_k, sums, far = _compiled_sums(features, responsibilities, _PRUNE)
        if not np.any(far) and n_k.min() < len(X) * np.exp(_PRUNE) / np.finfo(float).eps:
            log_likelihood, n_k, sums, far = _compiled_sums(features, responsibilities,
                                                            _LOG_FLOOR)
    if np.any(far):
        log_likelihood, n_k, sums = _em_sums_numpy(X, features, responsibilities)
    return _m_step(log_likelihood, n_k, sums, len(X), dim, reg_covar)


def _compiled_sums(features, responsibilities, prune, with_sums=True):
    """:func:`_em_kernels.em_sums` of rows given by their quadratic ``features`` under the
    mixture of ``responsibilities`` (centred at 0), entries at most ``prune`` below their
    row's peak left out: (Σ log p(x), n_k, Σ γ features, far rows)."""
    return _em_kernels.em_sums(np.ascontiguousarray(features),
                               np.ascontiguousarray(responsibilities.coefficients),
                               responsibilities.constant, _LOG_FLOOR, _EXP_FLOOR, prune,
                               with_sums)


def _em_sums_numpy(X, features, responsibilities):
    """Σ log p(x), n_k and Σ γ features of :func:`_em_iteration`, block by block in numpy."""
    n_components = len(responsibilities.constant)
    sums = np.zeros((n_components, features.shape[1]))      # Σ γ x_i x_j (i ≤ j) and Σ γ x
    n_k = np.zeros(n_components)
    log_likelihood = 0.0
    for rows, resp, log_norm in responsibilities.blocks(X, features):
        log_likelihood += log_norm.sum()
        n_k += resp.sum(axis=0)
        sums += resp.T @ features[rows]
    return log_likelihood, n_k, sums


def _m_step(log_likelihood, n_k, sums, n_rows, dim, reg_covar):
    """Weights, means and full covariances from the E-step's sums (the M-step of §3.4's EM)."""
    n_components = len(n_k)
    n_k = n_k + 10 * np.finfo(float).eps
    upper = np.triu_indices(dim)
    second = np.empty((n_components, dim, dim))
    second[:, upper[0], upper[1]] = sums[:, :len(upper[0])]
    second[:, upper[1], upper[0]] = sums[:, :len(upper[0])]
    means = sums[:, len(upper[0]):] / n_k[:, None]
    covariances = second / n_k[:, None, None] - means[:, :, None] * means[:, None, :]
    covariances += reg_covar * np.eye(dim)
    return log_likelihood / n_rows, n_k / n_rows, means, covariances


def fit_em(X, weights, means, covariances, reg_covar=1e-6, max_iter=100, tol=1e-3):
    """Expectation-Maximisation from an initial mixture (Alg. 3 line 4, fitGMM).

    Stops when the mean log-likelihood changes by less than ``tol`` (scikit-learn's rule).
    Returns ``(weights, means, covariances, precisions_chol, mean_log_likelihood, n_iter,
    converged)``.
    """
    offset = X.mean(axis=0)                  # centring keeps the moment form well conditioned
    X = X - offset
    means = means - offset
    features = np.ascontiguousarray(quadratic_features(X))     # row-major once, for the kernel
    precisions_chol = precisions_cholesky(covariances)
    log_likelihood, converged, n_iter = -np.inf, False, 0
    for n_iter in range(1, max_iter + 1):
        previous = log_likelihood
        log_likelihood, weights, means, covariances = _em_iteration(
            X, features, weights, means, precisions_chol, reg_covar)
        precisions_chol = precisions_cholesky(covariances)
        if abs(log_likelihood - previous) < tol:
            converged = True
            break
    return (weights, means + offset, covariances, precisions_chol, log_likelihood, n_iter,
            converged)
