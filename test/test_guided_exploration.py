"""lpa_transfer.exploration.guided: correspondences from guided exploration (Alg. 7, §6.4)."""
import numpy as np
import pytest

from lpa_transfer.robots.kinematics import Kinematics
from lpa_transfer.goal_babbling.goal_babbling import GoalBabbling
from lpa_transfer.exploration.guided import guided_exploration, shared_limits
from lpa_transfer.robots.kinematics import hold_at_home, pad_transferred, restrict
from lpa_transfer.robots.kinematics import planar_forward_kinematics
from two_link import GB_SOURCE_LINKS, GB_TARGET_BOUNDS, GB_TARGET_LINKS, table_6_1_arm

#: A 3-joint target whose first joint the 2-joint source lacks (as Poppy's torso, §6.5.2).
TORSO_LINKS = (0.2, 0.7, 0.4)
TORSO_LIMITS = np.array([(-0.5, 0.5), (-1.2, 0.3), (0.4, 2.9)])
TORSO_HOME = np.array([0.3, -0.6, 1.5])


def torso_arm():
    return Kinematics(TORSO_LIMITS, TORSO_HOME,
                      lambda q: planar_forward_kinematics(q, TORSO_LINKS))


def test_pad_transferred_puts_home_values_in_the_joints_the_source_lacks():
    home = np.array([10.0, 11.0, 12.0, 13.0, 14.0])
    q_shared = np.array([[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]])
    padded = pad_transferred(q_shared, home, [4, 0, 2])
    np.testing.assert_array_equal(padded, [[2.0, 11.0, 3.0, 13.0, 1.0],
                                           [5.0, 11.0, 6.0, 13.0, 4.0]])


@pytest.mark.parametrize("q_shared, shared_joints, message", [
    ([[1.0, 2.0]], [0, 1, 2], "q_shared has 2 columns but 3 shared joints"),
    ([[1.0, 2.0]], [0, 0], "distinct joint indices in \\[0, 3\\)"),
    ([[1.0, 2.0]], [0, 3], "distinct joint indices in \\[0, 3\\)"),
    ([[1.0, 2.0]], [0.0, 1.0], "non-empty 1-D sequence of joint indices"),
    ([[1.0, np.nan]], [0, 1], "q_shared contains NaN"),
])
def test_pad_transferred_rejects_bad_input(q_shared, shared_joints, message):
    with pytest.raises(ValueError, match=message):
        pad_transferred(q_shared, [0.0, 0.0, 0.0], shared_joints)


def test_restrict_moves_only_the_given_joints():
    robot = torso_arm()
    sub = restrict(robot, [1, 2])
    q = np.array([[-0.5, 1.0], [0.0, 2.0]])
    np.testing.assert_allclose(sub.forward(q),
                               robot.forward(np.column_stack((np.full(2, 0.3), q))))
    np.testing.assert_array_equal(sub.joint_limits, TORSO_LIMITS[1:])
    np.testing.assert_array_equal(sub.home, TORSO_HOME[1:])
    narrowed = restrict(robot, [1, 2], [(-1.2, -0.8), (0.4, 1.0)])
    np.testing.assert_array_equal(narrowed.home, [-0.8, 1.0])   # home clipped into them
    with pytest.raises(ValueError, match="joint_limits must be 2 finite"):
        restrict(robot, [1, 2], [(0.0, 1.0)])


def test_hold_at_home_babbles_only_the_given_joints_with_full_rows():
    """The source of §6.5.2 explores with its shared joints only: goal babbling on the held
    robot never moves the other joint, and its rows keep every joint."""
    robot = torso_arm()
    held = hold_at_home(robot, [1, 2])
    np.testing.assert_array_equal(held.joint_limits[0], [0.3, 0.3])
    np.testing.assert_array_equal(held.joint_limits[1:], TORSO_LIMITS[1:])
    babbling = GoalBabbling(((-0.5, -1.0), (1.2, 1.0)), seed=3).start(held)
    q, x = babbling.run_for(30.0)
    assert q.shape == (300, 3)
    np.testing.assert_array_equal(q[:, 0], 0.3)
    assert np.ptp(q[:, 1]) > 0.3 and np.ptp(q[:, 2]) > 0.3
    np.testing.assert_allclose(x, robot.forward(q))
    with pytest.raises(ValueError, match="distinct joint indices"):
        hold_at_home(robot, [1, 3])


