"""lpa_transfer.recording.bag: rosbag2-layout MCAP files, cross-checked with the independent mcap_ros2 decoder."""
from collections import namedtuple

import pytest

from lpa_transfer.recording import bag

import rclpy.serialization as rclpy_serialization
from sensor_msgs.msg import JointState

from lpa_transfer_interfaces.msg import CorrespondenceSample, Matrix

SEPARATOR = "=" * 80
Decoded = namedtuple("Decoded", "topic type_name ros_msg")  # one message as mcap_ros2 decodes it


def joint_state(i):
    message = JointState(name=[f"joint_{k}" for k in range(7)],
                         position=[i + 0.125 * k for k in range(7)], velocity=[-1.5 * i] * 7)
    message.header.stamp.sec, message.header.stamp.nanosec = 1000 + i, 250_000_000
    message.header.frame_id = "base"
    return message


def sample(i):
    message = CorrespondenceSample(source_robot="a", target_robot="b", index=i,
                                   source=[0.5 * i, 1.0], target=[2.0, -0.25 * i, 3.0])
    message.header.stamp.sec = 7
    return message


def write_bag(path, joint_states=20, samples=5):
    """A bag with JointState on /joint_states and CorrespondenceSample on /samples."""
    with bag.BagWriter(path) as writer:
        writer.add_topic("/joint_states", "sensor_msgs/msg/JointState", [{"depth": 10}])
        writer.add_topic("/samples", "lpa_transfer_interfaces/CorrespondenceSample")
        for i in range(max(joint_states, samples)):
            t = 1_000_000_000 + i * 1_000_000
            if i < joint_states:
                cdr = rclpy_serialization.serialize_message(joint_state(i))
                writer.write("/joint_states", cdr, t, bag.header_stamp_ns("sensor_msgs/msg/JointState", cdr))
            if i < samples:
                writer.write("/samples", rclpy_serialization.serialize_message(sample(i)), t + 1)
    return path


def test_joint_state_definition_holds_nested_types_once():
    text = bag.message_definition("sensor_msgs/msg/JointState")
    assert text.startswith(bag.msg_file_text("sensor_msgs/msg/JointState"))
    assert f"{SEPARATOR}\nMSG: std_msgs/msg/Header\n" in text
    assert f"{SEPARATOR}\nMSG: builtin_interfaces/msg/Time\n" in text
    assert text.count("MSG: ") == 2
    assert bag.message_definition("sensor_msgs/JointState") == text


def test_short_names_resolve_in_own_package():
    text = bag.message_definition("lpa_transfer_interfaces/msg/CorrespondenceBatch")
    assert text.count("MSG: lpa_transfer_interfaces/msg/Matrix\n") == 1  # two Matrix fields
    assert bag.field_types("Header h\nMatrix[] m\nuint8[<=3] x\nstring<=5 s  # c\nint32 K=1", "p") == [
        "std_msgs/msg/Header", "p/msg/Matrix"]


def test_header_stamp_only_for_leading_header():
    cdr = rclpy_serialization.serialize_message(joint_state(3))
    assert bag.header_stamp_ns("sensor_msgs/msg/JointState", cdr) == 1003_250_000_000
    matrix = rclpy_serialization.serialize_message(Matrix(rows=1))
    assert bag.header_stamp_ns("lpa_transfer_interfaces/msg/Matrix", matrix) is None


def test_unknown_type_is_a_clear_error():
    with pytest.raises(bag.BagError, match="no definition"):
        bag.message_definition("no_such_pkg/msg/Nothing")


def test_written_bag_decodes_identically_with_mcap_ros2(tmp_path):
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    path = write_bag(tmp_path / "two_topics.mcap")
    with open(path, "rb") as stream:
        decoded = [Decoded(channel.topic, schema.name, ros_msg) for schema, channel, _, ros_msg in
                   make_reader(stream, decoder_factories=[DecoderFactory()]).iter_decoded_messages()]
    assert [m.topic for m in decoded].count("/joint_states") == 20
    ours = list(bag.read_messages(path))
    assert len(ours) == len(decoded) == 25
    for theirs, mine in zip(decoded, ours):
        assert theirs.topic == mine.topic
        assert theirs.type_name == mine.type_name
        expected = rclpy_serialization.deserialize_message(
            mine.data, JointState if mine.topic == "/joint_states" else CorrespondenceSample)
        if mine.topic == "/joint_states":
            assert list(theirs.ros_msg.position) == list(expected.position)
            assert list(theirs.ros_msg.name) == list(expected.name)
            assert theirs.ros_msg.header.stamp.sec == expected.header.stamp.sec
            assert mine.publish_time_ns == expected.header.stamp.sec * 10**9 + 250_000_000
        else:
            assert theirs.ros_msg.index == expected.index
            assert list(theirs.ros_msg.target) == list(expected.target)
            assert mine.publish_time_ns == mine.log_time_ns


