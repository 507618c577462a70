"""LWPR (lpa_transfer.learners.lwpr): learning, receptive-field bookkeeping, API and input checks,
and equality with the frozen numpy implementation (test/oracles/reference_lwpr.py) that the compiled
kernels replaced.

Accuracy thresholds were measured with the seeds used here and on two further seeds and have
a margin above the worst of them (noted next to each). nMSE = MSE / variance of the
noise-free targets on a held-out grid. Everything is seeded; the learner is deterministic.
"""
import functools
import importlib.util

import numpy as np
import pytest
from sklearn.base import clone
from sklearn.exceptions import NotFittedError
from sklearn.utils.estimator_checks import check_estimator

from conftest import ROOT
from lpa_transfer.learners.lwpr import LWPR

#: The 2-D "cross" function of the LWPR paper (Vijayakumar et al. 2005) and reference library.
CROSS = dict(init_D=25.0, init_alpha=250.0, w_gen=0.2, norm_in=1.0)
GRID = np.linspace(-1, 1, 41)
X_GRID = np.array([[a, b] for a in GRID for b in GRID])


def cross(X):
    return np.max([np.exp(-10 * X[:, 0] ** 2), np.exp(-50 * X[:, 1] ** 2),
                   1.25 * np.exp(-5 * (X[:, 0] ** 2 + X[:, 1] ** 2))], axis=0)


def cross_data(n, seed):
    rng = np.random.default_rng(seed)
    X = rng.uniform(-1, 1, (n, 2))
    return X, cross(X) + 0.1 * rng.standard_normal(n)


def nmse(prediction, truth):
    return float(np.mean((prediction - truth) ** 2) / np.var(truth))


@pytest.fixture(scope="module")
def cross_run():
    """4000 noisy cross samples learned online in 10 chunks: (model, [(nMSE, n_rfs)])."""
    X, Y = cross_data(4000, seed=0)
    model, history = LWPR(**CROSS), []
    for chunk in np.array_split(np.arange(4000), 10):
        model.partial_fit(X[chunk], Y[chunk])
        history.append((nmse(model.predict(X_GRID), cross(X_GRID)),
                        int(model.n_receptive_fields_[0])))
    return model, history


def test_learns_a_sine():
    rng = np.random.default_rng(0)
    x = rng.uniform(-np.pi, np.pi, (1000, 1))
    y = np.sin(2 * x[:, 0]) + 0.1 * rng.standard_normal(1000)
    model = LWPR(init_D=4.0, norm_in=1.0).fit(x, y)
    queries = np.linspace(-3, 3, 300)[:, None]
    assert nmse(model.predict(queries), np.sin(2 * queries[:, 0])) < 0.05   # 0.023


def test_learns_the_cross_function_and_improves_with_data(cross_run):
    model, history = cross_run
    first_error, last_error = history[0][0], history[-1][0]
    assert last_error < 0.05                  # 0.039 after 4000 samples (seeds 1, 2: 0.042)
    assert first_error > 2.5 * last_error     # 0.19 after 400 samples (seeds 1, 2: 0.16-0.21)
    assert model.n_data_ == 4000


def test_receptive_fields_are_created_and_their_number_levels_off(cross_run):
    model, history = cross_run
    counts = [rfs for _, rfs in history]
    assert counts == sorted(counts)                       # no pruning with w_prune = 1
    assert counts[0] >= 10 and counts[-1] <= 80           # 24 -> 58
    assert counts[-1] - counts[4] < counts[4] - counts[0]  # growth slows as the space fills
    fields = model.receptive_fields_[0]
    assert len(fields["c"]) == counts[-1]
    assert fields["trustworthy"].mean() > 0.9


def test_pruning_removes_overlapping_receptive_fields():
    X, Y = cross_data(800, seed=3)
    settings = dict(init_D=25.0, w_gen=0.4, update_D=False, norm_in=1.0)
    pruned = LWPR(w_prune=0.5, **settings).fit(X, Y)
    kept = LWPR(w_prune=1.0, **settings).fit(X, Y)
    assert pruned.n_pruned_[0] > 0 and kept.n_pruned_[0] == 0
    assert pruned.n_receptive_fields_[0] < kept.n_receptive_fields_[0]
    assert nmse(pruned.predict(X_GRID), cross(X_GRID)) < 0.5     # still a fit: 0.16


