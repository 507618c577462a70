"""Correspondences read off splines (thesis §5.4.1): lpa_transfer.inverse_dynamics.interpolation."""
import numpy as np
import pytest

from lpa_transfer.inverse_dynamics.interpolation import interpolated, spline_states

DT = 0.01


def tracked(noise, seed=0, samples=120):
    """Two joints on smooth paths sampled every DT: q exact, q̇ and τ with measurement noise,
    q̈ by backward difference of the noisy q̇ (as the learners record it); and the true q̈."""
    rng = np.random.default_rng(seed)
    t = np.arange(samples) * DT
    q = np.column_stack((np.sin(3 * t), 0.5 * np.cos(2 * t)))
    qd = np.column_stack((3 * np.cos(3 * t), -np.sin(2 * t))) + noise * rng.standard_normal(q.shape)
    qdd_true = np.column_stack((-9 * np.sin(3 * t), -2 * np.cos(2 * t)))
    qdd = np.vstack((qdd_true[:1], np.diff(qd, axis=0) / DT))
    tau = 2.0 * qdd_true + 0.3 * q + noise * rng.standard_normal(q.shape)
    return np.hstack((q, qd, qdd, tau)), qdd_true


def test_spline_accelerations_are_nearer_the_truth_than_backward_differences():
    rows, qdd_true = tracked(noise=0.01)
    smooth = spline_states(rows, stretch=60, dt=DT)
    raw_error = np.sqrt(((rows[:, 4:6] - qdd_true) ** 2).mean())
    spline_error = np.sqrt(((smooth[:, 4:6] - qdd_true) ** 2).mean())
    assert spline_error < raw_error / 3, (spline_error, raw_error)
    np.testing.assert_array_equal(smooth[:, :2], rows[:, :2])      # q as measured


def test_exact_smooth_data_stay_close():
    rows, qdd_true = tracked(noise=0.0)
    smooth = spline_states(rows, stretch=60, dt=DT)
    np.testing.assert_allclose(smooth[:, 2:4], rows[:, 2:4], atol=5e-3)
    # away from the stretches' ends the derivative of a spline through exact q̇ is the true q̈
    inner = np.r_[5:55, 65:115]
    np.testing.assert_allclose(smooth[inner, 4:6], qdd_true[inner], atol=0.05)


def test_each_stretch_is_splined_alone_and_still_joints_stay():
    rows, _ = tracked(noise=0.01)
    rows[:, [1, 3, 5, 7]] = [0.2, 0.0, 0.0, 1.5]              # joint 2 held still
    whole = spline_states(rows, stretch=60, dt=DT)
    first = spline_states(rows[:60], stretch=60, dt=DT)
    np.testing.assert_array_equal(whole[:60], first)
    np.testing.assert_array_equal(whole[:, [1, 3, 5, 7]], rows[:, [1, 3, 5, 7]])
    # a tail shorter than a spline needs is kept as measured
    short = spline_states(rows[:63], stretch=60, dt=DT)
    np.testing.assert_array_equal(short[60:], rows[60:63])


def test_none_returns_the_rows_and_bad_settings_are_refused():
    rows, _ = tracked(noise=0.01)
    assert interpolated(rows, "none", 60, DT) is rows
    with pytest.raises(ValueError, match="interpolation must be one of"):
        interpolated(rows, "cubic", 60, DT)
    with pytest.raises(ValueError, match=r"\(N, 4n\)"):
        spline_states(rows[:, :7], 60, DT)
    with pytest.raises(ValueError, match="dt must be > 0"):
        spline_states(rows, 60, 0.0)
    bad = rows.copy()
    bad[3, 2] = np.nan
    with pytest.raises(ValueError, match="finite"):
        spline_states(bad, 60, DT)


@pytest.mark.parametrize("samples, dt, scale, lam", [(5, DT, 1.0, None), (7, 0.02, 1e-4, None),
                                                     (120, DT, 50.0, None), (840, DT, 1.0, None),
                                                     (60, 1 / 3, 1.0, 0.37)])
def test_the_fast_spline_is_scipys_to_the_bit(samples, dt, scale, lam):
    """_gcv.smoothing_spline chooses λ and builds the spline as scipy's make_smoothing_spline
    does, bit for bit (the chapter 5 references depend on it; a scipy upgrade that changes
    its GCV fails here)."""
    from scipy.interpolate import make_smoothing_spline

    from lpa_transfer.inverse_dynamics._gcv import smoothing_spline
    rng = np.random.default_rng(samples)
    t = np.arange(samples) * dt
    y = scale * np.cumsum(rng.standard_normal(samples)) + np.sin(5 * t)
    theirs, ours = make_smoothing_spline(t, y, lam=lam), smoothing_spline(y, dt, lam)
    assert np.array_equal(theirs.t, ours.t) and np.array_equal(theirs.c, ours.c)
    assert np.array_equal(theirs.derivative()(t), ours.derivative()(t))
