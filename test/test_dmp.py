"""Joint-space DMPs (thesis §4.4.4, eq. 4.1-4.5): reproduction of a smooth demonstration,
a new start and goal, one DMP from several demonstrations (§4.5.2), determinism and input
checks."""
import numpy as np
import pytest
from movement_primitives.dmp import DMP, canonical_system_alpha
from movement_primitives.dmp._dmp import determine_forces
from movement_primitives.dmp._forcing_term import ForcingTerm
from sklearn.base import clone
from sklearn.exceptions import NotFittedError

from lpa_transfer.lfd.demonstrations import load_lasa
from lpa_transfer.lfd.dmp import JointDMP

GOAL_SHIFT = np.array([0.2, -0.1, 0.05, 0.3])


@pytest.fixture(scope="module")
def demo():
    """A LASA G mapped smoothly to 4 joints (rad): (times (1000,), Q (1000, 4))."""
    positions, times = load_lasa("GShape", n_demos=1)
    p = positions[0] / 1000.0
    mixing = np.array([[8.0, 2.0], [-3.0, 6.0], [5.0, -4.0], [1.0, 1.0]])
    return times[0], np.tanh(3 * p @ mixing.T) + np.array([0.1, -0.2, 0.3, 0.0])


@pytest.fixture(scope="module")
def noisy_demos(demo):
    """5 copies of ``demo``: durations ×(1, 0.8, 1.3, 0.9, 1.25) (mean τ: 1.05 × the demo's),
    1000/800/1200/900/1100 samples, a mild time warp on all but the first and white noise of
    0.004 rad (the first, noisiest) and 0.002 rad (the others).

    Returns (times_list, Q_list, clean first copy (1000, 4))."""
    times, Q = demo
    rng = np.random.default_rng(0)
    times_list, Q_list, cleans = [], [], []
    for scale, n, warp, noise in zip((1.0, 0.8, 1.3, 0.9, 1.25), (1000, 800, 1200, 900, 1100),
                                     (0.0, 0.03, -0.03, 0.02, -0.02),
                                     (0.004, 0.002, 0.002, 0.002, 0.002)):
        u = np.linspace(0.0, 1.0, n)
        warped = (u + warp * np.sin(np.pi * u)) * times[-1]
        clean = np.column_stack([np.interp(warped, times, q) for q in Q.T])
        times_list.append(1.0 + scale * times[-1] * u)           # need not start at 0
        Q_list.append(clean + rng.normal(0.0, noise, clean.shape))
        cleans.append(clean)
    return times_list, Q_list, cleans[0]


def test_fit_is_the_library_imitation(demo):
    times, Q = demo
    dmp = JointDMP().fit(times, Q)
    library = DMP(n_dims=4, execution_time=times[-1], n_weights_per_dim=30, alpha_y=25.0,
                  beta_y=6.25)
    library.imitate(times, Q)
    np.testing.assert_allclose(dmp.weights_, library.forcing_term.weights_, rtol=1e-10, atol=0)
    assert dmp.n_demonstrations_ == 1


def test_fit_many_on_one_demonstration_is_fit(demo):
    times, Q = demo
    one = JointDMP().fit(times, Q)
    many = JointDMP().fit_many([times], [Q])
    np.testing.assert_allclose(many.weights_, one.weights_, rtol=1e-10, atol=0)
    for name in ("start_", "goal_", "times_", "tau_", "n_features_in_", "n_demonstrations_"):
        np.testing.assert_array_equal(getattr(many, name), getattr(one, name))


def test_fit_many_averages_out_the_noise_of_the_first_demonstration(noisy_demos):
    """One DMP from all 5 copies reproduces the first (start and goal of its noisy samples)
    with an RMSE of 0.016 rad from the clean trajectory; one fitted on the first copy alone,
    the noisiest, has 0.032 rad (the finite differences amplify its noise)."""
    times_list, Q_list, clean = noisy_demos
    dmp = JointDMP().fit_many(times_list, Q_list)
    assert dmp.n_demonstrations_ == 5 and dmp.weights_.shape == (4, 30)
    assert dmp.tau_ == pytest.approx(np.mean([t[-1] - t[0] for t in times_list]))
    np.testing.assert_array_equal(dmp.start_, Q_list[0][0])
    np.testing.assert_array_equal(dmp.goal_, Q_list[0][-1])
    np.testing.assert_allclose(dmp.times_, np.linspace(0.0, dmp.tau_, 1000), atol=1e-12)
    R = dmp.reproduce()
    single = JointDMP().fit(times_list[0], Q_list[0]).reproduce()
    error, single_error = (np.sqrt(((X - clean) ** 2).mean()) for X in (R, single))
    assert error < 0.02
    assert error < 0.6 * single_error