@pytest.mark.parametrize("pruning", [dict(), dict(w_gen=0.4, w_prune=0.5)])
def test_multi_output_equals_independent_single_output_models(pruning):
    X, y = cross_data(300, seed=4)
    Y = np.column_stack((y, np.sin(3 * X[:, 0]) * X[:, 1], 2.0 * X[:, 0] - X[:, 1]))
    settings = dict(CROSS, **pruning)
    joint = LWPR(**settings).fit(X, Y)
    assert (joint.n_pruned_ > 0).any() == bool(pruning)
    for j in range(3):
        alone = LWPR(**settings).fit(X, Y[:, j])
        np.testing.assert_allclose(joint.predict(X_GRID)[:, j], alone.predict(X_GRID),
                                   rtol=1e-9, atol=1e-12)
        assert joint.n_receptive_fields_[j] == alone.n_receptive_fields_[0]


def test_distance_metric_learning_repairs_a_too_wide_init_D():
    X, Y = cross_data(1000, seed=5)
    fixed = LWPR(init_D=2.0, update_D=False, w_gen=0.2, norm_in=1.0).fit(X, Y)
    learned = LWPR(init_D=2.0, init_alpha=250.0, w_gen=0.2, norm_in=1.0).fit(X, Y)
    fixed_error = nmse(fixed.predict(X_GRID), cross(X_GRID))
    learned_error = nmse(learned.predict(X_GRID), cross(X_GRID))
    assert learned_error < 0.6 * fixed_error      # 0.73 -> 0.25 (other seeds: 0.7 -> 0.19-0.26)
    D = learned.receptive_fields_[0]["D"]
    assert np.median(np.diagonal(D, axis1=1, axis2=2)) > 2 * 2.0      # narrowed: 14.5
    np.testing.assert_allclose(fixed.receptive_fields_[0]["D"][0], 2.0 * np.eye(2))


def test_full_metric_with_meta_learning_learns_the_cross():
    X, Y = cross_data(2000, seed=6)
    model = LWPR(diag_only=False, meta=True, norm_out=1.0, **CROSS).fit(X, Y)
    assert nmse(model.predict(X_GRID), cross(X_GRID)) < 0.12     # 0.073 (seeds 0, 1: 0.071)
    D = model.receptive_fields_[0]["D"]
    assert np.abs(D[:, 0, 1]).max() > 0                          # off-diagonal entries learned
    np.testing.assert_allclose(D, D.transpose(0, 2, 1))


def test_low_dimensional_structure_in_ten_inputs_is_found_by_the_projections():
    """The cross on a 2-D plane in 10-D (plus small noise off the plane), as in the paper's
    and the reference library's high-dimensional tests: local PLS needs only 2 projections."""
    rng = np.random.default_rng(7)
    rotation, _ = np.linalg.qr(rng.standard_normal((10, 10)))
    X, Y = cross_data(2500, seed=7)
    X10 = np.hstack((X, 0.02 * rng.standard_normal((2500, 8)))) @ rotation.T
    grid10 = np.hstack((X_GRID, np.zeros((len(X_GRID), 8)))) @ rotation.T
    model = LWPR(**CROSS).fit(X10, Y)
    assert nmse(model.predict(grid10), cross(X_GRID)) < 0.1    # 0.064 (3000 samples: 0.052-0.062)
    assert model.receptive_fields_[0]["n_projections"].max() <= 3    # 2 of 10 possible
    linear = np.linalg.lstsq(np.c_[X10, np.ones(2500)], Y, rcond=None)[0]
    assert nmse(np.c_[grid10, np.ones(len(grid10))] @ linear, cross(X_GRID)) > 0.9


