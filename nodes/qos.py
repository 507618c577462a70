"""The QoS profiles of the nodes' topics, and the QoS a recorder or player offers for a topic.

One place for them, so that publishers and subscribers of the same topic agree.
"""
from rclpy.qos import (DurabilityPolicy, HistoryPolicy, LivelinessPolicy, QoSProfile,
                       ReliabilityPolicy)

#: Correspondence topics: every sample must arrive (reliable, deep queue); the batch is
#: latched (transient local) so that a subscriber that joins late still gets the last one.
SAMPLE_QOS = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
BATCH_QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                       durability=DurabilityPolicy.TRANSIENT_LOCAL)
#: /clock (rosgraph_msgs/Clock) from robot_sim and the player: what rclpy's TimeSource
#: subscribes with (best effort, only the latest time matters).
CLOCK_QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT)
#: robot_description and /tf_static: latched (reliable, transient local, depth 1), as
#: robot_state_publisher and tf2's static broadcaster offer them.
LATCHED_QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                         durability=DurabilityPolicy.TRANSIENT_LOCAL)
#: task_markers: latched as above, but the last MARKERS_DEPTH arrays stay with the writer
#: until acknowledged, so a recorder that lags behind a few trials still records every array
#: (with depth 1, an array not yet acknowledged is dropped when the next one is published); a
#: late viewer replays them in order, each clearing the one before.
MARKERS_DEPTH = 10
MARKERS_QOS = QoSProfile(depth=MARKERS_DEPTH, reliability=ReliabilityPolicy.RELIABLE,
                         durability=DurabilityPolicy.TRANSIENT_LOCAL)
#: /tf: as tf2's TransformBroadcaster offers it (reliable, volatile, depth 100).
TF_QOS = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)


def qos_to_dict(qos):
    """A QoS profile as the lower-case dict ``lpa_transfer.recording.bag.qos_profiles_yaml`` writes."""
    return {"history": qos.history.name.lower(), "depth": qos.depth,
            "reliability": qos.reliability.name.lower(),
            "durability": qos.durability.name.lower(), "liveliness": qos.liveliness.name.lower()}


def qos_from_offered(offered, depth):
    """A keep-last QoS of ``depth`` compatible with every offered profile (dicts or QoSProfiles).

    As rosbag2 does: best effort if any publisher offers only that, transient-local only if
    every publisher offers it; with nothing offered, reliable and volatile.
    """
    profiles = [qos_to_dict(p) if isinstance(p, QoSProfile) else p for p in offered]
    reliable = all(p.get("reliability") == "reliable" for p in profiles)
    transient_local = bool(profiles) and all(
        p.get("durability") == "transient_local" for p in profiles)
    return QoSProfile(
        history=HistoryPolicy.KEEP_LAST, depth=depth,
        reliability=ReliabilityPolicy.RELIABLE if reliable else ReliabilityPolicy.BEST_EFFORT,
        durability=(DurabilityPolicy.TRANSIENT_LOCAL if transient_local
                    else DurabilityPolicy.VOLATILE),
        liveliness=LivelinessPolicy.AUTOMATIC)
