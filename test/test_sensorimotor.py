"""lpa_transfer.learners.sensorimotor: the weighted K-nearest-neighbour sensorimotor models (§6.3.2)."""
import numpy as np
import pytest
from sklearn.exceptions import NotFittedError

from lpa_transfer.learners.sensorimotor import (KNNRegressor, SensorimotorModel, make_model,
                                                make_sensorimotor_model)


def data(n, seed=0, d=2, m=3):
    rng = np.random.default_rng(seed)
    return rng.uniform(-1, 1, (n, d)), rng.normal(size=(n, m))


def brute_force(X, Y, weights, queries, k, kernel):
    """The documented formula ŷ = Σ w_j y_j / Σ w_j, w_j = s_j κ(d_j), by exhaustive search."""
    distances = np.linalg.norm(queries[:, None] - X[None], axis=2)
    nearest = np.argsort(distances, axis=1)[:, :k]
    d = np.take_along_axis(distances, nearest, 1)
    w = weights[nearest] * (1 / d if kernel == "distance" else 1.0)
    return np.einsum("mk,mko->mo", w, Y[nearest]) / w.sum(axis=1, keepdims=True)


def test_defaults_are_the_thesis_k3_with_distance_weights():
    model = KNNRegressor()
    assert model.n_neighbors == 3 and model.weights == "distance"
    assert model.get_params()["n_neighbors"] == 3


@pytest.mark.parametrize("kernel", ["distance", "uniform"])
def test_prediction_is_the_documented_weighted_mean(kernel):
    X, Y = data(400)
    weights = np.random.default_rng(1).uniform(0.2, 3.0, 400)
    queries = np.random.default_rng(2).uniform(-1, 1, (50, 2))
    model = KNNRegressor(weights=kernel).fit(X, Y, sample_weight=weights)
    np.testing.assert_allclose(model.predict(queries),
                               brute_force(X, Y, weights, queries, 3, kernel), rtol=1e-12)


def test_a_training_input_predicts_its_own_output_exactly():
    X, Y = data(300)
    model = KNNRegressor().fit(X, Y)
    np.testing.assert_array_equal(model.predict(X), Y)


def test_uniform_k1_is_the_nearest_neighbour():
    X, Y = data(200)
    queries = X[:20] + 1e-4
    np.testing.assert_array_equal(KNNRegressor(1, weights="uniform").fit(X, Y).predict(queries),
                                  Y[:20])


def test_sample_weights_shift_the_prediction_towards_heavier_samples():
    X, Y = np.array([[0.0], [2.0]]), np.array([[0.0], [10.0]])
    query = np.array([[1.0]])
    assert KNNRegressor(2).fit(X, Y).predict(query)[0, 0] == pytest.approx(5.0)
    heavier = KNNRegressor(2).fit(X, Y, sample_weight=[1.0, 3.0]).predict(query)[0, 0]
    assert heavier == pytest.approx(7.5)
    lighter = KNNRegressor(2).fit(X, Y, sample_weight=[1.0, 0.25]).predict(query)[0, 0]
    assert lighter == pytest.approx(2.0)


def test_incremental_learning_equals_batch_learning_across_tree_rebuilds():
    X, Y = data(3000, seed=3)
    queries = np.random.default_rng(4).uniform(-1, 1, (40, 2))
    online = KNNRegressor()
    for start in range(0, 3000, 37):   # queries in between trigger lazy tree rebuilds
        online.partial_fit(X[start:start + 37], Y[start:start + 37])
        online.predict(queries[:1])
    batch = KNNRegressor().fit(X, Y)
    assert online.n_samples_ == batch.n_samples_ == 3000
    np.testing.assert_array_equal(online.kneighbors(queries)[1], batch.kneighbors(queries)[1])
    np.testing.assert_allclose(online.predict(queries), batch.predict(queries), rtol=1e-12)


def test_tail_of_unindexed_samples_is_searched():
    """A sample appended after the tree was built is found as a neighbour at once."""
    X, Y = data(2000)
    model = KNNRegressor(1).fit(X, Y)
    model.predict(X[:1])   # builds the tree over the 2000
    model.partial_fit([[5.0, 5.0]], [[1.0, 2.0, 3.0]])
    np.testing.assert_array_equal(model.predict([[5.0, 5.1]]), [[1.0, 2.0, 3.0]])
    assert model.kneighbors([[5.0, 5.1]])[1][0, 0] == 2000


