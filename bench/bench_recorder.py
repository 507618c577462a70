"""Joint-state throughput the recorder node sustains without loss.

For each rate, a fresh recorder process (its own ROS domain) records /joint_states (JointState,
7 joints) while this process publishes at that rate for ``--seconds``; the recorder is stopped
with SIGINT and the bag's count is compared with what was sent. Publishing is reliable with
depth 1000 on both sides, so loss means the recorder could not keep up within that queue.

    python -m bench.bench_recorder --rates 500 1000 2000 4000 --seconds 5
"""
import argparse
import signal
import tempfile
import time
from pathlib import Path

import rclpy
from rclpy.duration import Duration
from rclpy.qos import QoSProfile
from sensor_msgs.msg import JointState

from lpa_transfer.recording import bag

from bench.ros_harness import NodeProcess, ros_params, unique_domain_id, wait_until  # noqa: E402


def publish_at_rate(publisher, rate_hz, seconds):
    """Publish JointState at ``rate_hz`` for ``seconds`` (busy-wait pacing); returns count, duration."""
    message = JointState(name=[f"joint_{k}" for k in range(7)], position=[0.0] * 7,
                         velocity=[0.0] * 7, effort=[0.0] * 7)
    total, start = int(rate_hz * seconds), time.perf_counter()
    for i in range(total):
        while time.perf_counter() < start + i / rate_hz:
            pass
        message.position[0] = float(i)
        publisher.publish(message)
    return total, time.perf_counter() - start


def bench_rate(rate_hz, seconds, work_dir):
    domain_id = unique_domain_id()
    context = rclpy.Context()
    rclpy.init(context=context, domain_id=domain_id)
    node = rclpy.create_node("bench_publisher", context=context)
    publisher = node.create_publisher(JointState, "/joint_states", QoSProfile(depth=1000))
    output = Path(work_dir) / f"rate_{rate_hz}.mcap"
    recorder = NodeProcess("recorder", domain_id, Path(work_dir) / "log", ros_params(output=output))
    try:
        wait_until(publisher.get_subscription_count, what="the recorder's subscription")
        sent, duration = publish_at_rate(publisher, rate_hz, seconds)
        publisher.wait_for_all_acked(Duration(seconds=10))
    finally:
        recorder.stop(signal.SIGINT, timeout=30)
        node.destroy_node()
        rclpy.try_shutdown(context=context)
    recorded = bag.summary(output)["/joint_states"].message_count
    return sent, recorded, sent / duration


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rates", type=int, nargs="+", default=[500, 1000, 2000, 4000])
    parser.add_argument("--seconds", type=float, default=5.0)
    args = parser.parse_args()
    print(f"{'target Hz':>9} {'achieved Hz':>11} {'sent':>6} {'recorded':>8} {'loss %':>7}")
    with tempfile.TemporaryDirectory() as work_dir:
        for rate_hz in args.rates:
            sent, recorded, achieved = bench_rate(rate_hz, args.seconds, work_dir)
            print(f"{rate_hz:>9} {achieved:>11.0f} {sent:>6} {recorded:>8} "
                  f"{100.0 * (sent - recorded) / sent:>7.2f}", flush=True)


if __name__ == "__main__":
    main()
