"""Compiled kernels of LPA transfer (thesis Alg. 4, eq. 3.11-3.12): the responsibilities of
a block of rows from its log-densities, the collection of the non-negligible (point, k)
pairs, their sort by cluster and the weighted sum of the local maps' values.

Why compiled: with a few clusters per point out of ~20, numpy spent most of a transfer in
passes over (rows, K) arrays (constant, peak, exp, sum, division, the pair indices) and over
the pairs (sort, gathers, scatters), not in the two matrix products, which stay BLAS calls.

Same operations as the numpy code they replace (gmm.Responsibilities.blocks and the sparse
path of local_procrustes.mix_local_maps), entry by entry and in the same order, so the
results are the same bits: exp of the same values (the C library's, as numpy's without
AVX-512), entries at or below ``log_floor`` set to e^log_floor, each row's total summed in
numpy's pairwise order (:func:`_pairwise_sum`), a point's weighted terms added in increasing
k. No fast-math: it would reorder operations.
"""
import math

import numpy as np
from numba import njit

#: numpy's pairwise summation adds up to this many terms with 8 accumulators and splits
#: longer runs in halves (numpy/_core/src/umath/loops_utils.h.src, PW_BLOCKSIZE).
_PAIRWISE_BLOCK = 128


@njit(inline="always")
def _block_sum(values, start, n):
    """Σ values[start:start + n], n <= _PAIRWISE_BLOCK, as numpy's pairwise sum adds a block:
    plainly below 8 terms, else 8 interleaved partial sums joined pairwise, then the rest."""
    if n < 8:
        total = 0.0
        for i in range(start, start + n):
            total += values[i]
        return total
    r0, r1, r2, r3 = values[start], values[start + 1], values[start + 2], values[start + 3]
    r4, r5, r6, r7 = values[start + 4], values[start + 5], values[start + 6], values[start + 7]
    whole = n - n % 8
    i = 8
    while i < whole:
        j = start + i
        r0 += values[j]
        r1 += values[j + 1]
        r2 += values[j + 2]
        r3 += values[j + 3]
        r4 += values[j + 4]
        r5 += values[j + 5]
        r6 += values[j + 6]
        r7 += values[j + 7]
        i += 8
    total = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    while i < n:
        total += values[start + i]
        i += 1
    return total


@njit(cache=True)
def _pairwise_sum(values, n):
    """Σ values[:n] in the order of numpy's ``sum`` along a contiguous row: blocks of at most
    _PAIRWISE_BLOCK terms, longer runs split in halves (a multiple of 8 first) whose sums are
    added. The halving is walked with an explicit stack (numba's recursion is avoided)."""
    if n <= _PAIRWISE_BLOCK:
        return _block_sum(values, 0, n)
    starts = np.empty(64, dtype=np.intp)
    sizes = np.empty(64, dtype=np.intp)
    state = np.zeros(64, dtype=np.intp)        # 0: left half next, 1: right half, 2: join
    sums = np.empty(64)
    depth, n_sums = 0, 0
    starts[0], sizes[0] = 0, n
    while depth >= 0:
        size = sizes[depth]
        if size <= _PAIRWISE_BLOCK:
            sums[n_sums] = _block_sum(values, starts[depth], size)
            n_sums += 1
            depth -= 1
            continue
        half = size // 2
        half -= half % 8
        if state[depth] == 0:
            state[depth] = 1
            starts[depth + 1], sizes[depth + 1], state[depth + 1] = starts[depth], half, 0
            depth += 1
        elif state[depth] == 1:
            state[depth] = 2
            starts[depth + 1], sizes[depth + 1] = starts[depth] + half, size - half
            state[depth + 1] = 0
            depth += 1
        else:
            n_sums -= 1
            sums[n_sums - 1] = sums[n_sums - 1] + sums[n_sums]
            depth -= 1
    return sums[0]


