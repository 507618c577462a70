"""lpa_transfer.exploration.babbling: seeded straight-line babbling in joint or task space."""
import dataclasses

import numpy as np
import pytest

from lpa_transfer.exploration.babbling import BabblingProgram, box_around, polyline
from lpa_transfer.robots.kinematics import Kinematics, planar_kinematics, robot_kinematics
from lpa_transfer.robots.inverse_kinematics import solve_path
from lpa_transfer.robots.kinematics import home_pose, planar_forward_kinematics
from two_link import elbow_ik, robot

TWO_LINK = ("two_link_source", "two_link_target")
#: task_lines waypoint boxes mostly inside each 2-link robot's workspace
TASK_BOXES = {"two_link_source": ((0.1, 0.3), (0.3, 0.45)),
              "two_link_target": ((0.3, 0.3), (0.5, 0.5))}


def kinematics(name, home=None):
    return planar_kinematics(robot(name), home)


def inside(commands, limits):
    limits = np.asarray(limits)
    return bool(((commands >= limits[:, 0]) & (commands <= limits[:, 1])).all())


def segment_ends(program, commands):
    return commands[program.samples_per_segment - 1::program.samples_per_segment]


# -- polyline ---------------------------------------------------------------------------------
def test_polyline_shape_endpoints_and_even_spacing():
    points = polyline([0.0, 0.0], [[1.0, 0.0], [1.0, 2.0]], 4)
    assert points.shape == (8, 2)
    np.testing.assert_allclose(points, [[0.25, 0], [0.5, 0], [0.75, 0], [1, 0],
                                        [1, 0.5], [1, 1], [1, 1.5], [1, 2]])


def test_polyline_lines_are_straight_and_start_after_the_start():
    rng = np.random.default_rng(0)
    start, waypoints = rng.normal(size=3), rng.normal(size=(5, 3))
    points = polyline(start, waypoints, 7)
    assert points.shape == (35, 3)
    np.testing.assert_allclose(points[6::7], waypoints)   # each line ends at its waypoint
    assert not np.isclose(points, start).all(axis=1).any()   # the start is not repeated
    starts = np.vstack((start, waypoints[:-1]))
    for line_start, line in zip(starts, points.reshape(5, 7, 3)):
        steps = np.diff(np.vstack((line_start, line)), axis=0)
        np.testing.assert_allclose(steps, np.tile(steps[0], (7, 1)), atol=1e-12)   # even, straight


def test_polyline_with_one_sample_per_segment_is_the_waypoints():
    waypoints = np.array([[1.0, 2.0], [3.0, 4.0], [-1.0, 0.5]])
    np.testing.assert_array_equal(polyline([9.0, 9.0], waypoints, 1), waypoints)


def test_polyline_minimum_jerk_starts_and_ends_each_line_at_rest():
    """time_law "minimum_jerk": the same straight lines and waypoints, spaced by
    s(τ) = 10τ³ − 15τ⁴ + 6τ⁵: small steps at both ends of a line, the largest mid-line."""
    start, waypoints = np.zeros(2), np.array([[1.0, 0.0], [1.0, 2.0]])
    linear = polyline(start, waypoints, 20)
    smooth = polyline(start, waypoints, 20, "minimum_jerk")
    np.testing.assert_allclose(smooth[19::20], waypoints)
    np.testing.assert_allclose(smooth[:20, 1], 0.0)       # still on the first line
    steps = np.linalg.norm(np.diff(np.vstack((start, smooth)), axis=0), axis=1).reshape(2, 20)
    for line, length in zip(steps, (1.0, 2.0)):
        assert line[0] < 0.01 * length and line[-1] < 0.01 * length
        assert line.max() == pytest.approx(length * 1.875 / 20, rel=0.02)  # peak speed 1.875
    assert not np.allclose(smooth, linear)
    with pytest.raises(ValueError, match="time_law must be one of"):
        polyline(start, waypoints, 20, "cubic")


# -- home_pose, Kinematics --------------------------------------------------------------------
def test_home_pose_defaults_to_zero_clipped_into_the_limits():
    limits = [(0.5, 1.0), (-1.0, 1.0), (-2.0, -1.0)]
    np.testing.assert_array_equal(home_pose(limits), [0.5, 0.0, -1.0])
    np.testing.assert_array_equal(home_pose(limits, []), [0.5, 0.0, -1.0])
    home = home_pose(limits, [0.7, -0.3, -1.5])
    assert home.dtype == np.float64
    np.testing.assert_array_equal(home, [0.7, -0.3, -1.5])