def test_projections_are_added_while_they_cut_the_error_up_to_max_projections():
    """One wide RF on y = Σ x_i / s_i with input scales s_i = 2^-i: the first PLS direction
    (∝ s) misses much, the next ones reduce the error (MSE ratio 0.75, hence threshold 0.95)."""
    rng = np.random.default_rng(17)
    scales = 0.5 ** np.arange(6)
    X, X_test = rng.standard_normal((2, 1500, 6)) * scales
    settings = dict(init_D=0.01, update_D=False, norm_in=1.0, add_threshold=0.95)
    grown = LWPR(**settings).fit(X, (X / scales).sum(axis=1))
    capped = LWPR(max_projections=2, **settings).fit(X, (X / scales).sum(axis=1))
    assert grown.receptive_fields_[0]["n_projections"].tolist() == [3]
    assert capped.receptive_fields_[0]["n_projections"].tolist() == [2]
    truth = (X_test / scales).sum(axis=1)
    assert nmse(grown.predict(X_test), truth) < 0.8 * nmse(capped.predict(X_test), truth)  # .37/.57


def test_same_data_in_the_same_order_gives_identical_models():
    X, Y = cross_data(300, seed=8)
    a = LWPR(**CROSS).fit(X, Y).predict(X_GRID)
    b = clone(LWPR(**CROSS)).fit(X.copy(), Y.copy()).predict(X_GRID)
    np.testing.assert_array_equal(a, b)


def test_fit_equals_partial_fit_in_chunks_and_sample_by_sample():
    X, Y = cross_data(200, seed=9)
    settings = dict(CROSS, norm_out=0.5)
    whole = LWPR(**settings).fit(X, Y)
    chunks = LWPR(**settings)
    for part in np.array_split(np.arange(200), 7):
        chunks.partial_fit(X[part], Y[part])
    single = LWPR(**settings)
    for x, y in zip(X, Y):
        single.update(x, y)
    for other in (chunks, single):
        np.testing.assert_array_equal(whole.predict(X_GRID), other.predict(X_GRID))


def test_update_returns_the_prediction_made_before_learning():
    X, Y = cross_data(200, seed=10)
    model = LWPR(**CROSS).fit(X[:199], Y[:199])
    before = model.predict(X[199:])[0]
    assert model.update(X[199], Y[199]) == before
    assert model.predict(X[199:])[0] != before
    assert model.n_data_ == 200


def test_n_epochs_passes_over_the_data():
    X, Y = cross_data(200, seed=11)
    once, twice = (LWPR(n_epochs=n, **CROSS).fit(X, Y) for n in (1, 2))
    assert (once.n_data_, twice.n_data_) == (200, 400)
    assert nmse(twice.predict(X_GRID), cross(X_GRID)) < nmse(once.predict(X_GRID),
                                                             cross(X_GRID))


def test_output_shapes_follow_the_targets():
    X, y = cross_data(60, seed=12)
    single = LWPR(**CROSS).fit(X, y)
    assert single.predict(X[:5]).shape == (5,)
    assert isinstance(single.update(X[0], y[0]), float)
    multi = LWPR(**CROSS).fit(X, np.column_stack((y, -y)))
    assert multi.predict(X[:5]).shape == (5, 2)
    assert multi.update(X[0], [y[0], -y[0]]).shape == (2,)      # one sample given as (d,)
    multi.partial_fit(X[1], [y[1], -y[1]])
    with pytest.raises(ValueError, match="2-D"):                # scikit-learn convention
        multi.predict(X[0])
    assert (single.n_features_in_, multi.n_outputs_) == (2, 2)


def test_confidence_bounds_and_the_fallback_far_from_the_data(cross_run):
    model, _ = cross_run
    queries = np.array([[0.0, 0.0], [0.5, -0.5], [40.0, 40.0]])
    prediction, confidence = model.predict_with_confidence(queries)
    np.testing.assert_array_equal(prediction, model.predict(queries))
    assert np.all(np.isfinite(confidence[:2]) & (confidence[:2] > 0) & (confidence[:2] < 1))
    assert confidence[2] == np.inf              # no receptive field is active there
    assert -0.5 < prediction[2] < 1.5           # β0 of the nearest field, not an extrapolation


def test_an_untrained_region_predicts_zero_before_any_field_exists():
    model = LWPR(**CROSS)
    assert model.update([0.3, 0.3], 1.0) == 0.0          # no field yet: 0 (reference library)
    assert model.predict([[0.3, 0.3]])[0] == 1.0          # β0 of the one untrusted field


