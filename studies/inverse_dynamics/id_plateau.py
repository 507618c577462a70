#!/usr/bin/env python3
"""Why do initialised youBot learners level off above learning from scratch? (thesis §5.5.3)

Usage: ``python -m studies.inverse_dynamics.id_plateau [--seed S] [--trials N] [--target youbot]
[--stars ...] [--variants default norm_out=1 ...] [--swap] [--start-noise SIGMA --starts K
[--reference DIR]]``, from the repository root; in process, library only, deterministic.

For each star the target learns from scratch, from its own babbling (random) and from PA-mapped
source experience plus its own babbling (own+transfer-PA), under LWPR variants (``name=value``,
JSON values; ``default`` changes nothing). Printed per condition: first and last trials' error
(mm) and, after the last trial, LWPR's ``norm_out_``, receptive fields per output, their median
width on the task, the share of the last trial's activation on fields the initial data made,
and how far the learner's own data lie from the desired states (normalised input units).

``--swap`` separates initial data from collected experience: for every pair of conditions a
fresh learner gets the first's initial data, then offline the second's experience, and runs
one trial without learning. ``--start-noise`` asks how much learning from scratch varies:
``--starts`` more scratch learners start from rest moved by N(0, SIGMA) rad per joint; with
``--reference`` (a run with a learning_curves.csv) the convergence table and time saved are
recomputed with all those scratch runs as learning from scratch.
"""
import argparse
import json
from pathlib import Path

import numpy as np
import yaml
from sklearn.neighbors import NearestNeighbors

from lpa_transfer.robots import PID
from lpa_transfer.inverse_dynamics import (CONFIG, FeedForwardLearner, StarRobot, babble,
                                           make_regressor)
from lpa_transfer.transfer import ProcrustesAnalysis


def parse_variant(text):
    """``default`` → {}; ``a=1,b=false`` → {"a": 1, "b": False} (values as JSON)."""
    if text == "default":
        return {}
    pairs = (item.split("=", 1) for item in text.split(","))
    return {key: json.loads(value) for key, value in pairs}


def learner(robot, overrides, samples=None):
    name, params = robot.regressor
    model = FeedForwardLearner(make_regressor(name, **dict(params, **overrides)),
                               PID.from_gains(robot.pid_gains))
    if samples is not None:
        model.initialise(samples)
    return model


def on_task(regressor, inputs, n_initial):
    """(median width of the most active RFs, share of activation on the first ``n_initial``
    RFs of each output) over ``inputs`` (module docstring)."""
    x = inputs / regressor.norm_in_
    widths, initial, total = [], 0.0, 0.0
    for fields, k0 in zip(regressor.receptive_fields_, n_initial):
        diff = x[:, None, :] - fields["c"][None]
        distance = np.einsum("nki,kij,nkj->nk", diff, fields["D"], diff)
        best = fields["D"][distance.argmin(axis=1)]
        widths.append(np.median(1 / np.sqrt(np.diagonal(best, axis1=1, axis2=2))))
        w = np.exp(-0.5 * distance)
        w[w <= regressor.cutoff] = 0.0
        initial, total = initial + w[:, :k0].sum(), total + w.sum()
    return float(np.median(widths)), initial / total


