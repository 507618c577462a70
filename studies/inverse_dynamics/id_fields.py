#!/usr/bin/env python3
"""Where do the chapter 5 learners' receptive fields lie after learning?

Usage: ``python -m studies.inverse_dynamics.id_fields [--setup S] [--seed N] [--trials 15]
[--targets ...] [--stars ...] [--every-trial]``, from the repository root.

For one set-up of ``inverse_dynamics.in_process`` and one babbling seed, each target robot and star
learns the star from scratch and from each initial data set of §5.5.3 (random, transfer-PA,
transfer-LPA, own+transfer) for ``--trials`` trials, as in_process runs them. After the last
trial (``--every-trial``: after each) it prints, per condition, the columns of
:func:`fields_on_task`: where the learner's receptive fields lie along the star's desired
states, how much the fields made by the initial data weigh in the prediction there, the
torques predicted, and the metrics of the fields the own samples made; beside them the
trial's error. Pruning moves the newest field into a pruned field's row, so once fields are
pruned the shares of initial-data fields are upper bounds.
The idea measured: LWPR places a new field only where no field answers above ``w_gen``, so
fields made by initial data away from the task hold the task's samples with the shapes and
centres those data gave them, where learning from scratch places its fields on the task;
and fields activated below ``w_gen`` still answer where the task has no field of its own.
"""
import argparse

import numpy as np

from lpa_transfer.inverse_dynamics import in_process


#: The columns :func:`fields_on_task` fills, as the table heads them.
COLUMNS = ("fields", "initial", "active/output", "of initial", "weight init", "init alone",
           "tau max", "tau alone", "D own")


def fields_on_task(learner, n_initial_fields, desired):
    """The learner's fields along ``desired`` (every 10th state), by :data:`COLUMNS`: fields
    and those the initial data made; mean fields per output activated above ``w_gen`` and
    the share of those the initial data made; the share of the prediction's weight Σ w_k
    held by initial-data fields (the trustworthy fields above ``cutoff``, those the
    prediction averages over, however weakly activated); the share of states answered by
    initial-data fields alone (where learning from scratch would answer 0 or from its own
    fields); the largest |predicted torque| (N·m) over the states and over those answered
    alone (nan: none); the geometric mean of diag D over the fields the own samples made
    (a new field copies the metric of the most active trustworthy field above 0.1 w_gen,
    which may be one the initial data made; nan: none)."""
    lwpr = learner.regressor
    rfs = lwpr._rfs
    states = desired[::10]
    Xn = lwpr._check_queries(states)
    torque = np.abs(lwpr.predict(states)).max(axis=1)
    active, initial, weight, alone = [], [], [], []
    for x in Xn:
        rows, _ = rfs.activations(x, lwpr.w_gen)
        active.append(len(rows) / lwpr.n_outputs_)
        initial.append(np.mean(rows < n_initial_fields) if len(rows) else 0.0)
        rows, w = rfs.answering(x, lwpr.cutoff)
        weight.append(w[rows < n_initial_fields].sum() / w.sum() if w.sum() > 0 else 0.0)
        alone.append(len(rows) > 0 and bool(np.all(rows < n_initial_fields)))
    alone = np.array(alone)
    own = np.arange(n_initial_fields, rfs.n)
    width = (np.exp(np.mean(np.log(np.einsum("kii->ki", rfs.metrics(own)))))
             if len(own) else np.nan)
    return dict(zip(COLUMNS, (
        rfs.n, n_initial_fields, np.mean(active), np.mean(initial), np.mean(weight),
        np.mean(alone), torque.max(), torque[alone].max() if alone.any() else np.nan, width)))


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--setup", default="zero_answer", choices=sorted(in_process.SETUPS))
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--trials", type=int, default=15)
    parser.add_argument("--targets", nargs="+", default=["pincher", "youbot"])
    parser.add_argument("--stars", nargs="+", default=["star1"])
    parser.add_argument("--every-trial", action="store_true",
                        help="print the fields after every trial, not only after the last")
    args = parser.parse_args(argv)
    print(f"set-up {args.setup}, seed {args.seed}, {args.trials} trials")
    print(f"{'target':<8} {'star':<6} {'condition':<14} {'trial':>5} "
          + " ".join(f"{column:>13}" for column in COLUMNS) + f" {'error (mm)':>10}")

    def show(target, star, condition, robot, learner, made, errors):
        desired = np.hstack(robot.trajectory[:3])          # the star's (q, q̇, q̈) rows
        figures = fields_on_task(learner, made, desired)
        print(f"{target:<8} {star:<6} {condition:<14} {len(errors):>5} "
              + " ".join(f"{figures[column]:>13.0f}" if column in ("fields", "initial")
                         else f"{figures[column]:>13.3f}" for column in COLUMNS)
              + f" {1e3 * errors[-1]:>10.2f}", flush=True)

    for target, star, condition, robot, learner, made, errors in in_process.runs(
            args.setup, args.seed, args.trials, targets=args.targets, stars=args.stars,
            watch=show if args.every_trial else None):
        if target in args.targets and not args.every_trial:   # (else a source's experience)
            show(target, star, condition, robot, learner, made, errors)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
