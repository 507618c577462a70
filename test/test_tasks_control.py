"""Star tasks (thesis §5.5.1), PID feedback and the PID position servo (§5.4.1)."""
import types

import numpy as np
import pytest

from lpa_transfer.robots.kinematics import robot_kinematics
from lpa_transfer.robots.control import PID, start_servo
from lpa_transfer.robots.simulator import RobotSimulator, robot_urdf
from lpa_transfer.robots.trajectories import minimum_jerk
from lpa_transfer.inverse_dynamics.tasks import (joint_trajectory, star_task, star_tips,
                                                 star_trajectory, tracking_error)
from two_link import robot

DT = 0.01


def test_minimum_jerk_starts_and_ends_at_rest():
    s = minimum_jerk(60)
    assert s[-1] == pytest.approx(1.0) and np.all(np.diff(s) > 0)
    velocity = np.diff(np.concatenate(([0.0], s)))
    assert velocity[0] < 1e-3 and velocity[-1] < 1e-3 and velocity.max() > 0.02


def test_star_has_seven_lines_of_one_radius_and_lasts_8_4_s():
    centre, u, v = np.array([0.2, 0.1, 0.0]), np.array([1.0, 0, 0]), np.array([0, 1.0, 0])
    tips = star_tips(centre, u, v, 0.05)
    assert tips.shape == (7, 3)
    assert np.allclose(np.linalg.norm(tips - centre, axis=1), 0.05) and np.allclose(tips[:, 2], 0)
    path = star_trajectory(centre, u, v, 0.05, DT)
    assert path.shape == (840, 3)                      # 7 lines x 1.2 s at 100 Hz = 8.4 s
    assert np.allclose(path[59], tips[0]) and np.allclose(path[119], centre)
    assert np.allclose(path[179], tips[1]) and np.allclose(path[-1], centre)
    distance = np.linalg.norm(path - centre, axis=1)
    assert distance.max() == pytest.approx(0.05)       # straight lines: never beyond a tip


def test_star_spread_and_errors():
    tips = star_tips([0, 0], [1, 0], [0, 1], 1.0, spread=np.pi / 2)
    assert np.allclose(tips[0], [1, 0]) and np.allclose(tips[-1], [0, 1])
    with pytest.raises(ValueError, match="radius must be positive"):
        star_tips([0, 0], [1, 0], [0, 1], 0.0)
    with pytest.raises(ValueError, match="one length"):
        star_tips([0, 0, 0], [1, 0], [0, 1], 1.0)
    with pytest.raises(ValueError, match="longer than a leg"):
        star_trajectory([0, 0], [1, 0], [0, 1], 1.0, dt=2.0)


def test_joint_trajectory_follows_the_task_through_inverse_kinematics():
    kinematics = robot_kinematics(robot("two_link_target"))
    q_start = np.array([0.5, 1.2])
    centre = kinematics.forward(q_start[None])[0]
    path = star_trajectory(centre, [1, 0], [0, 1], 0.05, DT)
    q, qd, qdd, residuals = joint_trajectory(kinematics, path, q_start, DT)
    assert residuals.max() < 1e-6
    assert np.allclose(kinematics.forward(q), path, atol=1e-6)
    assert np.allclose(qd, np.gradient(q, DT, axis=0)) and np.allclose(qdd,
                                                                        np.gradient(qd, DT, axis=0))


def test_star_task_is_the_star_around_the_home_pose_in_joint_space():
    kinematics = robot_kinematics(robot("two_link_target"), [0.5, 1.2])
    q, qd, qdd, x_d = star_task(kinematics, 0.05, DT, start_angle=0.3)
    centre = kinematics.forward(kinematics.home[None])[0]
    assert np.allclose(x_d, star_trajectory(centre, [1, 0], [0, 1], 0.05, DT, start_angle=0.3))
    assert q.shape == qd.shape == qdd.shape == (840, 2)
    assert np.allclose(kinematics.forward(q), x_d, atol=1e-6)
    with pytest.raises(ValueError, match="leaves the robot's workspace"):
        # far beyond the 1.1 m arm; sampled at 0.1 s (6 points a leg, as the check does not
        # depend on dt), as at DT each of its hundreds of unreachable points runs the inverse
        # kinematics to its iteration limit (10-15 s)
        star_task(kinematics, 5.0, 0.1)


