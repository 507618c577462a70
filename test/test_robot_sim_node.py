"""The robot_sim node as a separate process over real DDS: lock-step stepping, joint_states
with simulated-time stamps, bad requests, clean exit on SIGINT."""
import math
import signal

import numpy as np
import pytest

from conftest import ROOT
from lpa_transfer.robots.kinematics import planar_forward_kinematics
from lpa_transfer.robots.params import load_robot_params
from ros_harness import ClientNode, NodeProcess, ros_params, unique_domain_id

from sensor_msgs.msg import JointState

from lpa_transfer_interfaces.srv import StepRobot

ROBOT = ROOT / "scenarios" / "robots" / "two_link_source.toml"
LENGTHS = load_robot_params(ROBOT).link_lengths


class SimClient(ClientNode):
    """A step client and a joint_states subscriber in this process, on their own context."""

    def __init__(self, domain_id):
        super().__init__(domain_id, "robot_sim_test_client")
        self.client = self.node.create_client(StepRobot, "/robot_sim/step")
        self.joint_states = []
        self.node.create_subscription(JointState, "/joint_states", self.joint_states.append, 50)

    def step(self, command, n_steps):
        return self.call(self.client, StepRobot.Request(command=[float(c) for c in command],
                                                        n_steps=n_steps))

    def spin_until(self, predicate, timeout=5.0):
        return super().spin_until(predicate, timeout, what="joint_states")


@pytest.fixture(scope="module")
def sim(tmp_path_factory):
    domain_id = unique_domain_id()
    node = NodeProcess("robot_sim", domain_id, tmp_path_factory.mktemp("robot_sim"),
                       ros_params(robot=ROBOT, physics_step=0.001, lockstep=True))
    client = SimClient(domain_id)
    try:
        yield node, client
    finally:
        client.close()
        node.stop()


def stamp_seconds(stamp):
    return stamp.sec + stamp.nanosec * 1e-9


def test_lockstep_step_moves_towards_the_commanded_pose(sim):
    node, client = sim
    target = np.array([0.6, 1.2])
    # the module's node has run other tests' steps: back to the initial pose, and the clock
    # counts on from where it is
    from lpa_transfer_interfaces.srv import ResetRobot

    reset = client.node.create_client(ResetRobot, "/robot_sim/reset")
    home = client.call(reset, ResetRobot.Request())
    assert home.success, home.message
    errors, t = [], home.sim_time
    for _ in range(3):
        response = client.step(target, 500)
        assert response.success, response.message
        q = np.array(response.joint_state.position)
        errors.append(np.abs(q - target).max())
        assert response.sim_time == pytest.approx(t + 0.5, abs=1e-9)
        t = response.sim_time
        assert list(response.joint_state.name) == ["joint1", "joint2"]
        assert stamp_seconds(response.joint_state.header.stamp) == pytest.approx(t, abs=1e-9)
        ee = response.end_effector
        expected = planar_forward_kinematics(q[None], LENGTHS)[0]
        assert abs(ee.x - expected[0]) <= 1e-6 and abs(ee.y - expected[1]) <= 1e-6
        assert abs(ee.z) <= 1e-6
    assert errors[-1] < 1e-2 and errors[-1] <= errors[0], errors


def test_joint_states_are_published_with_sim_time_stamps(sim):
    node, client = sim
    # DDS discovery of the subscriber can lag the first request: step until messages arrive.
    for _ in range(50):
        assert client.step([0.3, 0.4], 10).success
        client.executor.spin_once(timeout_sec=0.05)
        if client.joint_states:
            break
    n_before = len(client.joint_states)
    response = client.step([0.3, 0.4], 10)
    client.spin_until(lambda: len(client.joint_states) > n_before)
    last = client.joint_states[-1]
    assert stamp_seconds(last.header.stamp) == pytest.approx(response.sim_time, abs=1e-9)
    np.testing.assert_array_equal(last.position, response.joint_state.position)
    assert len(last.effort) == 2 and all(math.isfinite(e) for e in last.effort)


