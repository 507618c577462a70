"""recorder and player nodes as separate processes over real DDS (each test on its own domain)."""
import signal
import time

import pytest

from lpa_transfer.recording import bag
from ros_harness import (ClientNode, NodeProcess, ros_params, run_to_end, unique_domain_id,
                         wait_until)

from rclpy.duration import Duration
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.serialization import deserialize_message, serialize_message
from builtin_interfaces.msg import Time
from rosgraph_msgs.msg import Clock
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
        record.window = [time.time_ns()]
        for i in range(joint_states):
            joints.publish(joint_state(i))
            if i % (joint_states // SAMPLES) == 0 and i // (joint_states // SAMPLES) < SAMPLES:
                samples.publish(sample(i // (joint_states // SAMPLES)))
            time.sleep(0.002)
        for publisher in (joints, samples):
            assert publisher.wait_for_all_acked(Duration(seconds=10))
        record.window.append(time.time_ns())
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
    # rosbag2's times: publish = the publisher's send time, log = the recorder's receive
    # time (both wall clock here), not the header stamps (i s + 1 µs), which stay in the data
    sent = [m.publish_time_ns for m in recorded]
    start, end = record.window
    assert sent == sorted(sent) and start <= sent[0] and sent[-1] <= end
    assert all(0 <= m.log_time_ns - m.publish_time_ns < 10**9 for m in recorded)
    stamps = [deserialize_message(m.data, JointState).header.stamp for m in recorded]
    assert [(s.sec, s.nanosec) for s in stamps] == [(i, 1000) for i in range(JOINT_STATES)]


def test_a_topic_seen_first_through_a_subscriber_is_recorded_from_its_best_effort_publisher(
        ros_node, tmp_path):
    """A node on sim time subscribes to its robot's /clock before the robot publishes it
    (best effort): the recorder must subscribe with the publisher's QoS, not a guess."""
    domain_id, output = unique_domain_id(), tmp_path / "run.mcap"
    test = ros_node(domain_id)
    best_effort = QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT)
    test.node.create_subscription(Clock, "/robot/clock", lambda msg: None, best_effort)
    recorder = NodeProcess("recorder", domain_id, tmp_path / "log",
                           ros_params(output=output, discovery_period=0.2))
    try:
        wait_until(lambda: "recording to" in recorder.log(), what="the recorder's start")
        time.sleep(1.0)                              # scans that see only the subscriber
        clock = test.node.create_publisher(Clock, "/robot/clock", best_effort)
        wait_until(lambda: clock.get_subscription_count() == 2,
                   what="the recorder's subscription to /robot/clock")
        for i in range(20):
            clock.publish(Clock(clock=Time(sec=i)))
            time.sleep(0.01)
        time.sleep(0.5)
    finally:
        assert recorder.stop(signal.SIGINT) == 0, recorder.log()
    recorded = list(bag.read_messages(output, topics=["/robot/clock"]))
    assert [deserialize_message(m.data, Clock).clock.sec for m in recorded] == list(range(20))


def test_recorder_finalises_on_sigterm(ros_node, tmp_path):
    path = record(ros_node, tmp_path, signal.SIGTERM, joint_states=80)
    assert bag.summary(path)["/joint_states"].message_count == 80


def test_player_replays_samples_in_order(ros_node, tmp_path):
    """A bag written directly (the recorder is tested above), played with a topic subset and
    the standard ``-r`` remap, with the player's defaults: it waits for the listener, so a
    listener started beside it receives every message."""
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
        input=path, rate=0.0, topics="['/samples']") + ["-r", "/samples:=/replayed"])
    try:
        # the player ends by itself once it has published the bag
        test.spin_until(lambda: not player.alive(), timeout=20, what="the player to finish")
        test.spin_until(lambda: len(received) >= SAMPLES, timeout=10,
                        what=f"all {SAMPLES} replayed samples")
    finally:
        assert player.stop() == 0, player.log()
    assert [(m.index, list(m.source), list(m.target)) for m in received] == [
        (s.index, list(s.source), list(s.target)) for s in map(sample, range(SAMPLES))], player.log()


