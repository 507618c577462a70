#!/usr/bin/env python3
"""What a better mapping could save on chapter 5 (which factor caps the saving, and by how
much): the final set-up's transfer with parts of the mapped data replaced by the truth.

For each seed the babbling session and the mappings of an ``inverse_dynamics.in_process``
set-up (``--setup``: ``zero_answer`` or ``zero_spline_mj``, config.yaml's final one) are
rebuilt, the source's star experience from scratch is mapped, and the target learns the star
(as transfer-PA does) from initial data with part of the mapping's output replaced by the truth:
``<M> states, true τ`` (the target's own dynamics at the mapped states: no torque error),
``own states, <M> τ`` (the target's own states of the same trial and period, the task's true
correspondences: no state error), ``own data`` (a mapping without error). <M> is PA
(``--methods``, also LPA). The savings are §5.5.3's (analysis.convergence_table, mean curves,
within 10 % of scratch's final error), beside the same seeds' scratch and random runs kept in
``--kept``, with the seed-by-seed saving and its Wilcoxon test against random.

Usage (repository root, after ``source tools/env.sh``)::

    python -m studies.inverse_dynamics.id_mapping_ceiling run --seed N [--setup S] [--trials 20]
        [--out DIR] [--parts]
    python -m studies.inverse_dynamics.id_mapping_ceiling report [--out DIR] [--kept DIR] [--parts]

``--parts`` runs, kept apart, which of the mapped state's parts keeps the saving down:
``<M> q, own q̇ q̈, true τ`` and ``<M> q q̇, own q̈, true τ``.
"""
import argparse
import json
import sys
from pathlib import Path

import numpy as np

from lpa_transfer.inverse_dynamics import (BABBLING_SECONDS, SETUPS, convergence_table, load,
                                           per_seed_savings, set_up)
from lpa_transfer.inverse_dynamics.in_process import TOLERANCE
from studies.inverse_dynamics.id_seed_accuracy import experiences
from studies.inverse_dynamics.id_transfer_headroom import MOVING

SETUP = "zero_answer"
KEPT = Path("scenarios/inverse_dynamics/reference_results/twenty_trials_in_process/seeds")
OUT = Path("runs/id_mapping_ceiling")
OWN = "own data"
#: the runs' directory under --out: the ceiling's conditions, or --parts'
NAMES = {False: "mapping_ceiling", True: "mapping_ceiling_parts"}


def true_torques(robot, rows):
    """``rows`` (q, q̇, q̈, τ per joint) with τ replaced by the robot's inverse dynamics at
    their (q, q̇, q̈)."""
    n = robot.params.n_joints
    out = np.array(rows, dtype=float)
    out[:, 3 * n:] = [robot.sim.inverse_dynamics(r[:n], r[n:2 * n], r[2 * n:3 * n]) for r in rows]
    return out


def torque_residual(robot, own):
    """RMS of (sampled τ - the inverse dynamics' τ at the sample's q, q̇, q̈) over the spread
    of the sampled τ (moving joints): how far the samples' own relation is from the model
    (q̈ is a backward difference over the control period, τ the period's command)."""
    n = robot.params.n_joints
    moving = own[:, :n].std(axis=0) > MOVING
    model = true_torques(robot, own)[:, 3 * n:][:, moving]
    sampled = own[:, 3 * n:][:, moving]
    return float(np.sqrt(((model - sampled) ** 2).mean()) / sampled.std())


#: The state parts of a sample (columns q, q̇, q̈ per joint, then τ).
PARTS = ("q", "q̇", "q̈")
#: name (with <M> for the method) -> (the state parts the mapping gives, the rest the own
#: data's; the torques: "true" at the composed state, or the mapping's)
CEILING = {"<M> states, true τ": (PARTS, "true"), "own states, <M> τ": ((), "mapped")}
#: ``--parts``: which mapped state part keeps the saving down
PARTS_CONDITIONS = {"<M> q, own q̇ q̈, true τ": (("q",), "true"),
                    "<M> q q̇, own q̈, true τ": (("q", "q̇"), "true")}


def composed(robot, own, mapped, parts, torques):
    """Samples with the state ``parts`` from ``mapped`` and the others from ``own`` (the
    same trial and period: the task's true correspondences), and the mapping's torques or
    the true ones at the composed state."""
    n = robot.params.n_joints
    rows = np.array(own, dtype=float)
    for k, part in enumerate(PARTS):
        if part in parts:
            rows[:, k * n:(k + 1) * n] = mapped[:, k * n:(k + 1) * n]
    if torques == "mapped":
        rows[:, 3 * n:] = mapped[:, 3 * n:]
        return rows
    return true_torques(robot, rows)


def run(seed, n_trials, methods, conditions=CEILING, setup=SETUP):
    """{"robot/star/condition": curve (mm per trial)} of the ceiling's ``conditions`` and the
    own data for one seed of ``setup``, and {"robot/star": the torque residual of the own
    data}."""
    experiment, names, robots, _, models = set_up(setup, seed)
    stars = experiment["stars"]
    own = experiences(robots, names, stars, n_trials)
    curves, residuals = {}, {}
    for star in stars:
        for target in names:
            source = next(name for name in names if name != target)
            robot = robots[star][target]
            residuals[f"{target}/{star}"] = torque_residual(robot, own[target, star])
            initial = {OWN: own[target, star]}
            for method in methods:
                mapped = models[target][method].transfer(own[source, star])
                for name, (parts, torques) in conditions.items():
                    initial[name.replace("<M>", method)] = composed(robot, own[target, star],
                                                                    mapped, parts, torques)
            for condition, samples in initial.items():
                errors = robot.trials(robot.learner(samples), n_trials)[0]
                curves[f"{target}/{star}/{condition}"] = [1e3 * e for e in errors]
    return curves, residuals