def test_clock_carries_the_simulated_time_to_a_node_on_sim_time(sim):
    """/clock (the robot is in the root namespace) is the time of the last advance, and a node
    with use_sim_time reads it as its ROS clock: its clock and the stamps agree."""
    from rclpy.parameter import Parameter
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from rosgraph_msgs.msg import Clock

    node, client = sim
    clocks = []
    client.node.create_subscription(Clock, "/clock", clocks.append, QoSProfile(
        depth=10, reliability=ReliabilityPolicy.BEST_EFFORT))
    client.node.set_parameters([Parameter("use_sim_time", value=True)])
    for _ in range(50):          # until discovery lets the clock through
        assert client.step([0.2, 0.1], 10).success
        client.executor.spin_once(timeout_sec=0.05)
        if clocks:
            break
    response = client.step([0.2, 0.1], 10)
    client.spin_until(lambda: clocks and stamp_seconds(clocks[-1].clock) >= response.sim_time)
    assert stamp_seconds(clocks[-1].clock) == pytest.approx(response.sim_time, abs=1e-9)
    assert client.node.get_clock().now().nanoseconds == pytest.approx(
        response.sim_time * 1e9, abs=1)
    assert client.node.get_clock().now().to_msg() == response.joint_state.header.stamp
    client.node.set_parameters([Parameter("use_sim_time", value=False)])


@pytest.mark.parametrize("command, message", [([0.1], "must have 2 values"),
                                              ([0.1, 0.2, 0.3], "must have 2 values"),
                                              ([math.nan, 0.1], "NaN or infinite"),
                                              ([0.1, math.inf], "NaN or infinite")])
def test_bad_command_fails_and_the_next_request_works(sim, command, message):
    node, client = sim
    before = client.step([0.5, 0.5], 1).sim_time
    bad = client.step(command, 10)
    assert not bad.success and message in bad.message
    assert bad.sim_time == pytest.approx(before, abs=1e-12)
    good = client.step([0.5, 0.5], 10)
    assert good.success, good.message
    assert good.sim_time == pytest.approx(before + 0.01, abs=1e-9)
    assert node.alive()


def test_zero_steps_counts_as_one(sim):
    node, client = sim
    before = client.step([0.5, 0.5], 1).sim_time
    assert client.step([0.5, 0.5], 0).sim_time == pytest.approx(before + 0.001, abs=1e-9)


def test_free_running_mode_follows_joint_commands(tmp_path):
    from std_msgs.msg import Float64MultiArray

    domain_id = unique_domain_id()
    with NodeProcess("robot_sim", domain_id, tmp_path,
                     ros_params(robot=ROBOT, lockstep=False, control_rate=100.0)) as node:
        client = SimClient(domain_id)
        try:
            publisher = client.node.create_publisher(Float64MultiArray, "/joint_commands", 10)
            client.spin_until(lambda: client.joint_states, timeout=10)

            def reached():
                publisher.publish(Float64MultiArray(data=[0.4, 0.9]))
                last = client.joint_states[-1].position
                return np.abs(np.array(last) - [0.4, 0.9]).max() < 1e-2

            client.spin_until(reached, timeout=10)
            stamps = [stamp_seconds(m.header.stamp) for m in client.joint_states[-5:]]
            # Each tick advances 1 / (100 Hz * 1 ms) = 10 physics steps (0.01 s of sim time).
            ticks = np.diff(stamps) / 0.01
            assert (ticks >= 1 - 1e-6).all(), stamps
            np.testing.assert_allclose(ticks, np.round(ticks), atol=1e-6)
            assert node.stop() == 0, node.log()
        finally:
            client.close()


def test_reset_puts_the_robot_at_rest_and_the_clock_runs_on(sim):
    from lpa_transfer_interfaces.srv import ResetRobot

    node, client = sim
    reset = client.node.create_client(ResetRobot, "/robot_sim/reset")
    moved = client.step([1.0, 2.0], 300)
    answer = client.call(reset, ResetRobot.Request(positions=[0.5, 0.25]))
    assert answer.success, answer.message
    assert list(answer.joint_state.position) == pytest.approx([0.5, 0.25])
    assert list(answer.joint_state.velocity) == [0.0, 0.0]
    assert answer.sim_time == pytest.approx(moved.sim_time)
    x, y = planar_forward_kinematics(np.array([[0.5, 0.25]]), LENGTHS)[0]
    assert (answer.end_effector.x, answer.end_effector.y) == pytest.approx((x, y), abs=1e-6)
    bad = client.call(reset, ResetRobot.Request(positions=[0.5, 9.0]))
    assert not bad.success and "outside the joint limits" in bad.message
    home = client.call(reset, ResetRobot.Request())          # empty: the initial pose
    assert home.success and list(home.joint_state.position) == pytest.approx([0.0, 0.0])
    assert client.step([0.0, 0.0], 1).success


