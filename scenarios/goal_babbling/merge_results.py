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
import csv
import json
import sys
from pathlib import Path
from types import SimpleNamespace

sys.path.insert(0, str(Path(__file__).resolve().parent))
from run_experiment import write_outputs  # noqa: E402

from lpa_transfer.robot_params import load_robot_params  # noqa: E402

PER_SHARE = ("seeds_done",)


def read_curves(run_dir):
    """({condition: [run per seed]}, seeds) from a run's learning_curves.csv."""
    curves, seeds = {}, []
    with open(Path(run_dir) / "learning_curves.csv", newline="") as handle:
        for row in csv.DictReader(handle):
            seed = int(row["seed"])
            seeds += [] if seed in seeds else [seed]
            runs = curves.setdefault(row["condition"], {})
            run = runs.setdefault(seed, dict(times=[], mean_error=[], rate=[], n_transferred=[]))
            run["times"].append(float(row["learning_time_s"]))
            run["mean_error"].append(float(row["mean_error_m"]))
            run["rate"].append(float(row["reaching_rate"]))
            run["n_transferred"].append(int(row["n_transferred_active"]))
    for name, runs in curves.items():
        if sorted(runs) != sorted(seeds):
            raise ValueError(f"{run_dir}: condition {name} has seeds {sorted(runs)}, the run "
                             f"has {sorted(seeds)}")
    return {name: [runs[seed] for seed in seeds] for name, runs in curves.items()}, seeds


def settings_of(run_dirs):
    """The shared settings (without the seeds) of the runs that wrote a results.json."""
    found = {}
    for run_dir in run_dirs:
        path = Path(run_dir) / "results.json"
        if path.exists():
            settings = json.loads(path.read_text())["settings"]
            found[run_dir] = {k: v for k, v in settings.items() if k not in PER_SHARE}
    if not found:
        raise ValueError(f"none of {list(run_dirs)} holds a results.json with the settings")
    first_dir, first = next(iter(found.items()))
    for run_dir, settings in found.items():
        if settings != first:
            differing = sorted(k for k in set(first) | set(settings)
                               if first.get(k) != settings.get(k))
            raise ValueError(f"{run_dir} ran other settings than {first_dir}: {differing}")
    return first


def merge(run_dirs):
    """(curves, experiment-like settings) of the runs in ``run_dirs`` together."""
    settings = settings_of(run_dirs)
    curves, seeds = {}, []
    for run_dir in run_dirs:
        run_curves, run_seeds = read_curves(run_dir)
        if curves and sorted(run_curves) != sorted(curves):
            raise ValueError(f"{run_dir} holds conditions {sorted(run_curves)}, not "
                             f"{sorted(curves)}")
        repeated = set(run_seeds) & set(seeds)
        if repeated:
            raise ValueError(f"seeds {sorted(repeated)} appear in more than one run")
        seeds += run_seeds
        for name, runs in run_curves.items():
            curves.setdefault(name, []).extend(runs)
    robots = {side: load_robot_params(path) for side, path in settings["robot_files"].items()}
    return curves, SimpleNamespace(seeds_done=seeds, robots=robots, **settings)


def main(argv):
    if len(argv) < 3:
        print(__doc__, file=sys.stderr)
        return 2
    curves, experiment = merge(argv[2:])
    print(write_outputs(curves, experiment, Path(argv[1])), end="")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
