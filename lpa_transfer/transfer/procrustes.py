"""Procrustes Analysis with PCA (thesis §3.2, eq. 3.1-3.6, Alg. 1-2).

The maths is written once, batched over a leading "cluster" axis, so that the global model
(:class:`ProcrustesAnalysis`, one cluster) and Local Procrustes Analysis (one PA per cluster,
Alg. 3 lines 5-7) share the same code.

Conventions: column vectors as in the thesis, so for a source point z_s

    s = B_s (z_s - ω_s)              (eq. 3.1, B_s: d x D_s, PCA whitening)
    t = B_t (z_t - ω_t)              (eq. 3.2)
    A = Σ_ts Σ_ss⁻¹                  (eq. 3.6; the thesis prints Σ_ss⁻¹ Σ_ts, which is the
                                       row-vector form; with column vectors the minimiser of
                                       eq. 3.5 is Σ_ts Σ_ss⁻¹)
    ẑ_t = B_t⁺ A s + ω_t             (Alg. 2; B_t⁺ is the Moore-Penrose pseudo-inverse)

which collapses to the affine map ẑ_t = W z_s + b with W = B_t⁺ A B_s, b = ω_t - W ω_s.
With d = D_s = D_t this is the least-squares affine regression from source to target.
"""
import numpy as np

from lpa_transfer import _validation as check
from lpa_transfer._estimator import Estimator
from lpa_transfer.transfer.model_io import SavableModel

#: Eigenvalues below RCOND times the largest one are treated as zero variance: their whitened
#: coordinate is set to 0 instead of being amplified by 1/sqrt(λ) (a pseudo-inverse).
RCOND = 1e-10


def grouped_moments(Z, labels, n_groups):
    """Counts, means and maximum-likelihood covariances of the rows of ``Z`` per label.

    ``labels`` holds integers in ``[0, n_groups)`` and every group must be non-empty.
    Returns ``counts (K,)``, ``means (K, D)``, ``covariances (K, D, D)``. The centred rows
    are laid out as a zero-padded (K, max N_k, D) stack so that all K covariances come from
    one batched matrix product.
    """
    order = np.argsort(labels, kind="stable")
    sorted_Z, sorted_labels = Z[order], labels[order]
    counts = np.bincount(labels, minlength=n_groups)
    starts = np.concatenate(([0], np.cumsum(counts)[:-1]))
    means = np.add.reduceat(sorted_Z, starts, axis=0) / counts[:, None]
    padded = np.zeros((n_groups, counts.max(), Z.shape[1]))
    padded[sorted_labels, np.arange(len(Z)) - starts[sorted_labels]] = \
        sorted_Z - means[sorted_labels]
    covariances = np.swapaxes(padded, 1, 2) @ padded / counts[:, None, None]
    return counts, means, covariances


def pca_whitening(covariances, latent_dim):
    """PCA whitening matrices of eq. 3.1/3.2 for a batch of covariances (K, D, D).

    Returns ``B`` (K, d, D) with the top-d principal directions scaled by λ^(-1/2), and its
    pseudo-inverse ``B_pinv`` (K, D, d) used to map back to the original space (Alg. 2).
    """
    eigvals, eigvecs = np.linalg.eigh(covariances)           # ascending order
    eigvals = eigvals[:, ::-1][:, :latent_dim]
    eigvecs = eigvecs[:, :, ::-1][:, :, :latent_dim]
    largest = np.maximum(eigvals[:, :1], np.finfo(float).tiny)
    kept = eigvals > RCOND * largest
    safe = np.where(kept, eigvals, 1.0)
    inv_sqrt = np.where(kept, 1.0 / np.sqrt(safe), 0.0)
    sqrt = np.where(kept, np.sqrt(safe), 0.0)
    B = inv_sqrt[:, :, None] * np.swapaxes(eigvecs, 1, 2)
    B_pinv = eigvecs * sqrt[:, None, :]
    return B, B_pinv


