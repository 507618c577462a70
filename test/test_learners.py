"""LocallyWeightedRegression, the forward-kinematics learner standing in for LWPR."""

import numpy as np
import pytest
from sklearn.base import clone

from lpa_transfer.robots.kinematics import planar_forward_kinematics, sample_joint_uniform
from lpa_transfer.learners.locally_weighted import LocallyWeightedRegression

LIMITS = [[0.0, np.pi / 2], [0.0, np.pi]]   # Table 3.1


def fk_data(n, seed):
    q = sample_joint_uniform(n, LIMITS, np.random.default_rng(seed))
    return q, planar_forward_kinematics(q, (0.6, 0.2))


@pytest.mark.parametrize("bandwidth", [None, 0.5])
def test_recovers_an_affine_function(bandwidth):
    rng = np.random.default_rng(0)
    X, queries = rng.normal(size=(300, 3)), rng.normal(size=(50, 3))
    W, b = rng.normal(size=(3, 2)), rng.normal(size=2)
    model = LocallyWeightedRegression(n_neighbors=8, bandwidth=bandwidth).fit(X, X @ W + b)
    np.testing.assert_allclose(model.predict(queries), queries @ W + b, atol=1e-5)


def test_one_dimensional_targets_keep_their_shape():
    X = np.linspace(0, 1, 20)[:, None]
    prediction = LocallyWeightedRegression(n_neighbors=4).fit(X, 2 * X[:, 0]).predict([[0.5]])
    assert prediction.shape == (1,)
    assert prediction[0] == pytest.approx(1.0, abs=1e-6)


def test_learns_two_link_forward_kinematics():
    q, x = fk_data(2000, 1)
    q_test, x_test = fk_data(1000, 2)
    error = np.sqrt(np.mean(np.sum((LocallyWeightedRegression().fit(q, x).predict(q_test)
                                    - x_test) ** 2, axis=1)))
    assert error < 5e-3     # metres; the thesis' LWPR ground truth reaches 6.1 mm from 10,000


def test_vectorised_10k_queries_on_10k_points_equal_one_by_one_queries():
    q, x = fk_data(10_000, 3)
    q_test, _ = fk_data(10_000, 4)
    model = LocallyWeightedRegression().fit(q, x)
    batch = model.predict(q_test)
    assert batch.shape == (10_000, 2) and np.isfinite(batch).all()
    every_500th = np.vstack([model.predict(row[None]) for row in q_test[::500]])
    np.testing.assert_allclose(batch[::500], every_500th, rtol=1e-12, atol=1e-15)


def test_deterministic_and_clonable():
    q, x = fk_data(500, 5)
    q_test, _ = fk_data(200, 6)
    a = LocallyWeightedRegression(n_neighbors=7).fit(q, x).predict(q_test)
    b = clone(LocallyWeightedRegression(n_neighbors=7)).fit(q.copy(), x.copy()).predict(q_test)
    np.testing.assert_array_equal(a, b)


def test_more_neighbours_than_points_is_clipped():
    q, x = fk_data(5, 7)
    model = LocallyWeightedRegression(n_neighbors=50).fit(q, x)
    assert model.n_neighbors_ == 5
    assert np.isfinite(model.predict(q)).all()


def test_far_queries_stay_finite():
    q, x = fk_data(100, 8)
    assert np.isfinite(LocallyWeightedRegression(bandwidth=1e-3).fit(q, x)
                       .predict([[50.0, -50.0]])).all()


@pytest.mark.parametrize("X, Y, match", [
    (np.zeros(10), np.zeros(10), "X"),
    (np.zeros((10, 2)), np.zeros((9, 2)), "same number of rows"),
    ([[np.nan, 0.0]] * 3, np.zeros((3, 2)), "NaN"),
    (np.zeros((3, 2)), [[np.inf, 0.0]] * 3, "NaN"),
])
def test_fit_rejects_bad_data(X, Y, match):
    with pytest.raises(ValueError, match=match):
        LocallyWeightedRegression().fit(X, Y)


@pytest.mark.parametrize("params", [dict(n_neighbors=0), dict(n_neighbors=2.5),
                                    dict(bandwidth=0.0), dict(bandwidth=-1.0),
                                    dict(ridge=-1.0)])
def test_fit_rejects_bad_hyperparameters(params):
    with pytest.raises(ValueError):
        LocallyWeightedRegression(**params).fit(np.zeros((5, 2)), np.zeros((5, 2)))


def test_predict_checks_fitted_and_width():
    with pytest.raises(ValueError, match="not fitted"):
        LocallyWeightedRegression().predict(np.zeros((1, 2)))
    q, x = fk_data(50, 9)
    model = LocallyWeightedRegression().fit(q, x)
    with pytest.raises(ValueError, match="columns"):
        model.predict(np.zeros((1, 3)))
    with pytest.raises(ValueError, match="NaN"):
        model.predict([[np.nan, 0.0]])