def test_player_publishes_the_bag_time_on_clock(ros_node, tmp_path):
    """clock:=50 publishes the playback position in the bag's log time on /clock (as ros2
    bag play --clock): increasing, within the bag's span."""
    path, first = tmp_path / "timed.mcap", 5 * 10**9
    with bag.BagWriter(path) as writer:
        writer.add_topic("/samples", "lpa_transfer_interfaces/msg/CorrespondenceSample")
        for i in range(SAMPLES):     # 40 messages over 1 s of bag time
            writer.write("/samples", serialize_message(sample(i)), first + i * 25_000_000)
    domain_id = unique_domain_id()
    test = ros_node(domain_id)
    clocks, received = [], []
    test.node.create_subscription(Clock, "/clock", clocks.append, QoSProfile(
        depth=100, reliability=ReliabilityPolicy.BEST_EFFORT))
    test.node.create_subscription(CorrespondenceSample, "/samples", received.append, RELIABLE_1000)
    player = NodeProcess("player", domain_id, tmp_path / "log_play", ros_params(
        input=path, rate=1.0, clock=50.0))
    try:
        test.spin_until(lambda: not player.alive(), timeout=20, what="the player to finish")
        test.spin_for(0.2)
    finally:
        assert player.stop() == 0, player.log()
    times = [c.clock.sec * 10**9 + c.clock.nanosec for c in clocks]
    assert len(received) == SAMPLES
    assert len(times) >= 20, times           # 1 s at 50 Hz, less what discovery took
    assert times == sorted(times)
    assert first <= times[0] and times[-1] <= first + 1_100_000_000
    assert times[-1] - times[0] >= 500_000_000


def written_bag(path):
    with bag.BagWriter(path) as writer:
        writer.add_topic("/samples", "lpa_transfer_interfaces/msg/CorrespondenceSample")
        for i in range(SAMPLES):
            writer.write("/samples", serialize_message(sample(i)), i)
    return path


def fatal_lines(log):
    return [line for line in log.splitlines() if "FATAL" in line]


@pytest.mark.parametrize("case", ["missing", "not MCAP", "no requested topic"])
def test_player_faults_are_one_fatal_line_and_exit_1(tmp_path, case):
    inputs = {"missing": tmp_path / "nothing.mcap", "not MCAP": tmp_path / "text.mcap",
              "no requested topic": written_bag(tmp_path / "run.mcap")}
    (tmp_path / "text.mcap").write_text("not a bag\n")
    expected = {"missing": "no such file", "not MCAP": "is not a readable MCAP bag",
                "no requested topic": "none of the requested topics ['/sampels']"}
    player = NodeProcess("player", unique_domain_id(), tmp_path / "log", ros_params(
        input=inputs[case], topics="['/sampels']", start_delay=0.0))
    assert run_to_end(player, timeout=30) == 1, player.log()
    fatal = fatal_lines(player.log())
    assert len(fatal) == 1 and expected[case] in fatal[0], player.log()
    assert "Traceback" not in player.log()


def test_player_warns_about_absent_topics_and_unheard_messages(tmp_path):
    player = NodeProcess("player", unique_domain_id(), tmp_path / "log", ros_params(
        input=written_bag(tmp_path / "run.mcap"), topics="['/samples', '/sampels']",
        start_delay=0.0, rate=0.0, wait_timeout=1.0))
    assert run_to_end(player, timeout=30) == 0, player.log()
    log = player.log()
    assert "not in" in log and "so not played: ['/sampels']" in log
    assert f"published to no subscriber on: ['/samples ({SAMPLES})']" in log


def test_recorder_unwritable_output_is_one_fatal_line_and_exit_1(tmp_path):
    (tmp_path / "a_file").write_text("")
    recorder = NodeProcess("recorder", unique_domain_id(), tmp_path / "log",
                           ros_params(output=tmp_path / "a_file" / "run.mcap"))
    assert run_to_end(recorder, timeout=30) == 1, recorder.log()
    fatal = fatal_lines(recorder.log())
    assert len(fatal) == 1 and "cannot write the bag" in fatal[0], recorder.log()
    assert "Traceback" not in recorder.log()