def in_place_of_transfer(kept, ours, robot, stars, condition):
    """Curves (m) in which ``condition``'s runs (from the kept runs or ours) take
    transfer-PA's place beside the kept learning from scratch and random initialisation."""
    curves = {}
    for star in stars:
        key = f"{robot}/{star}/{condition}"
        curves[f"{robot}/{star}/transfer-PA"] = np.asarray(kept.get(key, ours.get(key))) / 1e3
        for name in ("uninitialised", "random"):
            curves[f"{robot}/{star}/{name}"] = np.asarray(kept[f"{robot}/{star}/{name}"]) / 1e3
    return curves


def cells(curves, rows, robot, condition):
    """Per star of a report row: ``condition``'s mean first trial (mm) and its trials to
    convergence (``rows`` of analysis.convergence_table)."""
    return " | ".join(f"{1e3 * np.mean(curves[f'{robot}/{s}/{condition}'], axis=0)[0]:.2f}, {k}"
                      for _, s, c, k, _ in rows if c == condition)


def report(out, kept_dir, name=NAMES[False]):
    """The ceiling's savings beside the kept runs' scratch, random and transfer, as text."""
    ours, seeds = load(out, name)
    if not ours:
        raise SystemExit(f"error: no runs under {out / name}")
    first = json.loads(next(iter(sorted((out / name).glob("seed_*.json")))).read_text())
    setup = first.get("setup", SETUP)
    kept, kept_seeds = load(kept_dir, setup)
    if missing := sorted(set(seeds) - set(kept_seeds)):
        raise SystemExit(f"error: {kept_dir / setup} lacks the kept runs of seeds {missing}")
    kept = {k: [v[kept_seeds.index(s)] for s in seeds] for k, v in kept.items()}
    robots = sorted({k.split("/")[0] for k in ours}, reverse=True)
    stars = sorted({k.split("/")[1] for k in ours})
    conditions = ["random", "transfer-PA", "transfer-LPA",
                  *sorted({k.split("/")[2] for k in ours} - {OWN}), OWN]
    lines = [f"set-up {setup}, {len(seeds)} seed(s) {seeds}; time saved by the mean curves (within "
             f"{100 * TOLERANCE:.0f} % of scratch's final error, {BABBLING_SECONDS} s of "
             "babbling charged) and seed by seed: median [quartiles], seeds saving more than "
             "random (Wilcoxon p)", ""]
    for robot in robots:
        lines += [f"| {robot} | " + " | ".join(f"{s}: trial 1 (mm), converged" for s in stars)
                  + " | saved | seed by seed | more than random |", "|---" * (4 + len(stars))
                  + "|"]
        for condition in conditions:
            curves = in_place_of_transfer(kept, ours, robot, stars, condition)
            rows, saved = convergence_table(curves, [robot], stars, TOLERANCE, BABBLING_SECONDS)
            if condition == conditions[0]:     # learning from scratch, the same in every table
                lines.append(f"| uninitialised | {cells(curves, rows, robot, 'uninitialised')}"
                             " | - | - | - |")
            each, (more, _, n, p) = per_seed_savings(curves, [robot], stars, TOLERANCE,
                                                     BABBLING_SECONDS)[robot]["transfer-PA"]
            q1, q2, q3 = np.percentile(100 * each, [25, 50, 75])
            lines.append(f"| {condition} | {cells(curves, rows, robot, 'transfer-PA')}"
                         f" | {100 * saved[robot]['transfer-PA']:.1f} % | {q2:.1f} % [{q1:.1f}, "
                         f"{q3:.1f}] | " + ("-" if condition == "random" else
                                            f"{more} of {n} (p {p:.3f})") + " |")
        lines.append("")
    lines.append("The own data's sampled τ against the inverse dynamics at their q, q̇, q̈ (RMS "
                 "over the τ spread): " + ", ".join(
                     f"{k} {v:.3f}" for k, v in first["torque_residual"].items()))
    return "\n".join(lines)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    sub = parser.add_subparsers(dest="command", required=True)
    one = sub.add_parser("run")
    one.add_argument("--seed", type=int, required=True)
    one.add_argument("--setup", choices=sorted(SETUPS), default=SETUP)
    one.add_argument("--trials", type=int, default=20)
    one.add_argument("--methods", nargs="+", default=["PA"], choices=["PA", "LPA"])
    one.add_argument("--out", type=Path, default=OUT)
    one.add_argument("--parts", action="store_true",
                     help=f"run {', '.join(PARTS_CONDITIONS)} instead (kept apart)")
    many = sub.add_parser("report")
    many.add_argument("--out", type=Path, default=OUT)
    many.add_argument("--kept", type=Path, default=KEPT)
    many.add_argument("--parts", action="store_true", help="report the --parts runs")
    args = parser.parse_args(argv)
    if args.command == "report":
        print(report(args.out, args.kept, NAMES[args.parts]))
        return 0
    path = args.out / NAMES[args.parts] / f"seed_{args.seed}.json"
    for other in path.parent.glob("seed_*.json"):
        if (found := json.loads(other.read_text()).get("setup", SETUP)) != args.setup:
            raise SystemExit(f"error: {other} is of set-up {found}; give another --out for "
                             f"{args.setup}")
    curves, residuals = run(args.seed, args.trials, args.methods,
                            PARTS_CONDITIONS if args.parts else CEILING, args.setup)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps({"setup": args.setup, "seed": args.seed, "methods": args.methods,
                                "curves": curves, "torque_residual": residuals}))
    print(f"wrote {path}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