@pytest.mark.parametrize("positions, message", [
    ([0.2, 0.0, -1.5], "lies outside the joint limits"),
    ([0.7, 1.5, -1.5], "lies outside the joint limits"),
    ([0.7, 0.0], "needs 3 finite joint values"),
    ([0.7, np.nan, -1.5], "needs 3 finite joint values"),
])
def test_home_pose_errors(positions, message):
    with pytest.raises(ValueError, match=message):
        home_pose([(0.5, 1.0), (-1.0, 1.0), (-2.0, -1.0)], positions)


def test_planar_kinematics_of_a_robot_file():
    params = robot("two_link_target")
    k = planar_kinematics(params)
    assert k.n_joints == 2
    np.testing.assert_array_equal(k.joint_limits, params.joint_limits)
    np.testing.assert_array_equal(k.home, [0.0, 0.0])
    q = np.array([[0.3, 1.2], [1.0, 0.1]])
    np.testing.assert_array_equal(k.forward(q), planar_forward_kinematics(q, [0.6, 0.2]))
    np.testing.assert_array_equal(planar_kinematics(params, [0.4, 2.0]).home, [0.4, 2.0])
    with pytest.raises(ValueError, match="outside the joint limits"):
        planar_kinematics(params, [-0.1, 0.0])
    with pytest.raises(dataclasses.FrozenInstanceError):
        k.home = np.ones(2)


# -- joint_lines ------------------------------------------------------------------------------
@pytest.mark.parametrize("name", [*TWO_LINK, "three_dof_arm"])
def test_joint_lines_stay_inside_the_joint_limits(name):
    k = kinematics(name)
    program = BabblingProgram("joint_lines", n_segments=30, samples_per_segment=4, seed=5)
    commands = program.commands(k)
    assert commands.shape == (120, k.n_joints) and program.n_samples == 120
    assert inside(commands, k.joint_limits)
    # The waypoints spread over the ranges (not stuck in a corner).
    span = commands.max(axis=0) - commands.min(axis=0)
    assert (span > 0.7 * (k.joint_limits[:, 1] - k.joint_limits[:, 0])).all()


def test_joint_lines_start_at_home_and_run_straight_between_waypoints():
    k = kinematics("three_dof_arm", home=[0.5, -1.0, 1.0])
    program = BabblingProgram("joint_lines", n_segments=6, samples_per_segment=5, seed=2)
    commands = program.commands(k)
    limits = k.joint_limits
    waypoints = limits[:, 0] + program.unit_waypoints(3) * (limits[:, 1] - limits[:, 0])
    np.testing.assert_allclose(segment_ends(program, commands), waypoints)
    np.testing.assert_allclose(commands[0], k.home + (waypoints[0] - k.home) / 5)
    np.testing.assert_allclose(commands, polyline(k.home, waypoints, 5))


def test_same_seed_same_commands_other_seed_other_commands():
    for name in TWO_LINK:
        k = kinematics(name)
        first = BabblingProgram("joint_lines", 10, 5, seed=3).commands(k)
        np.testing.assert_array_equal(first, BabblingProgram("joint_lines", 10, 5,
                                                             seed=3).commands(k))
        other = BabblingProgram("joint_lines", 10, 5, seed=4).commands(k)
        assert not np.isclose(first[4::5], other[4::5]).any()   # every waypoint differs


def test_waypoint_column_depends_only_on_seed_and_joint():
    """Robots babbling with one seed move their common joints alike (in proportion to their
    ranges): a 2-joint and a 3-joint robot share their first two normalized columns."""
    program = BabblingProgram("joint_lines", n_segments=12, samples_per_segment=3, seed=7)
    unit2, unit3 = program.unit_waypoints(2), program.unit_waypoints(3)
    assert unit2.shape == (12, 2) and unit3.shape == (12, 3)
    assert ((unit3 >= 0) & (unit3 < 1)).all()
    np.testing.assert_array_equal(unit2, unit3[:, :2])
    assert not np.allclose(unit3[:, 0], unit3[:, 1])   # each column its own stream
    two, three = kinematics("two_link_source"), kinematics("three_dof_arm")
    normalized = [(segment_ends(program, program.commands(k)) - k.joint_limits[:, 0])
                  / (k.joint_limits[:, 1] - k.joint_limits[:, 0]) for k in (two, three)]
    np.testing.assert_allclose(normalized[0], normalized[1][:, :2], atol=1e-12)
    np.testing.assert_allclose(normalized[0], unit2, atol=1e-12)
    other_seed = BabblingProgram("joint_lines", 12, 3, seed=8).unit_waypoints(2)
    assert not np.isclose(other_seed, unit2).any()


