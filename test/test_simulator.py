"""lpa_transfer.simulator: the pybullet robot simulator behind the robot_sim node."""
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("pybullet")

from lpa_transfer.kinematics import planar_forward_kinematics  # noqa: E402
from lpa_transfer.planar_chain import planar_chain_urdf  # noqa: E402
from lpa_transfer.robot_params import load_robot_params  # noqa: E402
from lpa_transfer.simulator import RobotSimulator, robot_urdf  # noqa: E402

SOURCE = load_robot_params(Path(__file__).resolve().parents[1] / "scenarios" / "robots"
                           / "two_link_source.toml")


@pytest.fixture
def make():
    sims = []

    def make(control_mode="position", **kwargs):
        sims.append(RobotSimulator(robot_urdf(SOURCE), control_mode, **kwargs))
        return sims[-1]

    yield make
    for sim in sims:
        sim.close()


def test_joints_and_limits_come_from_the_robot_file(make):
    sim = make()
    assert sim.joint_names == ["joint1", "joint2"]
    np.testing.assert_allclose(sim.joint_limits, SOURCE.joint_limits)
    np.testing.assert_array_equal(sim.effort_limits, SOURCE.effort_limits)
    np.testing.assert_array_equal(SOURCE.effort_limits, [10.0, 5.0])   # from the .toml


def test_end_effector_at_zero_pose_is_the_stretched_chain(make):
    state = make().state()
    np.testing.assert_array_equal(state.positions, [0, 0])
    np.testing.assert_allclose(state.end_effector, [SOURCE.link_lengths.sum(), 0, 0], atol=1e-6)


def test_end_effector_matches_planar_forward_kinematics(make):
    sim = make(initial_positions=[0.7, 1.3])
    for command in ([0.3, 2.0], [1.2, 0.4]):
        state = sim.step(command, 300)
        expected = planar_forward_kinematics(state.positions[None], SOURCE.link_lengths)[0]
        np.testing.assert_allclose(state.end_effector, [*expected, 0.0], atol=1e-6)


def test_position_mode_reaches_the_commanded_pose(make):
    sim = make()
    state = sim.step([0.5, 1.0], 1500)
    np.testing.assert_allclose(state.positions, [0.5, 1.0], atol=1e-3)
    np.testing.assert_allclose(state.velocities, 0, atol=1e-3)
    assert state.time == pytest.approx(1.5)


def test_position_commands_beyond_the_limits_are_clipped(make):
    sim = make()
    state = sim.step([5.0, -3.0], 2000)
    np.testing.assert_allclose(state.positions, [np.pi / 2, 0.0], atol=1e-3)


def test_torque_mode_with_zero_torque_falls_under_gravity(make):
    sim = make("torque", initial_positions=[0.8, 1.0])
    speeds = [np.abs(sim.step([0.0, 0.0], 20).velocities).max() for _ in range(5)]
    assert speeds[0] > 0.1 and all(np.diff(speeds) > 0), speeds
    np.testing.assert_array_equal(sim.state().efforts, [0, 0])


def test_torques_are_clipped_to_the_effort_limits(make):
    sim = make("torque", initial_positions=[0.8, 1.0])
    state = sim.step([100.0, -100.0], 1)
    np.testing.assert_array_equal(state.efforts, [10.0, -5.0])
    state = sim.step([3.0, -1.0], 1)
    np.testing.assert_array_equal(state.efforts, [3.0, -1.0])


def test_clipped_torque_moves_the_arm_like_the_limit_torque(make):
    a, b = make("torque", initial_positions=[0.8, 1.0]), make("torque", initial_positions=[0.8, 1.0])
    np.testing.assert_array_equal(a.step([1e6, 0], 50).positions, b.step([10.0, 0], 50).positions)


def test_same_inputs_give_the_same_trajectory(make):
    def run(sim):
        rng = np.random.default_rng(3)
        return np.array([sim.step(rng.uniform(-5, 5, 2), 7).positions for _ in range(50)])

    first = run(make("torque", initial_positions=[0.8, 1.0]))
    second = run(make("torque", initial_positions=[0.8, 1.0]))   # in the same process
    np.testing.assert_array_equal(first, second)


def test_reset_returns_to_a_pose_at_rest_and_restarts_the_clock(make):
    sim = make("torque", initial_positions=[0.8, 1.0])
    sim.step([0, 0], 100)
    state = sim.reset([0.2, 0.3])
    np.testing.assert_allclose(state.positions, [0.2, 0.3])
    np.testing.assert_array_equal(state.velocities, [0, 0])
    assert state.time == 0


@pytest.mark.parametrize("command, message", [([0.1], "must have 2 values"),
                                              ([0.1, 0.2, 0.3], "must have 2 values"),
                                              ([np.nan, 0.1], "NaN or infinite"),
                                              ([0.1, np.inf], "NaN or infinite")])
def test_bad_commands_raise_without_touching_the_simulation(make, command, message):
    sim, untouched = make(initial_positions=[0.8, 1.0]), make(initial_positions=[0.8, 1.0])
    sim.step([0.2, 0.4], 10), untouched.step([0.2, 0.4], 10)
    with pytest.raises(ValueError, match=message):
        sim.step(command, 10)
    assert sim.time == untouched.time
    np.testing.assert_array_equal(sim.step([0.3, 0.5], 10).positions,
                                  untouched.step([0.3, 0.5], 10).positions)


def test_bad_construction_arguments(make):
    with pytest.raises(ValueError, match="control_mode"):
        make("velocity")
    with pytest.raises(ValueError, match="outside the joint limits"):
        make(initial_positions=[-1.0, 0.0])
    with pytest.raises(ValueError, match="not found"):
        RobotSimulator("/nonexistent/robot.urdf")


def test_urdf_file_path_and_three_links(tmp_path):
    path = tmp_path / "arm.urdf"
    path.write_text(planar_chain_urdf([0.2, 0.2, 0.1], [1, 1, 1], effort_limits=[20, 10, 5]))
    with RobotSimulator(str(path), initial_positions=[0.1, 0.2, 0.3]) as sim:
        assert sim.n_joints == 3
        state = sim.state()
        expected = planar_forward_kinematics(state.positions[None], [0.2, 0.2, 0.1])[0]
        np.testing.assert_allclose(state.end_effector[:2], expected, atol=1e-6)


def test_serial_chain_files_run_in_the_simulator():
    """robot_urdf of a kind = "serial" file: the youBot tracks a pose in position mode, and
    the Pincher's torques are clipped to its 2.5 N·m (thesis §5.5.1)."""
    from lpa_transfer.serial_chain import forward_kinematics

    robots = Path(__file__).resolve().parents[1] / "scenarios" / "robots"
    youbot = load_robot_params(robots / "youbot_arm.toml")
    target = [0.5, 0.6, -0.8, 0.4, 1.0]
    with RobotSimulator(robot_urdf(youbot)) as sim:
        state = sim.step(target, 1500)
    np.testing.assert_allclose(state.positions, target, atol=1e-3)
    np.testing.assert_allclose(state.end_effector, forward_kinematics(youbot, [state.positions])[0],
                               atol=1e-6)
    pincher = load_robot_params(robots / "pincher_arm.toml")
    with RobotSimulator(robot_urdf(pincher), "torque") as sim:
        np.testing.assert_array_equal(sim.step([5.0, -5.0, 1.0, 0.0], 1).efforts,
                                      [2.5, -2.5, 1.0, 0.0])
