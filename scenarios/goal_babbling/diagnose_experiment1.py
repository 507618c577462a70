#!/usr/bin/env python3
"""Experiment 1 (thesis §6.5.1): diagnose why plain LPA ends below scratch, in
process (lpa_transfer.goal_babbling.diagnosis; no ROS graph). Writes into OUTPUT_DIR
(default runs/diagnosis_exp1): diagnosis.json (everything), mapping.csv (per seed and
T_guided: correspondences, mapping error, shares within 1/5/10 mm), runs.csv (per seed,
condition, evaluation: rate, neighbour shares, split rates), finals.csv (final rates over
grids and thresholds), reference_check.csv (seed 0 in process against the graph's curves).

    python scenarios/goal_babbling/diagnose_experiment1.py [--seeds 0 1 2] [--out DIR]
        [--modes kinematic physics]

Modes: ``kinematic`` (analytic arms throughout) and ``physics`` (pybullet arms in position
mode for the source, guided exploration and the target's babbling, as robot_sim over the
graph; see lpa_transfer.goal_babbling.diagnosis). Every table has a ``mode`` column.
"""
import argparse
import csv
import json
import time
from pathlib import Path

from lpa_transfer.goal_babbling import diagnosis as dx

ROOT = Path(__file__).resolve().parents[2]
PHYSICS = (str(ROOT / "scenarios/robots/goal_babbling_source.toml"),
           str(ROOT / "scenarios/robots/goal_babbling_target.toml"))
GUIDED = (60.0, 120.0, 180.0, 240.0)
VARIANTS_LATE = ("from_guided", "synthesized", "oracle_exact", "oracle_filter_10",
                 "weighted_0.3")


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    parser.add_argument("--out", default=str(ROOT / "runs" / "diagnosis_exp1"))
    parser.add_argument("--variant-times", type=float, nargs="+", default=[180.0, 240.0])
    parser.add_argument("--guided", type=float, nargs="*", default=list(GUIDED),
                        help="T_guided of the plain LPA runs")
    parser.add_argument("--variants", nargs="*", default=list(VARIANTS_LATE))
    parser.add_argument("--no-scratch", action="store_true")
    parser.add_argument("--no-plain", action="store_true",
                        help="no plain LPA runs at the --guided times (only --yielding ones)")
    parser.add_argument("--yielding", nargs="*", default=[], choices=["own", "gated"],
                        help="also LPA into a YieldingModel exploring so, at every --guided")
    parser.add_argument("--modes", nargs="+", default=["kinematic", "physics"],
                        choices=["kinematic", "physics"])
    args = parser.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    config = dx.default_config()
    start, every = time.perf_counter(), {}
    for mode in args.modes:
        physics = PHYSICS if mode == "physics" else None
        results = every[mode] = {}
        for seed in args.seeds:
            runs = {} if args.no_scratch else {
                "scratch": dx.run_scratch(config, seed, physics=physics)}
            for guided in args.guided:
                if not args.no_plain:
                    runs[f"LPA/T{guided:g}"] = dx.run_transfer_condition(
                        config, seed, guided, physics=physics)
                for explore in args.yielding:
                    runs[f"LPA-yielding-{explore}/T{guided:g}"] = dx.run_transfer_condition(
                        config, seed, guided, physics=physics,
                        yielding=dict(gate_radius=config.threshold, explore=explore))
            for guided in args.variant_times:
                for variant in args.variants:
                    runs[f"LPA-{variant}/T{guided:g}"] = dx.run_transfer_condition(
                        config, seed, guided, variant, physics=physics)
            results[seed] = runs
            print(f"{mode} seed {seed} done after {time.perf_counter() - start:.0f} s",
                  flush=True)
            (out / "diagnosis.json").write_text(json.dumps(every, indent=1, default=float))
    write_tables(every, out)
    print(f"wall time {time.perf_counter() - start:.0f} s")


