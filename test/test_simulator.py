"""lpa_transfer.robots.simulator: the pybullet robot simulator behind the robot_sim node."""
from pathlib import Path

import numpy as np
import pytest


from lpa_transfer.robots.kinematics import planar_forward_kinematics
from lpa_transfer.robots.planar_chain import planar_chain_urdf
from lpa_transfer.robots.params import load_robot_params
from lpa_transfer.robots.simulator import RobotSimulator, robot_urdf

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
    from lpa_transfer.robots.serial_chain import forward_kinematics

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


# -- joint drives: damping and armature ------------------------------------------------------
ROBOTS = Path(__file__).resolve().parents[1] / "scenarios" / "robots"
GRAVITY = 9.81


def pendulum(armature, damping):
    """A one-link planar arm (uniform rod 0.4 m, 1.6 kg) on a joint with the given drive."""
    from lpa_transfer.robots.params import RobotParams

    return RobotParams("pendulum", [0.4], [(-3.0, 1.0)], "test", link_masses=[1.6],
                       effort_limits=[40.0], joint_armature=[armature], joint_damping=[damping])


@pytest.mark.parametrize("armature, damping", [(0.0, 0.0), (0.2, 0.0), (0.0, 0.5), (0.2, 0.5)])
def test_damping_dissipates_energy_and_armature_keeps_it(armature, damping):
    """A free pendulum (torque 0) from 0.5 rad below horizontal, 2 s: without damping its
    energy ½ (m L²/3 + A) q̇² + m g (L/2) sin q stays (|ΔE| < 0.01 J of the 3.1 J the swing
    exchanges: the armature's torque transformation adds or removes none); with damping D it
    loses exactly what D q̇² dissipates (pybullet applies D in torque mode)."""
    mass, length = 1.6, 0.4
    inertia = mass * length ** 2 / 3 + armature

    def energy(state):
        return (0.5 * inertia * state.velocities[0] ** 2
                + mass * GRAVITY * length / 2 * np.sin(state.positions[0]))

    with RobotSimulator(robot_urdf(pendulum(armature, damping)), "torque",
                        initial_positions=[-0.5]) as sim:
        assert sim.armature.tolist() == [armature] and sim.joint_damping.tolist() == [damping]
        state = sim.state()
        start, dissipated, swing = energy(state), 0.0, 0.0
        for _ in range(2000):
            dissipated += damping * state.velocities[0] ** 2 * sim.physics_step
            state = sim.step([0.0])
            swing = max(swing, abs(state.positions[0] + 0.5))
    assert swing > 0.8                           # it did swing
    if damping == 0:
        assert abs(energy(state) - start) < 0.01
    else:
        assert energy(state) - start < -1.0      # a third of the 3.1 J exchanged
        assert energy(state) - start == pytest.approx(-dissipated, rel=1e-3)


