"""Chapter 6 with a yielding transfer: the tables of its reference results.

Reads what ``studies.goal_babbling.nao_poppy_rates`` printed for experiment 2 (Nao -> Poppy,
one file or more, curves every 600 s) and the ``runs.csv`` of
``scenarios/goal_babbling/diagnose_experiment1.py`` for experiment 1 (2-link arms, physics
mode), and prints per condition the mean reaching-rate curve over the seeds, the final rate
against scratch's (paired Wilcoxon signed-rank test over the seeds) and when the mean curve
first reaches scratch's final mean rate and half of it.

    python -m studies.goal_babbling.yielding_summary --experiment2 FILE... \
        --experiment1 RUNS.csv...
"""
import argparse
import csv
import re
from collections import defaultdict
from pathlib import Path

import numpy as np
from scipy.stats import wilcoxon

#: The time of a finals.csv rate (experiment 1's total_seconds)
END = 1000.0


def read_experiment2(paths, interval=600.0):
    """{condition: {seed: rates}} from nao_poppy_rates' printed curves (scratch's first value
    is at ``interval`` s, as the others')."""
    curves, seed = defaultdict(dict), None
    for path in paths:
        for line in open(path):
            found = re.match(r".*seed (\d+)$", line.strip())
            if found:
                seed = int(found.group(1))
                continue
            parts = re.match(r"^  (\S.*?)\s{2,}([\d. ]+)$", line.rstrip())
            if parts and seed is not None:
                curves[parts.group(1)][seed] = [float(v) for v in parts.group(2).split()]
    n = max(len(v) for c in curves.values() for v in c.values())
    return curves, interval * np.arange(1, n + 1)


def read_experiment1(paths, final="grid0.05_thr10mm"):
    """{condition: {seed: rates}} and the times of each condition, from runs.csv files; the
    last rate of every curve is the one at the end (``final`` of the finals.csv beside it:
    the scratch curve's last evaluation is at the last multiple of the interval)."""
    rows = defaultdict(lambda: defaultdict(dict))
    for path in paths:
        for row in csv.DictReader(open(path)):
            rows[row["condition"]][int(row["seed"])][float(row["time_s"])] = float(row["rate"])
        for row in csv.DictReader(open(Path(path).with_name("finals.csv"))):
            rows[row["condition"]][int(row["seed"])][END] = float(row[final])
    curves, times = {}, {}
    for condition, seeds in rows.items():
        curves[condition] = {s: [v[t] for t in sorted(v)] for s, v in seeds.items()}
        times[condition] = np.array(sorted(next(iter(seeds.values()))))
    return curves, times


def first_time(times, curve, level):
    """First time the curve reaches ``level`` (None: never)."""
    reached = np.flatnonzero(np.asarray(curve) >= level - 1e-12)
    return float(times[reached[0]]) if len(reached) else None


def summary(curves, times_of, scratch="scratch"):
    """Rows: condition, seeds, final mean ± std, final against scratch's (mean difference,
    Wilcoxon p), time to half and to all of scratch's final mean rate."""
    base = curves[scratch]
    base_final = np.mean([v[-1] for v in base.values()])
    rows = []
    for condition, seeds in curves.items():
        times = times_of(condition)
        common = sorted(set(seeds) & set(base))
        finals = np.array([seeds[s][-1] for s in common])
        mean = np.mean([seeds[s] for s in common], axis=0)
        difference = finals - np.array([base[s][-1] for s in common])
        p = (wilcoxon(difference).pvalue if condition != scratch and np.any(difference)
             else float("nan"))
        rows.append((condition, len(common), finals.mean(), finals.std(ddof=1),
                     difference.mean(), p, first_time(times, mean, 0.5 * base_final),
                     first_time(times, mean, base_final), mean))
    return rows


def show(title, rows, times_of):
    print(f"\n{title}")
    print(f"{'condition':<24} {'seeds':>5} {'final':>13} {'- scratch':>10} {'p':>6} "
          f"{'50 % at':>8} {'100 % at':>9}  mean curve")
    for condition, n, final, std, diff, p, half, full, mean in rows:
        when = [f"{t:g}" if t is not None else "never" for t in (half, full)]
        print(f"{condition:<24} {n:>5} {final:>6.3f} ± {std:.3f} {diff:>+10.3f} {p:>6.3f} "
              f"{when[0]:>8} {when[1]:>9}  " + " ".join(f"{v:.2f}" for v in mean))
    for name in dict.fromkeys([rows[0][0], rows[-1][0]]):
        print(f"times of {name}'s curve: " + " ".join(f"{t:g}" for t in times_of(name)))


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--experiment2", nargs="*", default=[])
    parser.add_argument("--experiment1", nargs="*", default=[])
    args = parser.parse_args(argv)
    if args.experiment2:
        curves, times = read_experiment2(args.experiment2)
        show("Experiment 2 (Nao -> Poppy), reaching rate", summary(curves, lambda c: times),
             lambda c: times)
    if args.experiment1:
        curves, times = read_experiment1(args.experiment1)
        for guided in sorted({c.rsplit("/T", 1)[1] for c in curves if "/T" in c}, key=float):
            chosen = {c: v for c, v in curves.items()
                      if c == "scratch" or c.endswith(f"/T{guided}")}
            times_of = lambda c: times[c]   # noqa: E731
            show(f"Experiment 1, T_guided {guided} s, reaching rate (scratch from 60 s)",
                 summary(chosen, times_of), times_of)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