@pytest.mark.parametrize("X, Y, message", [
    ([[0.0, np.nan]], [1.0], "X contains NaN"),
    ([[0.0, 1.0]], [np.inf], "Y contains NaN or infinite"),
    ([[0.0, 1.0, 2.0]], [1.0], "X has 3 features"),
    (np.zeros((0, 2)), np.zeros(0), "X is empty"),
    ([[0.0, 1.0], [1.0, 0.0]], [1.0], "same number of rows"),
    ([[0.0, 1.0]], [[1.0, 2.0]], "Y has 2 columns"),
    ("abc", [1.0], "X must be a numeric"),
    ([[1j, 0.0]], [1.0], "complex"),
    ([[0.0, 1.0]], None, "target y is None"),
])
def test_bad_batches_raise_and_are_not_learned(X, Y, message):
    model = LWPR(**CROSS).fit(*cross_data(50, seed=13))
    before = model.predict(X_GRID)
    with pytest.raises(ValueError, match=message):
        model.partial_fit(X, Y)
    np.testing.assert_array_equal(model.predict(X_GRID), before)
    assert model.n_data_ == 50


@pytest.mark.parametrize("x, y, message", [
    ([np.inf, 0.0], 1.0, "X contains NaN"),
    ([0.0, 0.0], np.nan, "Y contains NaN"),
    ([0.0, 0.0, 0.0], 1.0, "X has 3 features"),
    ([[0.0, 0.0], [1.0, 1.0]], [1.0, 1.0], "single sample"),
])
def test_bad_single_samples_raise_in_update(x, y, message):
    model = LWPR(**CROSS).fit(*cross_data(50, seed=13))
    with pytest.raises(ValueError, match=message):
        model.update(x, y)
    assert model.n_data_ == 50


def test_a_bad_row_anywhere_in_a_batch_rejects_the_whole_batch():
    X, Y = cross_data(100, seed=14)
    model = LWPR(**CROSS).fit(X[:50], Y[:50])
    Y_bad = Y[50:].copy()
    Y_bad[-1] = np.nan
    with pytest.raises(ValueError, match="row 49"):
        model.partial_fit(X[50:], Y_bad)
    assert model.n_data_ == 50


@pytest.mark.parametrize("params, message", [
    (dict(init_D=-1.0), "positive definite"),
    (dict(init_D=[[1.0, 0.5], [0.5, 1.0]]), "off-diagonal"),
    (dict(init_D=[1.0, 2.0, 3.0]), "init_D must be"),
    (dict(init_alpha=0.0), "init_alpha"),
    (dict(w_gen=1.5), "w_gen"),
    (dict(final_lambda=1.0), "final_lambda"),
    (dict(kernel="bisquare"), "gaussian"),
    (dict(update_D="yes"), "update_D"),
    (dict(max_projections=0), "max_projections"),
    (dict(norm_in=[1.0, -1.0]), "norm_in"),
    (dict(n_epochs=0), "n_epochs"),
])
def test_bad_hyperparameters_raise(params, message):
    with pytest.raises(ValueError, match=message):
        LWPR(**params).fit(*cross_data(10, seed=15))


def test_predicting_before_fitting_raises():
    with pytest.raises(NotFittedError):
        LWPR().predict([[0.0, 0.0]])


def test_sklearn_parameters_are_stored_unchanged_and_clonable():
    init_D = np.array([[30.0, 0.0], [0.0, 10.0]])
    model = LWPR(init_D=init_D, init_alpha=0.01, diag_only=True)
    assert model.get_params()["init_D"] is init_D
    copy = clone(model).set_params(w_gen=0.2)
    assert copy.get_params()["init_alpha"] == 0.01 and copy.w_gen == 0.2
    X, Y = cross_data(100, seed=16)
    np.testing.assert_allclose(copy.partial_fit(X[:1], Y[:1]).receptive_fields_[0]["D"][0],
                               init_D)
    fitted = copy.fit(X, Y)
    assert not hasattr(clone(fitted), "n_data_")
    assert fitted.score(X, Y) == pytest.approx(1 - nmse(fitted.predict(X), Y))


@pytest.mark.filterwarnings("ignore::sklearn.exceptions.SkipTestWarning")  # no pandas etc.
def test_scikit_learn_estimator_checks():
    expected_failures = {
        "check_dtype_object": "non-numeric input raises ValueError (project convention), "
                              "not TypeError",
        "check_supervised_y_2d": "a (n, 1) target is a 2-D target: predictions keep its shape",
    }
    results = check_estimator(LWPR(init_D=1.0), on_fail=None,
                              expected_failed_checks=expected_failures)
    assert [r["check_name"] for r in results if r["status"] == "failed"] == []


