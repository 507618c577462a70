"""Local Procrustes Analysis (thesis Alg. 3-5) on the §3.6 robots, plus its parts."""
import numpy as np
import pytest
from sklearn.exceptions import NotFittedError
from sklearn.mixture import GaussianMixture

from lpa_transfer import LocalProcrustesAnalysis, ProcrustesAnalysis
from lpa_transfer.transfer import _em_kernels, _transfer_kernels, gmm, local_procrustes
from lpa_transfer.transfer.init_em import cluster_errors, init_em, two_means
from lpa_transfer.transfer.procrustes import grouped_moments, procrustes_maps
from two_link import correspondences, mapping_rmse_mm

# Thesis §3.5: keep c_min small and control the number of clusters with N_min (§3.6: 7).
LPA_2LINK = dict(n_min=7, c_min=1e-7, cluster_dims=[0, 1])


@pytest.fixture(scope="module")
def test_set():
    return correspondences(10_000, seed=999)


def mean_rmse(n, runs, test_set):
    pa, lpa = [], []
    for run in range(runs):
        source, target = correspondences(n, seed=run)
        pa.append(mapping_rmse_mm(ProcrustesAnalysis().fit(source, target), *test_set))
        model = LocalProcrustesAnalysis(random_state=run, **LPA_2LINK).fit(source, target)
        lpa.append(mapping_rmse_mm(model, *test_set))
    return np.mean(pa), np.mean(lpa)


def test_acceptance_n200_lpa_within_10mm_and_040_of_pa(test_set):
    pa, lpa = mean_rmse(200, runs=10, test_set=test_set)
    assert pa > 20, "PA should be poor on this non-linear pair (thesis Fig. 3-6)"
    assert lpa <= 10.0
    assert lpa <= 0.4 * pa


def test_acceptance_n400_lpa_within_4mm(test_set):
    _, lpa = mean_rmse(400, runs=10, test_set=test_set)
    assert lpa <= 4.0


def test_deterministic_under_random_state(test_set):
    source, target = correspondences(300, seed=5)
    first = LocalProcrustesAnalysis(random_state=11, **LPA_2LINK).fit(source, target)
    second = LocalProcrustesAnalysis(random_state=11, **LPA_2LINK).fit(source, target)
    assert np.array_equal(first.transfer(test_set[0]), second.transfer(test_set[0]))
    others = [LocalProcrustesAnalysis(random_state=s, **LPA_2LINK).fit(source, target)
              for s in (1, 2, 3)]
    assert any(not np.array_equal(first.labels_, other.labels_) for other in others)


def test_exact_on_an_affine_relation_whatever_the_clusters():
    rng = np.random.default_rng(0)
    source = rng.uniform(-1, 1, size=(400, 3))
    target = source @ rng.normal(size=(3, 3)) + 0.5
    lpa = LocalProcrustesAnalysis(n_min=10, c_min=0.0, random_state=0).fit(source, target)
    assert lpa.n_clusters_ > 5
    assert np.abs(lpa.transfer(source[:50]) - target[:50]).max() < 1e-9


def test_every_local_map_sees_n_min_points_and_never_blows_up():
    # Regression: after EM a 5-point cluster fitted its 4-D map exactly, with huge
    # coefficients, and made LPA 11x worse than PA on this pair of the Fig. 3-8 sweep.
    test_source, test_target = correspondences(5000, seed=999, target_links=(0.3, 1.0))
    for seed in range(8):
        source, target = correspondences(100, seed=seed, target_links=(0.3, 1.0))
        lpa = LocalProcrustesAnalysis(random_state=seed, **LPA_2LINK).fit(source, target)
        assert lpa.cluster_sizes_.min() >= 7
        pa = ProcrustesAnalysis().fit(source, target)
        assert (mapping_rmse_mm(lpa, test_source, test_target)
                < mapping_rmse_mm(pa, test_source, test_target))


def test_large_c_min_keeps_one_cluster_equal_to_pa():
    source, target = correspondences(200, seed=1)
    lpa = LocalProcrustesAnalysis(n_min=7, c_min=1.0).fit(source, target)
    assert lpa.n_clusters_ == 1
    pa = ProcrustesAnalysis().fit(source, target)
    np.testing.assert_allclose(lpa.transfer(source), pa.transfer(source), atol=1e-12)