def test_tracking_error_is_the_mean_distance():
    desired = np.zeros((4, 2))
    actual = np.array([[3.0, 4.0], [0, 0], [0, 1.0], [0, 0]])
    assert tracking_error(desired, actual) == pytest.approx(1.5)
    with pytest.raises(ValueError, match="one shape"):
        tracking_error(desired, actual[:3])


def test_pid_terms():
    pid = PID(kp=2.0, ki=10.0, kd=0.5)
    torque = pid.torque([1.0], [0.0], np.array([0.0]), np.array([0.4]), dt=0.1)
    assert torque == pytest.approx([2.0 * 1.0 + 10.0 * 0.1 - 0.5 * 0.4])
    torque = pid.torque([1.0], [0.0], np.array([0.0]), np.array([0.0]), dt=0.1)
    assert torque == pytest.approx([2.0 + 10.0 * 0.2])           # the integral accumulates
    pid.reset()
    assert pid.torque([1.0], [0.0], np.array([0.0]), np.array([0.0]), 0.1) == pytest.approx([3.0])
    with pytest.raises(ValueError, match="kd must be finite and >= 0"):
        PID(1.0, 0.0, -1.0)
    assert PID.from_gains([2.0, 10.0, 0.5]).kp == 2.0
    with pytest.raises(ValueError, match=r"target_pid must be \[kp, ki, kd\], got \[1.0\]"):
        PID.from_gains([1.0], "target_pid")


def test_pid_servo_drives_a_torque_mode_robot_to_position_commands():
    """At 1 kHz: these light links make a 100 Hz zero-order-hold PID with this Kd unstable."""
    params = robot("two_link_source")
    with RobotSimulator(robot_urdf(params), control_mode="torque") as sim:
        servo = start_servo(sim.step, params.n_joints, PID(kp=40.0, ki=40.0, kd=2.0))
        target = np.array([0.8, 1.0])
        for fraction in np.linspace(0.001, 1.0, 500):        # a 0.5 s ramp, then hold 1 s
            servo.step(fraction * target, 1)
        for _ in range(1000):
            state = servo.step(target, 1)
    assert np.abs(state.positions - target).max() < 0.01
    assert np.abs(state.efforts).max() <= params.effort_limits.max()


def test_pid_servo_torques_do_not_depend_on_how_long_the_clock_has_run():
    """The servo's command velocity divides by the period between two clock readings
    (steps x 1 ms); their float difference carries rounding that grows with the time run, so
    the same commands gave other torques after longer runs. It uses the rounded difference."""
    def torques_from(start_steps):
        clock, applied = [start_steps], []

        def step(torque, n_steps):
            applied.append(np.asarray(torque, dtype=np.float64).copy())
            clock[0] += n_steps
            return types.SimpleNamespace(time=clock[0] * 0.001, positions=np.zeros(1),
                                         velocities=np.zeros(1))
        servo = start_servo(step, 1, PID(kp=1.0, ki=0.0, kd=1.0))
        for command in (0.1, 0.3, 0.2, 0.7):
            servo.step([command], 10)
        return np.concatenate(applied[1:])

    reference = torques_from(0)
    assert reference[2] == pytest.approx(1.0 * 0.2 + 1.0 * (0.2 - 0.3) / 0.01)
    for start_steps in (14400, 57600, 1000003):
        np.testing.assert_array_equal(torques_from(start_steps), reference)


def test_linear_star_legs_run_at_constant_speed_and_minimum_jerk_stays_the_default():
    """The linear time law: ``time_law="linear"`` moves along each 0.6 s leg at constant speed
    (the speed jumps at the centre and the tips); the default is unchanged."""
    centre = np.array([0.3, 0.4])
    linear = star_trajectory(centre, [1, 0], [0, 1], 0.05, DT, time_law="linear")
    default = star_trajectory(centre, [1, 0], [0, 1], 0.05, DT)
    assert np.array_equal(default, star_trajectory(centre, [1, 0], [0, 1], 0.05, DT,
                                                   time_law="minimum_jerk"))
    n_leg = 60
    first_leg = np.vstack((centre, linear[:n_leg]))
    steps = np.linalg.norm(np.diff(first_leg, axis=0), axis=1)
    np.testing.assert_allclose(steps, 0.05 / n_leg, rtol=1e-9)       # equal steps: constant
    np.testing.assert_allclose(linear[n_leg - 1], default[n_leg - 1])  # both reach the tip
    assert not np.allclose(linear, default)
    with pytest.raises(ValueError, match="time_law must be one of"):
        star_trajectory(centre, [1, 0], [0, 1], 0.05, DT, time_law="cubic")
