#!/usr/bin/env python3
"""Where do the chapter 5 learners' receptive fields lie after learning? (issue 26's cap)

Usage: ``python -m bench.id_fields [--setup S] [--seed N] [--trials 15] [--targets ...]
[--stars ...] [--every-trial]``, from the repository root.

For one set-up of ``bench/id_ablation.py`` and one babbling seed, each target robot and star
learns the star from scratch and from each initial data set of §5.5.3 (random, transfer-PA,
transfer-LPA, own+transfer) for ``--trials`` trials, as id_ablation runs them. After the last
trial (``--every-trial``: after each) it prints, per condition, the receptive fields of the
learner's LWPR (all outputs), how many of them were made by the initial data, and along the
star's desired states the mean number of fields per output activated above ``w_gen`` (the
ones that keep new fields from being made there) and of those the share made by the initial
data (the rows below that count; pruning moves the newest field into a pruned field's row,
so once fields are pruned the share is an upper bound); beside them the trial's error.
The idea measured: LWPR places a new field only where no field answers above ``w_gen``, so
fields made by initial data away from the task hold the task's samples with the shapes and
centres those data gave them, where learning from scratch places its fields on the task.
"""
import argparse

import numpy as np

from bench import id_ablation


def fields_on_task(learner, n_initial_fields, desired):
    """(fields, fields made by the initial data, mean fields per output above w_gen along
    ``desired``, share of those made by the initial data)."""
    lwpr = learner.regressor
    rfs = lwpr._rfs
    Xn = lwpr._check_queries(desired)
    active, initial = [], []
    for x in Xn[::10]:
        rows, _ = rfs.activations(x, lwpr.w_gen)
        active.append(len(rows) / lwpr.n_outputs_)
        initial.append(np.mean(rows < n_initial_fields) if len(rows) else 0.0)
    return rfs.n, n_initial_fields, float(np.mean(active)), float(np.mean(initial))


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--setup", default="zero_answer", choices=sorted(id_ablation.SETUPS))
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--trials", type=int, default=15)
    parser.add_argument("--targets", nargs="+", default=["pincher", "youbot"])
    parser.add_argument("--stars", nargs="+", default=["star1"])
    parser.add_argument("--every-trial", action="store_true",
                        help="print the fields after every trial, not only after the last")
    args = parser.parse_args(argv)
    print(f"set-up {args.setup}, seed {args.seed}, {args.trials} trials")
    print(f"{'target':<8} {'star':<6} {'condition':<14} {'trial':>5} {'fields':>6} "
          f"{'initial':>7} {'active/output':>13} {'of initial':>10} {'error (mm)':>10}")

    def show(target, star, condition, robot, learner, made, errors):
        desired = np.hstack(robot.trajectory[:3])          # the star's (q, q̇, q̈) rows
        n, n0, active, share = fields_on_task(learner, made, desired)
        print(f"{target:<8} {star:<6} {condition:<14} {len(errors):>5} {n:>6} {n0:>7} "
              f"{active:>13.2f} {share:>10.2f} {1e3 * errors[-1]:>10.2f}", flush=True)

    for target, star, condition, robot, learner, made, errors in id_ablation.runs(
            args.setup, args.seed, args.trials, targets=args.targets, stars=args.stars,
            watch=show if args.every_trial else None):
        if target in args.targets and not args.every_trial:   # (else a source's experience)
            show(target, star, condition, robot, learner, made, errors)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