# -- task_lines -------------------------------------------------------------------------------
@pytest.mark.parametrize("name", TWO_LINK)
def test_task_lines_reach_their_task_points_through_inverse_kinematics(name):
    k = kinematics(name)
    low, high = TASK_BOXES[name]
    program = BabblingProgram("task_lines", 10, 5, seed=0, task_low=low, task_high=high)
    commands = program.commands(k)
    assert commands.shape == (50, 2)
    assert inside(commands, k.joint_limits)
    points = program.task_points(k.forward(k.home[None])[0])
    np.testing.assert_array_equal(points[4::5], program.task_waypoints())
    assert ((program.task_waypoints() >= low) & (program.task_waypoints() <= high)).all()
    reached = np.linalg.norm(k.forward(commands) - points, axis=1)
    _, reachable = elbow_ik(points, robot(name).link_lengths)
    assert 40 <= reachable.sum() < 50   # mostly reachable; a few points out of the limits
    assert (reached[reachable] < 1e-6).all()
    # Unreachable points end at least as near as any pose of a dense grid over the limits.
    grid = np.stack(np.meshgrid(np.linspace(0, np.pi / 2, 200), np.linspace(0, np.pi, 400)),
                    -1).reshape(-1, 2)
    hands = k.forward(grid)
    for point, distance in zip(points[~reachable], reached[~reachable]):
        assert 1e-4 < distance <= np.linalg.norm(hands - point, axis=1).min() + 1e-9
    # Warm-started along the path from home.
    expected, _ = solve_path(k.forward, points, k.home, k.joint_limits)
    np.testing.assert_array_equal(commands, expected)


def test_task_lines_share_waypoints_across_robots_and_are_seeded():
    program = BabblingProgram("task_lines", 8, 4, seed=1, task_low=(0.3, 0.3),
                              task_high=(0.5, 0.5))
    source, target = kinematics("two_link_source"), kinematics("two_link_target")
    source_points = program.task_points(source.forward(source.home[None])[0])
    target_points = program.task_points(target.forward(target.home[None])[0])
    np.testing.assert_allclose(source_points[:4], np.linspace([0.55, 0], source_points[3], 5)[1:])
    np.testing.assert_allclose(target_points[:4], np.linspace([0.8, 0], target_points[3], 5)[1:])
    np.testing.assert_array_equal(source_points[4:], target_points[4:])   # from waypoint 1 on
    # Seeded: a program rebuilt from the same values commands the same joints, and those
    # joints put the target's hand on its task points. The first point is out of reach (its
    # base joint would need an angle below its lower limit 0): the solver stops at the limit.
    commands = program.commands(target)
    np.testing.assert_array_equal(dataclasses.replace(program).commands(target), commands)
    np.testing.assert_allclose(target.forward(commands[1:]), target_points[1:], atol=1e-6)
    assert commands[0, 0] == target.joint_limits[0, 0]
    other = dataclasses.replace(program, seed=2)
    assert not np.isclose(other.task_waypoints(), program.task_waypoints()).any()
    # The task-space stream is not the joint-space one.
    assert not np.isclose(program.task_waypoints(), program.unit_waypoints(2)).any()


# -- validation -------------------------------------------------------------------------------
@pytest.mark.parametrize("kwargs, message", [
    (dict(program="random_walk"), r"program must be one of \('joint_lines', 'task_lines'\)"),
    (dict(n_segments=0), "n_segments must be an integer >= 1, got 0"),
    (dict(n_segments=2.5), "n_segments must be an integer >= 1"),
    (dict(n_segments=True), "n_segments must be an integer >= 1"),
    (dict(samples_per_segment=0), "samples_per_segment must be an integer >= 1, got 0"),
    (dict(time_law="linear "), "time_law must be one of"),
    (dict(program="task_lines", task_low=(0.5, 0.0), task_high=(0.4, 1.0)),
     "task_lines needs finite task_low <= task_high"),
    (dict(program="task_lines", task_low=(0.0, 0.0), task_high=(1.0, 1.0, 1.0)),
     "of one length"),
    (dict(program="task_lines", task_low=(0.0, np.nan), task_high=(1.0, 1.0)),
     "task_lines needs finite"),
    (dict(program="task_lines", task_low=(0.0, 0.0), task_high=(1.0, np.inf)),
     "task_lines needs finite"),
    (dict(program="task_lines", task_low=((0.0, 0.0),), task_high=((1.0, 1.0),)),
     "task_lines needs finite"),
])
def test_bad_programs_raise(kwargs, message):
    with pytest.raises(ValueError, match=message):
        BabblingProgram(**kwargs)


