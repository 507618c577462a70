#!/usr/bin/env python3
"""Sweep time on one node against two (lpa_transfer/sweeps.py on Dask).

Runs the same small chapter 5 sweep (smoke size, learning from scratch with start noise,
``--seeds`` seeds, one task per seed's whole graph) on clusters of network-namespace hosts
made by scenarios/multi_host/sweep_cluster.sh: one node with one task slot pinned to CPU 0,
then two nodes with one slot each, pinned to CPU 0 and CPU 1 (each "machine" a core of its
own). With ``--local`` it also times the seeds one after the other in one graph (run.sh) and
the default local sweep (``--workers`` = the cores, unpinned), which is what ``make ch5`` does.
Prints each wall time (the sweep's own, cluster start-up excluded, and the whole script's)
and the ratio two nodes / one node, and checks that every variant merged to the same
results.json. Needs root (network namespaces); takes a few minutes.

Usage, from the repository root after ``source tools/env.sh``::

    python -m bench.bench_sweep [--seeds 4] [--local] [--keep DIR]
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCENARIO = ROOT / "scenarios" / "inverse_dynamics"
SCRATCH = ("experiment:\n  ros__parameters:\n    conditions: [uninitialised]\n"
           "    start_noise: 0.001\n")


def timed(command, log, env=None):
    start = time.monotonic()
    with open(log, "w") as out:
        code = subprocess.run(command, stdout=out, stderr=subprocess.STDOUT, cwd=ROOT,
                              env=env).returncode
    if code == 77:
        sys.exit(f"skipped: {Path(log).read_text().strip()}")
    if code != 0:
        sys.exit(f"failed ({code}): {' '.join(map(str, command))}; see {log}")
    return time.monotonic() - start


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seeds", type=int, default=4)
    parser.add_argument("--local", action="store_true",
                        help="also the sequential run and the default local sweep")
    parser.add_argument("--keep", type=Path, help="work directory (default: a temporary one)")
    args = parser.parse_args(argv)
    work = args.keep or Path(tempfile.mkdtemp(prefix="bench_sweep_"))
    work.mkdir(parents=True, exist_ok=True)
    scratch = work / "scratch.yaml"
    scratch.write_text(SCRATCH)
    seeds = [str(s) for s in range(args.seeds)]
    sweep = ["graph", "ch5", "--override", str(SCENARIO / "smoke.yaml"), "--override",
             str(scratch), "--seeds", *seeds]
    cluster = ["bash", str(ROOT / "scenarios" / "multi_host" / "sweep_cluster.sh"), "--pin"]
    rows, merged = [], {}
    for name, nodes in (("one node, 1 slot on CPU 0", 1), ("two nodes, 1 slot each", 2)):
        out = work / f"nodes{nodes}"
        whole = timed(cluster + ["--nodes", str(nodes), "--logs", str(work / f"logs{nodes}"),
                                 *sweep, "--out", str(out)], work / f"nodes{nodes}.log")
        own = json.loads((out / "sweep.json").read_text())["wall_seconds"]
        rows.append((name, own, whole))
        merged[name] = (out / "results.json").read_bytes()
    if args.local:
        both = work / "seeds.yaml"
        both.write_text(f"experiment:\n  ros__parameters:\n    seeds: [{', '.join(seeds)}]\n")
        env = dict(os.environ, ROS_DOMAIN_ID="150", ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST")
        whole = timed(["bash", str(SCENARIO / "run.sh"), "--override",
                       str(SCENARIO / "smoke.yaml"), "--override", str(scratch), "--override",
                       str(both), "--out", str(work / "sequential")], work / "sequential.log",
                      env)
        rows.append(("one graph, seeds one after the other", whole, whole))
        merged["sequential"] = (work / "sequential" / "results.json").read_bytes()
        out = work / "local"
        whole = timed([sys.executable, "-m", "lpa_transfer.sweeps", *sweep, "--out", str(out)],
                      work / "local.log")
        own = json.loads((out / "sweep.json").read_text())["wall_seconds"]
        rows.append((f"local sweep, {len(os.sched_getaffinity(0))} slots", own, whole))
        merged["local"] = (out / "results.json").read_bytes()
    print(f"chapter 5 smoke sweep, learning from scratch, {args.seeds} seeds "
          f"({os.cpu_count()} CPUs; load average at the end "
          f"{os.getloadavg()[0]:.1f})")
    for name, own, whole in rows:
        print(f"  {name:40s} sweep {own:6.1f} s   whole script {whole:6.1f} s")
    print(f"  two nodes / one node: {rows[1][1] / rows[0][1]:.2f} (sweep), "
          f"{rows[1][2] / rows[0][2]:.2f} (whole script)")
    same = len(set(merged.values())) == 1
    print(f"  every variant's results.json byte-identical: {same}")
    print(f"  work directory: {work}")
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
