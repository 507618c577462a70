"""recorder: record topics into an MCAP bag (rosbag2 layout), our stand-in for ``ros2 bag record``.

Run: ``recorder --ros-args -p output:=run.mcap`` (or
``python -m lpa_transfer_nodes.recorder ...``).

Subscriptions are raw (serialized CDR), written in the callback with rosbag2's times:
``log_time`` the receive time on this node's ROS clock (wall time, or the simulated time with
``use_sim_time:=true``), ``publish_time`` the publisher's send time from the middleware's
message info (wall time). A message's own ``header.stamp`` stays in its payload. On
SIGINT/SIGTERM the node
stops discovery, drains messages still queued, closes the bag (readable, with summary), logs
the per-topic counts and exits 0. An output it cannot create, or a write that fails (a full
disk), is one FATAL line and exit 1; after a failed write it still tries to close the bag so
that what reached the disk stays readable.

Parameters (output, topics, topic_regex, exclude, ...): docs/nodes.md.
"""
import re
import time

import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter

from lpa_transfer.recording.bag import BagError, BagWriter
from lpa_transfer_nodes.conversions import message_class
from lpa_transfer_nodes.entry import init_with_stop_event
from lpa_transfer_nodes.params import declare, declare_array, describe_use_sim_time
from lpa_transfer_nodes.qos import qos_from_offered, qos_to_dict

DEFAULT_EXCLUDE = ["/rosout", "/parameter_events"]
#: s: the longest a received message waits in memory before it is in the file (a SIGKILL
#: loses at most about this much; compression works per chunk, so shorter costs ratio)
FLUSH_PERIOD = 0.25


class Recorder(Node):
    """Subscribes to every matching topic it discovers and writes what arrives to a bag."""

    def __init__(self):
        super().__init__("recorder")
        output = declare(self, "output", "", "path of the .mcap bag to write (required)")
        if not output:
            raise ValueError("parameter 'output' (path of the .mcap file) is required")
        self.topics = set(declare_array(self, "topics", Parameter.Type.STRING_ARRAY,
                                        "topics to record; unset: every topic discovered"))
        regex = declare(self, "topic_regex", "", "record only topics this regular expression "
                        "finds (re.search); empty: no filter")
        try:
            self.topic_regex = re.compile(regex) if regex else None
        except re.error as exc:
            raise ValueError(f"the parameter topic_regex must be a regular expression, got "
                             f"{regex!r}: {exc}") from None
        self.exclude = set(declare_array(self, "exclude", Parameter.Type.STRING_ARRAY,
                                         f"topics never recorded; unset: {DEFAULT_EXCLUDE}")
                           or DEFAULT_EXCLUDE)
        self.include_hidden = declare(self, "include_hidden_topics", False,
                                      "also record hidden topics (a name part starting with "
                                      "'_', e.g. an action's /_action/feedback), as rosbag2's "
                                      "--include-hidden-topics")
        self.qos_depth = declare(self, "qos_depth", 1000, "queue depth of each subscription",
                                 positive=True)
        period = declare(self, "discovery_period", 0.5,
                         "how often (s) the graph is scanned for new topics", positive=True,
                         finite=True)
        describe_use_sim_time(self)
        try:
            self.bag = BagWriter(output, flush_period_s=FLUSH_PERIOD)
        except OSError as exc:
            raise ValueError(f"cannot write the bag {output!r}: {exc.strerror or exc}") from None
        self.write_error = None   # the first failed write (OSError); the node then stops
        self.subscribed = {}  # topic -> type name
        self.skipped = set()  # topics whose type could not be recorded (warned once)
        self.discover()
        self.discovery_timer = self.create_timer(period, self.discover)
        self.flush_timer = self.create_timer(FLUSH_PERIOD / 2, self.flush)
        self.get_logger().info(f"recording to {output}")

    def wanted(self, topic):
        hidden = any(part.startswith("_") for part in topic.split("/"))
        return (topic not in self.exclude and topic not in self.skipped
                and (self.include_hidden or not hidden or topic in self.topics)
                and (not self.topics or topic in self.topics)
                and (self.topic_regex is None or self.topic_regex.search(topic)))

    def discover(self):
        """Subscribe to matching topics that have a publisher since the last scan. A topic
        seen only through its subscribers waits for a later scan, as in rosbag2: its QoS is
        not known yet, and a reliable guess would never match a best-effort publisher (the
        /<robot>/clock of a learner that started before its robot_sim)."""
        for topic, type_names in self.get_topic_names_and_types():
            if topic in self.subscribed or not self.wanted(topic):
                continue
            if len(type_names) != 1:
                self.get_logger().warning(f"skipping {topic}: several types {type_names}")
                continue
            offered = [info.qos_profile for info in self.get_publishers_info_by_topic(topic)]
            if offered:
                try:
                    self.subscribe(topic, type_names[0], offered)
                except (BagError, ImportError, AttributeError, ValueError) as exc:
                    # a type the bag cannot describe (e.g. an action's messages): that topic
                    # is left out, said once; the others are recorded
                    self.skipped.add(topic)
                    self.get_logger().warning(f"not recording {topic} [{type_names[0]}]: {exc}")

    def subscribe(self, topic, type_name, offered):
        self.bag.add_topic(topic, type_name, [qos_to_dict(qos) for qos in offered])
        self.create_subscription(
            message_class(type_name), topic,
            lambda data, info, topic=topic: self.on_message(topic, data, info),
            qos_from_offered(offered, self.qos_depth), raw=True)
        self.subscribed[topic] = type_name
        self.get_logger().info(f"subscribed to {topic} [{type_name}]")

    def on_message(self, topic, data, info):
        """Write one message: log time = received now, publish time = sent (message info)."""
        if self.write_error is not None:
            return
        received_ns = self.get_clock().now().nanoseconds
        try:
            self.bag.write(topic, data, received_ns, info.get("source_timestamp") or None)
        except OSError as exc:
            self.write_error = exc

    def flush(self):
        """Close the chunk in progress at least every FLUSH_PERIOD, messages arriving or not."""
        if self.write_error is None:
            try:
                self.bag.flush_if_due()
            except OSError as exc:
                self.write_error = exc

    def finish(self):
        """Close the bag and log what it holds; OSError if it cannot be written."""
        self.bag.close()
        counts = ", ".join(f"{topic}: {count}" for topic, count in sorted(self.bag.counts.items()))
        self.get_logger().info(f"closed {self.bag.path}; messages per topic: {counts or 'none'}")


