"""Joint-space DMPs (thesis §4.4.4, eq. 4.1-4.5): reproduction of a smooth demonstration,
a new start and goal, determinism and input checks."""
import numpy as np
import pytest
from sklearn.base import clone
from sklearn.exceptions import NotFittedError

from lpa_transfer.demonstrations import load_lasa
from lpa_transfer.dmp import JointDMP

GOAL_SHIFT = np.array([0.2, -0.1, 0.05, 0.3])


@pytest.fixture(scope="module")
def demo():
    """A LASA G mapped smoothly to 4 joints (rad): (times (1000,), Q (1000, 4))."""
    positions, times = load_lasa("GShape", n_demos=1)
    p = positions[0] / 1000.0
    mixing = np.array([[8.0, 2.0], [-3.0, 6.0], [5.0, -4.0], [1.0, 1.0]])
    return times[0], np.tanh(3 * p @ mixing.T) + np.array([0.1, -0.2, 0.3, 0.0])


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
    dmp = JointDMP().fit(times, Q)
    with pytest.raises(ValueError, match="goal must be a finite vector of 4"):
        dmp.reproduce(goal=np.zeros(3))
    with pytest.raises(ValueError, match="start must be a finite vector"):
        dmp.reproduce(start=np.full(4, np.nan))
    with pytest.raises(ValueError, match="strictly increasing"):
        dmp.reproduce(times=times[::-1])
