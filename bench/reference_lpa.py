"""A plain Local Procrustes Analysis "as written in the thesis": the benchmark baseline.

Straight from §3.2-3.5 (Alg. 1-5) with numpy, scipy and scikit-learn, one Python loop per
cluster, no batching: the yardstick for the speed and the accuracy of the library's
``LocalProcrustesAnalysis``. It is bench code, not library code.

Choices the thesis leaves open (stated so that the comparison is fair):

* PA (Alg. 1): ML covariances; PCA whitening B = Λ^{-1/2} Uᵀ of the top ``latent_dim``
  eigenpairs (eigenvalues floored at 1e-12·λ_max so a flat direction does not divide by 0);
  with column vectors the minimiser of eq. 3.5 is A = Σ_ts Σ_ss⁻¹ (the thesis prints the
  row-vector form Σ_ss⁻¹ Σ_ts); map back with pinv(B_t) (Alg. 2).
* initEM (Alg. 5): in every pass *every* cluster is re-fitted and, if c_k > c_min, split by
  ``KMeans(2)`` in the clustering space; a split is kept only if both halves have ≥ n_min
  points; stop when a pass keeps no split or K reaches k_max. KMeans uses one seed per
  initEM run, so re-trying a rejected split gives the same halves (the loop terminates).
* Run initEM ``n_init`` times and keep the partition whose mixture (weights N_k/N, means,
  covariances + reg_covar·I) has the highest log-likelihood; then EM with scikit-learn.
* After EM a component that owns fewer than latent_dim + 1 points cannot have a PA: it is
  dropped (the remaining weights renormalised) and the points reassigned, until none is left.
"""
import numpy as np
from scipy.special import logsumexp
from scipy.stats import multivariate_normal
from sklearn.cluster import KMeans
from sklearn.mixture import GaussianMixture


def fit_procrustes(source, target, latent_dim):
    """Alg. 1 on one set of correspondences: Φ = (A, B_s, B_t⁺, ω_s, ω_t)."""
    omega_s, omega_t = source.mean(axis=0), target.mean(axis=0)
    B_s, B_t = _whitening(source - omega_s, latent_dim), _whitening(target - omega_t, latent_dim)
    S, T = (source - omega_s) @ B_s.T, (target - omega_t) @ B_t.T        # eq. 3.1, 3.2
    sigma_ss, sigma_ts = S.T @ S / len(S), T.T @ S / len(S)
    A = sigma_ts @ np.linalg.inv(sigma_ss)                               # eq. 3.6
    return A, B_s, np.linalg.pinv(B_t), omega_s, omega_t


def _whitening(centred, latent_dim):
    eigvals, eigvecs = np.linalg.eigh(centred.T @ centred / len(centred))
    eigvals, eigvecs = eigvals[::-1][:latent_dim], eigvecs[:, ::-1][:, :latent_dim]
    eigvals = np.maximum(eigvals, 1e-12 * max(eigvals[0], 1e-300))
    return np.diag(eigvals ** -0.5) @ eigvecs.T


def apply_procrustes(phi, source):
    """Alg. 2: ẑ_t = B_t⁺ A B_s (z_s − ω_s) + ω_t, row-wise."""
    A, B_s, B_t_pinv, omega_s, omega_t = phi
    return (source - omega_s) @ (B_t_pinv @ A @ B_s).T + omega_t


def cluster_error(phi, source, target):
    """c_k = (1/N_k) sqrt(Σ ‖f_k(z_s) − z_t‖²), eq. 3.15 exactly."""
    return np.sqrt(((apply_procrustes(phi, source) - target) ** 2).sum()) / len(source)