def test_shared_limits_intersect_the_ranges():
    source = table_6_1_arm(GB_SOURCE_LINKS)
    limits = shared_limits(source, torso_arm(), [0, 1], [1, 2])
    np.testing.assert_allclose(limits, [(-1.2, 0.0), (0.4, 2.9)])
    with pytest.raises(ValueError, match="pair the shared joints one to one"):
        shared_limits(source, torso_arm(), [0, 1], [1])
    with pytest.raises(ValueError, match="ranges do not overlap"):
        shared_limits(source, torso_arm(), [1], [1])


def test_guided_exploration_pairs_share_their_commands_table_6_1():
    source, target = table_6_1_arm(GB_SOURCE_LINKS), table_6_1_arm(GB_TARGET_LINKS)
    babbler = GoalBabbling(GB_TARGET_BOUNDS, seed=3)
    source_pairs, target_pairs, followed = guided_exploration(babbler, source, target, [0, 1],
                                                              [0, 1], seconds=20)
    assert followed.all()            # within the shared ranges, every pair corresponds
    assert source_pairs.shape == target_pairs.shape == (200, 4)
    commands = target_pairs[:, :2]
    np.testing.assert_array_equal(source_pairs[:, :2], commands)
    np.testing.assert_allclose(source_pairs[:, 2:], source.forward(commands))
    np.testing.assert_allclose(target_pairs[:, 2:], target.forward(commands))
    assert babbler.time_ == 20.0 and babbler.model_.inverse.n_samples_ == 201
    assert np.ptp(commands, axis=0).min() > 0.1   # it explored


def test_guided_exploration_holds_the_target_only_joints_at_home():
    source, target = table_6_1_arm(GB_SOURCE_LINKS), torso_arm()
    babbler = GoalBabbling(((0.0, -1.2), (1.3, 0.6)), seed=0)
    source_pairs, target_pairs, followed = guided_exploration(babbler, source, target, [0, 1],
                                                              [1, 2], seconds=10)
    assert followed.all()
    commands = target_pairs[:, :2]
    np.testing.assert_array_equal(source_pairs[:, :2], commands)
    limits = shared_limits(source, target, [0, 1], [1, 2])
    assert ((commands >= limits[:, 0]) & (commands <= limits[:, 1])).all()
    padded = pad_transferred(commands, TORSO_HOME, [1, 2])
    np.testing.assert_array_equal(padded[:, 0], 0.3)
    np.testing.assert_allclose(target_pairs[:, 2:], target.forward(padded))
    np.testing.assert_allclose(source_pairs[:, 2:], source.forward(commands))


def test_guided_exploration_in_the_targets_own_ranges_pairs_what_the_source_follows():
    """target_range 'own': the target explores its whole range of the shared joints (its
    first shared joint reaches 0.3 rad, the source's only 0); the source executes the
    commands clipped into its range, and only the commands it could follow are pairs."""
    source, target = table_6_1_arm(GB_SOURCE_LINKS), torso_arm()
    guided = guided_exploration(GoalBabbling(((0.0, -1.2), (1.3, 0.6)), seed=0), source,
                                target, [0, 1], [1, 2], seconds=60, target_range="own")
    limits = shared_limits(source, target, [0, 1], [1, 2])
    commands = guided.target[:, :2]
    assert commands[:, 0].max() > 0.05 and (commands[:, 0] <= 0.3).all()   # its own range
    inside = ((commands >= limits[:, 0]) & (commands <= limits[:, 1])).all(axis=1)
    np.testing.assert_array_equal(guided.followed, inside)
    assert 0.1 < inside.mean() < 0.95
    np.testing.assert_array_equal(guided.source[:, :2],
                                  np.clip(commands, limits[:, 0], limits[:, 1]))
    np.testing.assert_allclose(guided.source[:, 2:], source.forward(guided.source[:, :2]))
    source_pairs, target_pairs = guided.correspondences()
    assert len(source_pairs) == inside.sum()
    np.testing.assert_array_equal(source_pairs[:, :2], target_pairs[:, :2])
    # the same seed in the shared ranges explores less of the target's body
    shared = guided_exploration(GoalBabbling(((0.0, -1.2), (1.3, 0.6)), seed=0), source,
                                target, [0, 1], [1, 2], seconds=60)
    assert shared.followed.all() and shared.target[:, 0].max() <= 0.0
    with pytest.raises(ValueError, match="target_range must be one of"):
        guided_exploration(GoalBabbling(((0.0, -1.2), (1.3, 0.6))), source, target, [0, 1],
                           [1, 2], seconds=1, target_range="wide")