def test_k_max_and_n_min_bound_the_partition():
    source, target = correspondences(500, seed=2)
    assert LocalProcrustesAnalysis(k_max=6, **LPA_2LINK).fit(source, target).n_clusters_ <= 6
    labels, k = init_em(source, target, source[:, :2], c_min=1e-7, n_min=12, k_max=500,
                        latent_dim=4, rng=np.random.default_rng(0))
    sizes = np.bincount(labels, minlength=k)
    assert k > 10 and sizes.min() >= 12 and sizes.sum() == 500


def test_cluster_error_is_eq_3_15():
    source, target = correspondences(60, seed=3)
    labels = (source[:, 0] > np.median(source[:, 0])).astype(np.intp)
    joint = np.hstack((source, target))
    counts, means, covs = grouped_moments(joint, labels, 2)
    maps = procrustes_maps(means, covs, 4, 4)
    errors = cluster_errors(source, target, labels, maps, counts)
    for k in range(2):
        pa = ProcrustesAnalysis().fit(source[labels == k], target[labels == k])
        residual = pa.transfer(source[labels == k]) - target[labels == k]
        expected = np.sqrt((residual ** 2).sum()) / counts[k]
        np.testing.assert_allclose(errors[k], expected, rtol=1e-9)


def test_responsibilities_are_a_distribution(test_set):
    lpa = LocalProcrustesAnalysis(**LPA_2LINK).fit(*correspondences(300, seed=4))
    gamma = lpa.responsibilities(test_set[0][:500])
    assert gamma.shape == (500, lpa.n_clusters_)
    np.testing.assert_allclose(gamma.sum(axis=1), 1.0, atol=1e-12)
    assert (gamma >= 0).all()


def test_em_matches_scikit_learn_from_the_same_start():
    rng = np.random.default_rng(0)
    X = np.vstack([rng.normal(c, 0.3, size=(200, 2)) for c in ((0, 0), (2, 1), (0, 3))])
    start = gmm.from_partition(X, rng.integers(0, 3, 600), 3, 1e-6)   # a random partition
    reference = GaussianMixture(3, weights_init=start[0], means_init=start[1],
                                precisions_init=np.linalg.inv(start[2]), tol=1e-6,
                                max_iter=500).fit(X)
    weights, means, covs, _, log_likelihood, _, converged = gmm.fit_em(X, *start, tol=1e-6,
                                                                       max_iter=500)
    assert converged
    order = np.argsort(means[:, 0] * 10 + means[:, 1])
    ref_order = np.argsort(reference.means_[:, 0] * 10 + reference.means_[:, 1])
    np.testing.assert_allclose(means[order], reference.means_[ref_order], atol=1e-4)
    np.testing.assert_allclose(covs[order], reference.covariances_[ref_order], atol=1e-4)
    np.testing.assert_allclose(log_likelihood, reference.score(X), atol=1e-4)