class ReferenceLPA:
    """Plain LPA (Alg. 3-5), same constructor arguments as the library's model."""

    def __init__(self, n_min=7, c_min=1e-3, k_max=None, latent_dim=None, cluster_dims=None,
                 n_init=3, random_state=0, reg_covar=1e-6):
        self.n_min, self.c_min, self.k_max = n_min, c_min, k_max
        self.latent_dim, self.cluster_dims = latent_dim, cluster_dims
        self.n_init, self.random_state, self.reg_covar = n_init, random_state, reg_covar

    def init_em(self, source, target, space, seed):
        """Alg. 5: hierarchical splitting; returns cluster labels and K."""
        labels, K = np.zeros(len(source), dtype=int), 1
        k_max = self.k_max or len(source)
        while K < k_max:
            changed = False
            for k in range(K):
                members = np.flatnonzero(labels == k)
                phi = fit_procrustes(source[members], target[members], self.latent_dim_)
                if cluster_error(phi, source[members], target[members]) <= self.c_min \
                        or len(members) < 2 or K >= k_max:
                    continue
                halves = KMeans(2, random_state=seed).fit_predict(space[members])
                if min(np.sum(halves == 0), np.sum(halves == 1)) >= self.n_min:
                    labels[members[halves == 1]] = K
                    K, changed = K + 1, True
            if not changed:
                break
        return labels, K

    def partition_mixture(self, space, labels, K):
        """Alg. 5 line 17: π_k, μ_k, Σ_k of a hard partition."""
        weights = np.bincount(labels, minlength=K) / len(space)
        means = np.array([space[labels == k].mean(axis=0) for k in range(K)])
        covs = np.array([np.cov(space[labels == k].T, bias=True).reshape(space.shape[1], -1)
                         + self.reg_covar * np.eye(space.shape[1]) for k in range(K)])
        return weights, means, covs

    @staticmethod
    def log_likelihood(space, weights, means, covs):
        """Σ_i log Σ_k π_k N(x_i | μ_k, Σ_k) (eq. 3.8)."""
        logs = [np.log(w) + multivariate_normal(m, c).logpdf(space)
                for w, m, c in zip(weights, means, covs)]
        return logsumexp(np.column_stack(logs), axis=1).sum()

    def fit(self, source, target):
        """Alg. 3: initEM (best of n_init), EM, hard assignment, one PA per cluster."""
        source, target = np.asarray(source, float), np.asarray(target, float)
        self.latent_dim_ = self.latent_dim or min(source.shape[1], target.shape[1])
        self.cluster_dims_ = (np.arange(source.shape[1]) if self.cluster_dims is None
                              else np.asarray(self.cluster_dims))
        space = source[:, self.cluster_dims_]
        best = None
        for seed in np.random.default_rng(self.random_state).integers(2 ** 31, size=self.n_init):
            labels, K = self.init_em(source, target, space, int(seed))
            mixture = self.partition_mixture(space, labels, K)
            score = self.log_likelihood(space, *mixture)
            if best is None or score > best[0]:
                best = (score, K, mixture)
        _, K, (weights, means, covs) = best
        self.n_init_clusters_ = K
        self.gmm_ = GaussianMixture(K, covariance_type="full", reg_covar=self.reg_covar,
                                    weights_init=weights, means_init=means,
                                    precisions_init=np.linalg.inv(covs)).fit(space)
        labels = self.gmm_.predict(space)
        while True:                               # drop components too small for a PA
            counts = np.bincount(labels, minlength=self.gmm_.n_components)
            keep = counts >= self.latent_dim_ + 1
            if keep.all():
                break
            g = self.gmm_
            g.weights_ = g.weights_[keep] / g.weights_[keep].sum()
            g.means_, g.covariances_ = g.means_[keep], g.covariances_[keep]
            g.precisions_cholesky_ = g.precisions_cholesky_[keep]
            g.precisions_ = g.precisions_[keep]
            g.n_components = int(keep.sum())
            labels = g.predict(space)
        self.n_clusters_ = self.gmm_.n_components
        self.maps_ = [fit_procrustes(source[labels == k], target[labels == k], self.latent_dim_)
                      for k in range(self.n_clusters_)]
        return self

    def transfer(self, source):
        """Alg. 4: ẑ_t = Σ_k γ_k(x_s) f_k(z_s) (eq. 3.10-3.12)."""
        source = np.asarray(source, float)
        gamma = self.gmm_.predict_proba(source[:, self.cluster_dims_])      # eq. 3.11
        return sum(gamma[:, k, None] * apply_procrustes(phi, source)
                   for k, phi in enumerate(self.maps_))
