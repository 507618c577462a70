"""A pybullet robot behind goal babbling's environment (lpa_transfer.robots.environment)."""
import numpy as np
import pytest

from lpa_transfer.robots.kinematics import execute, robot_kinematics
from lpa_transfer.goal_babbling.goal_babbling import GoalBabbling
from lpa_transfer.exploration.guided import guided_exploration
from lpa_transfer.robots.environment import stepped_environment, task_dims
from lpa_transfer.robots.params import load_robot_params
from lpa_transfer.robots.simulator import RobotSimulator, robot_urdf

ROBOTS = "scenarios/robots/goal_babbling_{}.toml"
HOME = [-0.785398, 1.65]
BOUNDS = ((0.1, -1.1), (1.1, 0.4))


def simulated(side, n_steps=100):
    robot = load_robot_params(ROBOTS.format(side))
    kinematics = robot_kinematics(robot, HOME)
    sim = RobotSimulator(robot_urdf(robot), initial_positions=HOME)
    return kinematics, stepped_environment(kinematics, sim.step, n_steps), sim


def test_observed_pairs_follow_the_true_kinematics_even_when_the_robot_lags():
    kinematics, environment, sim = simulated("target", n_steps=20)
    with sim:
        commands = np.array([[-1.2, 2.5], [-0.2, 0.6], [-0.8, 1.7]])
        positions, points = execute(environment, commands)
    assert task_dims(kinematics) == 2
    assert np.abs(positions - commands).max() > 0.05        # 20 ms is too short to get there
    np.testing.assert_allclose(points, kinematics.forward(positions), atol=1e-6)


def test_goal_babbling_on_a_simulated_arm_learns_what_it_observed():
    kinematics, environment, sim = simulated("target")
    seen = []
    environment = stepped_environment(kinematics, sim.step, 100,
                                      on_sample=lambda command, state: seen.append(state.time))
    with sim:
        babbling = GoalBabbling(BOUNDS, seed=3).start(environment)
        positions, points = babbling.run_for(30.0)
    assert positions.shape == (300, 2) and len(seen) == 301          # the home, then 300
    np.testing.assert_allclose(np.diff(seen), 0.1, atol=1e-9)        # 100 steps of 1 ms each
    np.testing.assert_allclose(points, kinematics.forward(positions), atol=1e-6)
    np.testing.assert_array_equal(babbling.model_.inverse.Y_[1:], positions)
    assert not np.array_equal(babbling.commands_, positions)         # commands are not observed


def test_guided_exploration_pairs_each_robots_own_observations():
    source_kinematics, source, source_sim = simulated("source")
    target_kinematics, target, target_sim = simulated("target")
    with source_sim, target_sim:
        babbling = GoalBabbling(BOUNDS, seed=1)
        source_pairs, target_pairs, followed = guided_exploration(babbling, source, target,
                                                                  [0, 1], [0, 1], 20.0)
    assert followed.all()                                # the same ranges: all are pairs
    assert source_pairs.shape == target_pairs.shape == (200, 4)
    np.testing.assert_allclose(source_pairs[:, 2:], source_kinematics.forward(source_pairs[:, :2]),
                               atol=1e-6)
    np.testing.assert_allclose(target_pairs[:, 2:], target_kinematics.forward(target_pairs[:, :2]),
                               atol=1e-6)
    lag = np.abs(source_pairs[:, :2] - target_pairs[:, :2])
    assert lag.max() < 0.3 and np.median(lag) < 0.02     # both follow the same commands


def test_n_steps_must_be_a_positive_integer():
    kinematics, _, sim = simulated("target")
    with sim, pytest.raises(ValueError, match="n_steps"):
        stepped_environment(kinematics, sim.step, 0)
