"""`make bench`: every speed figure of the project in one table, beside its reference and goal.

Runs the benchmarks one after another, each in its own process (as a user would run them), and
reads their figures from their output: LWPR (``bench_lwpr``), LPA transfer and fit
(``bench_lpa``), the mapping service round trip (``bench_mapping_service``) and the chapter 5
control period over the graph (``bench_control_period``). Ratios against a reference are
measured in the same run. The goals are issue "Speed"'s; the figures of the last run on the
development host are kept in bench/README.md. ``--only NAME ...`` runs some of them.

Usage (repository root, after ``source tools/env.sh``): ``python -m bench.table``.
"""
import argparse
import os
import re
import subprocess
import sys
import time


def _run(module, *args):
    start = time.perf_counter()
    result = subprocess.run([sys.executable, "-m", f"bench.{module}", *args],
                            capture_output=True, text=True)
    if result.returncode != 0:
        raise RuntimeError(f"bench.{module} failed:\n{result.stdout}\n{result.stderr}")
    return result.stdout, time.perf_counter() - start


def _find(pattern, text, what):
    match = re.search(pattern, text, re.S)
    if match is None:
        raise RuntimeError(f"could not read {what} from the output:\n{text}")
    return match


def lwpr():
    out, _ = _run("bench_lwpr")
    trials = _find(r"\[trials.*?predict\(x\) \+ partial_fit\(x, y\)\s+[\d.]+ µs\s+[\d.]+ µs\s+"
                   r"(\d+)/s\s+[\d.]+ µs\s+[\d.]+ µs\s+(\d+)/s", out, "the LWPR cycle rate")
    two = _find(r"\[2 inputs.*?compiled\s+median\s+([\d.]+) µs.*?reference\s+median\s+"
                r"([\d.]+) µs", out, "the 2-input update")
    return [("LWPR predict+update, 15-in/5-out after 16,800 samples", f"{trials[1]}/s",
             f"{trials[2]}/s", ">= 10,000/s", int(trials[1]) >= 10_000),
            ("LWPR update, 2 inputs (median)", f"{two[1]} µs", f"{two[2]} µs", "<= 50 µs",
             float(two[1]) <= 50)]


def lpa():
    out, _ = _run("bench_lpa")
    transfer = _find(r"transfer 16,800 x 20 -> 16: ([\d.]+) ms .*?reference ([\d.]+) ms: "
                     r"([\d.]+)x", out, "the LPA transfer")
    fit = _find(r"fit N = 5000: library (\S+ \S+), reference (\S+ \S+): ([\d.]+)x", out,
                "the LPA fit")
    return [("LPA transfer 16,800 x 20 -> 16", f"{transfer[1]} ms ({transfer[3]}x)",
             f"{transfer[2]} ms", "<= 12 ms, >= 5x",
             float(transfer[1]) <= 12 and float(transfer[3]) >= 5),
            ("LPA fit N = 5000 (2-link)", f"{fit[1]} ({fit[3]}x)", fit[2], ">= 30x",
             float(fit[3]) >= 30)]


def mapping_service():
    out, _ = _run("bench_mapping_service")
    end = _find(r"end to end \(build, call, read\)\s+median\s+([\d.]+) ms", out,
                "the round trip")
    return [("mapping service round trip, 16,800 x 20 (median)", f"{end[1]} ms", "-",
             "<= 30 ms", float(end[1]) <= 30)]


def control_period():
    out, _ = _run("bench_control_period", "--trials", "3")
    graph = _find(r"graph: .*?\s([\d.]+)\s+([\d.]+)\n", out, "the graph's control period")
    local = _find(r"in process: .*?\s([\d.]+)\s+([\d.]+)\n", out, "the in-process period")
    return [("chapter 5 graph, simulated s per wall s per robot", graph[2],
             f"{local[2]} (in process, no ROS)", ">= 10 (at least 5)", float(graph[2]) >= 10)]


BENCHES = {"lwpr": lwpr, "lpa": lpa, "mapping_service": mapping_service,
           "control_period": control_period}


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--only", nargs="+", choices=sorted(BENCHES), default=list(BENCHES))
    args = parser.parse_args()
    load_before = os.getloadavg()[0]
    rows = []
    for name in args.only:
        print(f"running bench.{name} ...", file=sys.stderr, flush=True)
        rows += BENCHES[name]()
    print(f"{os.cpu_count()} cores; load average {load_before:.2f} before, "
          f"{os.getloadavg()[0]:.2f} after")
    header = f"| {'figure':<52} | {'now':<18} | {'reference':<26} | {'goal':<18} | met |"
    print(header + "\n|" + "|".join("-" * len(c) for c in header.split("|")[1:-1]) + "|")
    for figure, now, reference, goal, met in rows:
        print(f"| {figure:<52} | {now:<18} | {reference:<26} | {goal:<18} | "
              f"{'yes' if met else 'no':<3} |")
    print("make test: its own duration is printed by pytest (goal <= 8 min on 2 cores)")


if __name__ == "__main__":
    main()
