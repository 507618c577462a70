"""player: replay an MCAP bag onto the ROS graph, our stand-in for ``ros2 bag play``.

Run: ``player --ros-args -p input:=run.mcap`` (or
``python -m lpa_transfer_nodes.player ...``).

Messages are published as the recorded CDR bytes, with the QoS the recorded publishers offered.
Exits 0 when done (after the reliable subscribers acknowledged everything) or on SIGINT/SIGTERM.

Parameters (input, rate, topics, remap, loop, ...): docs/nodes.md.
"""
import time

import rclpy
from rclpy.duration import Duration
from rclpy.node import Node
import yaml

from lpa_transfer.recording.bag import read_messages, summary
from lpa_transfer_nodes._ros_util import (init_with_stop_event, message_class, qos_from_offered,
                                          array_parameter)


def parse_remaps(entries):
    """``['/a:=/b', ...]`` -> ``{'/a': '/b'}``."""
    remaps = {}
    for entry in entries:
        source, separator, target = entry.partition(":=")
        if not separator or not source or not target:
            raise ValueError(f"remap entry {entry!r} is not 'from:=to'")
        remaps[source] = target
    return remaps


class Player(Node):
    """One publisher per played topic; ``play()`` publishes the bag's messages in log time order."""

    def __init__(self, stop):
        super().__init__("player")
        self.stop = stop
        self.input = self.declare_parameter("input", "").value
        if not self.input:
            raise ValueError("parameter 'input' (path of the .mcap file) is required")
        self.rate = self.declare_parameter("rate", 1.0).value
        self.loop = self.declare_parameter("loop", False).value
        self.start_delay = self.declare_parameter("start_delay", 1.0).value
        self.min_subscribers = self.declare_parameter("wait_for_subscribers", 0).value
        self.wait_timeout = self.declare_parameter("wait_timeout", 10.0).value
        depth = self.declare_parameter("qos_depth", 1000).value
        remaps = parse_remaps(array_parameter(self, "remap"))
        wanted = set(array_parameter(self, "topics"))
        self.topic_info = {topic: info for topic, info in summary(self.input).items()
                           if not wanted or topic in wanted}
        self.publishers_by_topic = {
            topic: self.create_publisher(
                message_class(info.type_name), remaps.get(topic, topic),
                qos_from_offered(yaml.safe_load(info.offered_qos_profiles or "[]") or [], depth))
            for topic, info in self.topic_info.items()}

    def sleep(self, seconds):
        """Sleep unless stopped; returns False if stopped."""
        return not self.stop.wait(max(0.0, seconds))

    def wait_for_subscribers(self):
        deadline = time.monotonic() + self.wait_timeout
        missing = list(self.publishers_by_topic.values())
        while missing and time.monotonic() < deadline and self.sleep(0.05):
            missing = [p for p in missing if p.get_subscription_count() < self.min_subscribers]
        if missing:
            self.get_logger().warning(
                f"playing although {[p.topic_name for p in missing]} have fewer than "
                f"{self.min_subscribers} subscribers")

    def play_once(self):
        """Publish the bag once; returns the number of messages published."""
        published, start_wall, start_log = 0, time.monotonic(), None
        for message in read_messages(self.input, topics=list(self.topic_info)):
            if self.stop.is_set():
                break
            if self.rate > 0:
                start_log = message.log_time_ns if start_log is None else start_log
                due = start_wall + (message.log_time_ns - start_log) * 1e-9 / self.rate
                if not self.sleep(due - time.monotonic()):
                    break
            self.publishers_by_topic[message.topic].publish(message.data)
            published += 1
        return published

    def play(self):
        if not (self.sleep(self.start_delay)):
            return
        if self.min_subscribers > 0:
            self.wait_for_subscribers()
        while True:
            published = self.play_once()
            self.get_logger().info(f"published {published} messages from {self.input}")
            if not self.loop or self.stop.is_set():
                break
        for publisher in self.publishers_by_topic.values():
            if not publisher.wait_for_all_acked(Duration(seconds=self.wait_timeout)):
                self.get_logger().warning(f"{publisher.topic_name}: not all messages acknowledged")


def main(args=None):
    stop = init_with_stop_event(args)
    player = Player(stop)
    try:
        player.play()
    finally:
        player.destroy_node()
        rclpy.try_shutdown()


if __name__ == "__main__":
    main()
