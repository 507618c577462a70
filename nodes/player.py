"""player: replay an MCAP bag onto the ROS graph, our stand-in for ``ros2 bag play``.

Run: ``player --ros-args -p input:=run.mcap`` (or
``python -m lpa_transfer_nodes.player ...``); rename topics with the standard
``-r /from:=/to``.

Messages are published as the recorded CDR bytes, with the QoS the recorded publishers offered.
By default it waits (up to ``wait_timeout``) until every played topic has a subscriber, so a
listener started beside it does not miss the first messages while discovery completes; it warns
about requested topics the bag does not hold and about topics it published to nobody.
Exits 0 when done (after the reliable subscribers acknowledged everything) or on SIGINT/SIGTERM;
a missing, unreadable or non-MCAP input, or no requested topic in the bag, is one FATAL line and
exit 1.

Parameters (input, rate, topics, loop, ...): docs/nodes.md.
"""
import os
import time

from rclpy.duration import Duration
from rclpy.node import Node
import yaml

from lpa_transfer.recording.bag import read_messages, summary
from lpa_transfer_nodes._ros_util import (array_parameter, message_class, qos_from_offered,
                                          run_job)


def bag_topics(path):
    """The bag's topics (``summary``), or ValueError saying why ``path`` cannot be played."""
    if not os.path.isfile(path):
        raise ValueError(f"input {path!r}: no such file")
    try:
        return summary(path)
    except Exception as exc:  # BagError, OSError, mcap's McapError (InvalidMagic, ...)
        raise ValueError(f"input {path!r} is not a readable MCAP bag: "
                         f"{type(exc).__name__}: {exc}") from None


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
        self.min_subscribers = self.declare_parameter("wait_for_subscribers", 1).value
        self.wait_timeout = self.declare_parameter("wait_timeout", 10.0).value
        depth = self.declare_parameter("qos_depth", 1000).value
        wanted = array_parameter(self, "topics")
        topics = bag_topics(self.input)
        absent = [topic for topic in wanted if topic not in topics]
        if wanted and len(absent) == len(set(wanted)):
            raise ValueError(f"none of the requested topics {wanted} is in {self.input} "
                             f"(it holds {sorted(topics)})")
        if absent:
            self.get_logger().warning(f"not in {self.input}, so not played: {absent}")
        self.topic_info = {topic: info for topic, info in topics.items()
                           if not wanted or topic in wanted}
        self.publishers_by_topic = {
            topic: self.create_publisher(
                message_class(info.type_name), topic,
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
        """Publish the bag once; returns the number of messages published per topic."""
        published, start_wall, start_log = dict.fromkeys(self.topic_info, 0), time.monotonic(), None
        for message in read_messages(self.input, topics=list(self.topic_info)):
            if self.stop.is_set():
                break
            if self.rate > 0:
                start_log = message.log_time_ns if start_log is None else start_log
                due = start_wall + (message.log_time_ns - start_log) * 1e-9 / self.rate
                if not self.sleep(due - time.monotonic()):
                    break
            self.publishers_by_topic[message.topic].publish(message.data)
            published[message.topic] += 1
        return published

    def play(self):
        if not (self.sleep(self.start_delay)):
            return
        if self.min_subscribers > 0:
            self.wait_for_subscribers()
        while True:
            published = self.play_once()
            self.get_logger().info(f"published {sum(published.values())} messages from "
                                   f"{self.input}")
            unheard = [f"{publisher.topic_name} ({published[topic]})"
                       for topic, publisher in self.publishers_by_topic.items()
                       if published[topic] and publisher.get_subscription_count() == 0]
            if unheard:
                self.get_logger().warning(f"published to no subscriber on: {unheard}")
            if not self.loop or self.stop.is_set():
                break
        for publisher in self.publishers_by_topic.values():
            if not publisher.wait_for_all_acked(Duration(seconds=self.wait_timeout)):
                self.get_logger().warning(f"{publisher.topic_name}: not all messages acknowledged")


def main(args=None):
    run_job("player", Player, lambda player: player.play(), args)


if __name__ == "__main__":
    main()