def test_recorder_on_a_full_disk_stops_with_one_fatal_line_and_exit_1(ros_node, tmp_path):
    """/dev/full: every write fails with ENOSPC, as on a full disk."""
    domain_id = unique_domain_id()
    test = ros_node(domain_id)
    samples = test.node.create_publisher(CorrespondenceSample, "/samples", RELIABLE_1000)
    recorder = NodeProcess("recorder", domain_id, tmp_path / "log",
                           ros_params(output="/dev/full", discovery_period=0.1))
    try:
        wait_until(samples.get_subscription_count, what="the recorder's subscription")
        deadline = time.monotonic() + 10
        i = 0
        while recorder.alive() and time.monotonic() < deadline:   # past the 1 s flush period
            samples.publish(sample(i))
            i += 1
            test.spin_for(0.05)
    finally:
        code = recorder.stop()
    assert code == 1, recorder.log()
    fatal = fatal_lines(recorder.log())
    assert len(fatal) == 1 and "No space left on device" in fatal[0], recorder.log()
    assert "Traceback" not in recorder.log()


def test_a_sigkilled_recorder_loses_at_most_the_last_flush_period(ros_node, tmp_path):
    """A killed recorder: SIGKILL while 200 messages a second arrive. Every message sent more
    than 0.3 s before the kill is in the file, for our truncated reader and mcap's own stream
    reader (the recorder closes a chunk every 0.25 s whether or not messages follow)."""
    from mcap.stream_reader import StreamReader
    from mcap.records import Message

    domain_id, output = unique_domain_id(), tmp_path / "killed.mcap"
    test = ros_node(domain_id)
    samples = test.node.create_publisher(CorrespondenceSample, "/samples", RELIABLE_1000)
    recorder = NodeProcess("recorder", domain_id, tmp_path / "log",
                           ros_params(output=output, discovery_period=0.1))
    wait_until(samples.get_subscription_count, what="the recorder's subscription")
    sent, killed = [], None
    for i in range(400):                                   # 2 s at 200 a second
        samples.publish(sample(i))
        sent.append(time.monotonic())
        test.spin_for(0.005)
        if i == 300:                                       # killed while messages still flow
            killed = time.monotonic()
            recorder.stop(signal.SIGKILL)
    due = {i for i, t in enumerate(sent) if t < killed - 0.3}
    ours = {deserialize_message(m.data, CorrespondenceSample).index
            for m in bag.read_messages(output, allow_truncated=True)}
    assert due <= ours, sorted(due - ours)[:10]
    independent = 0
    with open(output, "rb") as stream:
        try:
            for record in StreamReader(stream, skip_magic=False).records:
                independent += isinstance(record, Message)
        except Exception:   # the file ends mid-record: everything before it was read
            pass
    assert independent >= len(due)


def test_hidden_topics_are_left_out_and_an_unrecordable_type_is_skipped(ros_node, tmp_path):
    """As rosbag2: hidden topics (an action's /_action/...) are not recorded by default. With
    include_hidden_topics, a topic whose type the bag cannot describe (an action's feedback
    message, which has no .msg file) is skipped with one warning; the recorder records the
    rest and exits 0 (it used to die with a traceback)."""
    from std_msgs.msg import String
    from lpa_transfer_interfaces.action import RunTrials

    feedback_type = RunTrials.Impl.FeedbackMessage
    for include, expected in ((False, {"/visible"}), (True, {"/visible", "/robot/_hidden"})):
        domain_id, output = unique_domain_id(), tmp_path / f"hidden_{include}.mcap"
        test = ros_node(domain_id)
        publishers = [test.node.create_publisher(String, "/visible", 10),
                      test.node.create_publisher(String, "/robot/_hidden", 10),
                      test.node.create_publisher(feedback_type, "/robot/_action/feedback", 10)]
        recorder = NodeProcess("recorder", domain_id, tmp_path / f"log_{include}",
                               ros_params(output=output, discovery_period=0.1,
                                          include_hidden_topics=include))
        wait_until(lambda: publishers[0].get_subscription_count(), what="the recording")
        test.spin_for(0.5)                         # a few discovery scans
        for publisher in publishers[:2]:
            publisher.publish(String(data="x"))
        test.spin_for(0.5)
        assert recorder.stop(signal.SIGINT) == 0, recorder.log()
        assert set(bag.summary(output)) == expected
        warned = "not recording /robot/_action/feedback" in recorder.log()
        assert warned == include, recorder.log()
        assert "Traceback" not in recorder.log()