@pytest.mark.parametrize("regularization", [0.0, 1e-2])
def test_fit_many_weights_solve_the_stacked_regression(noisy_demos, regularization):
    """Independently of the module: the library's targets and features per demonstration on
    times rescaled to [0, mean duration], stacked, and solved by least squares (ridge)."""
    times_list, Q_list, _ = noisy_demos
    tau = np.mean([t[-1] - t[0] for t in times_list])
    alpha_x = canonical_system_alpha(0.01, tau, 0.0)
    term = ForcingTerm(4, 30, tau, 0.0, 0.8, alpha_x)
    X, F = [], []
    for times, Q in zip(times_list, Q_list):
        rescaled = (times - times[0]) / (times[-1] - times[0]) * tau
        X.append(term.design_matrix(rescaled).T)
        F.append(determine_forces(rescaled, Q, np.full(4, 25.0), np.full(4, 6.25), alpha_x,
                                  False)[0])
    X, F = np.vstack(X), np.vstack(F)
    if regularization:
        expected = np.linalg.solve(X.T @ X + regularization * np.eye(30), X.T @ F).T
    else:
        expected = np.linalg.lstsq(X, F, rcond=None)[0].T
    weights = JointDMP(regularization=regularization).fit_many(times_list, Q_list).weights_
    np.testing.assert_allclose(weights, expected, rtol=1e-6, atol=1e-6 * np.abs(expected).max())

    def loss(W):
        return ((X @ W.T - F) ** 2).sum() + regularization * (W ** 2).sum()
    rng = np.random.default_rng(1)
    for _ in range(5):
        assert loss(weights) < loss(weights + 1e-3 * rng.normal(size=weights.shape))


@pytest.mark.parametrize("integrator", ["rk4", "euler"])
def test_reproduces_the_demonstration(demo, integrator):
    times, Q = demo
    dmp = JointDMP(integrator=integrator).fit(times, Q)
    assert dmp.weights_.shape == (4, 30)
    assert dmp.tau_ == pytest.approx(times[-1] - times[0])
    np.testing.assert_array_equal(dmp.start_, Q[0])
    np.testing.assert_array_equal(dmp.goal_, Q[-1])
    R = dmp.reproduce()
    assert R.shape == Q.shape
    np.testing.assert_array_equal(R[0], Q[0])
    relative_rmse = np.sqrt(((R - Q) ** 2).mean(axis=0)) / np.ptp(Q, axis=0)
    assert relative_rmse.max() < 0.005
    assert np.abs(R[-1] - Q[-1]).max() < 0.005


def test_fewer_weights_fit_worse(demo):
    times, Q = demo
    errors = [np.sqrt(((JointDMP(n_weights_per_dim=n).fit(times, Q).reproduce() - Q) ** 2)
                      .mean()) for n in (5, 30)]
    assert errors[1] < errors[0] / 3


def test_converges_to_a_new_goal_from_a_new_start(demo):
    times, Q = demo
    dmp = JointDMP().fit(times, Q)
    start, goal = Q[0] + 0.05, Q[-1] + GOAL_SHIFT
    dt = times[1] - times[0]
    long = np.arange(0.0, 4 * dmp.tau_, dt)                   # past τ: the point attractor
    R = dmp.reproduce(long, start=start, goal=goal)
    np.testing.assert_array_equal(R[0], start)
    at_tau = np.searchsorted(long, dmp.tau_)
    assert np.abs(R[at_tau] - goal).max() < 0.005
    assert np.abs(R[-1] - goal).max() < 1e-4
    # the shape is kept: until τ the reproduction strays from the demonstration by about
    # the shift of its start and goal (at most 0.3 rad), not more
    assert np.abs(R[:at_tau] - Q[:at_tau]).max() < np.abs(GOAL_SHIFT).max() + 0.05