def test_joint_lines_ignore_task_bounds_and_numpy_integers_are_accepted():
    program = BabblingProgram("joint_lines", np.int64(3), np.int32(2), task_low=(1.0,))
    assert program.commands(kinematics("two_link_source")).shape == (6, 2)


def test_task_dimension_mismatch_raises():
    program = BabblingProgram("task_lines", 3, 2, task_low=(0.0, 0.0, 0.0),
                              task_high=(0.5, 0.5, 0.5))
    with pytest.raises(ValueError, match="task_low/task_high have 3 coordinates but the "
                                         "robot's task space has 2"):
        program.commands(kinematics("two_link_target"))


def test_custom_kinematics_any_forward():
    """Kinematics take any forward map; task_lines of a 1-joint 'robot' moving along x."""
    k = Kinematics(np.array([[-1.0, 1.0]]), np.array([0.0]), lambda q: 0.5 * q)
    program = BabblingProgram("task_lines", 4, 3, seed=0, task_low=(-0.4,), task_high=(0.4,))
    commands = program.commands(k)
    np.testing.assert_allclose(0.5 * commands, program.task_points([0.0]), atol=1e-7)


def test_task_lines_use_each_robots_own_box():
    """Boxes of the robots (§5.4.1) replace the program's; without any box it is an error."""
    program = BabblingProgram("task_lines", 6, 3, seed=4)
    with pytest.raises(ValueError, match="task_lines needs finite task_low <= task_high"):
        program.task_waypoints()
    small, large = ((0.1, 0.1), (0.2, 0.3)), ((0.0, 0.2), (0.4, 0.6))
    unit_small = (program.task_waypoints(small) - small[0]) / np.subtract(*small[::-1])
    unit_large = (program.task_waypoints(large) - large[0]) / np.subtract(*large[::-1])
    np.testing.assert_allclose(unit_small, unit_large)          # same relative places
    k = dataclasses.replace(robot_kinematics(robot("two_link_target")), task_box=large)
    points = program.task_points(k.forward(k.home[None])[0], k.task_box)
    assert ((points[2::3] >= large[0]) & (points[2::3] <= large[1])).all()
    assert program.commands(k).shape == (18, 2)


def test_box_around_the_home_end_effector():
    """§5.5.3 'vicinity' boxes: centred on the home pose's end effector; two robots babbling
    one seed in boxes scaled like their tasks visit the same task-relative places."""
    small = robot_kinematics(robot("pincher_arm"), [0.0, 0.3, 1.0, 0.8])
    large = robot_kinematics(robot("youbot_arm"), [0.0, 0.0, 1.2, 0.8, 0.0])
    boxes = [box_around(small, [0.05, 0.05, 0.0]), box_around(large, [0.1, 0.1, 0.0])]
    for k, (low, high) in zip((small, large), boxes):
        centre = k.forward(k.home[None])[0]
        np.testing.assert_allclose((np.add(low, high)) / 2, centre)
        assert low[2] == high[2] == centre[2]
    program = BabblingProgram("task_lines", 5, 4, seed=3)
    relative = [(program.task_waypoints(box) - k.forward(k.home[None])[0]) / scale
                for k, box, scale in zip((small, large), boxes, (0.05, 0.1))]
    np.testing.assert_allclose(relative[0], relative[1], atol=1e-12)
    assert np.abs(relative[0][:, :2]).max() <= 1 and (relative[0][:, 2] == 0).all()
    for bad in ([0.1, 0.1], [0.1, -0.1, 0.0], [np.nan, 0.1, 0.0]):
        with pytest.raises(ValueError, match="half-width needs 3 finite values"):
            box_around(small, bad)


def test_robot_kinematics_of_a_serial_arm_is_its_3d_forward_kinematics():
    from lpa_transfer.robots.serial_chain import forward_kinematics
    youbot = robot("youbot_arm")
    k = robot_kinematics(youbot)
    q = np.array([[0.1, 0.2, -0.3, 0.4, 0.5]])
    np.testing.assert_array_equal(k.forward(q), forward_kinematics(youbot, q))
    assert k.forward(q).shape == (1, 3)
    assert robot_kinematics(robot("two_link_source")).forward(q[:, :2]).shape == (1, 2)
