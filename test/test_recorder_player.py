"""recorder and player nodes as separate processes over real DDS (each test on its own domain)."""
import signal
import time

import pytest

from lpa_transfer.recording import bag
from lpa_transfer_nodes.testing import ClientNode, NodeProcess, ros_params, unique_domain_id, wait_until

from rclpy.duration import Duration
from rclpy.qos import QoSProfile
from rclpy.serialization import deserialize_message, serialize_message
from sensor_msgs.msg import JointState

from lpa_transfer_interfaces.msg import CorrespondenceSample

JOINT_STATES, SAMPLES = 500, 40
RELIABLE_1000 = QoSProfile(depth=1000)


@pytest.fixture
def ros_node():
    nodes = []

    def make(domain_id):
        nodes.append(ClientNode(domain_id, "test_node"))
        return nodes[-1]

    yield make
    for node in nodes:
        node.close()


def joint_state(i):
    message = JointState(name=[f"j{k}" for k in range(7)], position=[i + 0.01 * k for k in range(7)])
    message.header.stamp.sec, message.header.stamp.nanosec = i, 1000
    return message


def sample(i):
    return CorrespondenceSample(source_robot="src", target_robot="tgt", index=i,
                                source=[0.5 * i, -1.0], target=[float(i), 2.0, 3.0])


def record(ros_node, tmp_path, stop_signal, joint_states=JOINT_STATES):
    """Run the recorder, publish joint states (~500 Hz) and samples, stop it; returns the bag path."""
    domain_id, output = unique_domain_id(), tmp_path / "run.mcap"
    test = ros_node(domain_id)
    joints = test.node.create_publisher(JointState, "/joint_states", RELIABLE_1000)
    samples = test.node.create_publisher(CorrespondenceSample, "/samples", RELIABLE_1000)
    recorder = NodeProcess("recorder", domain_id, tmp_path / "log",
                           ros_params(output=output, discovery_period=0.2))
    try:
        wait_until(lambda: joints.get_subscription_count() and samples.get_subscription_count(),
                   what="the recorder's subscriptions")
        for i in range(joint_states):
            joints.publish(joint_state(i))
            if i % (joint_states // SAMPLES) == 0 and i // (joint_states // SAMPLES) < SAMPLES:
                samples.publish(sample(i // (joint_states // SAMPLES)))
            time.sleep(0.002)
        for publisher in (joints, samples):
            assert publisher.wait_for_all_acked(Duration(seconds=10))
    finally:
        assert recorder.stop(stop_signal) == 0, recorder.log()
    assert "closed" in recorder.log()
    return output


def test_recorder_keeps_every_message_on_sigint(ros_node, tmp_path):
    path = record(ros_node, tmp_path, signal.SIGINT)
    info = bag.summary(path)
    assert {t: (i.type_name, i.message_count) for t, i in info.items()} == {
        "/joint_states": ("sensor_msgs/msg/JointState", JOINT_STATES),
        "/samples": ("lpa_transfer_interfaces/msg/CorrespondenceSample", SAMPLES)}
    recorded = list(bag.read_messages(path, topics=["/joint_states"]))
    positions = [list(deserialize_message(m.data, JointState).position) for m in recorded]
    assert positions == [list(joint_state(i).position) for i in range(JOINT_STATES)]
    assert [m.publish_time_ns for m in recorded] == [i * 10**9 + 1000 for i in range(JOINT_STATES)]


def test_recorder_finalises_on_sigterm(ros_node, tmp_path):
    path = record(ros_node, tmp_path, signal.SIGTERM, joint_states=80)
    assert bag.summary(path)["/joint_states"].message_count == 80


def test_player_replays_samples_in_order(ros_node, tmp_path):
    """A bag written directly (the recorder is tested above), played with a topic subset and remap."""
    path = tmp_path / "to_play.mcap"
    with bag.BagWriter(path) as writer:
        writer.add_topic("/joint_states", "sensor_msgs/msg/JointState")
        writer.add_topic("/samples", "lpa_transfer_interfaces/msg/CorrespondenceSample")
        for i in range(SAMPLES):
            writer.write("/joint_states", serialize_message(joint_state(i)), 2 * i)
            writer.write("/samples", serialize_message(sample(i)), 2 * i + 1)
    domain_id = unique_domain_id()
    test = ros_node(domain_id)
    received = []
    test.node.create_subscription(CorrespondenceSample, "/replayed", received.append, RELIABLE_1000)
    player = NodeProcess("player", domain_id, tmp_path / "log_play", ros_params(
        input=path, rate=0.0, topics="['/samples']", remap="['/samples:=/replayed']",
        start_delay=0.0, wait_for_subscribers=1))
    try:
        # the player ends by itself once it has published the bag
        test.spin_until(lambda: not player.alive(), timeout=20, what="the player to finish")
        test.spin_until(lambda: len(received) >= SAMPLES, timeout=10,
                        what=f"all {SAMPLES} replayed samples")
    finally:
        assert player.stop() == 0, player.log()
    assert [(m.index, list(m.source), list(m.target)) for m in received] == [
        (s.index, list(s.source), list(s.target)) for s in map(sample, range(SAMPLES))], player.log()
