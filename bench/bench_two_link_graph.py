#!/usr/bin/env python3
"""How much faster than real time the 2-link graph scenario runs (issue 3 benchmark).

Runs ``scenarios/two_link_graph/run.sh`` (default: its full config.yaml) in a temporary run
directory on its own ROS domain and prints simulated time against wall time for the
correspondence collection (two lock-stepped robot_sim nodes driven over DDS), the evaluation
(one robot babbling, transfers through the service) and the whole run including the nodes'
start-up and shutdown.

Usage: python -m bench.bench_two_link_graph [--config scenarios/two_link_graph/config.yaml]
"""
import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
from bench.ros_harness import unique_domain_id  # noqa: E402


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--config", type=Path,
                        default=ROOT / "scenarios" / "two_link_graph" / "config.yaml")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as work:
        out = Path(work) / "run"
        start = time.perf_counter()
        run = subprocess.run(["bash", str(ROOT / "scenarios" / "two_link_graph" / "run.sh"),
                              "--config", str(args.config.resolve()), "--out", str(out)],
                             env=dict(os.environ, ROS_DOMAIN_ID=str(unique_domain_id())),
                             capture_output=True, text=True)
        if run.returncode != 0:
            sys.exit(f"the scenario failed:\n{run.stderr}")
        total_wall = time.perf_counter() - start
        log = (out / "logs" / "correspondence_collector.log").read_text()
        collected = re.search(r"collected (\d+) pairs over ([\d.]+) s of simulated time in "
                              r"([\d.]+) s", log)
        evaluation = json.loads((out / "evaluation.json").read_text())
        with np.load(out / "correspondences.npz") as pairs:
            n_pairs = len(pairs["source"])
    pairs_sim, pairs_wall = float(collected[2]), float(collected[3])
    eval_sim = evaluation["experience_sim_s"] + evaluation["own_babbling_sim_s"]
    rows = [("collection (2 robots, lock-step over DDS)", pairs_sim, pairs_wall),
            ("evaluation (babbling, transfers, learner)", eval_sim, evaluation["wall_s"]),
            ("whole run incl. node start-up/shutdown", pairs_sim + eval_sim, total_wall)]
    print(f"2-link graph scenario, {args.config.name}: {n_pairs} correspondences, "
          f"{evaluation['n_experience']} experience samples")
    for name, simulated, wall in rows:
        print(f"  {name:<44} {simulated:8.1f} s simulated in {wall:6.1f} s wall: "
              f"{simulated / wall:6.1f}x real time")


if __name__ == "__main__":
    main()
