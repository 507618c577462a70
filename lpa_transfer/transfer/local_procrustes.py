"""Local Procrustes Analysis: a non-linear domain mapping from local PAs (thesis §3.3-3.5).

Learning (Alg. 3): initEM (Alg. 5) partitions the correspondences, ``n_init`` times, and the
partition whose mixture has the highest log-likelihood initialises EM on the source input
space; points are assigned to their most responsible component and one PA (Alg. 1) is fitted
per cluster. Transfer (Alg. 4): ẑ_t = Σ_k γ_k(x_s) f_k(z_s) (eq. 3.10-3.12), with the
responsibilities γ_k computed in the clustering space x_s (eq. 3.11).
"""
import numpy as np

from lpa_transfer import _validation as check
from lpa_transfer._estimator import Estimator
from lpa_transfer.transfer import _transfer_kernels, gmm
from lpa_transfer.transfer.init_em import init_em
from lpa_transfer.transfer.model_io import SavableModel
from lpa_transfer.transfer.procrustes import grouped_moments, procrustes_maps

#: Responsibilities below this contribute less than double precision to eq. 3.12.
_NEGLIGIBLE_RESPONSIBILITY = 1e-17
#: Cost model behind the choice between the dense and the sparse path of
#: :func:`mix_local_maps`, in multiply-adds of a large matrix product: the dense path costs
#: (D_s + 1)·D_t + _DENSE_ENTRY_COST per (point, cluster) entry; the sparse path
#: _SPARSE_PAIR_COST·(D_s + D_t + _SPARSE_PAIR_VALUES) per non-negligible pair (gathers,
#: scatters and call overheads dominate it) plus _SPARSE_CLUSTER_COST per cluster each time
#: it evaluates its collected pairs. Fitted to the crossovers that
#: ``python -m bench.bench_lpa --crossover`` measures.
_DENSE_ENTRY_COST = 120
_SPARSE_PAIR_COST = 35
_SPARSE_PAIR_VALUES = 40
_SPARSE_CLUSTER_COST = 120_000
#: Elements (points x clusters x target dimensions) of the dense path's work arrays.
_BLOCK_ELEMENTS = 1 << 17
#: Rows per matrix product of the dense path (fewer if the block is smaller).
_DENSE_ROWS = 256
#: Source and target values of the (point, cluster) pairs the sparse path gathers before it
#: evaluates them: at least _SPARSE_ELEMENTS, more for many clusters so that there are about
#: _SPARSE_PAIRS_PER_CLUSTER pairs per cluster (its per-cluster cost is then amortised), but
#: never more than _SPARSE_MAX_ELEMENTS.
_SPARSE_ELEMENTS = 1 << 21
_SPARSE_PAIRS_PER_CLUSTER = 64
_SPARSE_MAX_ELEMENTS = 1 << 23