def write_tables(every, out):
    rows = {name: [] for name in ("mapping", "runs", "finals", "reference_check")}
    for mode, results in every.items():
        for name, table in tables(results).items():
            header = ["mode", *table[0]]
            rows[name] = rows[name] or [header]
            rows[name] += [[mode, *row] for row in table[1:]]
    for name, table in rows.items():
        if table:
            with open(out / f"{name}.csv", "w", newline="") as f:
                csv.writer(f).writerows(table)


class _Rows(list):
    def writerow(self, row):
        self.append(list(row))


def tables(results):
    """{table name: rows (header first)} of one mode's results."""
    made = {}
    w = made["mapping"] = _Rows()
    w.writerow(["seed", "condition", "n_correspondences", "n_transferred",
                "pair_residual_median_rad", "pair_residual_p95_rad", "pair_residual_max_rad",
                "mapping_error_mean_mm", "mapping_error_median_mm", "mapping_error_p90_mm",
                "within_1mm", "within_5mm", "within_10mm", "density_share_transferred_start",
                "density_majority_start", "density_share_transferred_end",
                "density_majority_end"])
    for seed, runs in results.items():
        for name, run in runs.items():
            if name == "scratch":
                continue
            i = run["info"]
            w.writerow([seed, name, i["n_correspondences"], i["n_transferred"],
                        i["pair_residual_median_rad"], i["pair_residual_p95_rad"],
                        i["pair_residual_max_rad"],
                        i["mapping_error_mean_mm"], i["mapping_error_median_mm"],
                        i["mapping_error_p90_mm"], i["within_1mm"], i["within_5mm"],
                        i["within_10mm"], run["density_start"]["density_share_transferred"],
                        run["density_start"]["density_points_transferred_majority"],
                        run["density_end"]["density_share_transferred"],
                        run["density_end"]["density_points_transferred_majority"]])
    w = made["runs"] = _Rows()
    w.writerow(["seed", "condition", "time_s", "rate", "mean_error_m",
                "babble_neighbours_transferred", "eval_neighbours_transferred",
                "rate_all_own", "n_all_own", "rate_transferred_accurate",
                "n_transferred_accurate", "rate_transferred_inaccurate",
                "n_transferred_inaccurate"])
    for seed, runs in results.items():
        for time_s, rate, error in runs.get("scratch", {}).get("curve", []):
            w.writerow([seed, "scratch", time_s, rate, error] + [""] * 8)
        for name, run in runs.items():
            if name == "scratch":
                continue
            for p in run["curve"]:
                w.writerow([seed, name, p["time"], p["rate"], p["mean_error"],
                            p["babble_neighbours_transferred"],
                            p["eval_neighbours_transferred"], *p["rate_all_own"],
                            *p["rate_transferred_accurate"],
                            *p["rate_transferred_inaccurate"]])
    w = made["finals"] = _Rows()
    keys = list(next(iter(results[next(iter(results))].values()))["sweep"])
    w.writerow(["seed", "condition", *keys])
    for seed, runs in results.items():
        for name, run in runs.items():
            w.writerow([seed, name, *[run["sweep"][k] for k in keys]])
    reference = ROOT / "scenarios/goal_babbling/reference_results/learning_curves.csv"
    if 0 in results and "scratch" in results[0] and reference.exists():
        graph = {}
        with open(reference) as f:
            for row in csv.DictReader(f):
                if row["seed"] == "0":
                    graph[(row["condition"], float(row["learning_time_s"]))] = \
                        float(row["reaching_rate"])
        w = made["reference_check"] = _Rows()
        w.writerow(["condition", "time_s", "rate_in_process", "rate_graph"])
        for time_s, rate, _ in results[0]["scratch"]["curve"]:
            w.writerow(["scratch", time_s, rate, graph.get(("scratch", time_s), "")])
        for guided in GUIDED:
            name = f"LPA/T{guided:g}"
            for p in results[0][name]["curve"]:
                w.writerow([name, p["time"], p["rate"], graph.get((name, p["time"]), "")])
    return made


if __name__ == "__main__":
    main()
