"""lpa_transfer.goal_babbling.reaching: test points through the reachable workspace, reaching error and rate
(§6.5), on the Table 6.1 target arm."""
import dataclasses

import numpy as np
import pytest

from lpa_transfer.goal_babbling.reaching import (Reaching, coverage, evaluate_reaching,
                                                 evaluation_points, grid, reachable_share,
                                                 reaching_errors, reaching_rate)
from two_link import GB_HOME, GB_TARGET_LINKS, TABLE_6_1_LIMITS, elbow_ik, table_6_1_arm


class AnalyticIK:
    """A perfect inverse model: the closed-form elbow solution."""

    def predict(self, points):
        return elbow_ik(points, GB_TARGET_LINKS, TABLE_6_1_LIMITS)[0]


class Constant:
    def __init__(self, q):
        self.q = np.asarray(q, dtype=np.float64)

    def predict(self, points):
        return np.tile(self.q, (len(points), 1))


@pytest.fixture(scope="module")
def target():
    return table_6_1_arm(GB_TARGET_LINKS)


@pytest.fixture(scope="module")
def points(target):
    return evaluation_points(target, spacing=0.08, n_joint_samples=5000)


def test_grid_is_regular_and_centred_in_the_box():
    points = grid(((0.0, 0.0), (1.0, 0.45)), 0.2)
    xs, ys = np.unique(points[:, 0]), np.unique(points[:, 1])
    np.testing.assert_allclose(xs, [0.0, 0.2, 0.4, 0.6, 0.8, 1.0])
    np.testing.assert_allclose(ys, [0.025, 0.225, 0.425])
    assert points.shape == (18, 2)
    assert grid(((0.0, 0.3), (1.0, 0.3)), 0.5).shape == (3, 2)   # a fixed coordinate


def test_evaluation_points_are_reachable_evenly_spaced_and_deterministic(target, points):
    assert len(points) > 40
    _, reachable = elbow_ik(points, GB_TARGET_LINKS, TABLE_6_1_LIMITS)
    assert reachable.all()
    candidates = grid((points.min(axis=0), points.max(axis=0)), 0.08)
    spacing = np.diff(np.unique(np.round(points[:, 0], 9)))
    np.testing.assert_allclose(spacing[spacing < 0.1], 0.08)   # on a 0.08 m grid
    np.testing.assert_array_equal(points, evaluation_points(target, spacing=0.08,
                                                            n_joint_samples=5000))
    # the workspace is a partial annulus: some grid points in its bounding box are dropped
    assert len(points) < len(candidates)


def test_unreachable_grid_points_are_left_out(target):
    """The arm cannot come nearer its base than |0.7 + 0.4 e^{2.9 i}| ≈ 0.33 m."""
    points = evaluation_points(target, ((0.0, -0.1), (0.15, 0.0)), spacing=0.05,
                               n_joint_samples=2000)
    assert points.shape == (0, 2)


def test_perfect_model_reaches_every_point(target, points):
    result = evaluate_reaching(AnalyticIK(), target, points)
    assert isinstance(result, Reaching)
    assert result.rate == 1.0 and result.mean_error < 1e-9


def test_home_only_model_reaches_few_points(target, points):
    errors = reaching_errors(Constant(GB_HOME), target, points)
    result = evaluate_reaching(Constant(GB_HOME), target, points)
    assert 0.0 <= result.rate < 0.1 and result.mean_error == pytest.approx(errors.mean())
    x_home = target.forward(GB_HOME[None])[0]
    np.testing.assert_allclose(errors, np.linalg.norm(points - x_home, axis=1))


def test_commands_are_clipped_into_the_joint_limits(target, points):
    beyond = reaching_errors(Constant([1.0, 5.0]), target, points[:3])
    clipped = reaching_errors(Constant([0.0, 2.9]), target, points[:3])
    np.testing.assert_allclose(beyond, clipped)


def test_reaching_rate_counts_errors_within_the_threshold():
    assert reaching_rate([0.005, 0.01, 0.02]) == pytest.approx(2 / 3)
    assert reaching_rate([0.005, 0.01, 0.02], threshold=0.015) == pytest.approx(2 / 3)
    assert reaching_rate([0.005, 0.01, 0.02], threshold=0.001) == 0.0


@pytest.mark.parametrize("errors", [[], [np.nan], [[0.1]]])
def test_reaching_rate_rejects_bad_errors(errors):
    with pytest.raises(ValueError, match="errors must be a non-empty 1-D array"):
        reaching_rate(errors)


def test_bad_points_and_bounds_raise(target):
    with pytest.raises(ValueError, match="points contains NaN"):
        reaching_errors(AnalyticIK(), target, [[np.nan, 0.0]])
    with pytest.raises(ValueError, match="points holds no test points"):
        reaching_errors(AnalyticIK(), target, np.empty((0, 2)))
    with pytest.raises(ValueError, match="3 coordinates but the robot's task space has 2"):
        evaluation_points(target, ((0, 0, 0), (1, 1, 1)), n_joint_samples=10)
    with pytest.raises(ValueError, match="spacing must be > 0"):
        grid(((0, 0), (1, 1)), 0.0)


def test_coverage_counts_points_near_reached_positions():
    points = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [2.0, 2.0]])
    reached = np.array([[0.005, 0.0], [1.0, 0.02], [2.0, 2.0]])
    assert coverage(points, reached, 0.01) == 0.5        # (0, 0) and (2, 2)
    assert coverage(points, reached, 0.03) == 0.75
    with pytest.raises(ValueError, match="same width"):
        coverage(points, np.zeros((2, 3)), 0.01)
    with pytest.raises(ValueError, match="reached contains NaN"):
        coverage(points, [[np.nan, 0.0]], 0.01)


def test_reachable_share_of_an_arm_and_of_the_same_arm_held_in_a_narrower_range(target,
                                                                                points):
    """The whole arm reaches (nearly) all its test points; with its elbow range halved it
    reaches fewer: the ceiling a source with that range could teach."""
    assert reachable_share(target, points, 0.02, n_joint_samples=20000) > 0.95
    limits = np.array(target.joint_limits)
    limits[1, 1] = limits[1].mean()
    narrow = dataclasses.replace(target, joint_limits=limits)
    share = reachable_share(narrow, points, 0.02, n_joint_samples=20000)
    assert 0.2 < share < 0.8
    assert share == reachable_share(narrow, points, 0.02, n_joint_samples=20000)   # seeded