def test_layout_matches_rosbag2(tmp_path):
    from mcap.reader import make_reader

    with open(write_bag(tmp_path / "layout.mcap"), "rb") as stream:
        reader = make_reader(stream)
        assert reader.get_header().profile == "ros2"
        info = reader.get_summary()
    assert {s.encoding for s in info.schemas.values()} == {"ros2msg"}
    assert {c.message_encoding for c in info.channels.values()} == {"cdr"}
    qos = {c.topic: c.metadata["offered_qos_profiles"] for c in info.channels.values()}
    assert qos["/joint_states"].startswith("- history: keep_last\n  depth: 10\n")
    assert qos["/samples"] == "[]\n"


def test_summary_counts_topics(tmp_path):
    info = bag.summary(write_bag(tmp_path / "counts.mcap", joint_states=12, samples=3))
    assert {topic: (i.type_name, i.message_count) for topic, i in info.items()} == {
        "/joint_states": ("sensor_msgs/msg/JointState", 12),
        "/samples": ("lpa_transfer_interfaces/msg/CorrespondenceSample", 3)}


def test_truncated_file_is_a_clear_error_and_readable_on_request(tmp_path):
    """As if the recorder was killed after its first flush: 30 messages in a complete chunk."""
    path = tmp_path / "cut.mcap"
    with bag.BagWriter(path) as writer:
        writer.add_topic("/joint_states", "sensor_msgs/msg/JointState")
        for i in range(40):
            writer.write("/joint_states", rclpy_serialization.serialize_message(joint_state(i)), i)
            if i == 29:
                writer.flush()
                flushed_size = path.stat().st_size
    path.write_bytes(path.read_bytes()[:flushed_size + 10])
    with pytest.raises(bag.BagError, match="truncated"):
        list(bag.read_messages(path))
    with pytest.raises(bag.BagError, match="truncated"):
        bag.summary(path)
    recovered = list(bag.read_messages(path, allow_truncated=True))
    assert [m.log_time_ns for m in recovered] == list(range(30))


def test_write_to_unknown_topic_fails(tmp_path):
    with bag.BagWriter(tmp_path / "x.mcap") as writer:
        with pytest.raises(bag.BagError, match="not added"):
            writer.write("/nowhere", b"\0\1\0\0", 1)


def finished_bag(path, n=600):
    """n samples in chunks of 100 messages (as a recorder flushing while it records)."""
    with bag.BagWriter(path) as writer:
        writer.add_topic("/samples", "lpa_transfer_interfaces/msg/CorrespondenceSample")
        for i in range(n):
            writer.write("/samples", rclpy_serialization.serialize_message(sample(i)), 1000 * i)
            if i % 100 == 99:
                writer.flush()
    return path


def test_no_single_bit_flip_is_read_silently(tmp_path):
    """A damaged bag: 150 random single-bit flips of a finished bag; each read either gives
    the original messages or raises BagError naming the file (CRCs are checked)."""
    import numpy as np

    path = finished_bag(tmp_path / "run.mcap")
    original = path.read_bytes()
    expected = [(m.topic, m.data, m.log_time_ns) for m in bag.read_messages(path)]
    rng, flipped, errors = np.random.default_rng(0), tmp_path / "flipped.mcap", 0
    for _ in range(150):
        data = bytearray(original)
        data[int(rng.integers(len(data)))] ^= 1 << int(rng.integers(8))
        flipped.write_bytes(bytes(data))
        try:
            got = [(m.topic, m.data, m.log_time_ns) for m in bag.read_messages(flipped)]
        except bag.BagError as error:
            assert str(flipped) in str(error)
            errors += 1
            continue
        assert got == expected            # a flip that changes nothing read (e.g. padding)
    assert errors > 0


def test_a_killed_recording_is_recovered_into_a_finalised_bag(tmp_path):
    """A bag cut mid-file (a killed recorder, a full disk): --recover writes a finalised
    copy with every complete message, which the normal reader and summary accept."""
    import subprocess
    import sys

    path = finished_bag(tmp_path / "run.mcap", n=3000)
    # a file cut short, as a SIGKILL leaves it: no summary, the last chunk incomplete
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(path.read_bytes()[:len(path.read_bytes()) * 2 // 3])
    with pytest.raises(bag.BagError, match="--recover IN OUT"):
        list(bag.read_messages(cut))
    complete = [m.data for m in bag.read_messages(cut, allow_truncated=True)]
    assert 0 < len(complete) < 3000
    out = tmp_path / "recovered.mcap"
    result = subprocess.run([sys.executable, "-m", "lpa_transfer.recording.bag", "--recover",
                             str(cut), str(out)], capture_output=True, text=True, timeout=60)
    assert result.returncode == 0, result.stderr
    assert f"recovered {len(complete)} messages" in result.stdout
    assert [m.data for m in bag.read_messages(out)] == complete
    assert bag.summary(out)["/samples"].message_count == len(complete)
