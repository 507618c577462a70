#!/usr/bin/env python3
"""Join the results of chapter 5 runs that each ran a share of the seeds.

Usage: ``python scenarios/inverse_dynamics/merge_results.py OUT_DIR RUN_DIR...``

Each RUN_DIR holds the ``results.json`` of one ``run.sh`` (e.g. two graphs on two ROS
domains, ``--override`` files with seeds [0, 2, 4, ...] and [1, 3, 5, ...]). The runs must
share their settings (robots, stars, trials, convergence rule) and not repeat a seed. OUT_DIR
receives the same outputs as one run over all the seeds: results.json, learning_curves.csv,
the figures and report.txt.
"""
import json
import sys
from pathlib import Path
from types import SimpleNamespace

sys.path.insert(0, str(Path(__file__).resolve().parent))
from run_experiment import SETTINGS, write_outputs  # noqa: E402


def merge(run_dirs):
    """(curves, traces, experiment-like settings) of the runs in ``run_dirs`` together."""
    results = [json.loads((Path(d) / "results.json").read_text()) for d in run_dirs]
    settings = results[0]["settings"]
    for run_dir, result in zip(run_dirs, results):
        if result.get("settings") != settings:
            raise ValueError(f"{run_dir} ran other settings: {result.get('settings')} "
                             f"against {settings}")
    seeds = [seed for result in results for seed in result["seeds"]]
    if len(set(seeds)) != len(seeds):
        raise ValueError(f"a seed appears in more than one run: {seeds}")
    curves = {key: [run for result in results for run in result["curves_m"][key]]
              for key in results[0]["curves_m"]}
    traces = {tuple(key.split("/")): value for key, value in results[0]["traces"].items()}
    return curves, traces, SimpleNamespace(done_seeds=seeds, **settings)


def main(argv):
    if len(argv) < 3:
        print(__doc__, file=sys.stderr)
        return 2
    curves, traces, experiment = merge(argv[2:])
    print(write_outputs(curves, traces, experiment, Path(argv[1])), end="")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
