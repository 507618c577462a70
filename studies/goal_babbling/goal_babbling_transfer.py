"""Experiment 1 of thesis ch. 6 (§6.5.1, Table 6.1, Fig. 6-6/6-7) at full size: the target
2-link arm learns its inverse kinematics by goal babbling from scratch, or after guided
exploration for T_guided s and transfer of the source's experience with PA or LPA, with weight
1 (as the thesis) or through the negative-transfer guard (GuardedModel, §6.6). Prints, per
condition and T_guided, the reaching rate and mean error (mean over seeds) every 60 s.

    nice -n 15 python -m studies.goal_babbling.goal_babbling_transfer --seeds 2 --guided 60 240

Not run in CI: one 1000 s run takes ~5-20 s on one core, and the full grid (10 seeds, four
T_guided, five conditions) ~1.5 h.
"""
import argparse
import os
import sys
import time

for _variable in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_variable, "1")

import numpy as np  # noqa: E402

from lpa_transfer.goal_babbling import Experiment1, run_condition  # noqa: E402
from lpa_transfer.goal_babbling.experiment import CONDITIONS  # noqa: E402


def mean_curves(condition, seeds, config):
    runs = [run_condition(condition, seed, config) for seed in seeds]
    return (runs[0].times, np.mean([r.rate for r in runs], axis=0),
            np.mean([r.mean_error for r in runs], axis=0),
            np.mean([r.n_transferred for r in runs], axis=0))


def print_table(title, times, rows):
    print(f"\n{title}")
    print(f"{'condition':<16}" + "".join(f"{t:>8.0f}" for t in times))
    for name, values in rows:
        print(f"{name:<16}" + "".join(f"{v:>8.3f}" for v in values))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=3, help="runs per condition (seeds 0..n-1)")
    parser.add_argument("--guided", type=float, nargs="+", default=[60, 120, 180, 240],
                        help="T_guided values (s)")
    parser.add_argument("--seconds", type=float, default=1000.0,
                        help="target's total time and source's babbling time (s)")
    parser.add_argument("--conditions", nargs="+", default=list(CONDITIONS[1:]),
                        choices=CONDITIONS[1:])
    args = parser.parse_args()
    seeds = range(args.seeds)
    start = time.perf_counter()
    base = Experiment1(source_seconds=args.seconds, total_seconds=args.seconds)
    times, scratch_rate, scratch_error, _ = mean_curves("scratch", seeds, base)
    for guided in args.guided:
        config = Experiment1(source_seconds=args.seconds, total_seconds=args.seconds,
                             guided_seconds=guided)
        rates, errors, kept = [("scratch", scratch_rate)], [("scratch", 1000 * scratch_error)], []
        for condition in args.conditions:
            _, rate, error, n_transferred = mean_curves(condition, seeds, config)
            rates.append((condition, rate))
            errors.append((condition, 1000 * error))
            kept.append((condition, n_transferred / 1000))
        label = f"T_guided = {guided:.0f} s, {args.seeds} seeds"
        print_table(f"reaching rate (0.01 m), {label}", times, rates)
        print_table(f"mean reaching error (mm), {label}", times, errors)
        print_table(f"active transferred samples (thousands), {label}", times, kept)
        sys.stdout.flush()
    print(f"\n{time.perf_counter() - start:.0f} s")


if __name__ == "__main__":
    main()
