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

``clock`` > 0 publishes the playback time on ``/clock`` at that rate (Hz), like ``ros2 bag play
--clock``: the log time of the bag at the current playback position (it advances with wall
time times ``rate``), so nodes with ``use_sim_time:=true`` run on the recording's time.

Parameters (input, rate, topics, loop, ...): docs/nodes.md.
"""
import os
import threading
import time

from rclpy.duration import Duration
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rosgraph_msgs.msg import Clock
import yaml

from lpa_transfer.recording.bag import read_messages, summary
from lpa_transfer_nodes.conversions import message_class, sim_stamp
from lpa_transfer_nodes.entry import run_job
from lpa_transfer_nodes.params import STRINGS, declare_table, describe_use_sim_time
from lpa_transfer_nodes.qos import CLOCK_QOS, qos_from_offered


def bag_topics(path):
    """The bag's topics (``summary``), or ValueError saying why ``path`` cannot be played."""
    if not os.path.isfile(path):
        raise ValueError(f"input {path!r}: no such file")
    try:
        return summary(path)
    except Exception as exc:  # BagError, OSError, mcap's McapError (InvalidMagic, ...)
        raise ValueError(f"input {path!r} is not a readable MCAP bag: "
                         f"{type(exc).__name__}: {exc}") from None


INPUT = (("input", "", "path of the .mcap bag to play (required)"),)
PLAYBACK = (
    ("rate", 1.0, "playback speed: 1 as recorded, 2 twice as fast; 0 as fast as possible",
     dict(range=(0.0, None), finite=True)),
    ("loop", False, "play the bag again and again until stopped"),
    ("start_delay", 1.0, "seconds to wait before playing", dict(range=(0.0, None), finite=True)),
    ("wait_for_subscribers", 1, "subscribers each played topic waits for (up to wait_timeout) "
     "before playing; 0: do not wait", dict(range=(0, None))),
    ("wait_timeout", 10.0, "seconds to wait for subscribers, and for reliable subscribers to "
     "acknowledge at the end", dict(range=(0.0, None), finite=True)),
    ("clock", 0.0, "publish the playback time on /clock at this rate (Hz), like ros2 bag play "
     "--clock; 0: no /clock", dict(range=(0.0, None), finite=True)),
    ("qos_depth", 1000, "queue depth of each publisher", dict(positive=True)))
TOPICS = (("topics", STRINGS, "topics to play; unset: every topic of the bag"),)


class Player(Node):
    """One publisher per played topic; ``play()`` publishes the bag's messages in log time order."""

    def __init__(self, stop):
        super().__init__("player")
        self.stop = stop
        self.input = declare_table(self, INPUT)["input"]
        if not self.input:
            raise ValueError("parameter 'input' (path of the .mcap file) is required")
        p = declare_table(self, PLAYBACK)
        self.rate, self.loop, self.start_delay = p["rate"], p["loop"], p["start_delay"]
        self.min_subscribers, self.wait_timeout = p["wait_for_subscribers"], p["wait_timeout"]
        self.clock_rate, depth = p["clock"], p["qos_depth"]
        describe_use_sim_time(self)
        self.topic_info = self.played_topics(declare_table(self, TOPICS)["topics"])
        self.publishers_by_topic = {
            topic: self.create_publisher(
                message_class(info.type_name), topic,
                qos_from_offered(yaml.safe_load(info.offered_qos_profiles or "[]") or [], depth))
            for topic, info in self.topic_info.items()}
        if self.clock_rate > 0 and "/clock" in self.publishers_by_topic:
            self.get_logger().warning("the bag holds /clock and clock > 0: both are played on "
                                      "/clock; set topics to leave the recorded one out")
        self.clock_pub = (self.create_publisher(Clock, "/clock", CLOCK_QOS)
                          if self.clock_rate > 0 else None)
        self.playback = None   # (wall start, log-time start) of the pass being played
        self.finished = threading.Event()   # set when the last pass ends: the clock stops

    def played_topics(self, wanted):
        """The bag's topics to play (``wanted``; empty: all), with a warning for those it lacks
        and ValueError if it holds none of them."""
        topics = bag_topics(self.input)
        absent = [topic for topic in wanted if topic not in topics]
        if wanted and len(absent) == len(set(wanted)):
            raise ValueError(f"none of the requested topics {wanted} is in {self.input} "
                             f"(it holds {sorted(topics)})")
        if absent:
            self.get_logger().warning(f"not in {self.input}, so not played: {absent}")
        return {topic: info for topic, info in topics.items() if not wanted or topic in wanted}

    def publish_clock(self):
        """Publish the bag time at the playback position every 1/clock s until stopped."""
        while not self.stop.wait(1.0 / self.clock_rate) and not self.finished.is_set():
            if self.playback is not None:
                start_wall, start_log = self.playback
                now_ns = start_log + int((time.monotonic() - start_wall) * 1e9 * self.rate)
                self.clock_pub.publish(Clock(clock=sim_stamp(now_ns * 1e-9)))

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
            if start_log is None:
                start_log = message.log_time_ns
                self.playback = (start_wall, start_log)
            if self.rate > 0:
                due = start_wall + (message.log_time_ns - start_log) * 1e-9 / self.rate
                if not self.sleep(due - time.monotonic()):
                    break
            elif self.clock_pub is not None:     # as fast as possible: the clock jumps along
                self.playback = (time.monotonic(), message.log_time_ns)
            self.publishers_by_topic[message.topic].publish(message.data)
            published[message.topic] += 1
        return published

    def play(self):
        # the node answers its services (parameters) while it waits and plays
        self.spinner = SingleThreadedExecutor()
        self.spinner.add_node(self)
        spinning = threading.Thread(target=self.spin_until_finished, daemon=True)
        spinning.start()
        try:
            if not (self.sleep(self.start_delay)):
                return
            if self.min_subscribers > 0:
                self.wait_for_subscribers()
            if self.clock_pub is not None:
                threading.Thread(target=self.publish_clock, daemon=True).start()
            self.play_passes()
        finally:
            self.finished.set()
            spinning.join()

    def spin_until_finished(self):
        while not self.finished.is_set() and not self.stop.is_set():
            self.spinner.spin_once(timeout_sec=0.1)

    def play_passes(self):
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
        self.finished.set()          # the clock ends with the bag
        for publisher in self.publishers_by_topic.values():
            if not publisher.wait_for_all_acked(Duration(seconds=self.wait_timeout)):
                self.get_logger().warning(f"{publisher.topic_name}: not all messages acknowledged")


def main(args=None):
    run_job("player", Player, lambda player: player.play(), args)


if __name__ == "__main__":
    main()