def procrustes_maps(means, covariances, n_source_dims, latent_dim):
    """Alg. 1 for K clusters at once, from the joint moments of z = (z_s, z_t).

    ``means`` (K, D_s + D_t) and ``covariances`` (K, D_s + D_t, D_s + D_t) come from
    :func:`grouped_moments` on the stacked correspondences. Returns a dict with the thesis'
    parameters Φ = {A, B_s, B_t, ω_s, ω_t} per cluster and the composed affine map
    ``coef`` (K, D_t, D_s), ``intercept`` (K, D_t).
    """
    ds = n_source_dims
    cov_ss, cov_tt = covariances[:, :ds, :ds], covariances[:, ds:, ds:]
    cov_ts = covariances[:, ds:, :ds]
    B_s, _ = pca_whitening(cov_ss, latent_dim)
    B_t, B_t_pinv = pca_whitening(cov_tt, latent_dim)
    B_s_T = np.swapaxes(B_s, 1, 2)
    sigma_ss = B_s @ cov_ss @ B_s_T                           # ≈ I after whitening
    sigma_ts = B_t @ cov_ts @ B_s_T
    A = sigma_ts @ np.linalg.pinv(sigma_ss)                  # eq. 3.6, column-vector form
    coef = B_t_pinv @ A @ B_s
    omega_s, omega_t = means[:, :ds], means[:, ds:]
    intercept = omega_t - np.einsum("kij,kj->ki", coef, omega_s)
    return dict(A=A, B_source=B_s, B_target=B_t, mean_source=omega_s, mean_target=omega_t,
                coef=coef, intercept=intercept)


class ProcrustesAnalysis(SavableModel, Estimator):
    """Procrustes Analysis with PCA: a linear source -> target domain mapping (Alg. 1-2).

    Parameters
    ----------
    latent_dim : int or None
        Dimensionality d of the shared latent space (thesis §3.2). ``None`` uses
        ``min(D_s, D_t)``; it must not exceed either side's dimensionality.

    Learned attributes
    ------------------
    mean_source_, mean_target_ : ω_s (D_s,), ω_t (D_t,)
    B_source_, B_target_ : PCA whitening matrices B_s (d, D_s), B_t (d, D_t)
    A_ : alignment matrix (d, d), eq. 3.6
    coef_, intercept_ : the composed map ẑ_t = coef_ @ z_s + intercept_ (Alg. 2)
    latent_dim_, n_features_in_, n_features_out_, n_correspondences_
    """

    _learned = ("mean_source_", "mean_target_", "B_source_", "B_target_", "A_", "coef_",
                "intercept_", "latent_dim_", "n_features_in_", "n_features_out_",
                "n_correspondences_")

    def __init__(self, latent_dim=None):
        self.latent_dim = latent_dim

    def fit(self, source, target):
        """Learn Φ = {A, B_s, B_t, ω_s, ω_t} from correspondences (Alg. 1).

        ``source`` (N, D_s) and ``target`` (N, D_t): row i of each is in correspondence.
        """
        source, target = check.as_matrix(source, "source"), check.as_matrix(target, "target")
        d = check.resolve_latent_dim(self.latent_dim, source.shape[1], target.shape[1])
        source, target = check.as_correspondences(
            source, target, (d + 1, f"latent_dim + 1 = {d + 1} to estimate the PCA"))
        Z = np.hstack((source, target))
        _, means, covs = grouped_moments(Z, np.zeros(len(Z), dtype=np.intp), 1)
        params = procrustes_maps(means, covs, source.shape[1], d)
        for name, value in params.items():
            setattr(self, f"{name}_", value[0])
        self.latent_dim_ = d
        self.n_features_in_, self.n_features_out_ = source.shape[1], target.shape[1]
        self.n_correspondences_ = len(source)
        return self

    def transfer(self, source):
        """Map source points (M, D_s) into the target domain (M, D_t) (Alg. 2)."""
        source = check.as_transfer_input(self, source)
        with np.errstate(over="ignore", invalid="ignore"):   # checked: finite_transfer
            mapped = source @ self.coef_.T + self.intercept_
        return check.finite_transfer(mapped, source)