class LocalProcrustesAnalysis(SavableModel, Estimator):
    """Local Procrustes Analysis (Alg. 3-5).

    Parameters
    ----------
    n_min : int
        N_min, the fewest correspondences a cluster may hold (Alg. 5 line 10). Must be at
        least latent_dim + 1 so that every cluster's PCA is defined (§3.5: N_min ≥ d).
        With a small ``c_min`` it is the parameter that controls the number of clusters.
    c_min : float
        Clusters whose mapping error c_k exceeds c_min are split (Alg. 5 line 8). Note that
        c_k is defined by eq. 3.15 as (1/N_k)·sqrt(Σ‖f_k(z_s) − z_t‖²), i.e. the cluster's
        RMS error divided by sqrt(N_k): the same c_min means a looser per-point tolerance in a
        large cluster than in a small one, so with more data a fixed c_min stops splitting
        sooner. The thesis therefore keeps c_min small and controls K with n_min.
    k_max : int or None
        K_max, the largest number of clusters initEM may create (None: unbounded).
    latent_dim : int or None
        Latent dimensionality d shared by all local PAs; None means min(D_s, D_t).
    cluster_dims : sequence of int or None
        Source columns that span the input space x_s in which the mixture is fitted and the
        responsibilities are computed (§3.4, Fig. 3-2). None: all source columns.
    n_init : int
        How many times initEM is run; the partition with the highest log-likelihood wins.
    random_state : int or None
        Seed for initEM's 2-means splits; the same seed gives the same model.
    reg_covar, max_iter, tol :
        Mixture fitting: ridge added to each covariance diagonal, EM iteration cap and
        convergence threshold on the mean log-likelihood (as in scikit-learn).

    Learned attributes
    ------------------
    n_clusters_ : K after EM; weights_, means_, covariances_, precisions_cholesky_ : the
    mixture Π in the clustering space; A_, B_source_, B_target_, mean_source_, mean_target_ :
    the local PA parameters Φ (stacked over K); coef_ (K, D_t, D_s), intercept_ (K, D_t):
    the composed local maps f_k; cluster_sizes_ (points each local PA was fitted on, ≥ n_min),
    labels_ (most responsible component of each training point),
    n_init_clusters_ (K found by initEM), log_likelihood_, n_iter_, converged_,
    cluster_dims_, latent_dim_, n_features_in_, n_features_out_, n_correspondences_.
    """

    _learned = ("weights_", "means_", "covariances_", "precisions_cholesky_", "A_",
                "B_source_", "B_target_", "mean_source_", "mean_target_", "coef_",
                "intercept_", "cluster_sizes_", "labels_", "cluster_dims_", "n_clusters_",
                "n_init_clusters_", "log_likelihood_", "n_iter_", "converged_", "latent_dim_",
                "n_features_in_", "n_features_out_", "n_correspondences_")

    def __init__(self, n_min=7, c_min=1e-3, k_max=None, latent_dim=None, cluster_dims=None,
                 n_init=3, random_state=0, reg_covar=1e-6, max_iter=100, tol=1e-3):
        self.n_min = n_min
        self.c_min = c_min
        self.k_max = k_max
        self.latent_dim = latent_dim
        self.cluster_dims = cluster_dims
        self.n_init = n_init
        self.random_state = random_state
        self.reg_covar = reg_covar
        self.max_iter = max_iter
        self.tol = tol

    def _check_hyperparameters(self, n_source_dims, n_target_dims):
        check.check_int(self.n_min, "n_min", minimum=1)
        check.check_float(self.c_min, "c_min", minimum=0.0)
        if self.k_max is not None:
            check.check_int(self.k_max, "k_max", minimum=1)
        check.check_int(self.n_init, "n_init", minimum=1)
        check.check_int(self.max_iter, "max_iter", minimum=1)
        check.check_float(self.reg_covar, "reg_covar", minimum=0.0)
        check.check_float(self.tol, "tol", minimum=0.0)
        check.check_seed(self.random_state)
        d = check.resolve_latent_dim(self.latent_dim, n_source_dims, n_target_dims)
        if self.n_min < d + 1:
            raise ValueError(f"n_min={self.n_min} is smaller than latent_dim + 1 = {d + 1}: "
                             "every cluster needs that many points for its PCA (§3.5)")
        return d, self._resolve_cluster_dims(n_source_dims)

    def _resolve_cluster_dims(self, n_source_dims):
        if self.cluster_dims is None:
            return np.arange(n_source_dims)
        dims = np.asarray(self.cluster_dims)
        if (dims.ndim != 1 or len(dims) == 0 or not np.issubdtype(dims.dtype, np.integer)
                or dims.min() < 0 or dims.max() >= n_source_dims
                or len(np.unique(dims)) != len(dims)):
            raise ValueError(f"cluster_dims must be distinct source column indices in "
                             f"[0, {n_source_dims}), got {self.cluster_dims!r}")
        return dims.astype(np.intp)

    def fit(self, source, target):
        """Learn {Π, Φ} from correspondences (Alg. 3): ``source`` (N, D_s), ``target`` (N, D_t)."""
        source, target = check.as_matrix(source, "source"), check.as_matrix(target, "target")
        d, cluster_dims = self._check_hyperparameters(source.shape[1], target.shape[1])
        source, target = check.as_correspondences(source, target,
                                                  (self.n_min, f"n_min={self.n_min}"))
        space = source[:, cluster_dims]
        k_max = len(source) if self.k_max is None else self.k_max
        best = None
        for seed in np.random.SeedSequence(self.random_state).spawn(self.n_init):
            labels, k = init_em(source, target, space, self.c_min, self.n_min, k_max, d,
                                np.random.default_rng(seed))
            mixture = gmm.from_partition(space, labels, k, self.reg_covar)
            score = gmm.mean_log_likelihood(space, *mixture)
            if best is None or score > best[0]:
                best = (score, k, mixture)
        self.n_init_clusters_ = best[1]
        fitted = gmm.fit_em(space, *best[2], self.reg_covar, self.max_iter, self.tol)
        weights, means, covariances, precisions, self.log_likelihood_, self.n_iter_, \
            self.converged_ = fitted
        self.weights_, self.means_, self.covariances_ = weights, means, covariances
        self.precisions_cholesky_ = precisions
        self.n_clusters_ = len(weights)
        labels, fit_labels, fit_rows = _cluster_members(space, weights, means, precisions,
                                                        self.n_min)
        counts, joint_means, joint_covs = grouped_moments(
            np.hstack((source, target))[fit_rows], fit_labels, self.n_clusters_)
        for name, value in procrustes_maps(joint_means, joint_covs, source.shape[1],
                                           d).items():
            setattr(self, f"{name}_", value)
        self.cluster_sizes_, self.labels_, self.cluster_dims_ = counts, labels, cluster_dims
        self.latent_dim_ = d
        self.n_features_in_, self.n_features_out_ = source.shape[1], target.shape[1]
        self.n_correspondences_ = len(source)
        return self

    def responsibilities(self, source):
        """γ_k of each source point (M, K), computed in the clustering space (eq. 3.11)."""
        return self._responsibilities(check.as_transfer_input(self, source))

    def _responsibilities(self, source):
        return gmm.responsibilities(self._cluster_space(source), self.weights_, self.means_,
                                    self.precisions_cholesky_)

    def _cluster_space(self, source):
        """The clustering-space columns x_s of source points: a view when they are adjacent."""
        dims = self.cluster_dims_
        if np.array_equal(dims, np.arange(dims[0], dims[0] + len(dims))):
            return source[:, dims[0]:dims[0] + len(dims)]
        return source[:, dims]

    def transfer(self, source):
        """Map source points (M, D_s) to the target domain (M, D_t) (Alg. 4, eq. 3.12).

        ẑ_t = Σ_k γ_k f_k(z_s) with f_k(z_s) = W_k z_s + b_k; terms with γ_k < 1e-17 (below
        double precision next to the dominant γ ≥ 1/K) are skipped. Points are processed in
        blocks; see :func:`mix_local_maps` for how each block is evaluated.
        """
        source = check.as_transfer_input(self, source)
        blocks = gmm.Responsibilities(self.weights_, self.means_, self.precisions_cholesky_)
        gammas = ((rows, gamma) for rows, gamma, _ in blocks.blocks(self._cluster_space(source)))
        with np.errstate(over="ignore", invalid="ignore"):   # checked: finite_transfer
            mapped = mix_local_maps(source, gammas, self.coef_, self.intercept_)
        return check.finite_transfer(mapped, source)


