"""lpa_transfer.robots.inverse_kinematics: damped-least-squares IK over a forward-kinematics callable,
on the §3.6 2-link robots (scenarios/robots/two_link_{source,target}.toml)."""
import numpy as np
import pytest

from lpa_transfer.robots.inverse_kinematics import jacobian, solve, solve_many, solve_path
from lpa_transfer.robots.kinematics import planar_forward_kinematics
from two_link import TARGET_LINKS, elbow_ik, robot

ROBOTS = ("two_link_source", "two_link_target")


def arm(name):
    """(forward, link lengths, joint limits) of a robot file."""
    params = robot(name)
    lengths, limits = params.link_lengths, np.array(params.joint_limits)
    return (lambda q: planar_forward_kinematics(q, lengths)), lengths, limits


def counting(forward):
    """``forward`` that counts the joint vectors it is given (in ``.calls``)."""
    def wrapped(q):
        wrapped.calls += len(q)
        return forward(q)

    wrapped.calls = 0
    return wrapped


def test_robot_files_are_the_thesis_robots():
    for name, links in zip(ROBOTS, [(0.3, 0.25), (0.6, 0.2)]):
        _, lengths, limits = arm(name)
        np.testing.assert_allclose(lengths, links)
        np.testing.assert_allclose(limits, [(0, np.pi / 2), (0, np.pi)])


@pytest.mark.parametrize("name", ROBOTS)
def test_jacobian_matches_the_analytic_2_link_jacobian(name):
    forward, (l1, l2), limits = arm(name)
    rng = np.random.default_rng(0)
    for q in [np.zeros(2), *rng.uniform(limits[:, 0], limits[:, 1], (10, 2))]:
        s1, c1, s12, c12 = np.sin(q[0]), np.cos(q[0]), np.sin(q.sum()), np.cos(q.sum())
        analytic = [[-l1 * s1 - l2 * s12, -l2 * s12], [l1 * c1 + l2 * c12, l2 * c12]]
        J = jacobian(forward, q)
        assert J.shape == (2, 2)
        np.testing.assert_allclose(J, analytic, atol=1e-6)


def test_jacobian_shape_is_task_by_joint_dimensions():
    lengths = [0.3, 0.2, 0.1]

    def forward(q):   # 3 joints to (x, y, z = sum of angles)
        return np.column_stack((planar_forward_kinematics(q, lengths), q.sum(axis=1)))

    J = jacobian(forward, np.array([0.1, 0.2, 0.3]))
    assert J.shape == (3, 3)
    np.testing.assert_allclose(J[2], [1, 1, 1], atol=1e-6)
    np.testing.assert_allclose(J[:2, 2], [-0.1 * np.sin(0.6), 0.1 * np.cos(0.6)], atol=1e-6)


@pytest.mark.parametrize("name", ROBOTS)
def test_solve_reaches_reachable_points(name):
    forward, lengths, limits = arm(name)
    rng = np.random.default_rng(1)
    # Away from the stretched and folded arm (q2 = 0, π), where the damping slows convergence.
    q_true = rng.uniform(limits[:, 0] + [0, 0.2], limits[:, 1] - [0, 0.2], (40, 2))
    points = forward(q_true)
    for q_start in ([0.0, 0.0], limits.mean(axis=1), [1.5, 0.1]):
        for point, expected in zip(points, q_true):
            q, residual = solve(forward, point, q_start, limits)
            assert residual < 1e-6
            assert residual == pytest.approx(np.linalg.norm(forward(q[None])[0] - point), abs=1e-15)
            assert ((q >= limits[:, 0]) & (q <= limits[:, 1])).all()
            np.testing.assert_allclose(q, expected, atol=1e-5)   # the only solution in limits
    np.testing.assert_allclose(elbow_ik(points, lengths)[0], q_true, atol=1e-9)


def test_solve_at_the_target_returns_the_start_unchanged():
    forward, _, limits = arm("two_link_target")
    q_start = np.array([0.4, 1.2])
    q, residual = solve(forward, forward(q_start[None])[0], q_start, limits)
    np.testing.assert_array_equal(q, q_start)
    assert residual < 1e-15


def test_solve_clips_the_start_into_the_limits():
    forward, _, limits = arm("two_link_target")
    q, residual = solve(forward, forward(np.array([[np.pi / 2, 0.0]]))[0], [3.0, -1.0], limits)
    np.testing.assert_array_equal(q, [np.pi / 2, 0.0])
    assert residual < 1e-15
    q, _ = solve(forward, [0.0, 0.0], [3.0, -1.0], limits, max_iterations=0)
    np.testing.assert_array_equal(q, [np.pi / 2, 0.0])