def off_desired(robot, inputs):
    """Median distance of ``inputs`` (N, 3n) to the star's nearest desired state (q_d, q̇_d,
    q̈_d), in units of the learner's input scale."""
    scale = robot.regressor[1]["norm_in"]
    desired = np.hstack(robot.trajectory[:3]) / scale
    distance = NearestNeighbors(n_neighbors=1).fit(desired).kneighbors(inputs / scale)[0]
    return float(np.median(distance))


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--config", type=Path, default=CONFIG)
    parser.add_argument("--trials", type=int, default=15)
    parser.add_argument("--target", default="youbot")
    parser.add_argument("--stars", nargs="+", default=["star1", "star2"])
    parser.add_argument("--variants", nargs="+", default=["default", "norm_out=1.0"])
    parser.add_argument("--conditions", nargs="+",
                        default=["uninitialised", "random", "own+transfer-PA"])
    parser.add_argument("--swap", action="store_true",
                        help="the table of initial data x collected experience (docstring)")
    parser.add_argument("--start-noise", type=float, default=0.0,
                        help="rad; > 0 adds the perturbed scratch runs (docstring)")
    parser.add_argument("--starts", type=int, default=4)
    parser.add_argument("--reference", type=Path,
                        help="a run's directory: its table with these scratch runs (docstring)")
    args = parser.parse_args(argv)
    config = yaml.safe_load(args.config.read_text())
    experiment = config["experiment"]["ros__parameters"]
    names = experiment["robots"]
    source = next(name for name in names if name != args.target)
    scratch_runs = {}
    for star in args.stars:
        robots = {name: StarRobot(config, name, star) for name in names}
        pairs = dict(zip(names, babble(config, [robots[name] for name in names], star,
                                       args.seed)))
        experience = robots[source].trials(robots[source].learner(),
                                           experiment["n_source_trials"])[1]
        transferred = ProcrustesAnalysis(latent_dim=experiment["latent_dim"]).fit(
            pairs[source], pairs[args.target]).transfer(experience)
        initial = {"uninitialised": None, "random": pairs[args.target],
                   "own+transfer-PA": np.vstack((transferred, pairs[args.target]))}
        n = robots[args.target].params.n_joints
        for text in args.variants:
            overrides = parse_variant(text)
            print(f"\n{source} -> {args.target}, {star}, seed {args.seed}, variant {text}")
            collected, errors_of = {}, {}
            for condition in args.conditions:
                model = learner(robots[args.target], overrides, initial[condition])
                n_initial = (model.regressor.n_receptive_fields_ if initial[condition]
                             is not None else np.zeros(n, dtype=int))
                errors, seen = robots[args.target].trials(model, args.trials)
                regressor = model.regressor
                last = seen[-len(seen) // args.trials:, :3 * n]
                collected[condition], errors_of[condition] = seen, list(errors)
                print(f"  {condition:16s} trial 1 {1e3 * errors[0]:6.2f}  trial "
                      f"{args.trials} {1e3 * errors[-1]:5.2f} mm; norm_out "
                      + " ".join(f"{v:.3g}" for v in regressor.norm_out_)
                      + f"; RFs/output {regressor.n_receptive_fields_.mean():.0f}; "
                      "task RF width {:.3f}, activation on initial RFs {:.0%}".format(
                          *on_task(regressor, last, n_initial))
                      + "; own data off the desired states {:.3f} (last trial {:.3f})".format(
                          off_desired(robots[args.target], seen[:, :3 * n]),
                          off_desired(robots[args.target], last)), flush=True)
            if args.swap:
                swap(robots[args.target], dict(overrides, norm_out=1.0), initial, collected)
            if args.start_noise > 0:
                scratch_runs[star] = perturbed_starts(robots[args.target], overrides, args)
                if "uninitialised" in collected:
                    scratch_runs[star].insert(0, errors_of["uninitialised"])
    if args.reference is not None and scratch_runs:
        print_reference_table(args, experiment, scratch_runs)
    return 0


def print_reference_table(args, experiment, scratch_runs):
    """The reference's convergence table for the target, learning from scratch replaced by
    ``scratch_runs`` (star -> curves; module docstring)."""
    from lpa_transfer.inverse_dynamics import convergence_table, read_run
    cells = read_run(args.reference)[1]
    curves = {key: list(by_seed.values()) for key, by_seed in cells.items()
              if key.startswith(f"{args.target}/") and key.split("/")[1] in scratch_runs}
    for star, runs in scratch_runs.items():
        curves[f"{args.target}/{star}/uninitialised"] = runs
    rows, savings = convergence_table(curves, [args.target], list(scratch_runs),
                                      experiment["convergence_tolerance"],
                                      experiment["babbling_seconds"])
    print(f"\n{args.reference}: {args.target} as target, learning from scratch = "
          + ", ".join(f"{star} {len(runs)} runs (final {1e3 * np.mean(runs, axis=0)[-1]:.2f} "
                      "mm)" for star, runs in scratch_runs.items()))
    for _, star, condition, k, n in rows:
        print(f"  {star} {condition:16s} converged in {k if k <= n else f'> {n}'} trials")
    print("  training time saved: " + ", ".join(f"{c} {100 * v:.1f}%"
                                                for c, v in savings[args.target].items()))


def perturbed_starts(robot, overrides, args):
    """Print the first and last trials of ``--starts`` scratch learners started from perturbed
    rest positions (module docstring); their tracking errors (m)."""
    home = np.asarray(robot.kinematics.home, dtype=np.float64)
    runs = []
    for k in range(args.starts):
        rng = np.random.default_rng([args.seed, k])
        start = home + rng.normal(0.0, args.start_noise, home.shape)
        errors = robot.trials(learner(robot, overrides), args.trials, start=start)[0]
        print(f"  uninitialised, start {k} (noise {args.start_noise:g} rad): trial 1 "
              f"{1e3 * errors[0]:6.2f}  trial {args.trials} {1e3 * errors[-1]:5.2f} mm; "
              "trials " + " ".join(f"{1e3 * e:.2f}" for e in errors), flush=True)
        runs.append(errors)
    return runs


def swap(robot, overrides, initial, collected):
    """Print the frozen one-trial errors of the ``--swap`` table (module docstring)."""
    for start in collected:
        for source in collected:
            model = learner(robot, overrides, initial[start])
            model.initialise(collected[source])
            model.learn = False
            error = robot.trials(model, 1)[0][0]
            print(f"  initialised {start:13s} + the {source} learner's experience: "
                  f"{1e3 * error:.2f} mm (one trial, frozen)", flush=True)


if __name__ == "__main__":
    raise SystemExit(main())