def test_fit_resets_and_learned_attributes_are_read_only():
    X, Y = data(50)
    model = KNNRegressor().fit(X, Y).fit(X[:5], Y[:5])
    assert model.n_samples_ == 5 and model.X_.shape == (5, 2) and model.Y_.shape == (5, 3)
    np.testing.assert_array_equal(model.sample_weight_, np.ones(5))
    with pytest.raises(ValueError):
        model.X_[0, 0] = 1.0


def test_fewer_samples_than_k_and_1d_outputs():
    model = KNNRegressor().fit([[0.0], [1.0]], [3.0, 5.0])
    prediction = model.predict([[0.5], [1.0]])
    assert prediction.shape == (2,)
    np.testing.assert_allclose(prediction, [4.0, 5.0])


def test_not_fitted_before_data():
    with pytest.raises(NotFittedError, match="no samples"):
        KNNRegressor().predict([[0.0, 0.0]])
    with pytest.raises(NotFittedError):
        KNNRegressor().X_


@pytest.mark.parametrize("X, Y, weight, message", [
    ([[np.nan, 0.0]], [[1.0]], None, "X contains NaN"),
    ([[0.0, 0.0]], [[np.inf]], None, "Y contains NaN or infinite"),
    ([[0.0, 0.0], [1.0, 1.0]], [[1.0]], None, "same number of rows"),
    ([0.0, 1.0], [[1.0], [2.0]], None, "X must be a 2-D array"),
    (np.empty((0, 2)), np.empty((0, 1)), None, "no samples"),
    ([[0.0, 0.0]], [[1.0]], [0.0], "sample_weight must hold finite values > 0"),
    ([[0.0, 0.0]], [[1.0]], [1.0, 1.0], r"sample_weight must have shape \(1,\)"),
])
def test_bad_samples_raise_a_clear_value_error(X, Y, weight, message):
    with pytest.raises(ValueError, match=message):
        KNNRegressor().partial_fit(X, Y, sample_weight=weight)


def test_wrong_widths_raise_a_clear_value_error():
    model = KNNRegressor().fit(*data(10))
    with pytest.raises(ValueError, match="X has 3 columns but the model was fitted on 2"):
        model.predict(np.zeros((1, 3)))
    with pytest.raises(ValueError, match="Y has 2 columns but the model was fitted on 3"):
        model.partial_fit(np.zeros((1, 2)), np.zeros((1, 2)))
    with pytest.raises(ValueError, match="X contains NaN"):
        model.predict([[0.0, np.inf]])


@pytest.mark.parametrize("hyperparameters, message", [
    ({"n_neighbors": 0}, "n_neighbors must be an integer >= 1"),
    ({"weights": "gaussian"}, "weights must be one of"),
    ({"rebuild_fraction": 0.0}, "rebuild_fraction must be a number in"),
])
def test_bad_hyperparameters_raise(hyperparameters, message):
    with pytest.raises(ValueError, match=message):
        KNNRegressor(**hyperparameters).fit(*data(5))


def test_registry_builds_models_by_name():
    model = make_model("knn", n_neighbors=5)
    assert isinstance(model, KNNRegressor) and model.n_neighbors == 5
    with pytest.raises(ValueError,
                       match=r"unknown sensorimotor model 'lwpr'; available: \['knn'\]"):
        make_model("lwpr")


def test_sensorimotor_model_learns_inverse_and_forward_from_one_sample_stream():
    q, x = data(100, d=2, m=2)
    model = make_sensorimotor_model("knn", n_neighbors=1).update(q, x)
    np.testing.assert_array_equal(model.infer_command(x[:5]), q[:5])
    np.testing.assert_array_equal(model.predict_point(q[:5]), x[:5])
    inverse_only = SensorimotorModel(KNNRegressor()).update(q, x, sample_weight=np.full(100, 0.5))
    np.testing.assert_array_equal(inverse_only.inverse.sample_weight_, np.full(100, 0.5))
    with pytest.raises(ValueError, match="no forward model"):
        inverse_only.predict_point(q[:1])
