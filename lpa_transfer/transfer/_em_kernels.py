"""Compiled kernels of LPA's mixture fit: the E-step of the EM (thesis §3.4, eq. 3.8-3.9)
fused with the M-step's sums (:func:`em_sums`), and initEM's Lloyd iterations (§3.5, Alg. 5;
:func:`lloyd_two_means`).

Why compiled: LPA's mixtures have hundreds of components in a low-dimensional clustering
space (438 on the 2-link §3.6 pair at N = 5000), so a point's log-densities are a few
multiply-adds each, and most of a point's responsibilities are negligible. In numpy every
step (matrix product, peak, exp, normalisation, sums) is a pass over an (N, K) array, and
the passes, not the arithmetic, dominated the fit. One point at a time in compiled code
(numba, ``cache=True`` as the LWPR kernels) the same arithmetic stays in cache and the
negligible entries are skipped.

Same operations as gmm._em_iteration's numpy path, entry by entry: the log-density is the
dot product of the point's quadratic features with the component's coefficients plus its
constant; log-ratios to the row's peak are clamped at ``log_floor`` before exp; γ = e / Σe.
The numpy path adds the clamped entries (e^-700 ≈ 1e-304 of the peak's 1) to the M-step
sums too; here they are left out, which changes no sum by more than its last bit; and
log-ratios below -512 take exp by halves (``_SLOW_EXP``). Sums run
in another order than BLAS', so results agree to rounding (test_local_procrustes.py).
No fast-math: it would reorder operations.
"""
import math

import numpy as np
from numba import njit

#: Below this argument the C library's exp (glibc) leaves its fast path, about 4x slower per
#: call (docs/history.md); there e^r is computed as (e^(r/2))², equal to an ulp or two. Such
#: entries are below 1e-222 of their row's peak.
_SLOW_EXP = -512.0


@njit(inline="always")
def _add_constant(log_density, constant):
    """Adds ``constant`` to ``log_density`` in place; returns the largest entry and a number
    that is finite only when every entry is (0 * inf and 0 * nan are nan). Four independent
    accumulators, so the pass is not one serial chain of compares: max is exact in any
    order, and the check is 0 or nan whatever the order."""
    n_components = constant.shape[0]
    peak0 = peak1 = peak2 = peak3 = -np.inf
    check0 = check1 = check2 = check3 = 0.0
    whole = n_components - n_components % 4
    for k in range(0, whole, 4):
        value0 = log_density[k] + constant[k]
        value1 = log_density[k + 1] + constant[k + 1]
        value2 = log_density[k + 2] + constant[k + 2]
        value3 = log_density[k + 3] + constant[k + 3]
        log_density[k], log_density[k + 1] = value0, value1
        log_density[k + 2], log_density[k + 3] = value2, value3
        check0 += 0.0 * value0
        check1 += 0.0 * value1
        check2 += 0.0 * value2
        check3 += 0.0 * value3
        peak0, peak1 = max(peak0, value0), max(peak1, value1)
        peak2, peak3 = max(peak2, value2), max(peak3, value3)
    for k in range(whole, n_components):
        value0 = log_density[k] + constant[k]
        log_density[k] = value0
        check0 += 0.0 * value0
        peak0 = max(peak0, value0)
    return max(max(peak0, peak1), max(peak2, peak3)), (check0 + check1) + (check2 + check3)


