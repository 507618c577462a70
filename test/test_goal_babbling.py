"""lpa_transfer.goal_babbling.goal_babbling: online goal babbling (Alg. 6) and its exploration noise (eq. 6.1).

The robots are the 2-link arms of the thesis' goal-babbling experiment (Table 6.1), built
from their lengths here: the robot files two_link_source/target.toml are the §3.6 arms.
"""
import numpy as np
import pytest

from lpa_transfer.goal_babbling.goal_babbling import ExplorationNoise, GoalBabbling, subtargets
from lpa_transfer._validation import check_x_bounds
from lpa_transfer.robots.kinematics import planar_forward_kinematics
from lpa_transfer.goal_babbling.reaching import evaluate_reaching, evaluation_points
from two_link import GB_HOME, TABLE_6_1_LIMITS, GB_TARGET_BOUNDS, GB_TARGET_LINKS, table_6_1_arm

def babble(seed, n_steps, **hyperparameters):
    babbler = GoalBabbling(GB_TARGET_BOUNDS, seed=seed, **hyperparameters)
    commands, positions = babbler.start(table_6_1_arm(GB_TARGET_LINKS)).run(n_steps)
    return babbler, commands, positions


# -- sub-targets ------------------------------------------------------------------------------
def test_subtargets_are_evenly_spaced_on_the_line_and_end_at_the_goal():
    points = subtargets([0.0, 1.0], [1.0, 3.0], 4)
    np.testing.assert_allclose(points, [[0.25, 1.5], [0.5, 2.0], [0.75, 2.5], [1.0, 3.0]])


# -- exploration noise ------------------------------------------------------------------------
def noise_path(n_steps, sigma=0.1, drift=0.01, seed=0, n_joints=2, n_task=2):
    noise = ExplorationNoise(n_joints, n_task, sigma, drift, np.random.default_rng(seed))
    path = []
    for _ in range(n_steps):
        path.append(np.concatenate((noise.A_.ravel(), noise.b_)))
        noise.step()
    return noise, np.array(path)


def test_noise_is_the_linear_function_of_eq_6_1():
    noise, _ = noise_path(1)
    x = np.array([0.3, -0.7])
    np.testing.assert_allclose(noise(x), noise.A_ @ x + noise.b_)
    assert noise.A_.shape == (2, 2) and noise.b_.shape == (2,)


def test_noise_drifts_slowly_consecutive_close_distant_different():
    _, path = noise_path(3000)
    step = np.sqrt(((path[1:] - path[:-1]) ** 2).mean())
    far = np.sqrt(((path[2000:] - path[:-2000]) ** 2).mean())
    assert step < 0.02             # per-entry change of about drift = 0.01
    assert far > 0.1               # ~sqrt(2)·sigma once the walk has forgotten its start
    assert far > 10 * step


def test_noise_keeps_its_variance_sigma_squared():
    noise, _ = noise_path(300, sigma=0.2, drift=0.05, n_joints=40, n_task=40)
    assert np.std(noise.A_) == pytest.approx(0.2, rel=0.1)


def test_zero_sigma_means_no_noise():
    noise, path = noise_path(20, sigma=0.0)
    assert not path.any() and not noise(np.ones(2)).any()


# -- goal babbling ----------------------------------------------------------------------------
def test_inverse_model_starts_at_home():
    babbler = GoalBabbling(GB_TARGET_BOUNDS).start(table_6_1_arm(GB_TARGET_LINKS))
    x_home = planar_forward_kinematics(GB_HOME[None], GB_TARGET_LINKS)
    np.testing.assert_array_equal(babbler.model_.infer_command([[0.5, -0.5], [1.0, 0.0]]),
                                  [GB_HOME, GB_HOME])
    np.testing.assert_array_equal(babbler.position_, x_home[0])
    assert babbler.steps_ == 0 and babbler.time_ == 0.0