def test_reproduce_on_other_times_and_unevenly_sampled_demos(demo):
    times, Q = demo
    dmp = JointDMP().fit(times, Q)
    coarse = dmp.reproduce(times[::5])                        # 5x the step: RK4 still close
    assert np.abs(coarse - Q[::5]).max() < 0.05
    shifted = JointDMP().fit(times + 10.0, Q)                  # times need not start at 0
    np.testing.assert_allclose(shifted.reproduce(), dmp.reproduce(), atol=1e-9)
    uneven = np.sort(np.r_[times[::2], times[1::4]])
    keep = np.isin(times, uneven)
    R = JointDMP().fit(times[keep], Q[keep]).reproduce()
    assert np.abs(R - Q[keep]).max() < 0.05


def test_is_deterministic_and_leaves_the_fit_unchanged(demo):
    times, Q = demo
    dmp = JointDMP().fit(times, Q)
    first = dmp.reproduce(goal=Q[-1] + GOAL_SHIFT)
    weights = dmp.weights_.copy()
    np.testing.assert_array_equal(dmp.reproduce(goal=Q[-1] + GOAL_SHIFT), first)
    np.testing.assert_array_equal(dmp.weights_, weights)
    np.testing.assert_array_equal(clone(dmp).fit(times, Q).reproduce(), dmp.reproduce())


def test_regularization_shrinks_the_weights(demo):
    times, Q = demo
    plain = JointDMP().fit(times, Q)
    ridge = JointDMP(regularization=1e-2).fit(times, Q)
    assert np.abs(ridge.weights_).max() < np.abs(plain.weights_).max()


def test_rejects_bad_input(demo):
    times, Q = demo
    nan_Q = Q.copy()
    nan_Q[10, 2] = np.nan
    bad_times = times.copy()
    bad_times[5] = bad_times[4]
    cases = [((times, nan_Q), "Q contains NaN"),
             ((times[:2], Q[:2]), "at least 3 samples"),
             ((times, Q[:-1]), "Q has 999 rows but times has 1000"),
             ((bad_times, Q), "strictly increasing"),
             ((times[:, None], Q), "1-D"),
             ((np.where(times > 1, np.inf, times), Q), "times contains NaN"),
             ((times, Q[:, 0]), "2-D")]
    for args, message in cases:
        with pytest.raises(ValueError, match=message):
            JointDMP().fit(*args)
    for params, message in [(dict(n_weights_per_dim=1), "n_weights_per_dim"),
                            (dict(alpha_z=-1.0), "alpha_z"), (dict(beta_z=0.0), "beta_z"),
                            (dict(regularization=-1.0), "regularization"),
                            (dict(integrator="rk45"), "integrator")]:
        with pytest.raises(ValueError, match=message):
            JointDMP(**params).fit(times, Q)
    with pytest.raises(NotFittedError):
        JointDMP().reproduce()
    more = (times[:500], Q[:500, :3])
    for times_list, Q_list, message in [
            ([], [], "at least one demonstration"),
            ([times, times], [Q], "times_list has 2 demonstrations but Q_list has 1"),
            ([times, times[:-1]], [Q, Q], r"Q_list\[1\] has 1000 rows but times_list\[1\] has 999"),
            ([times, more[0]], [Q, more[1]], r"Q_list\[1\] has 3 joints .* Q_list\[0\] has 4"),
            ([times, times], [Q, nan_Q], r"Q_list\[1\] contains NaN"),
            ([times[:2], times], [Q[:2], Q], r"Q_list\[0\] must have at least 3 samples"),
            ([times, bad_times], [Q, Q], r"times_list\[1\] must be strictly increasing")]:
        with pytest.raises(ValueError, match=message):
            JointDMP().fit_many(times_list, Q_list)
    dmp = JointDMP().fit(times, Q)
    with pytest.raises(ValueError, match="goal must be a finite vector of 4"):
        dmp.reproduce(goal=np.zeros(3))
    with pytest.raises(ValueError, match="start must be a finite vector"):
        dmp.reproduce(start=np.full(4, np.nan))
    with pytest.raises(ValueError, match="strictly increasing"):
        dmp.reproduce(times=times[::-1])
