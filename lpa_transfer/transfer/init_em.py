"""initEM: hierarchical splitting that initialises LPA's mixture (thesis §3.5, Alg. 5).

Start with one cluster; in each pass, fit a PA per cluster (Alg. 1), compute its mapping
error c_k (eq. 3.15) and split every cluster with c_k > c_min into two by 2-means in the
clustering space; a split is kept only if both halves have at least n_min points; stop when a
pass changes nothing or K reaches k_max.

All clusters of a pass are handled at once (batched PA fits, batched 2-means), so a pass costs
a few array operations however many clusters there are. Two choices the thesis leaves open:

* a cluster whose split is rejected, or whose c_k ≤ c_min, is final: its points never change
  again, so neither would its c_k or (up to 2-means' random start) its split;
* when k_max would be exceeded, the clusters with the largest c_k are split first.
"""
import numpy as np

from lpa_transfer.transfer import _em_kernels
from lpa_transfer.transfer.procrustes import grouped_moments, procrustes_maps

_MAX_LLOYD_ITERATIONS = 100


def cluster_errors(source, target, labels, maps, counts):
    """c_k = (1/N_k) sqrt(Σ_i ||f_k(z_s^(i)) - z_t^(i)||²) for every cluster (eq. 3.15)."""
    predicted = np.einsum("nij,nj->ni", maps["coef"][labels], source)
    predicted += maps["intercept"][labels]
    squared = ((predicted - target) ** 2).sum(axis=1)
    return np.sqrt(np.bincount(labels, weights=squared, minlength=len(counts))) / counts


def two_means(X, groups, n_groups, rng, compiled=True):
    """Split each group of rows of X in two with Lloyd's 2-means (k-means++ seeding).

    ``groups`` (n,) labels rows 0..n_groups-1, sorted ascending. Returns a boolean array: True
    for rows that go to the second half. The Lloyd iterations run compiled
    (:func:`._em_kernels.lloyd_two_means`, the same halves bit for bit) unless ``compiled``
    is False.
    """
    counts = np.bincount(groups, minlength=n_groups)
    starts = np.concatenate(([0], np.cumsum(counts)[:-1]))
    # k-means++: a uniform first centre, then a second one drawn with probability ∝ d².
    first = starts + np.minimum((rng.random(n_groups) * counts).astype(np.intp), counts - 1)
    squared = ((X - X[first][groups]) ** 2).sum(axis=1)
    cumulative = np.cumsum(squared)
    before = cumulative[starts] - squared[starts]
    totals = np.add.reduceat(squared, starts)
    second = np.searchsorted(cumulative, before + rng.random(n_groups) * totals, side="right")
    second = np.clip(second, starts, starts + counts - 1)
    centres = np.stack((X[first], X[second]), axis=1)                     # (G, 2, d)
    if compiled and X.shape[1] <= _em_kernels.PAIRWISE_BLOCK:
        return _em_kernels.lloyd_two_means(np.ascontiguousarray(X, dtype=np.float64),
                                           groups, centres.reshape(2 * n_groups, -1),
                                           _MAX_LLOYD_ITERATIONS)
    keys = 2 * groups
    second_half = None
    for _ in range(_MAX_LLOYD_ITERATIONS):
        distances = ((X[:, None, :] - centres[groups]) ** 2).sum(axis=2)   # (n, 2)
        assignment = distances[:, 1] < distances[:, 0]
        if second_half is not None and np.array_equal(assignment, second_half):
            break
        second_half = assignment
        cells = keys + assignment
        sizes = np.bincount(cells, minlength=2 * n_groups)
        sums = np.stack([np.bincount(cells, weights=column, minlength=2 * n_groups)
                         for column in X.T], axis=1)          # row order, as a sparse product
        occupied = sizes > 0
        flat = centres.reshape(2 * n_groups, -1)
        flat[occupied] = sums[occupied] / sizes[occupied, None]
    return second_half


def init_em(source, target, cluster_space, c_min, n_min, k_max, latent_dim, rng):
    """Alg. 5: returns cluster labels (N,) and the number of clusters K."""
    joint = np.hstack((source, target))
    n_source_dims = source.shape[1]
    labels = np.zeros(len(source), dtype=np.intp)
    splittable = np.ones(1, dtype=bool)
    while splittable.any() and len(splittable) < k_max:
        n_clusters = len(splittable)
        counts, means, covariances = grouped_moments(joint, labels, n_clusters)
        maps = procrustes_maps(means, covariances, n_source_dims, latent_dim)
        errors = cluster_errors(source, target, labels, maps, counts)
        splittable &= (errors > c_min) & (counts >= 2 * n_min)
        candidates = np.flatnonzero(splittable)
        if len(candidates) == 0:
            break
        lookup = np.full(n_clusters, -1, dtype=np.intp)
        lookup[candidates] = np.arange(len(candidates))
        rows = np.flatnonzero(lookup[labels] >= 0)
        rows = rows[np.argsort(lookup[labels[rows]], kind="stable")]
        groups = lookup[labels[rows]]
        second_half = two_means(cluster_space[rows], groups, len(candidates), rng)
        second_sizes = np.bincount(groups, weights=second_half, minlength=len(candidates))
        kept = (second_sizes >= n_min) & (counts[candidates] - second_sizes >= n_min)
        splittable[candidates[~kept]] = False
        accepted = candidates[kept]
        accepted = accepted[np.argsort(-errors[accepted], kind="stable")]
        accepted = accepted[:k_max - n_clusters]
        new_label = np.full(n_clusters, -1, dtype=np.intp)
        new_label[accepted] = n_clusters + np.arange(len(accepted))
        moved = rows[second_half & (new_label[labels[rows]] >= 0)]
        labels[moved] = new_label[labels[moved]]
        splittable = np.concatenate((splittable, np.ones(len(accepted), dtype=bool)))
    return labels, len(splittable)