def mix_local_maps(source, gamma_blocks, coef, intercept, path=None):
    """ẑ_t = Σ_k γ_k (W_k z_s + b_k) (Alg. 4, eq. 3.12) for the rows of ``source`` (M, D_s).

    ``gamma_blocks`` yields ``(rows, γ)`` in increasing row order: a slice of consecutive rows
    and their responsibilities (R, K) (eq. 3.11). ``coef`` (K, D_t, D_s) and ``intercept``
    (K, D_t) hold the local maps f_k. Terms with γ_k < 1e-17 are dropped. Each block takes
    one of two paths, chosen by the share of its entries with γ_k ≥ 1e-17 against
    :func:`dense_share` (``path`` "dense" or "sparse" forces one):

    * sparse (responsibilities concentrated): the (point, k) pairs are collected over blocks
      and each f_k is evaluated on its own points only, one matrix product per cluster
      (:class:`_SparseTerms`);
    * dense (responsibilities spread): all K maps are evaluated on every point of the block
      by blocked matrix products and weighted by γ (:func:`_dense_block`).

    Both add a point's terms in increasing k, as the plain per-point sum does (the dense path
    group by group of clusters when K·D_t is large). They can differ in the last bits because
    a BLAS product may round an entry differently depending on the shape of the product and
    the entry's place in it. Work arrays stay near ``_BLOCK_ELEMENTS`` elements, and the
    collected pairs within ``_SPARSE_MAX_ELEMENTS`` values, whatever M.
    """
    if path not in (None, "dense", "sparse"):
        raise ValueError(f"path must be None, 'dense' or 'sparse', got {path!r}")
    out = np.zeros((len(source), intercept.shape[1]))
    sparse = _SparseTerms(source, coef, intercept, out)
    stacked = None
    crossover = dense_share(source.shape[1], intercept.shape[1], len(coef))
    for rows, gamma in gamma_blocks:
        gamma = np.ascontiguousarray(gamma)
        n_kept = _transfer_kernels.count_at_least(gamma, _NEGLIGIBLE_RESPONSIBILITY)
        if path == "dense" or (path is None and n_kept >= crossover * gamma.size):
            if stacked is None:
                stacked = _stacked_maps(coef, intercept)
            weights = np.where(gamma >= _NEGLIGIBLE_RESPONSIBILITY, gamma, 0.0)
            _dense_block(source[rows], weights, stacked, out[rows])
        else:
            sparse.add(rows, gamma, n_kept)
    sparse.flush()
    return out


