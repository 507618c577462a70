#!/usr/bin/env python3
"""Seed by seed: how close the transferred data land to the target's own data of the star,
beside the time the seed's transfer saved (what caps the saving, and by how much).

For each seed, the babbling session and the mappings of ``inverse_dynamics.in_process``'s set-up
(``--setup``, default ``zero_answer``, config.yaml's choice) are rebuilt; the source's
experience of each star from scratch (the same for every seed: learning from scratch starts at
rest at the star's centre) is mapped by PA and LPA, and the mapped samples are compared with
the target's own experience of the star: the median distance of their (q, q̇, q̈) to the
nearest own sample, in units of the learner's input scale
(``id_transfer_headroom.against_own``), and, against the own sample of the same trial and
period (both robots track their star in the same phase, so these are the task's true
correspondences), the RMS error of q, q̇, q̈ and τ over the own data's spread (moving
joints). The seed's saving is read from a chapter 5 run directory's results.json (``--run``;
default the final set-up's 10 seeds in process), each seed's curves alone
(``analysis.per_seed_savings``); Spearman's rank correlation joins the two over the seeds.

Usage (repository root, after ``source tools/env.sh``)::

    python -m studies.inverse_dynamics.id_seed_accuracy [--seeds 0 1 ...] [--trials 20]
        [--run RUN_DIR]
"""
import argparse
import json
from pathlib import Path

import numpy as np
from scipy.stats import spearmanr

from lpa_transfer.inverse_dynamics import (BABBLING_SECONDS, SETUPS, interpolated,
                                           per_seed_savings, set_up)
from lpa_transfer.inverse_dynamics.in_process import TOLERANCE
from studies.inverse_dynamics.id_transfer_headroom import MOVING, against_own

RUN = Path("scenarios/inverse_dynamics/reference_results/twenty_trials_in_process")
METHODS = ("PA", "LPA")
FIGURES = ("distance", "q", "qd", "qdd", "tau")


def on_the_task(robot, own, mapped):
    """RMS error of the mapped samples against the own sample of the same trial and period,
    over the own data's spread, for q, q̇, q̈ and τ (the moving joints' columns together)."""
    n = robot.params.n_joints
    moving = own[:, :n].std(axis=0) > MOVING
    errors = []
    for group in range(4):
        columns = np.arange(group * n, (group + 1) * n)[moving]
        errors.append(float(np.sqrt(((mapped[:, columns] - own[:, columns]) ** 2).mean())
                            / own[:, columns].std()))
    return errors


def experiences(robots, names, stars, n_trials):
    """{(name, star): the robot's experience of the star from scratch, ``n_trials`` trials}."""
    return {(name, star): robots[star][name].trials(robots[star][name].learner(), n_trials)[1]
            for star in stars for name in names}


def seed_accuracy(setup, seed, n_trials, own=None):
    """{(target, star, method): the FIGURES} of one seed, and the experiences (``own``, from
    :func:`experiences`, to reuse across seeds: they do not depend on the seed)."""
    experiment, names, robots, _, models = set_up(setup, seed)
    stars = experiment["stars"]
    if own is None:
        own = experiences(robots, names, stars, n_trials)
    interpolation = SETUPS[setup].get("interpolation", "none")
    dt = robots[stars[0]][names[0]].dt
    table = {}
    for star in stars:
        for target in names:
            source = next(name for name in names if name != target)
            mapped_from = interpolated(own[source, star], interpolation,
                                       len(robots[star][source].trajectory[0]), dt)
            for method in METHODS:
                mapped = models[target][method].transfer(mapped_from)
                robot = robots[star][target]
                table[target, star, method] = [against_own(robot, own[target, star], mapped)[0],
                                               *on_the_task(robot, own[target, star], mapped)]
    return table, own


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--setup", default="zero_answer", choices=sorted(SETUPS))
    parser.add_argument("--seeds", type=int, nargs="+", default=list(range(10)))
    parser.add_argument("--trials", type=int, default=20,
                        help="the source's trials from scratch transferred (as the run's)")
    parser.add_argument("--run", type=Path, default=RUN,
                        help="a chapter 5 run directory whose results.json gives the savings")
    args = parser.parse_args(argv)
    results = json.loads((args.run / "results.json").read_text())
    curves = {key: np.asarray(runs) for key, runs in results["curves_m"].items()}
    robots = sorted({key.split("/")[0] for key in curves})
    stars = sorted({key.split("/")[1] for key in curves})
    saved = per_seed_savings(curves, robots, stars, TOLERANCE, BABBLING_SECONDS)
    seeds_of_run = list(results["seeds"])
    own, rows = None, {}
    print(f"set-up {args.setup}, the source's {args.trials} trials mapped; savings from "
          f"{args.run} (scratch rule, each seed alone)")
    print(f"{'seed':>4} {'target':<8} {'star':<6} {'method':<4} "
          + " ".join(f"{name:>8}" for name in FIGURES) + "   saved (transfer-METHOD)")
    for seed in args.seeds:
        table, own = seed_accuracy(args.setup, seed, args.trials, own)
        for (target, star, method), figures in table.items():
            saving = saved[target][f"transfer-{method}"][0][seeds_of_run.index(seed)]
            rows.setdefault((target, method), []).append((*figures, saving))
            print(f"{seed:>4} {target:<8} {star:<6} {method:<4} "
                  + " ".join(f"{value:8.3f}" for value in figures)
                  + f"   {100 * saving:6.1f} %", flush=True)
    print("\nSpearman's rank correlation over the seeds of the saving with each figure "
          "(both stars' mean per seed):")
    for (target, method), values in sorted(rows.items()):
        values = np.asarray(values).reshape(len(args.seeds), -1, len(FIGURES) + 1).mean(axis=1)
        cells = []
        for column, name in enumerate(FIGURES):
            rho, p = spearmanr(values[:, column], values[:, -1])
            cells.append(f"{name} rho {rho:+.2f} (p {p:.3f})")
        print(f"  {target:<8} transfer-{method:<4} " + ", ".join(cells))


if __name__ == "__main__":
    main()