@pytest.mark.parametrize("q_start", [[0.0, 0.0], [np.pi / 4, np.pi / 2], [0.1, 0.5]])
def test_solve_respects_joint_limits_and_ends_at_the_nearest_point(q_start):
    """Points that need joint 1 beyond a limit: joint 1 stays at the limit and joint 2 brings
    the hand to the nearest point of the circle it sweeps there (centre: the elbow)."""
    forward, (l1, l2), limits = arm("two_link_target")
    for q_needed, q1_limit in (([-0.2, 2.0], 0.0), ([1.8, 0.5], np.pi / 2)):
        point = forward(np.array([q_needed]))[0]
        q, residual = solve(forward, point, q_start, limits)
        assert ((q >= limits[:, 0]) & (q <= limits[:, 1])).all()
        assert q[0] == q1_limit
        elbow = l1 * np.array([np.cos(q1_limit), np.sin(q1_limit)])
        nearest_q2 = np.arctan2(*(point - elbow)[::-1]) - q1_limit
        assert q[1] == pytest.approx(nearest_q2, abs=1e-4)
        assert residual == pytest.approx(abs(np.linalg.norm(point - elbow) - l2), abs=1e-8)
        assert residual > 0.05
        assert residual == pytest.approx(np.linalg.norm(forward(q[None])[0] - point), abs=1e-15)


@pytest.mark.parametrize("q_start", [[0.0, 0.0], [np.pi / 4, np.pi / 2]])
@pytest.mark.parametrize("angle", [0.3, 1.0])
@pytest.mark.parametrize("distance", [1.0, 1.5])
def test_points_beyond_the_reach_end_at_the_stretched_arm(q_start, angle, distance):
    forward, lengths, limits = arm("two_link_target")
    direction = np.array([np.cos(angle), np.sin(angle)])
    q, residual = solve(forward, distance * direction, q_start, limits)
    reach = lengths.sum()
    assert residual == pytest.approx(distance - reach, abs=1e-6)
    np.testing.assert_allclose(q, [angle, 0.0], atol=1e-3)
    # Near the stretched (singular) arm the distance to the point is flat in the sideways
    # direction (second order), so the hand is known less precisely than the residual.
    np.testing.assert_allclose(forward(q[None])[0], reach * direction, atol=1e-3)


@pytest.mark.parametrize("angle", [0.5, 1.2])
def test_points_inside_the_inner_radius_end_at_the_folded_arm(angle):
    forward, (l1, l2), limits = arm("two_link_target")
    direction = np.array([np.cos(angle), np.sin(angle)])
    q, residual = solve(forward, 0.3 * direction, [0.4, 1.5], limits)
    assert residual == pytest.approx((l1 - l2) - 0.3, abs=1e-6)   # the inner radius is 0.4
    np.testing.assert_allclose(q, [angle, np.pi], atol=1e-3)


def test_tolerance_and_max_iterations_bound_the_work():
    forward, _, limits = arm("two_link_source")
    point, q_start = forward(np.array([[1.0, 2.0]]))[0], np.array([0.2, 0.5])
    fine, coarse = counting(forward), counting(forward)
    _, fine_residual = solve(fine, point, q_start, limits)
    _, coarse_residual = solve(coarse, point, q_start, limits, tolerance=1e-2)
    assert fine_residual < 1e-7 <= coarse_residual < 1e-2
    assert coarse.calls < fine.calls
    q, residual = solve(forward, point, q_start, limits, max_iterations=0)
    np.testing.assert_array_equal(q, q_start)
    assert residual == pytest.approx(np.linalg.norm(forward(q_start[None])[0] - point))
    _, residual = solve(forward, point, q_start, limits, max_iterations=1)
    assert 1e-7 < residual < np.linalg.norm(forward(q_start[None])[0] - point)


def test_solve_path_warm_starts_and_keeps_one_elbow_configuration():
    """Without joint limits each point has two solutions (elbow up/down); along a line the
    path keeps the elbow it starts with, each solve starting at the previous solution."""
    forward, _, _ = arm("two_link_target")
    free = [(-np.pi, np.pi), (-np.pi, np.pi)]
    line = np.linspace([0.7, -0.1], [0.1, 0.6], 40)
    for q_start, sign in (([0.3, 0.5], 1), ([0.3, -0.5], -1)):
        Q, residuals = solve_path(forward, line, q_start, free)
        assert Q.shape == (40, 2) and residuals.shape == (40,)
        assert (residuals < 1e-6).all()
        np.testing.assert_allclose(forward(Q), line, atol=1e-6)
        assert (sign * Q[:, 1] > 0.3).all()
        assert np.abs(np.diff(Q, axis=0)).max() < 0.15   # the line's steps are 2.4 cm
        for k in range(1, len(line)):   # each solve is warm-started at the previous solution
            np.testing.assert_array_equal(Q[k], solve(forward, line[k], Q[k - 1], free)[0])