@njit(cache=True)
def quadratic_feature_rows(X, centre):
    """The (d(d+1)/2 + d, N) features of gmm.quadratic_features (row-major, one row per
    feature) of the rows of X less ``centre``: x_i x_j for i <= j in the order of
    np.triu_indices(d), then x."""
    n_rows, dim = X.shape
    out = np.empty((dim * (dim + 1) // 2 + dim, n_rows))
    centred = np.empty((dim, n_rows))
    for r in range(n_rows):
        for i in range(dim):
            centred[i, r] = X[r, i] - centre[i]
    feature = 0
    for i in range(dim):
        for j in range(i, dim):
            for r in range(n_rows):
                out[feature, r] = centred[i, r] * centred[j, r]
            feature += 1
    out[feature:] = centred
    return out


@njit(cache=True)
def block_responsibilities(weighted, constant, log_floor, exp_floor):
    """γ (eq. 3.9/3.11) in place of ``weighted`` (R, K), the rows' log π_k N(x | μ_k, Σ_k)
    less ``constant`` (K,). Returns the rows whose log-densities are not all finite (their
    γ and log p(x) are left to the caller), each row's peak log-density and its total Σe
    (log p(x) = peak + log total).

    Per row as gmm.Responsibilities' numpy path: add the constant, subtract the row's peak,
    e = exp(v) above ``log_floor`` and ``exp_floor`` = e^log_floor at or below it,
    γ = e / Σe (pairwise order).
    """
    n_rows, n_components = weighted.shape
    far = np.zeros(n_rows, dtype=np.bool_)
    peaks = np.zeros(n_rows)
    totals = np.ones(n_rows)
    live = np.empty(n_components, dtype=np.intp)
    ratios = np.empty(n_components)
    for i in range(n_rows):
        peak = -np.inf
        check = 0.0                                # 0, or nan if an entry is not finite
        for k in range(n_components):
            value = weighted[i, k] + constant[k]
            weighted[i, k] = value
            check += 0.0 * value
            peak = max(peak, value)
        if not math.isfinite(check):
            far[i] = True
            continue
        # exp only above the floor, on indices gathered without branches: a conditional exp
        # may be computed for every entry and then selected (LLVM speculates it), and exp far
        # below the floor is slow.
        n_live = 0
        for k in range(n_components):
            ratio = weighted[i, k] - peak
            ratios[k] = ratio
            weighted[i, k] = exp_floor
            live[n_live] = k
            n_live += ratio > log_floor
        for j in range(n_live):
            k = live[j]
            weighted[i, k] = math.exp(ratios[k])
        total = _pairwise_sum(weighted[i], n_components)
        for k in range(n_components):
            weighted[i, k] /= total
        peaks[i], totals[i] = peak, total
    return far, peaks, totals


@njit(cache=True)
def count_at_least(values, threshold):
    """How many entries of ``values`` (R, K) are >= ``threshold``."""
    count = 0
    for i in range(values.shape[0]):
        for k in range(values.shape[1]):
            count += values[i, k] >= threshold
    return count


@njit(cache=True)
def responsible_pairs(gamma, threshold, first_row, points, components, weights, size):
    """Appends the entries of ``gamma`` (R, K) with γ ≥ ``threshold`` at ``size`` in
    ``points`` (their row + ``first_row``), ``components`` and ``weights``, point by point in
    increasing k. Returns the new size."""
    n_rows, n_components = gamma.shape
    for i in range(n_rows):
        for k in range(n_components):
            value = gamma[i, k]
            if value >= threshold:
                points[size] = first_row + i
                components[size] = k
                weights[size] = value
                size += 1
    return size


@njit(cache=True)
def sort_by_cluster(points, components, weights, n_clusters):
    """The pairs sorted by cluster, stably (a counting sort): their points and weights, the
    cluster bounds (K + 1,) and whether each pair is its point's first (the one with the
    smallest k). The pairs come point by point in increasing k."""
    n_pairs = len(points)
    bounds = np.zeros(n_clusters + 1, dtype=np.intp)
    for j in range(n_pairs):
        bounds[components[j] + 1] += 1
    for k in range(n_clusters):
        bounds[k + 1] += bounds[k]
    fill = bounds[:-1].copy()
    sorted_points = np.empty(n_pairs, dtype=np.intp)
    sorted_weights = np.empty(n_pairs)
    first = np.empty(n_pairs, dtype=np.bool_)
    for j in range(n_pairs):
        slot = fill[components[j]]
        sorted_points[slot] = points[j]
        sorted_weights[slot] = weights[j]
        first[slot] = j == 0 or points[j] != points[j - 1]
        fill[components[j]] += 1
    return sorted_points, sorted_weights, bounds, first


@njit(cache=True)
def blend(local, points, weights, first, intercept, out):
    """The weighted terms γ (W_k z_p + b_k) of one cluster's pairs into their points' rows
    of ``out``: assigned for a point's first pair, added for the others. ``local`` holds
    W_k z_p (the BLAS product); b_k is added, then the sum is scaled by γ, as numpy did."""
    n_out = out.shape[1]
    for j in range(len(points)):
        p, gamma = points[j], weights[j]
        if first[j]:
            for t in range(n_out):
                out[p, t] = (local[j, t] + intercept[t]) * gamma
        else:
            for t in range(n_out):
                out[p, t] += (local[j, t] + intercept[t]) * gamma
