"""Local Procrustes Analysis: a non-linear domain mapping from local PAs (thesis §3.3-3.5).

Learning (Alg. 3): initEM (Alg. 5) partitions the correspondences, ``n_init`` times, and the
partition whose mixture has the highest log-likelihood initialises EM on the source input
space; points are assigned to their most responsible component and one PA (Alg. 1) is fitted
per cluster. Transfer (Alg. 4): ẑ_t = Σ_k γ_k(x_s) f_k(z_s) (eq. 3.10-3.12), with the
responsibilities γ_k computed in the clustering space x_s (eq. 3.11).
"""
import numpy as np
from sklearn.base import BaseEstimator

from lpa_transfer import _validation as check
from lpa_transfer.transfer import gmm
from lpa_transfer.transfer.init_em import init_em
from lpa_transfer.transfer.model_io import SavableModel
from lpa_transfer.transfer.procrustes import grouped_moments, procrustes_maps

#: Responsibilities below this contribute less than double precision to eq. 3.12.
_NEGLIGIBLE_RESPONSIBILITY = 1e-17


class LocalProcrustesAnalysis(SavableModel, BaseEstimator):
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
        return gmm.responsibilities(source[:, self.cluster_dims_], self.weights_, self.means_,
                                    self.precisions_cholesky_)

    def transfer(self, source):
        """Map source points (M, D_s) to the target domain (M, D_t) (Alg. 4, eq. 3.12).

        ẑ_t = Σ_k γ_k f_k(z_s). Terms with γ_k < 1e-17 (below double precision next to the
        dominant γ ≥ 1/K) are skipped, so each local map f_k is evaluated only on the points
        it is responsible for.
        """
        source = check.as_transfer_input(self, source)
        gamma = self._responsibilities(source)
        points, components = np.nonzero(gamma >= _NEGLIGIBLE_RESPONSIBILITY)
        order = np.argsort(components, kind="stable")
        points, components = points[order], components[order]
        bounds = np.concatenate(([0], np.cumsum(np.bincount(components,
                                                            minlength=self.n_clusters_))))
        out = np.zeros((len(source), self.n_features_out_))
        for k in np.flatnonzero(np.diff(bounds)):
            rows = points[bounds[k]:bounds[k + 1]]
            local = source[rows] @ self.coef_[k].T + self.intercept_[k]     # f_k(z_s)
            out[rows] += gamma[rows, k, None] * local
        return out


def _cluster_members(space, weights, means, precisions, n_min):
    """The training points of each local PA: cluster members by highest responsibility.

    Points are assigned to their most responsible component (§3.5, after EM). EM may leave a
    component with fewer than N_min points; a PA fitted on so few points interpolates them
    exactly, often with huge coefficients that wreck the transfer around it (seen on the §3.6
    link sweep, bench/README.md). Such a component's PA is fitted on its N_min most
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
