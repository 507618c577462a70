#!/usr/bin/env python3
"""Reproduce the thesis' illustrative 2-link example (§3.6, Table 3.1, Fig. 3-6 and Fig. 3-8).

A source robot (links 0.3/0.25 m) and a target robot (0.6/0.2 m) share joint limits
q1 ∈ [0, π/2], q2 ∈ [0, π]. Correspondences pair the two robots' domain points
z = (q, end-effector) at the same joint angles. PA and LPA mappings learned from N
correspondences are scored by

* the mapping error: RMSE of the end-effector of transferred source test points against the
  true target end-effector (Fig. 3-6a, Fig. 3-8 top row), and
* the model error: the source robot's experience is transferred, a forward-kinematics model
  is trained on it and tested on fresh target samples (Fig. 3-6b, Fig. 3-8 bottom row),

against the baselines "no transfer" (model from the N target points alone) and "ground
truth" (model from many true target samples). Experiment 1 sweeps N; experiment 2 sweeps the
target's link lengths at N = 100. A third sweep trains the target from scratch on up to
10,000 of its own samples to check "without transfer, this would not have happened until well
over 1000 points". Every forward-kinematics model is LWPR, as in §3.6 (config [target_model]).

Usage: run_two_link_fk.py [--config config.toml] [--out runs/two_link_fk] [--seed S] [--jobs J]
"""
import argparse
import sys
import time
import tomllib
from pathlib import Path

import matplotlib
matplotlib.use("Agg")
from lpa_transfer.illustrative_example import (LEARNER_KINDS, LINK_FIELDS,  # noqa: E402
                                               SCRATCH_FIELDS, SIZE_FIELDS, build_tasks,
                                               make_learner, plot_link_sweep, plot_scratch_sweep,
                                               plot_size_sweep, run_all, summary_text, write_csv)
from lpa_transfer.robots import load_robot_params  # noqa: E402

HERE = Path(__file__).resolve().parent
TEST_SET_KEYS = ("n_test", "n_experience", "n_target_test")
REQUIRED = {"": ("seed", "source_robot", "target_robot"),
            "lpa": ("n_min", "c_min", "cluster_dims", "n_init"), "target_model": ("learner",),
            "learners": (), "size_sweep": ("sizes", "runs", "n_ground_truth") + TEST_SET_KEYS,
            "link_sweep": ("length_start", "length_stop", "length_step", "n_train", "runs")
            + TEST_SET_KEYS,
            "scratch_sweep": ("sizes", "runs", "n_target_test", "learners", "compare_n")}


# --------------------------------------------------------------------------- configuration
def load_config(path):
    """Read the scenario TOML, check its keys and load the two robot files it names."""
    path = Path(path)
    with path.open("rb") as handle:
        cfg = tomllib.load(handle)
    for section, keys in REQUIRED.items():
        table = cfg.get(section, {}) if section else cfg
        missing = [key for key in keys if key not in table]
        if missing:
            raise ValueError(f"{path}: [{section or 'top level'}] is missing {missing}")
    check_learners(cfg, path)
    cfg["source"] = load_robot_params(path.parent / cfg["source_robot"])
    cfg["target"] = load_robot_params(path.parent / cfg["target_robot"])
    if cfg["source"].n_joints != cfg["target"].n_joints:
        raise ValueError(f"{path}: source and target robots must have the same number of "
                         "joints (correspondences pair equal joint angles)")
    return cfg


def check_learners(cfg, path):
    """Every learner named in the config must be a ``[learners.<name>]`` entry of a known
    ``kind`` whose hyperparameters its class accepts; compare_n must be a size-sweep size."""
    named = [cfg["target_model"]["learner"], *cfg["scratch_sweep"]["learners"]]
    for name in named:
        entry = cfg["learners"].get(name)
        if entry is None:
            raise ValueError(f"{path}: learner {name!r} has no [learners.{name}] table")
        if entry.get("kind") not in LEARNER_KINDS:
            raise ValueError(f"{path}: [learners.{name}] kind must be one of "
                             f"{sorted(LEARNER_KINDS)}, got {entry.get('kind')!r}")
        try:
            make_learner(cfg, name)
        except TypeError as exc:
            raise ValueError(f"{path}: [learners.{name}]: {exc}") from None
    if cfg["scratch_sweep"]["compare_n"] not in cfg["size_sweep"]["sizes"]:
        raise ValueError(f"{path}: [scratch_sweep] compare_n must be one of the size sweep's "
                         "sizes")



def parse_args(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--config", type=Path, default=HERE / "config.toml")
    parser.add_argument("--out", type=Path, default=Path("runs/two_link_fk"))
    parser.add_argument("--seed", type=int, default=None,
                        help="root seed (default: the config's 'seed')")
    parser.add_argument("--jobs", type=int, default=1,
                        help="worker processes (results do not depend on it)")
    args = parser.parse_args(argv)
    if args.jobs < 1:
        parser.error("--jobs must be >= 1")
    return args


def main(argv=None):
    args = parse_args(argv)
    try:
        cfg = load_config(args.config)
    except (OSError, ValueError, tomllib.TOMLDecodeError) as exc:
        sys.exit(f"error: {exc}")
    seed = cfg["seed"] if args.seed is None else args.seed
    args.out.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    size_tasks, link_tasks, scratch_tasks = build_tasks(cfg, seed)
    results = run_all(size_tasks + link_tasks + scratch_tasks, args.jobs)
    first_link, first_scratch = len(size_tasks), len(size_tasks) + len(link_tasks)
    size_rows = [row for rows in results[:first_link] for row in rows]
    link_rows = [row for rows in results[first_link:first_scratch] for row in rows]
    scratch_rows = [row for rows in results[first_scratch:] for row in rows]
    write_csv(args.out / "size_sweep.csv", SIZE_FIELDS, size_rows)
    write_csv(args.out / "link_sweep.csv", LINK_FIELDS, link_rows)
    write_csv(args.out / "scratch_sweep.csv", SCRATCH_FIELDS, scratch_rows)
    plot_size_sweep(size_rows, cfg, args.out / "fig3_6_mapping_and_model_error.png")
    plot_link_sweep(link_rows, cfg, args.out / "fig3_8_link_sweep.png")
    plot_scratch_sweep(scratch_rows, cfg, args.out / "points_without_transfer.png")
    config_text = Path(args.config).read_text()
    if args.seed is not None:
        config_text = f"# run with --seed {args.seed} (overrides 'seed' below)\n" + config_text
    (args.out / "config_used.toml").write_text(config_text)
    summary = summary_text(size_rows, link_rows, scratch_rows, cfg, seed,
                           time.perf_counter() - start)
    (args.out / "summary.txt").write_text(summary)
    print(summary, end="")
    print(f"outputs written to {args.out}")


if __name__ == "__main__":
    main()