def test_samples_are_what_the_robot_did_within_its_joint_limits():
    babbler, commands, positions = babble(0, 300)
    limits = TABLE_6_1_LIMITS
    assert ((commands >= limits[:, 0]) & (commands <= limits[:, 1])).all()
    np.testing.assert_allclose(positions, planar_forward_kinematics(commands, GB_TARGET_LINKS))
    assert babbler.model_.inverse.n_samples_ == babbler.model_.forward.n_samples_ == 301
    np.testing.assert_array_equal(babbler.model_.inverse.Y_[1:], commands)   # after home


def test_same_seed_same_run_bit_for_bit_other_seed_differs():
    first, second, other = (babble(seed, 300) for seed in (7, 7, 8))
    for a, b in zip(first[1:], second[1:]):
        np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(first[0].noise_.A_, second[0].noise_.A_)
    assert not np.allclose(first[1], other[1])


def test_returns_home_alternate_with_goals_when_p_home_is_1():
    babbler, commands, _ = babble(0, 60, n_subtargets=10, p_home=1.0)
    np.testing.assert_array_equal(commands[19::20], np.tile(GB_HOME, (3, 1)))
    assert not np.isclose(commands[9::20], GB_HOME).all(axis=1).any()


def test_callback_every_interval_of_simulated_time():
    times = []
    babbler = GoalBabbling(GB_TARGET_BOUNDS, steps_per_second=10).start(table_6_1_arm(GB_TARGET_LINKS))
    commands, _ = babbler.run_for(10.0, callback=lambda b: times.append(b.time_), interval=2.5)
    assert len(commands) == 100 and babbler.time_ == 10.0
    assert times == [2.5, 5.0, 7.5, 10.0]


def test_goal_babbling_reduces_the_reaching_error_over_time():
    """The learning curve of §6.5.1 (target arm of Table 6.1), tested at 0, 100 and 300 s."""
    target = table_6_1_arm(GB_TARGET_LINKS)
    points = evaluation_points(target, GB_TARGET_BOUNDS, spacing=0.1)
    babbler = GoalBabbling(GB_TARGET_BOUNDS, seed=1).start(target)
    curve = [evaluate_reaching(babbler.model_.inverse, target, points)]
    babbler.run_for(300, callback=lambda b: curve.append(
        evaluate_reaching(b.model_.inverse, target, points)), interval=100)
    errors = [result.mean_error for result in curve]
    assert len(points) > 50 and len(curve) == 4
    assert errors[0] > 0.2 and curve[0].rate < 0.05   # home only
    assert errors[0] > errors[1] > errors[3]
    assert errors[3] < 0.03 and curve[3].rate > 0.5


@pytest.mark.parametrize("hyperparameters, message", [
    ({"x_bounds": ((0.0, 0.0), (1.0,))}, "x_bounds must be finite"),
    ({"x_bounds": ((1.0, 0.0), (0.0, 1.0))}, "low <= high"),
    ({"x_bounds": ((0.0, 0.0, 0.0), (1.0, 1.0, 1.0))}, "3 coordinates but the robot's task"),
    ({"n_subtargets": 0}, "n_subtargets must be an integer >= 1"),
    ({"p_home": 1.5}, "need p_home <= 1"),
    ({"sigma": -0.1}, "sigma must be a finite number >= 0"),
    ({"home": (1.0, 1.0)}, "outside the joint limits"),
    ({"seed": -1}, "seed must be an integer >= 0"),
])
def test_bad_hyperparameters_raise_a_clear_value_error(hyperparameters, message):
    hyperparameters = {"x_bounds": GB_TARGET_BOUNDS, **hyperparameters}
    with pytest.raises(ValueError, match=message):
        GoalBabbling(**hyperparameters).start(table_6_1_arm(GB_TARGET_LINKS))


def test_exploring_before_start_raises():
    with pytest.raises(ValueError, match="call start"):
        GoalBabbling(GB_TARGET_BOUNDS).step()


def test_check_x_bounds_returns_arrays():
    low, high = check_x_bounds(([0, 1], [2, 3]))
    assert low.dtype == np.float64 and high.tolist() == [2.0, 3.0]
