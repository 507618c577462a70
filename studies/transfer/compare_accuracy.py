"""Paired accuracy of the library LPA against the plain ReferenceLPA over many seeds.

One run = one training set and one random_state, shared by both implementations, scored on the
same 10,000 test correspondences of the §3.6 pair (end-effector RMSE, mm). A single run varies
a lot with the partition, so "equal accuracy" is judged on the mean paired difference and its
standard error.

Usage: python -m studies.transfer.compare_accuracy [--sizes 200 1000] [--runs 20]
"""
import argparse

import numpy as np

from bench import datasets  # noqa: E402
from bench.bench_lpa import MODELS, TWO_LINK, rmse  # noqa: E402


def paired_errors(n, runs, test_source, test_target):
    """(runs, 2) end-effector RMSE (mm) of the library and the reference, run by run."""
    errors = np.empty((runs, len(MODELS)))
    for run in range(runs):
        source, target = datasets.two_link(n, seed=run)
        for column, model in enumerate(MODELS.values()):
            fitted = model(**{**TWO_LINK, "random_state": run}).fit(source, target)
            errors[run, column] = 1000 * rmse(fitted.transfer(test_source)[:, 2:],
                                              test_target[:, 2:])
    return errors


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[200, 1000])
    parser.add_argument("--runs", type=int, default=20)
    args = parser.parse_args()
    test_source, test_target = datasets.two_link(10_000, seed=10_000)
    print(f"{'N':>6} {'library mm':>11} {'reference mm':>13} {'lib - ref mm':>18}")
    for n in args.sizes:
        errors = paired_errors(n, args.runs, test_source, test_target)
        difference = errors[:, 0] - errors[:, 1]
        stderr = difference.std(ddof=1) / np.sqrt(args.runs)
        print(f"{n:>6} {errors[:, 0].mean():>11.3f} {errors[:, 1].mean():>13.3f} "
              f"{difference.mean():>+10.3f} ± {stderr:.3f}   ({args.runs} paired runs)")


if __name__ == "__main__":
    main()
