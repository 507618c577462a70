#!/usr/bin/env python3
"""Thesis §4.5 in process: how accurately LPA maps the human's letter demonstrations onto the
PR2 and the Meka (Fig. 4-10) and how well DMPs encode them (Fig. 4-12), for growing training
sizes and several N_min, beside the robots' own IK (the "IK method"); and Table 4.3, the Meka
taught by the human directly or via the PR2, its skills refined or unrefined.

Usage: python scenarios/lfd/accuracy.py [--config FILE.yaml] [--override FILE.yaml]...
                                        [--out DIR]
  defaults: scenarios/lfd/config.yaml, runs/lfd_accuracy; smoke.yaml shrinks it for the tests.
Writes to DIR: sweep.csv (robot, seed, N_min, training size, mapping and encoding error in
mm), multi_robot.csv (seed, condition, errors), ik_method.csv, fig4_10_12_accuracy.png
(mean ± std over the seeds) and report.txt (the tables beside the thesis' numbers). The same
config gives the same numbers. Shares of the seeds (``--override`` files naming seeds) run
side by side; ``--merge RUN_DIR...`` (with the same config and the other overrides) joins
them.
"""
import argparse
import sys
import time
from pathlib import Path

import matplotlib
matplotlib.use("Agg")
import yaml  # noqa: E402

from lpa_transfer.lfd import (JointDMP, RememberedPairs, accuracy_report,  # noqa: E402
                              accuracy_sweep, ik_method_errors, load_setup, multi_robot_transfer,
                              plot_accuracy, read_csvs, write_csvs)
from lpa_transfer.lfd.experiment import demonstrations  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]


def read_config(paths):
    """The experiment's parameters, the "/**" section's and the "experiment" section's (as
    the node graph's ``experiment`` node sees them); later files override earlier ones."""
    params = {}
    for path in paths:
        sections = yaml.safe_load(Path(path).read_text()) or {}
        for key in ("/**", "experiment"):
            params.update((sections.get(key) or {}).get("ros__parameters", {}))
    return params


def run(params):
    """Demonstrations, then per robot the sweep and the IK method, then Table 4.3."""
    setup = load_setup(ROOT / params["frames"], ROOT)
    demos = demonstrations(setup.demonstrator, params["shapes"],
                           (params["task_box_low"], params["task_box_high"]),
                           seed=params["layout_seed"], n_demos=params["n_demos"],
                           n_samples=params["n_samples"])
    dmp = JointDMP(n_weights_per_dim=params["dmp_weights_per_joint"])
    sweeps, ik_method = {}, {}
    pairs = RememberedPairs()   # Table 4.3's human -> robot pairs are the sweep's
    for name, learner in setup.learners.items():
        started = time.perf_counter()
        sweeps[name] = accuracy_sweep(learner, setup.demonstrator, demos,
                                      params["training_sizes"], params["n_mins"],
                                      params["seeds"], c_min=params["c_min"], dmp=dmp,
                                      pairs=pairs)
        ik_method[name] = ik_method_errors(learner, demos, dmp)
        log(f"{name}: sweep {time.perf_counter() - started:.0f} s")
    teacher, learner = (setup.learners[params[k]] for k in ("teacher", "learner"))
    table = []
    for seed in params["seeds"]:
        started = time.perf_counter()
        table.append(multi_robot_transfer(setup.demonstrator, teacher, learner, demos,
                                          params["multi_robot_pairs"],
                                          params["multi_robot_n_min"], seed,
                                          c_min=params["c_min"], dmp=dmp, pairs=pairs))
        log(f"multi-robot seed {seed}: {time.perf_counter() - started:.0f} s")
    return demos, sweeps, ik_method, table


def log(text):
    print(text, file=sys.stderr, flush=True)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--config", default=ROOT / "scenarios" / "lfd" / "config.yaml")
    parser.add_argument("--override", action="append", default=[])
    parser.add_argument("--out", default=ROOT / "runs" / "lfd_accuracy")
    parser.add_argument("--merge", nargs="+", metavar="RUN_DIR",
                        help="join the CSVs of runs over shares of the seeds (same config and "
                             "overrides but the seeds) instead of running")
    args = parser.parse_args(argv)
    params = read_config([args.config, *args.override])
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    started = time.perf_counter()
    if args.merge:
        params["seeds"], sweeps, ik_method, table = read_csvs(args.merge, params)
    else:
        _, sweeps, ik_method, table = run(params)
    write_csvs(out, params, sweeps, ik_method, table)
    plot_accuracy(out / "fig4_10_12_accuracy.png", params, sweeps, ik_method)
    text = accuracy_report(params, sweeps, ik_method, table, time.perf_counter() - started)
    (out / "report.txt").write_text(text)
    print(text, end="")


if __name__ == "__main__":
    main()