def test_sigint_exits_cleanly(tmp_path):
    """Its own node: the module's shared one must keep serving the other tests."""
    domain_id = unique_domain_id()
    node = NodeProcess("robot_sim", domain_id, tmp_path,
                       ros_params(robot=ROBOT, physics_step=0.001, lockstep=True))
    client = SimClient(domain_id)
    try:
        assert client.step([0.5, 0.5], 1).success
    finally:
        client.close()
    assert node.stop(signal.SIGINT, timeout=10) == 0, node.log()


def test_a_reset_sent_before_the_simulator_listens_is_sent_again(tmp_path):
    """A request sent before the server matched is lost (the race behind wait_for_services'
    settle time, seen in CI); robot_resetter sends a reset again, since it is idempotent, and
    gets its answer, where the same call sent once would wait in vain."""
    from lpa_transfer_interfaces.srv import ResetRobot
    from lpa_transfer_nodes.calls import ServiceTimeout, call_service
    from lpa_transfer_nodes.robot_clients import robot_resetter

    domain_id = unique_domain_id()
    client = ClientNode(domain_id, "reset_resend_client")
    nodes = []
    try:
        def call_before_the_server(timeout):
            reset_client = client.node.create_client(ResetRobot, "/robot_sim/reset")
            def call(srv_client, request, **options):
                assert not srv_client.service_is_ready()     # the first request goes nowhere
                nodes.append(NodeProcess("robot_sim", domain_id, tmp_path / str(len(nodes)),
                                         ros_params(robot=ROBOT, lockstep=True)))
                return call_service(client.executor, srv_client, request, timeout, **options)
            return reset_client, call

        reset_client, call = call_before_the_server(60.0)
        state = robot_resetter(call, reset_client, "two_link")([0.3, 0.2])
        assert state.positions == pytest.approx([0.3, 0.2])
        assert nodes.pop().stop() == 0

        sent_once, call = call_before_the_server(10.0)
        client.spin_until(lambda: not sent_once.service_is_ready(), timeout=10,
                          what="the first robot_sim gone")
        with pytest.raises(ServiceTimeout, match="did not answer within 10 s"):
            call(sent_once, ResetRobot.Request(positions=[0.3, 0.2]))
    finally:
        client.close()
        for node in nodes:
            assert node.stop() == 0


def test_a_pybullet_panda_runs_down_to_its_hand(tmp_path):
    """A branching URDF: robot:=panda.urdf branches at the hand; tip_link names the chain's end,
    and an unknown link is one FATAL line naming the links there are."""
    import pybullet_data

    from lpa_transfer.robots.kinematics import robot_kinematics

    panda = f"{pybullet_data.getDataPath()}/franka_panda/panda.urdf"
    domain_id = unique_domain_id()
    bad = NodeProcess("robot_sim", domain_id, tmp_path / "bad",
                      ros_params(robot=panda, tip_link="hand"))
    assert bad.process.wait(60) != 0
    fatal = [line for line in bad.log().splitlines() if "FATAL" in line]
    assert len(fatal) == 1 and "no link 'hand' (tip_link)" in fatal[0], bad.log()
    assert "'panda_hand'" in fatal[0]
    bad.stop()
    node = NodeProcess("robot_sim", domain_id, tmp_path / "good",
                       ros_params(robot=panda, tip_link="panda_hand"))
    client = SimClient(domain_id)
    try:
        target = np.array([0.3, -0.4, 0.2, -1.8, 0.1, 1.2, 0.5])
        response = client.step(target, 2000)
        assert response.success, (response.message, node.log())
        assert len(response.joint_state.name) == 7
        q = np.array(response.joint_state.position)
        robot = load_robot_params(panda, tip_link="panda_hand")
        hand = robot_kinematics(robot).forward(q[None])[0]
        ee = response.end_effector
        np.testing.assert_allclose([ee.x, ee.y, ee.z], hand, atol=1e-6)
    finally:
        client.close()
        assert node.stop() == 0, node.log()
