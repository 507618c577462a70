"""Discovery time and round trip of a running lpa_mapping service, as a user's node sees them
(issue 30: on one host and across network hosts).

Run by ``bench/mapping_round_trip.sh`` (one host) or ``scenarios/multi_host/run.sh --scenario
mapping_round_trip`` (the service on the mapping host, this client on the learners' host).
Measured: the time from this node's creation until the service's ``transfer`` is discovered;
then, on an LPA fitted through the service on 1000 seeded synthetic 4-D pairs (a rotation
plus a bend), the median and 90th percentile of ``--calls`` TransferPoints round trips of 1,
100 and 10 000 points (MappingClient: request built, call, answer read into NumPy).

Usage: ``python -m bench.mapping_round_trip [--calls 30]`` with lpa_mapping running.
"""
import argparse
import time

import numpy as np
import rclpy

from bench.bench_mapping_service import median_ms
from lpa_transfer_nodes.mapping_client import MappingClient

MODEL_ID = "round_trip"


def synthetic_pairs(n=1000, seed=0):
    """Seeded 4-D source points and their bent, rotated images (a 2-link-like mapping)."""
    rng = np.random.default_rng(seed)
    source = rng.uniform(-1.0, 1.0, (n, 4))
    angle = 0.4
    rotation = np.eye(4)
    rotation[:2, :2] = [[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]]
    target = source @ rotation.T
    target[:, 2] += 0.3 * np.sin(2 * source[:, 0])
    return source, target


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=30)
    parser.add_argument("--timeout", type=float, default=60.0)
    args = parser.parse_args()
    rclpy.init()
    try:
        node = rclpy.create_node("mapping_round_trip")
        start = time.perf_counter()
        mapping = MappingClient(node, timeout=args.timeout)
        if not mapping.client("transfer").wait_for_service(timeout_sec=args.timeout):
            raise SystemExit(f"/lpa_mapping/transfer not found within {args.timeout} s")
        print(f"discovery: /lpa_mapping/transfer found {time.perf_counter() - start:.3f} s "
              f"after the client node's creation", flush=True)
        source, target = synthetic_pairs()
        mapping.fit(MODEL_ID, source, target, method="lpa", n_min=30, random_state=0)
        rng = np.random.default_rng(1)
        for n_points in (1, 100, 10000):
            points = rng.uniform(-1.0, 1.0, (n_points, 4))
            mapping.transfer(MODEL_ID, points)                 # the first call warms up
            median, p90 = median_ms(lambda: mapping.transfer(MODEL_ID, points), args.calls)
            print(f"transfer of {n_points:>5} points: median {median:.2f} ms, 90th percentile "
                  f"{p90:.2f} ms ({args.calls} calls)", flush=True)
        node.destroy_node()
    finally:
        rclpy.try_shutdown()


if __name__ == "__main__":
    main()