def dense_share(n_source_dims, n_target_dims, n_clusters):
    """The share of non-negligible responsibilities from which the dense path is used.

    The dense path's cost grows with the number of (point, cluster) entries, the sparse
    path's with the number of non-negligible ones; this is the share at which the two costs
    of the module's cost model (``_DENSE_ENTRY_COST`` and ``_SPARSE_*_COST``) are equal.
    Bigger local maps favour the sparse path (it evaluates fewer of them), more clusters the
    dense path (the sparse path's per-cluster cost).
    """
    dense = (n_source_dims + 1) * n_target_dims + _DENSE_ENTRY_COST
    pairs = _sparse_capacity(n_source_dims, n_target_dims, n_clusters)
    sparse = (_SPARSE_PAIR_COST * (n_source_dims + n_target_dims + _SPARSE_PAIR_VALUES)
              + _SPARSE_CLUSTER_COST * n_clusters / pairs)
    return dense / sparse


def _sparse_capacity(n_source_dims, n_target_dims, n_clusters):
    """How many pairs the sparse path collects before it evaluates them."""
    values = n_source_dims + n_target_dims
    wanted = _SPARSE_PAIRS_PER_CLUSTER * n_clusters * values
    return max(1, min(max(_SPARSE_ELEMENTS, wanted), _SPARSE_MAX_ELEMENTS) // values)


def _stacked_maps(coef, intercept):
    """The K local maps as one (D_s + 1, K·D_t) matrix [W_kᵀ; b_kᵀ], cluster after cluster."""
    n_clusters, n_out, n_in = coef.shape
    stacked = np.empty((n_in + 1, n_clusters * n_out))
    stacked[:n_in] = coef.reshape(n_clusters * n_out, n_in).T
    stacked[n_in] = intercept.reshape(-1)
    return stacked


def _dense_block(source, weights, stacked, out):
    """out = Σ_k w_k (W_k z_s + b_k) for a block of rows, all K maps at once (eq. 3.12).

    ``weights`` (R, K) are the responsibilities with the negligible ones set to 0 and
    ``stacked`` comes from :func:`_stacked_maps`: [z_s, 1] @ stacked gives every f_k(z_s)
    (the offset is the product's last term). Rows and clusters are split so that each
    (rows, clusters, D_t) product stays near ``_BLOCK_ELEMENTS``; within a split the
    weighted terms are summed in increasing k.
    """
    n_rows, n_clusters = weights.shape
    n_in, n_out = source.shape[1], out.shape[1]
    rows_step = max(1, min(n_rows, _DENSE_ROWS))
    clusters_step = max(1, min(n_clusters, _BLOCK_ELEMENTS // (rows_step * n_out)))
    augmented = np.empty((rows_step, n_in + 1))
    augmented[:, n_in] = 1.0
    for start in range(0, n_rows, rows_step):
        rows = slice(start, min(start + rows_step, n_rows))
        points = augmented[:rows.stop - start]
        points[:, :n_in] = source[rows]
        for first in range(0, n_clusters, clusters_step):
            last = min(first + clusters_step, n_clusters)
            local = points @ stacked[:, first * n_out:last * n_out]        # f_k(z_s), k in split
            local = local.reshape(len(points), last - first, n_out)
            terms = np.einsum("rk,rkt->rt", weights[rows, first:last], local)
            if first == 0:
                out[rows] = terms
            else:
                out[rows] += terms


class _SparseTerms:
    """The sparse path of :func:`mix_local_maps`: the (point, k) pairs with γ_k ≥ 1e-17.

    Pairs are collected block by block and evaluated once about ``_SPARSE_ELEMENTS`` source
    and target values have gathered (and at the end): sorted by cluster, each f_k is one
    matrix product over its points. The clusters are taken in increasing k, so each point's
    weighted terms reach its row in increasing k: the first is assigned, the others added.
    Collection, sort and weighted sums are compiled (:mod:`._transfer_kernels`); the
    products stay BLAS calls over the same points as ever, which fixes their rounding.
    """

    def __init__(self, source, coef, intercept, out):
        self.source, self.coef, self.intercept, self.out = source, coef, intercept, out
        self.capacity = _sparse_capacity(source.shape[1], intercept.shape[1], len(coef))
        self.pending, self.size = [], 0

    def add(self, rows, gamma, n_kept):
        """Collect the pairs of a block: ``rows`` (a slice), γ (R, K, C-contiguous) and
        ``n_kept``, the number of its entries ≥ 1e-17 (taken point by point in increasing
        k)."""
        if n_kept == 0:
            return
        pairs = (np.empty(n_kept, dtype=np.intp), np.empty(n_kept, dtype=np.intp),
                 np.empty(n_kept))
        _transfer_kernels.responsible_pairs(gamma, _NEGLIGIBLE_RESPONSIBILITY, rows.start or 0,
                                        *pairs, 0)
        self.pending.append(pairs)
        self.size += n_kept
        if self.size >= self.capacity:
            self.flush()

    def flush(self):
        """Evaluate the collected pairs and write their terms to their points' rows of ``out``."""
        if not self.pending:
            return
        points, components, gamma = (parts[0] if len(parts) == 1 else np.concatenate(parts)
                                     for parts in zip(*self.pending))
        self.pending, self.size = [], 0
        points, gamma, bounds, first = _transfer_kernels.sort_by_cluster(
            points, components, gamma, len(self.coef))
        for k in np.flatnonzero(bounds[1:] > bounds[:-1]):
            block = slice(bounds[k], bounds[k + 1])
            rows = points[block]                              # each point at most once
            local = self.source.take(rows, axis=0) @ self.coef[k].T       # W_k z_s
            _transfer_kernels.blend(local, rows, gamma[block], first[block],
                                    self.intercept[k], self.out)


def _cluster_members(space, weights, means, precisions, n_min):
    """The training points of each local PA: cluster members by highest responsibility.

    Points are assigned to their most responsible component (§3.5, after EM). EM may leave a
    component with fewer than N_min points; a PA fitted on so few points interpolates them
    exactly, often with huge coefficients that wreck the transfer around it (seen on the §3.6
    link sweep, docs/history.md). Such a component's PA is fitted on its N_min most
    responsible points instead, borrowing neighbours' points, so every local map sees at
    least N_min correspondences and the EM solution is kept.
    Returns ``labels`` (N,), the most responsible component of each point, and the PAs'
    training sets as ``fit_labels`` and ``fit_rows`` (row indices, possibly repeated).
    """
    gamma = gmm.responsibilities(space, weights, means, precisions)
    labels = gamma.argmax(axis=1)
    rows = np.arange(len(space))
    small = np.flatnonzero(np.bincount(labels, minlength=len(weights)) < n_min)
    if len(small) == 0:
        return labels, labels, rows
    borrowed = np.argsort(-gamma[:, small], axis=0, kind="stable")[:n_min]     # (n_min, S)
    members = np.isin(labels, small)
    fit_labels = np.concatenate((labels[~members], np.tile(small, n_min)))
    return labels, fit_labels, np.concatenate((rows[~members], borrowed.ravel()))
