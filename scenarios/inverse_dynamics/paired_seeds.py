#!/usr/bin/env python3
"""Print the report's comparisons over the seeds for a run directory or a reference result
(its results.json or learning_curves.csv): each condition against 'random' seed by seed, and
each condition's final error (mean of its last 3 trials) against learning from scratch's.

Usage: ``python scenarios/inverse_dynamics/paired_seeds.py RUN_DIR [EARLY_TRIALS]``
(after ``source tools/env.sh``; EARLY_TRIALS defaults to 5).
"""
import sys
from types import SimpleNamespace

from lpa_transfer.inverse_dynamics import final_error_lines, paired_lines, read_run


def main(argv):
    if len(argv) not in (2, 3):
        print(__doc__, file=sys.stderr)
        return 2
    settings, cells, _ = read_run(argv[1])
    curves = {key: [by_seed[seed] for seed in sorted(by_seed)] for key, by_seed in cells.items()}
    early = int(argv[2]) if len(argv) == 3 else 5
    lines = paired_lines(curves, settings["robots"], settings["stars"], early)
    lines += [""] + final_error_lines(curves, SimpleNamespace(**settings))
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