def test_solve_path_needs_fewer_evaluations_than_cold_starts():
    forward, _, limits = arm("two_link_target")
    line = np.linspace([0.7, 0.3], [0.2, 0.5], 30)
    assert elbow_ik(line, TARGET_LINKS)[1].all()   # all reachable within the limits
    warm, cold = counting(forward), counting(forward)
    Q, residuals = solve_path(warm, line, [0.0, 0.0], limits)
    for point in line:
        solve(cold, point, [0.0, 0.0], limits)
    assert (residuals < 1e-6).all()
    assert warm.calls < 0.5 * cold.calls


def test_solve_path_with_limits_options_and_empty_paths():
    forward, _, limits = arm("two_link_source")
    points = np.array([[0.3, 0.3], [0.0, 1.0]])   # the second beyond the reach
    Q, residuals = solve_path(forward, points, [0.5, 0.5], limits)
    assert residuals[0] < 1e-6 and residuals[1] == pytest.approx(1.0 - 0.55, abs=1e-6)
    np.testing.assert_allclose(Q[1], [np.pi / 2, 0], atol=1e-3)
    assert ((Q >= limits[:, 0]) & (Q <= limits[:, 1])).all()
    Q, residuals = solve_path(forward, points, [0.5, 0.5], limits, max_iterations=0)
    np.testing.assert_array_equal(Q, [[0.5, 0.5], [0.5, 0.5]])
    np.testing.assert_allclose(residuals, np.linalg.norm(forward(Q) - points, axis=1))
    Q, residuals = solve_path(forward, np.empty((0, 2)), [0.5, 0.5], limits)
    assert Q.shape == (0, 2) and residuals.shape == (0,)


def test_a_stretched_arm_pulled_straight_in_leaves_the_singular_pose():
    """From q = (0, 0) (stretched, the 2-link robots' home) the gradient towards a point on
    the arm's line vanishes; the solver nudges off the singular pose and reaches it."""
    lengths, limits = np.array([0.6, 0.2]), np.array([[0.0, np.pi / 2], [0.0, np.pi]])
    forward = lambda q: planar_forward_kinematics(q, lengths)  # noqa: E731
    for target in ([0.5, 0.3], [0.3, 0.5]):
        q, residual = solve(forward, target, [0.0, 0.0], limits)
        assert residual < 1e-6, (target, q)
        assert np.allclose(forward(q[None])[0], target, atol=1e-6)


@pytest.mark.parametrize("name", ROBOTS)
def test_solve_many_ends_where_solve_does_row_by_row(name):
    """Reachable, unreachable (beyond the reach, inside the inner radius) and limit-bound
    targets, with starts at limits and at the singular stretched pose: each row as solve."""
    forward, (l1, l2), limits = arm(name)
    rng = np.random.default_rng(3)
    reachable = forward(rng.uniform(limits[:, 0], limits[:, 1], (20, 2)))
    angles = rng.uniform(-np.pi, np.pi, 10)
    ring = np.column_stack((np.cos(angles), np.sin(angles)))
    targets = np.vstack((reachable, 1.2 * (l1 + l2) * ring, 0.2 * abs(l1 - l2) * ring))
    starts = np.vstack((rng.uniform(-1, 4, (len(targets) - 2, 2)), [[0.0, 0.0], [0.3, 0.0]]))
    Q, residuals = solve_many(forward, targets, starts, limits)
    for i in range(len(targets)):
        q, residual = solve(forward, targets[i], starts[i], limits)
        np.testing.assert_allclose(Q[i], q, atol=1e-6)    # batched linear algebra rounds
        assert residuals[i] == pytest.approx(residual, abs=1e-6)   # differently; q agrees to 1e-6
    assert (residuals[:20] < 1e-7).all() and (residuals[20:30] > 0.1 * (l1 + l2)).all()


def test_solve_many_batches_the_forward_calls_and_checks_its_input():
    forward, _, limits = arm("two_link_target")
    calls = []

    def recording(q):
        calls.append(len(q))
        return forward(q)

    rng = np.random.default_rng(0)
    targets = forward(rng.uniform(limits[:, 0], limits[:, 1], (50, 2)))
    Q, residuals = solve_many(recording, targets, np.full((50, 2), 0.5), limits)
    assert (residuals < 1e-6).all() and max(calls) == 3 * 50    # q and its 2 offsets at once
    assert len(calls) < 0.2 * sum(calls)
    Q, residuals = solve_many(forward, np.empty((0, 2)), np.empty((0, 2)), limits)
    assert Q.shape == (0, 2) and residuals.shape == (0,)
    with pytest.raises(ValueError, match="rows"):
        solve_many(forward, targets, np.zeros((3, 2)), limits)