def test_armature_adds_to_the_joint_space_inertia():
    """From rest, one physics step of τ: the simulated q̈ solves (M(q) + diag A) q̈ = τ − g(q)
    with M and g from pybullet's own calculateMassMatrix / calculateInverseDynamics of the
    URDF (which knows nothing of the armature) — the armature is on the diagonal, exactly.
    With damping D (implicit: D acts on the velocity after the step) the diagonal is A + D·dt."""
    import dataclasses

    import pybullet as p

    from lpa_transfer.robots.planar_chain import load_fixed_robot

    youbot = load_robot_params(ROBOTS / "youbot_arm.toml")
    q0, tau = np.array([0.3, 0.5, 0.8, 0.5, 0.2]), np.array([1.0, 2.0, -1.0, 0.5, 0.2])
    client = p.connect(p.DIRECT)
    try:
        body = load_fixed_robot(p, robot_urdf(youbot), client)
        mass = np.array(p.calculateMassMatrix(body, q0.tolist(), physicsClientId=client))
        gravity = np.array(p.calculateInverseDynamics(body, q0.tolist(), [0.0] * 5, [0.0] * 5,
                                                      physicsClientId=client))
    finally:
        p.disconnect(client)
    armature = youbot.joint_armature
    assert (armature[3:] > 3 * np.diag(mass)[3:]).all()   # the wrist's drives dominate

    def acceleration(robot):
        with RobotSimulator(robot_urdf(robot), "torque", initial_positions=q0) as sim:
            return sim.step(tau, 1).velocities / sim.physics_step

    undamped = dataclasses.replace(youbot, joint_damping=np.zeros(5))
    accel = acceleration(undamped)
    np.testing.assert_allclose(accel, np.linalg.solve(mass + np.diag(armature), tau - gravity),
                               rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose((mass + np.diag(armature)) @ accel + gravity, tau, atol=1e-9)
    drive = np.diag(armature + youbot.joint_damping * 1e-3)
    np.testing.assert_allclose(acceleration(youbot), np.linalg.solve(mass + drive, tau - gravity),
                               rtol=1e-6, atol=1e-9)
    bare = dataclasses.replace(undamped, joint_armature=np.zeros(5))
    np.testing.assert_allclose(acceleration(bare), np.linalg.solve(mass, tau - gravity),
                               rtol=1e-6, atol=1e-9)


def test_inverse_dynamics_gives_the_torque_of_a_requested_acceleration():
    """One physics step of τ = inverse_dynamics(q, q̇, q̈) from a moving state gives q̈ (the
    drive model: armature, implicit damping, Coriolis and gravity), leaves the state alone,
    and is refused where it is not the model (position mode, V-REP's velocity motor)."""
    youbot = load_robot_params(ROBOTS / "youbot_arm.toml")
    q0, wanted = np.array([0.3, 0.5, 0.8, 0.5, 0.2]), np.array([2.0, -1.5, 3.0, -2.0, 1.0])
    with RobotSimulator(robot_urdf(youbot), "torque", initial_positions=q0) as sim:
        start = sim.step([1.0, 20.0, -5.0, 2.0, 0.5], 50)                  # moving
        qd0 = start.velocities.copy()
        assert (np.abs(qd0) > 0.01).all()
        tau = sim.inverse_dynamics(start.positions, qd0, wanted)
        np.testing.assert_array_equal(sim.state().velocities, qd0)        # untouched
        assert (np.abs(tau) < youbot.effort_limits).all()                  # not clipped below
        reached = (sim.step(tau, 1).velocities - qd0) / sim.physics_step
    np.testing.assert_allclose(reached, wanted, rtol=1e-6, atol=1e-6)
    with RobotSimulator(robot_urdf(youbot), "position") as sim, \
            pytest.raises(ValueError, match="torque mode's drive model"):
        sim.inverse_dynamics(q0, qd0, wanted)
    with RobotSimulator(robot_urdf(youbot), "torque", actuator="velocity_motor") as sim, \
            pytest.raises(ValueError, match="velocity_motor"):
        sim.inverse_dynamics(q0, qd0, wanted)


def test_armature_is_read_from_a_urdf_file_and_checked(tmp_path):
    from lpa_transfer.robots.serial_chain import LPA_URDF_NAMESPACE

    youbot = load_robot_params(ROBOTS / "youbot_arm.toml")
    path = tmp_path / "youbot.urdf"
    path.write_text(robot_urdf(youbot))
    with RobotSimulator(str(path), "torque") as sim:
        np.testing.assert_array_equal(sim.armature, youbot.joint_armature)
    path.write_text(robot_urdf(youbot).replace('<joint name="tool_joint" type="fixed">',
                                               '<joint name="tool_joint" type="fixed">'
                                               '<lpa:armature value="1"/>'))
    with pytest.raises(ValueError, match=r"lpa:armature on joints \['tool_joint'\]"):
        RobotSimulator(str(path), "torque")
    assert LPA_URDF_NAMESPACE in path.read_text()


def test_thesis_pid_at_100_hz_is_stable_on_the_youbot():
    """§5.5.2's youBot gains (K_p 100, K_i 0.01, K_d 2) at 100 Hz (torque held for 10 physics
    steps), no feed-forward, on a minimum-jerk joint move out and back (0.6 s each way, the
    star's leg time, up to 0.35 rad per joint). With the file's drives the torques stay far
    from the 100 N·m limits and the tool follows within centimetres (measured: mean 37 mm,
    max 48 mm, |τ| <= 9.1 N·m; the gravity sag of a PID without feed-forward); with the
    drives removed the same loop saturates and chatters between the limits (measured: 98 %
    of the periods saturated, 117 limit-to-limit flips, 207 mm mean error)."""
    import dataclasses

    from lpa_transfer.robots.serial_chain import forward_kinematics

    youbot = load_robot_params(ROBOTS / "youbot_arm.toml")
    q_centre, q_step, dt = np.array([0.0, 0.5, 0.8, 0.5, 0.0]), np.array(
        [0.2, 0.25, -0.35, 0.3, 0.2]), 0.01
    s = np.arange(1, 61) / 60
    s = 10 * s ** 3 - 15 * s ** 4 + 6 * s ** 5
    q_d = q_centre + np.concatenate((s, 1 - s))[:, None] * q_step
    qd_d = np.gradient(q_d, dt, axis=0)

    def track(robot):
        with RobotSimulator(robot_urdf(robot), "torque", initial_positions=q_centre) as sim:
            state, integral, torques, tool = sim.state(), np.zeros(5), [], []
            for target, speed in zip(q_d, qd_d):
                error = target - state.positions
                integral += error * dt
                state = sim.step(100 * error + 0.01 * integral
                                 + 2.0 * (speed - state.velocities), 10)
                torques.append(state.efforts)
                tool.append(state.end_effector)
        at_limit = np.sign(torques) * (np.abs(torques) >= youbot.effort_limits)
        flips = int((at_limit[1:] * at_limit[:-1] < 0).any(axis=1).sum())
        distance = np.linalg.norm(np.array(tool) - forward_kinematics(youbot, q_d), axis=1)
        return distance, np.abs(torques).max(), (at_limit != 0).any(axis=1).mean(), flips

    distance, peak, saturated, flips = track(youbot)
    assert distance.mean() < 0.06 and distance.max() < 0.08, distance
    assert peak < 20.0 and saturated == 0 and flips == 0
    distance, peak, saturated, flips = track(
        dataclasses.replace(youbot, joint_armature=np.zeros(5), joint_damping=np.zeros(5)))
    assert saturated > 0.5 and flips > 50 and distance.mean() > 0.1


def test_damping_on_a_light_link_is_stable_in_torque_mode():
    """pybullet's own (explicit) damping diverges when D·dt > 2·inertia: the youBot's wrist
    roll (7e-5 kg·m²) with D = 1 N·m·s/rad and no armature ran away to 100 rad/s in 10 ms.
    Applied implicitly by the simulator it settles at its terminal speed τ/D."""
    import dataclasses

    youbot = load_robot_params(ROBOTS / "youbot_arm.toml")
    light = dataclasses.replace(youbot, joint_armature=np.zeros(5))
    with RobotSimulator(robot_urdf(light), "torque",
                        initial_positions=[0.0, 0.5, 0.8, 0.5, 0.0]) as sim:
        for _ in range(5):
            state = sim.step([0.0, 0.0, 0.0, 0.0, 0.01], 10)
    assert state.velocities[4] == pytest.approx(0.01 / 1.0, rel=0.15)
    assert np.abs(state.velocities).max() < 2.0


def test_velocity_motor_actuator_is_a_torque_below_the_velocity_limit_and_caps_the_speed():
    """V-REP's torque mode (``actuator="velocity_motor"``, thesis ch. 5): while the joints are
    slower than their velocity limits it moves the arm as the same torques on the arm without
    armature and damping; then it holds a joint at its limit, as far as |τ| can."""
    import dataclasses

    youbot = load_robot_params(ROBOTS / "youbot_arm.toml")
    bare = dataclasses.replace(youbot, joint_armature=np.zeros(5), joint_damping=np.zeros(5))
    home, tau = [0.0, 0.5, 0.8, 0.5, 0.0], [3.0, 5.0, 2.0, 0.3, 0.0]
    with RobotSimulator(robot_urdf(bare), "torque", initial_positions=home) as torque, \
            RobotSimulator(robot_urdf(youbot), "torque", initial_positions=home,
                           actuator="velocity_motor") as motor:
        np.testing.assert_array_equal(motor.velocity_limits, youbot.velocity_limits)
        for _ in range(2):     # 20 ms: every joint still well below pi/2 rad/s
            expected, state = torque.step(tau, 10), motor.step(tau, 10)
            np.testing.assert_allclose(state.positions, expected.positions, atol=1e-9)
            np.testing.assert_allclose(state.velocities, expected.velocities, atol=1e-6)
        np.testing.assert_array_equal(state.efforts, tau)
        fastest = np.zeros(2)
        for _ in range(60):
            expected, state = torque.step(tau, 10), motor.step(tau, 10)
            fastest = np.maximum(fastest, np.abs([expected.velocities[0], state.velocities[0]]))
        # the free torque drives the base yaw (no gravity about its axis) far past its limit;
        # the motor holds it there (joints that gravity pulls run faster if |τ| cannot brake)
        assert fastest[0] > 3 * youbot.velocity_limits[0]
        assert fastest[1] <= youbot.velocity_limits[0] * 1.001


def test_unknown_actuator_is_refused():
    with pytest.raises(ValueError, match="actuator must be one of"):
        RobotSimulator(robot_urdf(load_robot_params(ROBOTS / "youbot_arm.toml")), "torque",
                       actuator="servo")
