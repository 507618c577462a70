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
import csv
import json
import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from run_experiment import SETTINGS, write_outputs  # noqa: E402

RTOL = 1e-6


def read_run(run_dir):
    """(settings, {key: {seed: curve}}, traces or None) of one run directory."""
    run_dir = Path(run_dir)
    if (run_dir / "results.json").exists():
        result = json.loads((run_dir / "results.json").read_text())
        cells = {key: dict(zip(result["seeds"], runs))
                 for key, runs in result["curves_m"].items()}
        settings = {"start_noise": 0.0, **result["settings"]}   # older runs: no start noise
        return settings, cells, result["traces"]
    path = run_dir / "learning_curves.csv"
    if not path.exists():
        raise ValueError(f"{run_dir} holds neither results.json nor learning_curves.csv")
    cells, robots, stars = {}, {}, {}
    with open(path, newline="") as handle:
        for row in csv.DictReader(handle):
            robots[row["target"]] = stars[row["star"]] = None   # ordered sets
            key = f"{row['target']}/{row['star']}/{row['condition']}"
            curve = cells.setdefault(key, {}).setdefault(int(row["seed"]), [])
            if int(row["trial"]) != len(curve) + 1:
                raise ValueError(f"{path}: {key} seed {row['seed']} trial {row['trial']} "
                                 f"out of order")
            curve.append(float(row["tracking_error_m"]))
    lengths = {len(curve) for seeds in cells.values() for curve in seeds.values()}
    if len(lengths) != 1:
        raise ValueError(f"{path}: curves of different lengths {sorted(lengths)}")
    return ({"robots": list(robots), "stars": list(stars), "n_trials": lengths.pop()},
            cells, None)


def merge(run_dirs):
    """(curves, traces, experiment-like settings) of the runs in ``run_dirs`` together."""
    runs = [(run_dir, *read_run(run_dir)) for run_dir in run_dirs]
    full = [run for run in runs if set(SETTINGS) <= set(run[1])]
    if not full:
        raise ValueError("at least one run must have a results.json (settings, traces)")
    settings, traces = full[0][1], full[0][3]
    cells, seeds = {}, {}
    for run_dir, run_settings, run_cells, _ in runs:
        if any(run_settings.get(key) != settings[key] for key in run_settings):
            raise ValueError(f"{run_dir} ran other settings: {run_settings} against {settings}")
        for key, by_seed in run_cells.items():
            for seed, curve in by_seed.items():
                seeds[seed] = None
                known = np.asarray(cells.setdefault(key, {}).setdefault(seed, curve))
                if known.shape != np.shape(curve) or not np.allclose(curve, known, rtol=RTOL,
                                                                      atol=0):
                    raise ValueError(f"{key} seed {seed} differs between runs ({run_dir}) by "
                                     f"more than a relative {RTOL:g}: {known.tolist()} against "
                                     f"{list(curve)}; the runs are not reproducible")
    seeds = list(seeds)
    for key, by_seed in cells.items():
        if set(by_seed) != set(seeds):
            raise ValueError(f"{key} lacks seed(s) {sorted(set(seeds) - set(by_seed))}")
        if key.endswith("/uninitialised"):
            check_start_noise(key, by_seed, settings["start_noise"])
    curves = {key: [by_seed[seed] for seed in seeds] for key, by_seed in cells.items()}
    return (curves, {tuple(key.split("/")): value for key, value in traces.items()},
            SimpleNamespace(done_seeds=seeds, **settings))


def check_start_noise(key, by_seed, start_noise):
    """Learning from scratch is the same for every seed without start noise and differs
    between any two seeds with it. A share run with other start noise (a CSV does not say)
    breaks that, and so does, without start noise, a share whose last digits differ (the
    shares of the 10-seed reference gave the youBot's final Star 1 error from scratch as
    2.31123, 2.31217 and 2.31280 mm, because the acceleration then depended on how long the
    simulator's clock had run; another host's floating point can do the same); either is
    refused."""
    seeds = sorted(by_seed)
    for i, a in enumerate(seeds):
        for b in seeds[i + 1:]:
            same = np.allclose(by_seed[a], by_seed[b], rtol=RTOL, atol=0)
            if same != (start_noise == 0):
                cause = ("a share ran with other start noise" if same else "a share ran "
                         "with other start noise, other code or on a host whose floating "
                         "point differs; join such shares only with start_noise > 0")
                raise ValueError(f"{key}: seeds {a} and {b} learn from scratch "
                                 f"{'alike' if same else 'differently'}, which runs with "
                                 f"start_noise {start_noise:g} cannot ({cause})")


def main(argv):
    if len(argv) < 3:
        print(__doc__, file=sys.stderr)
        return 2
    curves, traces, experiment = merge(argv[2:])
    print(write_outputs(curves, traces, experiment, Path(argv[1])), end="")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
