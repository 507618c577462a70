#!/usr/bin/env python3
"""Join the results of chapter 6 runs that each ran a share of the seeds.

Usage: ``python scenarios/goal_babbling/merge_results.py OUT_DIR RUN_DIR...``

Each RUN_DIR holds the ``learning_curves.csv`` of one ``run.sh`` (e.g. two graphs on two ROS
domains with ``--override`` files naming seeds [0, 1] and [2, ..., 9]); the curves are read from
it (every evaluation, full precision). The scenario's settings come from the runs'
``results.json``: at least one RUN_DIR needs one, and those that have one must agree (robots,
boxes, times, methods, ...). Runs must not repeat a seed, and every run must hold the same
conditions. OUT_DIR receives what one run over all the seeds writes: results.json,
learning_curves.csv, the figures and report.txt.
"""
import sys
from pathlib import Path

import matplotlib
matplotlib.use("Agg")
from lpa_transfer.goal_babbling.report import merge, write_outputs  # noqa: E402


def main(argv):
    if len(argv) < 3:
        print(__doc__, file=sys.stderr)
        return 2
    curves, experiment = merge(argv[2:])
    print(write_outputs(curves, experiment, Path(argv[1])), end="")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
