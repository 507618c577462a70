#!/usr/bin/env python3
"""Join the results of chapter 5 runs that each ran a share of the seeds or of the conditions.

Usage: ``python scenarios/inverse_dynamics/merge_results.py OUT_DIR RUN_DIR...``

Each RUN_DIR holds the ``results.json`` of one ``run.sh`` (e.g. two graphs on two ROS
domains, ``--override`` files with seeds [0, 2, 4, ...] and [1, 3, 5, ...], or with other
``conditions``), or only the ``learning_curves.csv`` of one (a reference result). The runs
must share their settings (robots, stars, trials, convergence rule, start noise; a CSV holds
only the first three, and a CSV of other start noise differs in its scratch curves). A curve that more than one run holds (learning from scratch, which every run
repeats, or a seed run twice) must be the same in each, to a relative ``RTOL``: the
simulation and the learners are deterministic, so a larger difference means a run is not
reproducible, and the merge refuses it. (Not bit for bit: the same condition run after other
conditions on the same nodes, or right after learning from scratch, differed in the 16th
digit, measured on the smoke configuration; the first curve read is kept.) Learning from
scratch must moreover be the same for every seed without start noise, and differ between
seeds with it (:func:`check_start_noise`).
Every condition must hold every seed. OUT_DIR receives the same outputs as one run over all
the seeds and conditions: results.json, learning_curves.csv, the figures and report.txt
(traces from the first run with a results.json).
"""
import sys
from pathlib import Path

import matplotlib
matplotlib.use("Agg")
from lpa_transfer.inverse_dynamics.report import merge, write_outputs  # noqa: E402


def main(argv):
    if len(argv) < 3:
        print(__doc__, file=sys.stderr)
        return 2
    curves, traces, experiment = merge(argv[2:])
    print(write_outputs(curves, traces, experiment, Path(argv[1])), end="")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
