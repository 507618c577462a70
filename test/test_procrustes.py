"""Procrustes Analysis (thesis Alg. 1-2): exactness on affine relations and input checks."""
import numpy as np
import pytest
from sklearn.exceptions import NotFittedError

from lpa_transfer import ProcrustesAnalysis


def affine_pair(n, ds, dt, rank=None, seed=0):
    """n correspondences of an exact affine relation; the relation depends on seed only."""
    rng = np.random.default_rng(seed)
    to_source = rng.normal(size=(rank or ds, ds)), rng.normal(size=ds)
    to_target = rng.normal(size=(rank or ds, dt)), rng.normal(size=dt)
    latent = np.random.default_rng([seed, n]).normal(size=(n, rank or ds))
    return latent @ to_source[0] + to_source[1], latent @ to_target[0] + to_target[1]


def test_reproduces_an_exact_affine_relation():
    source, target = affine_pair(200, 4, 4)
    new_source, new_target = affine_pair(50, 4, 4)  # same seed -> same relation
    pa = ProcrustesAnalysis().fit(source, target)
    assert np.abs(pa.transfer(new_source) - new_target).max() < 1e-9


def test_different_dimensionalities_through_latent_dim():
    # 3 latent factors drive a 6-D source and a 4-D target: d = 3 recovers the relation.
    source, target = affine_pair(300, 6, 4, rank=3, seed=1)
    pa = ProcrustesAnalysis(latent_dim=3).fit(source, target)
    assert pa.coef_.shape == (4, 6)
    assert pa.B_source_.shape == (3, 6) and pa.B_target_.shape == (3, 4)
    assert np.abs(pa.transfer(source) - target).max() < 1e-9


def test_full_latent_space_equals_least_squares_regression():
    rng = np.random.default_rng(2)
    source = rng.normal(size=(100, 3))
    target = np.tanh(source @ rng.normal(size=(3, 3))) + 0.1 * rng.normal(size=(100, 3))
    design = np.hstack((source, np.ones((100, 1))))
    solution = np.linalg.lstsq(design, target, rcond=None)[0]
    pa = ProcrustesAnalysis().fit(source, target)
    np.testing.assert_allclose(pa.transfer(source), design @ solution, atol=1e-10)


def test_alignment_is_not_transposed():
    # A strongly non-symmetric map: the row-vector form Σ_ss⁻¹Σ_ts would get it wrong.
    rng = np.random.default_rng(3)
    source = rng.normal(size=(500, 2)) * [1.0, 0.1]
    target = source @ np.array([[0.0, 5.0], [0.0, 0.0]]).T
    pa = ProcrustesAnalysis().fit(source, target)
    np.testing.assert_allclose(pa.transfer([[1.0, 0.0]]), [[0.0, 0.0]], atol=1e-9)
    np.testing.assert_allclose(pa.transfer([[0.0, 1.0]]), [[5.0, 0.0]], atol=1e-9)


def test_whitened_source_has_identity_covariance():
    source, target = affine_pair(400, 4, 4, seed=4)
    pa = ProcrustesAnalysis().fit(source, target)
    whitened = (source - pa.mean_source_) @ pa.B_source_.T
    np.testing.assert_allclose(np.cov(whitened.T, bias=True), np.eye(4), atol=1e-9)


@pytest.mark.parametrize("source, target, message", [
    (np.ones((10, 2)), np.ones((9, 2)), "same number of rows"),
    (np.full((10, 2), np.nan), np.ones((10, 2)), "NaN or infinite"),
    (np.ones((10, 2)), np.full((10, 2), np.inf), "NaN or infinite"),
    (np.ones((2, 2)), np.ones((2, 2)), "too few correspondences"),
    (np.ones(10), np.ones((10, 2)), "2-D"),
    ([["a", "b"]] * 5, np.ones((5, 2)), "numeric"),
])
def test_bad_training_input_is_rejected(source, target, message):
    with pytest.raises(ValueError, match=message):
        ProcrustesAnalysis().fit(source, target)


def test_latent_dim_larger_than_a_side_is_rejected():
    source, target = affine_pair(50, 4, 3)
    with pytest.raises(ValueError, match="larger than the target dimensionality 3"):
        ProcrustesAnalysis(latent_dim=4).fit(source, target)
    with pytest.raises(ValueError, match="latent_dim must be an integer"):
        ProcrustesAnalysis(latent_dim=0).fit(source, target)


def test_transfer_checks_width_and_fitting():
    with pytest.raises(NotFittedError, match="not fitted"):
        ProcrustesAnalysis().transfer(np.ones((3, 2)))
    assert issubclass(NotFittedError, ValueError)
    pa = ProcrustesAnalysis().fit(*affine_pair(50, 4, 4))
    with pytest.raises(ValueError, match="3 columns but the model was fitted on 4"):
        pa.transfer(np.ones((2, 3)))
    with pytest.raises(ValueError, match="NaN"):
        pa.transfer(np.full((2, 4), np.nan))