@pytest.mark.parametrize("dim, n_components", [(2, 60), (4, 7)])
def test_compiled_em_sums_equal_the_numpy_sums(dim, n_components):
    """The compiled E-step (_em_kernels) and the numpy path give the same log-likelihood,
    n_k and moment sums to rounding, on a mixture whose log-ratios span 0 to below -700
    (so the exp-by-halves branch under -512 and the floor are both taken)."""
    rng = np.random.default_rng(11)
    X = rng.normal(size=(900, dim)) * np.linspace(1.0, 3.0, dim)
    start = gmm.from_partition(X, rng.integers(0, n_components, len(X)), n_components, 1e-6)
    weights, means, covariances = start[0], X[rng.choice(len(X), n_components)], \
        start[2] * 0.02                                       # narrow: far entries abound
    features = gmm.quadratic_features(X)
    resp = gmm.Responsibilities(weights, means, gmm.precisions_cholesky(covariances),
                                np.zeros(dim))
    log_ratios = features @ resp.coefficients + resp.constant
    log_ratios -= log_ratios.max(axis=1, keepdims=True)
    assert (log_ratios < -700).any() and ((log_ratios < -512) & (log_ratios > -700)).any()
    expected = gmm._em_sums_numpy(X, features, resp)
    got = _em_kernels.em_sums(np.ascontiguousarray(features), resp.coefficients,
                              resp.constant, gmm._LOG_FLOOR, gmm._EXP_FLOOR, gmm._LOG_FLOOR)
    assert not got[3].any()
    np.testing.assert_allclose(got[0], expected[0], rtol=1e-13)
    np.testing.assert_allclose(got[1], expected[1], rtol=1e-11, atol=1e-290)
    np.testing.assert_allclose(got[2], expected[2], rtol=1e-11, atol=1e-290)
    # the cut at e^-50 of a row's peak: the same sums to rounding wherever n_k is not tiny
    pruned = _em_kernels.em_sums(np.ascontiguousarray(features), resp.coefficients,
                                 resp.constant, gmm._LOG_FLOOR, gmm._EXP_FLOOR, gmm._PRUNE)
    assert ((log_ratios > -700) & (log_ratios <= gmm._PRUNE)).any()
    kept = expected[1] > len(X) * np.exp(gmm._PRUNE) / np.finfo(float).eps
    np.testing.assert_allclose(pruned[0], expected[0], rtol=1e-13)
    np.testing.assert_allclose(pruned[1][kept], expected[1][kept], rtol=1e-11)
    np.testing.assert_allclose(pruned[2][kept], expected[2][kept], rtol=1e-11, atol=1e-290)
    compiled = gmm._em_iteration(X, features, weights, means,
                                 gmm.precisions_cholesky(covariances), 1e-6)
    plain = gmm._em_iteration(X, features, weights, means,
                              gmm.precisions_cholesky(covariances), 1e-6, compiled=False)
    for a, b in zip(compiled, plain):
        np.testing.assert_allclose(a, b, rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("n_components", [7, 60])
def test_the_compiled_mean_log_likelihood_is_the_numpy_one(n_components):
    """initEM's runs are ranked by the compiled E-step's log-likelihood (its M-step sums left
    out): the numpy path's to rounding, also on a narrow mixture (entries below the cut and
    the floor), and the numpy path's own value where a point overflows (-inf)."""
    rng = np.random.default_rng(14)
    X = rng.normal(size=(700, 3)) * [1.0, 2.0, 3.0] + 5.0             # away from the origin
    start = gmm.from_partition(X, rng.integers(0, n_components, len(X)), n_components, 1e-6)
    means, covariances = X[rng.choice(len(X), n_components)], start[2] * 0.05
    expected = gmm.log_likelihoods(X, start[0], means,
                                   gmm.precisions_cholesky(covariances)).mean()
    got = gmm.mean_log_likelihood(X, start[0], means, covariances)
    assert np.isfinite(got) and got != 0.0
    np.testing.assert_allclose(got, expected, rtol=1e-12)
    far = np.vstack((X, [[1e160, -1e160, 0.0]]))
    with np.errstate(over="ignore", invalid="ignore"):
        assert gmm.mean_log_likelihood(far, start[0], means, covariances) == -np.inf


def test_em_iteration_reruns_without_the_cut_for_a_starved_component():
    """A component whose every responsibility lies between the floor and the cut (here
    centred 20 standard deviations off the data) gets n_k = 0 from the pruned sums; the
    iteration then sums again without the cut, and the component's weight and moments are
    the numpy path's (tiny, not zero)."""
    rng = np.random.default_rng(13)
    X = rng.normal(size=(600, 2))
    weights = np.full(4, 0.25)
    means = np.array([[-1.0, 0.0], [1.0, 0.0], [0.0, 1.0], [20.0, 0.0]])
    precisions = gmm.precisions_cholesky(np.tile(np.eye(2), (4, 1, 1)))
    features = gmm.quadratic_features(X)
    resp = gmm.Responsibilities(weights, means, precisions, np.zeros(2))
    pruned = _em_kernels.em_sums(np.ascontiguousarray(features), resp.coefficients,
                                 resp.constant, gmm._LOG_FLOOR, gmm._EXP_FLOOR, gmm._PRUNE)
    assert pruned[1][3] == 0.0 and (pruned[1][:3] > 100).all()
    got = gmm._em_iteration(X, features, weights, means, precisions, 1e-6)
    plain = gmm._em_iteration(X, features, weights, means, precisions, 1e-6, compiled=False)
    assert 0 < plain[1][3] < 1e-17 and 0 < plain[2][3, 0] < 1e-40
    for a, b in zip(got, plain):
        np.testing.assert_allclose(a, b, rtol=1e-9, atol=1e-300)


def test_em_iteration_falls_back_to_numpy_for_overflowing_rows():
    """A point whose expanded quadratic overflows is flagged by the kernel, and the iteration
    is then the numpy path's (which gives such a point to its nearest component)."""
    rng = np.random.default_rng(12)
    X = np.vstack((rng.normal(size=(200, 2)), [[1e160, -1e160]]))
    start = gmm.from_partition(X[:200], rng.integers(0, 3, 200), 3, 1e-6)
    precisions = gmm.precisions_cholesky(start[2])
    resp = gmm.Responsibilities(start[0], start[1], precisions, np.zeros(2))
    with np.errstate(over="ignore", invalid="ignore"):       # the overflow is the test's point
        features = gmm.quadratic_features(X)
        flagged = _em_kernels.em_sums(np.ascontiguousarray(features), resp.coefficients,
                                      resp.constant, gmm._LOG_FLOOR, gmm._EXP_FLOOR,
                                      gmm._PRUNE)[3]
        got = gmm._em_iteration(X, features, start[0], start[1], precisions, 1e-6)
        plain = gmm._em_iteration(X, features, start[0], start[1], precisions, 1e-6,
                                  compiled=False)
    assert flagged.tolist() == [False] * 200 + [True]
    for a, b in zip(got, plain):
        assert np.array_equal(a, b, equal_nan=True)       # the same path, overflow included


@pytest.mark.parametrize("params, message", [
    (dict(n_min=3), "n_min=3 is smaller than latent_dim \\+ 1 = 5"),
    (dict(n_min=7, c_min=-1.0), "c_min must be"),
    (dict(n_min=7, k_max=0), "k_max must be"),
    (dict(n_min=7, n_init=0), "n_init must be"),
    (dict(n_min=7, cluster_dims=[0, 4]), "cluster_dims must be"),
    (dict(n_min=7, cluster_dims=[1, 1]), "cluster_dims must be"),
    (dict(n_min=7, latent_dim=5), "larger than the source dimensionality 4"),
    (dict(n_min=7, random_state=-1), "random_state must be"),
])
def test_bad_hyperparameters_are_rejected(params, message):
    with pytest.raises(ValueError, match=message):
        LocalProcrustesAnalysis(**params).fit(*correspondences(50, seed=0))


def test_bad_data_is_rejected():
    source, target = correspondences(50, seed=0)
    with pytest.raises(ValueError, match="need at least 7 \\(n_min=7\\)"):
        LocalProcrustesAnalysis().fit(source[:6], target[:6])
    with pytest.raises(ValueError, match="same number of rows"):
        LocalProcrustesAnalysis().fit(source, target[:-1])
    bad = source.copy()
    bad[3, 1] = np.nan
    with pytest.raises(ValueError,
                       match="source contains NaN or infinite values \\(first in row 3\\)"):
        LocalProcrustesAnalysis().fit(bad, target)
    with pytest.raises(NotFittedError):
        LocalProcrustesAnalysis().transfer(source)
    lpa = LocalProcrustesAnalysis(**LPA_2LINK).fit(source, target)
    with pytest.raises(ValueError, match="3 columns but the model was fitted on 4"):
        lpa.transfer(source[:, :3])


# Transfer (Alg. 4, eq. 3.12): the dense and the sparse path against each other and against
# the plain per-point sum. Both paths add a point's terms in increasing k like the per-point
# sum; BLAS may round an entry of f_k(z_s) differently with the shape of the product it is
# part of, so they agree to a few ulps rather than bit for bit.

def random_mixture(n_clusters, n_in, n_out, width, n_points=300, seed=0):
    """A mixture of K components in a 3-D clustering space, random local maps D_s -> D_t,
    and source points; ``width`` (relative to the components' spacing) sets how spread the
    responsibilities are. The offsets keep the outputs away from 0, where rtol means little."""
    rng = np.random.default_rng(seed)
    means = rng.uniform(-1, 1, (n_clusters, 3))
    precisions = np.tile(np.eye(3) / (width * n_clusters ** (-1 / 3)), (n_clusters, 1, 1))
    weights = rng.dirichlet(np.ones(n_clusters))
    coef = rng.normal(size=(n_clusters, n_out, n_in))
    intercept = 20.0 + rng.normal(size=(n_clusters, n_out))
    source = np.hstack((rng.uniform(-1, 1, (n_points, 3)), rng.normal(size=(n_points,
                                                                            n_in - 3))))
    gamma = gmm.responsibilities(source[:, :3], weights, means, precisions)
    return source, gamma, coef, intercept


def per_point_transfer(source, gamma, coef, intercept):
    """ẑ_t = Σ_k γ_k (W_k z_s + b_k) point by point, terms with γ_k < 1e-17 left out."""
    out = np.zeros((len(source), coef.shape[1]))
    for i, (point, weights) in enumerate(zip(source, gamma)):
        for k in np.flatnonzero(weights >= 1e-17):
            out[i] += weights[k] * (np.array([row @ point for row in coef[k]]) + intercept[k])
    return out


def blocks_of(gamma, size):
    return [(slice(start, start + size), gamma[start:start + size])
            for start in range(0, len(gamma), size)]


def mixed(source, gamma, coef, intercept, path, block=64):
    return local_procrustes.mix_local_maps(source, blocks_of(gamma, block), coef, intercept,
                                           path=path)


@pytest.mark.parametrize("n_clusters, width, spread", [
    (1, 1.0, False), (40, 0.05, False), (40, 2.0, True), (7, 5.0, True)])
def test_dense_and_sparse_paths_equal_the_per_point_sum(n_clusters, width, spread):
    source, gamma, coef, intercept = random_mixture(n_clusters, 6, 4, width)
    per_point = (gamma >= 1e-17).sum(axis=1).mean()
    assert (per_point > 3) == spread                  # the cases are what they claim to be
    expected = per_point_transfer(source, gamma, coef, intercept)
    for path in ("dense", "sparse", None):
        np.testing.assert_allclose(mixed(source, gamma, coef, intercept, path), expected,
                                   rtol=1e-12, atol=0)
    np.testing.assert_allclose(mixed(source, gamma, coef, intercept, "dense"),
                               mixed(source, gamma, coef, intercept, "sparse"),
                               rtol=1e-12, atol=0)


def test_paths_split_at_every_block_boundary(monkeypatch):
    # Blocks of 7 rows; the dense path split into 5-row products of 2 clusters each; the
    # sparse path evaluating its pairs every few blocks.
    source, gamma, coef, intercept = random_mixture(12, 5, 3, 0.7, n_points=101, seed=1)
    expected = per_point_transfer(source, gamma, coef, intercept)
    monkeypatch.setattr(local_procrustes, "_DENSE_ROWS", 5)
    monkeypatch.setattr(local_procrustes, "_BLOCK_ELEMENTS", 5 * 2 * 3)
    monkeypatch.setattr(local_procrustes, "_SPARSE_ELEMENTS", 8 * 40)
    monkeypatch.setattr(local_procrustes, "_SPARSE_PAIRS_PER_CLUSTER", 1)
    flushes = []
    original = local_procrustes._SparseTerms.flush
    monkeypatch.setattr(local_procrustes._SparseTerms, "flush",
                        lambda self: flushes.append(self.size) or original(self))
    for path in ("dense", "sparse"):
        np.testing.assert_allclose(mixed(source, gamma, coef, intercept, path, block=7),
                                   expected, rtol=1e-12, atol=0)
    assert len([size for size in flushes if size]) > 3


def test_a_point_without_responsibility_maps_to_zero_on_both_paths():
    source, gamma, coef, intercept = random_mixture(5, 4, 2, 0.5, n_points=20, seed=2)
    gamma[[0, 7, 19]] = 0.0
    for path in ("dense", "sparse"):
        out = mixed(source, gamma, coef, intercept, path, block=8)
        assert (out[[0, 7, 19]] == 0).all()
        np.testing.assert_allclose(out, per_point_transfer(source, gamma, coef, intercept),
                                   rtol=1e-12, atol=0)


def test_transfer_takes_the_dense_path_only_when_responsibilities_are_spread(monkeypatch):
    lpa = LocalProcrustesAnalysis(**LPA_2LINK).fit(*correspondences(400, seed=6))
    test_source = correspondences(2000, seed=7)[0]
    calls = []
    original = local_procrustes._dense_block
    monkeypatch.setattr(local_procrustes, "_dense_block",
                        lambda *args: calls.append(len(args[1])) or original(*args))
    fitted = lpa.precisions_cholesky_
    for scale, spread in ((30.0, False), (1.0, True), (1 / 30, True)):
        lpa.precisions_cholesky_ = fitted * scale        # narrower or wider components
        gamma = lpa.responsibilities(test_source)
        share = (gamma >= 1e-17).mean()
        assert (share >= local_procrustes.dense_share(4, 4, lpa.n_clusters_)) == spread
        calls.clear()
        transferred = lpa.transfer(test_source)
        assert sum(calls) == (len(test_source) if spread else 0)
        np.testing.assert_allclose(transferred, per_point_transfer(
            test_source, gamma, lpa.coef_, lpa.intercept_), rtol=1e-12, atol=1e-14)
        other = "sparse" if spread else "dense"
        np.testing.assert_allclose(transferred, local_procrustes.mix_local_maps(
            test_source, blocks_of(gamma, 500), lpa.coef_, lpa.intercept_, path=other),
            rtol=1e-12, atol=1e-14)


def test_dense_share_grows_with_the_size_of_the_local_maps_and_falls_with_k():
    shares = [local_procrustes.dense_share(d, d, 50) for d in (2, 4, 20, 40, 100)]
    assert all(0 < a < b for a, b in zip(shares, shares[1:]))
    shares = [local_procrustes.dense_share(20, 16, k) for k in (1, 100, 1000, 10_000)]
    assert all(a >= b > 0 for a, b in zip(shares, shares[1:]))
    with pytest.raises(ValueError, match="path must be"):
        local_procrustes.mix_local_maps(np.ones((2, 2)), [], np.ones((1, 2, 2)),
                                        np.ones((1, 2)), path="fast")


@pytest.mark.parametrize("width", [0.02, 3.0])
def test_transfer_work_arrays_stay_bounded(width):
    # 20,000 points x 600 clusters: γ alone would take 96 MB and the local maps 192 MB.
    import tracemalloc
    rng = np.random.default_rng(3)
    n_points, n_clusters = 20_000, 600
    model = LocalProcrustesAnalysis()
    model.weights_ = np.full(n_clusters, 1 / n_clusters)
    model.means_ = rng.uniform(-1, 1, (n_clusters, 2))
    model.precisions_cholesky_ = np.tile(np.eye(2) / (width * n_clusters ** -0.5),
                                         (n_clusters, 1, 1))
    model.coef_ = rng.normal(size=(n_clusters, 2, 3))
    model.intercept_ = rng.normal(size=(n_clusters, 2))
    model.cluster_dims_, model.n_clusters_ = np.arange(2), n_clusters
    model.n_features_in_, model.n_features_out_ = 3, 2
    source = rng.uniform(-1, 1, (n_points, 3))
    tracemalloc.start()
    try:
        transferred = model.transfer(source)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 20e6
    rows = rng.choice(n_points, 200, replace=False)          # from many blocks
    np.testing.assert_allclose(transferred[rows], per_point_transfer(
        source[rows], model.responsibilities(source[rows]), model.coef_, model.intercept_),
        rtol=1e-12, atol=1e-14)


def test_clustering_columns_need_not_be_adjacent():
    source, target = correspondences(300, seed=8)
    lpa = LocalProcrustesAnalysis(n_min=7, c_min=1e-7, cluster_dims=[2, 0]).fit(source, target)
    test_source = correspondences(500, seed=9)[0]
    gamma = lpa.responsibilities(test_source)
    np.testing.assert_array_equal(gamma, gmm.responsibilities(
        test_source[:, [2, 0]], lpa.weights_, lpa.means_, lpa.precisions_cholesky_))
    np.testing.assert_allclose(lpa.transfer(test_source), per_point_transfer(
        test_source, gamma, lpa.coef_, lpa.intercept_), rtol=1e-12, atol=1e-14)


def test_quadratic_features_are_the_upper_triangle_products():
    X = np.random.default_rng(4).normal(size=(37, 5))
    upper = np.triu_indices(5)
    expected = np.hstack((X[:, upper[0]] * X[:, upper[1]], X))
    assert np.array_equal(gmm.quadratic_features(X), expected)


def numpy_sparse_transfer(source, gamma, coef, intercept):
    """The sparse path as numpy computed it before its compiled kernels: pairs sorted by
    cluster (stably), one BLAS product per cluster over its points, b_k added, scaled by γ,
    a point's first term assigned and the others added in increasing k."""
    out = np.zeros((len(source), coef.shape[1]))
    points, components = np.divmod(np.flatnonzero(gamma >= 1e-17), gamma.shape[1])
    weights = gamma[points, components]
    first = np.ones(len(points), dtype=bool)
    first[1:] = points[1:] != points[:-1]
    order = np.argsort(components, kind="stable")
    points, components, weights, first = (a[order] for a in (points, components, weights,
                                                              first))
    for k in np.unique(components):
        block = components == k
        rows = points[block]
        local = source.take(rows, axis=0) @ coef[k].T
        local += intercept[k]
        local *= weights[block, None]
        lead = first[block]
        out[rows[lead]] = local[lead]
        out[rows[~lead]] += local[~lead]
    return out


@pytest.mark.parametrize("dim, n_clusters", [(5, 25), (10, 22), (15, 22), (20, 24)])
def test_compiled_transfer_is_the_numpy_transfer_bit_for_bit(dim, n_clusters, monkeypatch):
    # Models of the bench's 20-D -> 16-D shape (bench/bench_lpa.py TRANSFER_MODELS):
    # responsibilities over 5-20 source columns, 22-25 clusters, a few per point. The
    # compiled responsibilities and sparse path give the numpy code's bits.
    rng = np.random.default_rng(dim)
    model = LocalProcrustesAnalysis()
    model.weights_ = rng.dirichlet(np.ones(n_clusters))
    model.means_ = rng.uniform(-1, 1, (n_clusters, dim))
    width = 0.008 * dim                  # a few clusters per point, whatever the dimension
    scales = rng.uniform(width, 2.4 * width, (n_clusters, 1, 1))
    factors = scales * (np.eye(dim) + 0.3 * rng.normal(size=(n_clusters, dim, dim)) / dim)
    model.precisions_cholesky_ = gmm.precisions_cholesky(factors @ np.swapaxes(factors, 1, 2)
                                                         + 1e-3 * np.eye(dim))
    model.coef_ = rng.normal(size=(n_clusters, 16, 20))
    model.intercept_ = 5.0 + rng.normal(size=(n_clusters, 16))
    model.cluster_dims_, model.n_clusters_ = np.arange(dim), n_clusters
    model.n_features_in_, model.n_features_out_ = 20, 16
    labels = rng.integers(n_clusters, size=3001)
    source = rng.normal(size=(3001, 20))
    source[:, :dim] = model.means_[labels] + 1.6 * width * rng.normal(size=(3001, dim))
    transferred = model.transfer(source)
    gamma = model.responsibilities(source)
    kept = (gamma >= 1e-17).sum(axis=1).mean()
    assert 1.01 < kept < local_procrustes.dense_share(20, 16, n_clusters) * n_clusters
    monkeypatch.setattr(gmm, "_SIMD_EXP", True)              # numpy's responsibilities
    numpy_gamma = model.responsibilities(source)
    assert np.array_equal(gamma, numpy_gamma)
    assert np.array_equal(transferred, numpy_sparse_transfer(source, numpy_gamma, model.coef_,
                                                             model.intercept_))
    log_p = gmm.log_likelihoods(source[:, :dim], model.weights_, model.means_,
                                model.precisions_cholesky_)
    monkeypatch.setattr(gmm, "_SIMD_EXP", False)
    assert np.array_equal(log_p, gmm.log_likelihoods(source[:, :dim], model.weights_,
                                                     model.means_, model.precisions_cholesky_))


@pytest.mark.parametrize("n_components", [1, 7, 8, 9, 129, 300])
def test_compiled_row_totals_are_numpys_pairwise_sums(n_components):
    rng = np.random.default_rng(n_components)
    values = np.exp(-rng.exponential(30, (40, n_components)))
    totals = np.array([_transfer_kernels._pairwise_sum(row, n_components) for row in values])
    assert np.array_equal(totals, values.sum(axis=1))


@pytest.mark.parametrize("simd_exp", [False, True])
@pytest.mark.parametrize("live_share", [0.0, 0.05, 0.6, 1.0])
def test_floored_exp_is_exp_of_the_clamped_values(live_share, simd_exp, monkeypatch):
    monkeypatch.setattr(gmm, "_SIMD_EXP", simd_exp)      # both branches, whatever the CPU
    rng = np.random.default_rng(5)
    values = np.where(rng.random((50, 30)) < live_share, rng.uniform(-700, 0, (50, 30)),
                      rng.uniform(-3000, -700, (50, 30)))
    values[0, :3] = (-700.0, np.nextafter(-700.0, 0), 0.0)
    expected = np.exp(np.maximum(values, -700.0))
    assert np.array_equal(gmm._floored_exp(values.copy()), expected)
    strided = np.asfortranarray(values)
    assert np.array_equal(gmm._floored_exp(strided), expected)


def test_finite_inputs_far_from_the_data_take_the_nearest_maps_never_zeros():
    """Huge inputs: at |x| >= ~1e154 the expanded Mahalanobis term overflows; such points
    take the map of the component nearest in Mahalanobis distance, and what cannot be a
    finite answer is an error."""
    from two_link import correspondences

    source, target = correspondences(400, 3)
    model = LocalProcrustesAnalysis(n_min=20, c_min=1e-7, random_state=0).fit(source, target)
    direction = np.array([1.0, -0.5, 0.25, 2.0])
    for magnitude in (1e155, 1e200, 1e250):
        point = magnitude * direction[None]
        mapped = model.transfer(point)
        assert np.isfinite(mapped).all() and np.abs(mapped).max() > 0
        k = np.argmax(model.responsibilities(point)[0])
        assert model.responsibilities(point)[0, k] == 1.0
        np.testing.assert_allclose(mapped[0], model.coef_[k] @ point[0] + model.intercept_[k],
                                   rtol=1e-12)
        # the nearest component in Mahalanobis distance (direct, rescaled form)
        offsets = (point - model.means_) / magnitude
        distances = [o @ np.linalg.inv(np.linalg.inv(p @ p.T)) @ o
                     for o, p in zip(offsets, model.precisions_cholesky_)]
        assert k == int(np.argmin(distances))
    # a map that triples its input cannot answer finitely at 1e308: an error, for LPA and PA
    for cls in (LocalProcrustesAnalysis, ProcrustesAnalysis):
        tripled = cls().fit(source, 3.0 * source)
        with pytest.raises(ValueError, match="not finite: the inputs are too large"):
            tripled.transfer(np.full((1, 4), 1e308))
    near = source[:5]
    assert np.array_equal(model.transfer(near), model.transfer(np.vstack((near, 1e200 *
                                                                           direction)))[:5])


@pytest.mark.parametrize("n_dims", [2, 7, 10, 20])
def test_compiled_two_means_gives_the_numpy_halves(n_dims):
    """initEM's compiled Lloyd iterations split every group as the numpy loop does, bit for
    bit, below and above the 8 terms where numpy's summation turns pairwise."""
    rng = np.random.default_rng(n_dims)
    groups = np.sort(rng.integers(0, 40, 3000))
    X = rng.normal(size=(3000, n_dims)) * rng.uniform(0.01, 10.0, n_dims) + groups[:, None]
    compiled = two_means(X, groups, 40, np.random.default_rng(1))
    plain = two_means(X, groups, 40, np.random.default_rng(1), compiled=False)
    assert compiled.dtype == plain.dtype == bool
    assert np.array_equal(compiled, plain) and 0.2 < plain.mean() < 0.8