@njit(cache=True)
def em_sums(features, coefficients, constant, log_floor, exp_floor, prune, with_sums=True):
    """Σ_i log p(x_i), n_k = Σ_i γ_ik and Σ_i γ_ik features_i, under the given mixture.
    ``with_sums`` False computes Σ_i log p(x_i) alone (n_k and the sums stay 0).

    Entries whose log-ratio to their row's peak is at most ``prune`` (>= ``log_floor``) are
    left out of the sums and the row's total: each is below e^prune of the peak's share
    (gmm.py says when that stays within rounding and when it reruns with ``prune`` at the
    floor, which is the numpy path's arithmetic).

    ``features`` (N, F) are the points' quadratic features, ``coefficients`` (F, K) and
    ``constant`` (K,) the mixture's (gmm.Responsibilities). Rows whose log-densities are
    not finite (points so far away that the expanded quadratic overflows) are not summed;
    they are flagged in ``far`` (N,) for the caller.
    """
    n_rows, n_features = features.shape
    n_components = constant.shape[0]
    sums = np.zeros((n_components, n_features))
    n_k = np.zeros(n_components)
    far = np.zeros(n_rows, dtype=np.bool_)
    log_density = np.empty(n_components)
    live = np.empty(n_components, dtype=np.intp)
    log_likelihood = 0.0
    for i in range(n_rows):
        for k in range(n_components):
            log_density[k] = 0.0
        for f in range(n_features):
            value = features[i, f]
            for k in range(n_components):
                log_density[k] += value * coefficients[f, k]
        peak, check = _add_constant(log_density, constant)
        if not math.isfinite(check):
            far[i] = True
            continue
        n_live = 0                       # the entries above the cut, without branches
        n_floored = 0
        for k in range(n_components):
            ratio = log_density[k] - peak
            live[n_live] = k
            n_live += ratio > prune
            n_floored += ratio <= log_floor
        total = n_floored * exp_floor
        for j in range(n_live):
            k = live[j]
            ratio = log_density[k] - peak
            if ratio > _SLOW_EXP:
                log_density[k] = math.exp(ratio)
            else:
                half = math.exp(0.5 * ratio)
                log_density[k] = half * half
            total += log_density[k]
        log_likelihood += peak + math.log(total)
        if not with_sums:
            continue
        for j in range(n_live):
            k = live[j]
            gamma = log_density[k] / total
            n_k[k] += gamma
            for f in range(n_features):
                sums[k, f] += gamma * features[i, f]
    return log_likelihood, n_k, sums, far


#: numpy's pairwise summation adds blocks of up to this many terms with 8 accumulators
#: (numpy/_core/src/umath/loops_utils.h.src, PW_BLOCKSIZE); longer rows are not compiled here.
PAIRWISE_BLOCK = 128


@njit(inline="always")
def _squared_distance(X, i, centres, c):
    """||X[i] - centres[c]||², summed in the order of numpy's ``(diff ** 2).sum(axis=-1)``
    for rows of at most PAIRWISE_BLOCK terms: plainly below 8 terms, else 8 interleaved
    partial sums joined pairwise, then the rest."""
    n_dims = X.shape[1]
    if n_dims < 8:
        total = 0.0
        for j in range(n_dims):
            diff = X[i, j] - centres[c, j]
            total += diff * diff
        return total
    partial = np.empty(8)
    for j in range(8):
        diff = X[i, j] - centres[c, j]
        partial[j] = diff * diff
    j = 8
    while j < n_dims - n_dims % 8:
        for u in range(8):
            diff = X[i, j + u] - centres[c, j + u]
            partial[u] += diff * diff
        j += 8
    total = ((partial[0] + partial[1]) + (partial[2] + partial[3])) + \
        ((partial[4] + partial[5]) + (partial[6] + partial[7]))
    while j < n_dims:
        diff = X[i, j] - centres[c, j]
        total += diff * diff
        j += 1
    return total


@njit(cache=True)
def lloyd_two_means(X, groups, centres, max_iterations):
    """Lloyd's iterations of init_em.two_means for all groups at once, with its arithmetic
    (distances summed as numpy sums them, centre sums accumulated in row order as
    ``bincount``): the same halves bit for bit. ``centres`` (2G, d) holds each group's two
    seeds (rows 2g, 2g + 1) and is updated in place; returns the rows that go to the second
    half (True where the second centre is strictly nearer).
    """
    n_rows, n_dims = X.shape
    n_cells = centres.shape[0]
    assignment = np.zeros(n_rows, dtype=np.bool_)
    second_half = np.zeros(n_rows, dtype=np.bool_)
    for iteration in range(max_iterations):
        changed = iteration == 0
        for i in range(n_rows):
            cell = 2 * groups[i]
            nearer = _squared_distance(X, i, centres, cell + 1) < \
                _squared_distance(X, i, centres, cell)
            changed |= nearer != second_half[i]
            assignment[i] = nearer
        if not changed:
            break
        second_half[:] = assignment
        sizes = np.zeros(n_cells)
        sums = np.zeros((n_cells, n_dims))
        for i in range(n_rows):
            cell = 2 * groups[i] + second_half[i]
            sizes[cell] += 1.0
            for j in range(n_dims):
                sums[cell, j] += X[i, j]
        for cell in range(n_cells):
            if sizes[cell] > 0:
                for j in range(n_dims):
                    centres[cell, j] = sums[cell, j] / sizes[cell]
    return second_half