def drain(executor, recorder, quiet_s=0.3, limit_s=3.0):
    """Spin until no message arrived for ``quiet_s`` (at most ``limit_s``)."""
    deadline = time.monotonic() + limit_s
    last_total, last_change = -1, time.monotonic()
    while time.monotonic() < deadline and time.monotonic() - last_change < quiet_s:
        executor.spin_once(timeout_sec=0.05)
        total = sum(recorder.bag.counts.values())
        if total != last_total:
            last_total, last_change = total, time.monotonic()


def main(args=None):
    stop = init_with_stop_event(args)
    logger = rclpy.logging.get_logger("recorder")
    try:
        recorder = Recorder()
    except Exception as exc:  # a missing or unwritable output: say what, no traceback
        logger.fatal(str(exc))
        rclpy.try_shutdown()
        raise SystemExit(1) from None
    executor = SingleThreadedExecutor()
    executor.add_node(recorder)
    failure = None
    try:
        while rclpy.ok() and not stop.is_set() and recorder.write_error is None:
            executor.spin_once(timeout_sec=0.2)
        recorder.destroy_timer(recorder.discovery_timer)
        if recorder.write_error is None:
            drain(executor, recorder)
    finally:
        failure = recorder.write_error
        try:
            recorder.finish()
        except OSError as exc:
            failure = failure or exc
        if failure is not None:
            logger.fatal(f"cannot write the bag {recorder.bag.path}: "
                         f"{failure.strerror or failure}; stopped recording")
        executor.shutdown()
        recorder.destroy_node()
        rclpy.try_shutdown()
    if failure is not None:
        raise SystemExit(1)


if __name__ == "__main__":
    main()