# ----------------------------------------------------------------- equality with the reference
@functools.cache
def reference_lwpr():
    """The frozen numpy LWPR of test/oracles/reference_lwpr.py (loaded by path: oracles/ is
    no package)."""
    spec = importlib.util.spec_from_file_location("reference_lwpr",
                                                  ROOT / "test" / "oracles" / "reference_lwpr.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.LWPR


#: rtol of the equality checks. The kernels repeat the reference's operations in its order
#: per RF; only sums that numpy leaves to SIMD loops or BLAS round differently.
RTOL = 1e-9
#: Learned arrays compared per output (receptive_fields_ keys).
ARRAYS = ("c", "x0", "D", "M", "beta0", "beta", "U", "P", "n_projections", "n_data",
          "trustworthy")


def assert_close(actual, expected, what):
    """rtol RTOL; an absolute floor of 1e-12 of the array's scale for entries that are zero
    up to rounding (e.g. PLS directions orthogonal to an input)."""
    expected = np.asarray(expected)
    scale = float(np.abs(expected).max()) if expected.size and expected.dtype != bool else 1.0
    np.testing.assert_allclose(actual, expected, rtol=RTOL, atol=1e-12 * max(scale, 1e-300),
                               err_msg=what)


def sine_data(n, seed):
    rng = np.random.default_rng(seed)
    x = rng.uniform(-np.pi, np.pi, (n, 1))
    return x, np.sin(2 * x[:, 0]) + 0.1 * rng.standard_normal(n)


def three_outputs(n, seed):
    X, y = cross_data(n, seed)
    return X, np.column_stack((y, np.sin(3 * X[:, 0]) * X[:, 1], 2.0 * X[:, 0] - X[:, 1]))


def six_scales(n, seed):
    """y = Σ x_i / s_i with scales s_i = 2^-i (the projection test): adds projections."""
    scales = 0.5 ** np.arange(6)
    X = np.random.default_rng(seed).standard_normal((n, 6)) * scales
    return X, (X / scales).sum(axis=1)


EQUALITY_CASES = {
    "sine": (sine_data, 1000, dict(init_D=4.0, norm_in=1.0)),
    "cross": (cross_data, 1500, CROSS),
    "cross, meta": (cross_data, 1500, dict(CROSS, meta=True)),
    "cross, full metric": (cross_data, 1000, dict(CROSS, diag_only=False)),
    "cross, full metric, meta": (cross_data, 1000,
                                 dict(CROSS, diag_only=False, meta=True, norm_out=1.0)),
    "cross, pruning": (cross_data, 800, dict(init_D=25.0, w_gen=0.4, w_prune=0.5,
                                             norm_in=1.0)),
    "cross, pruning, fixed metrics": (cross_data, 800, dict(init_D=25.0, w_gen=0.4,
                                                            w_prune=0.5, update_D=False,
                                                            norm_in=1.0)),
    "3 outputs": (three_outputs, 600, CROSS),
    "3 outputs, pruning, meta": (three_outputs, 600, dict(CROSS, w_gen=0.4, w_prune=0.5,
                                                          meta=True)),
    "3 outputs, full metric, meta": (three_outputs, 400, dict(CROSS, diag_only=False,
                                                              meta=True)),
    "6 inputs, added projections": (six_scales, 1500, dict(init_D=0.01, update_D=False,
                                                           norm_in=1.0, add_threshold=0.95)),
}


@pytest.mark.parametrize("case", list(EQUALITY_CASES))
def test_equals_the_reference_implementation(case):
    """The compiled LWPR reproduces test/oracles/reference_lwpr.py: the predictions made while
    learning online (update), the final predictions and confidences, the number of
    receptive fields, the pruning counts and the learned arrays of every field, to RTOL."""
    data, n, params = EQUALITY_CASES[case]
    X, Y = data(n + 1, seed=21)
    queries = X_GRID if X.shape[1] == 2 else data(200, seed=22)[0]
    models = [learner(**params) for learner in (LWPR, reference_lwpr())]
    online = []
    for model in models:
        model.partial_fit(X[:n // 2], Y[:n // 2])             # norm_* from the first half
        online.append([model.update(x, y) for x, y in zip(X[n // 2:], Y[n // 2:])])
    new, ref = models
    assert_close(np.array(online[0]), np.array(online[1]), "update's predictions")
    np.testing.assert_array_equal(new.n_receptive_fields_, ref.n_receptive_fields_)
    np.testing.assert_array_equal(new.n_pruned_, ref.n_pruned_)
    assert ("pruning" in case) == bool(ref.n_pruned_.any())
    assert_close(new.predict(queries), ref.predict(queries), "predict")
    for got, want in zip(new.predict_with_confidence(queries[::7]),
                         ref.predict_with_confidence(queries[::7])):
        assert_close(got, want, "predict_with_confidence")
    for j, (got, want) in enumerate(zip(new.receptive_fields_, ref.receptive_fields_)):
        for name in ARRAYS:
            assert got[name].shape == want[name].shape, (j, name)
            assert_close(got[name], want[name], f"output {j}: {name}")
    if case.startswith("6 inputs"):
        assert ref.receptive_fields_[0]["n_projections"].tolist() == [3]


def test_equals_the_reference_with_15_inputs_and_5_outputs():
    """The benchmark's shape in small: 15 inputs -> 5 outputs, one 3-s trajectory repeated
    with noise (as repeated trials), so that fields become trustworthy; online update."""
    rng = np.random.default_rng(23)
    t = np.arange(300)[:, None] * 0.01
    task = np.sin(2 * np.pi * rng.uniform(0.2, 1.0, 15) * t + rng.uniform(0, 2 * np.pi, 15))
    X = np.vstack([task + 0.02 * rng.standard_normal(task.shape) for _ in range(5)])
    Y = np.column_stack([np.tanh(X[:, i:i + 3].sum(axis=1)) for i in range(0, 15, 3)])
    models = [learner(init_D=10.0, init_alpha=0.01).fit(X[:1200], Y[:1200])
              for learner in (LWPR, reference_lwpr())]
    new, ref = models
    assert ref.receptive_fields_[0]["trustworthy"].mean() > 0.9      # 57 of 58
    online = [np.array([model.update(x, y) for x, y in zip(X[1200:], Y[1200:])])
              for model in models]
    assert_close(online[0], online[1], "update's predictions")
    np.testing.assert_array_equal(new.n_receptive_fields_, ref.n_receptive_fields_)
    assert_close(new.predict(X[::5]), ref.predict(X[::5]), "predict")
    for got, want in zip(new.receptive_fields_, ref.receptive_fields_):
        for name in ARRAYS:
            assert_close(got[name], want[name], name)


def test_empty_prediction_zero_answers_0_where_no_field_is_active():
    """Outside the data: the authors' library predicts 0 where no receptive field is active;
    ours (default "nearest") the nearest field's offset. Inside the data both agree, also for
    the prediction made before learning in update()."""
    rng = np.random.default_rng(0)
    X = rng.uniform(-1, 1, size=(300, 2))
    Y = np.column_stack((np.sin(X[:, 0]) + 2.0, X[:, 1] ** 2 - 1.0))
    models = {rule: LWPR(init_D=50.0, norm_in=1.0, norm_out=1.0, empty_prediction=rule)
              for rule in ("nearest", "zero")}
    for model in models.values():
        model.fit(X, Y)
    far = np.array([[8.0, 8.0]])
    np.testing.assert_array_equal(models["zero"].predict(far), [[0.0, 0.0]])
    assert np.abs(models["nearest"].predict(far)).min() > 0.1
    inside = X[:20]
    np.testing.assert_array_equal(models["zero"].predict(inside), models["nearest"].predict(inside))
    assert np.array_equal(models["zero"].update(far[0], [0.0, 0.0]), [0.0, 0.0])
    default = LWPR(init_D=50.0, norm_in=1.0, norm_out=1.0).fit(X, Y)
    np.testing.assert_array_equal(default.predict(far), models["nearest"].predict(far))
    with pytest.raises(ValueError, match="empty_prediction must be"):
        LWPR(empty_prediction="mean").fit(X, Y)
