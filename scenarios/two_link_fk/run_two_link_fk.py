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
target's link lengths at N = 100.

Usage: run_two_link_fk.py [--config config.toml] [--out runs/two_link_fk] [--seed S] [--jobs J]
"""
import argparse
import concurrent.futures
import contextlib
import csv
import dataclasses
import math
import sys
import time
import tomllib
from pathlib import Path

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.colors import LogNorm  # noqa: E402
from matplotlib.ticker import (FormatStrFormatter, LogLocator, NullFormatter,  # noqa: E402
                               NullLocator)
from tqdm import tqdm  # noqa: E402

from lpa_transfer import LocalProcrustesAnalysis, ProcrustesAnalysis  # noqa: E402
from lpa_transfer.robots.kinematics import (domain_data, end_effector_rmse,  # noqa: E402
                                            planar_forward_kinematics, sample_joint_uniform)
from lpa_transfer.learners.locally_weighted import LocallyWeightedRegression  # noqa: E402
from lpa_transfer.robots.params import load_robot_params  # noqa: E402

HERE = Path(__file__).resolve().parent
TRANSFER_METHODS = ("PA", "LPA")
SIZE_FIELDS = ("method", "n_train", "run", "mapping_rmse_m", "model_rmse_m", "n_clusters")
LINK_FIELDS = ("method", "target_link1_m", "target_link2_m", "delta_link1_m", "delta_link2_m",
               "run", "mapping_rmse_m", "model_rmse_m", "n_clusters")
PLAIN_NUMBERS = FormatStrFormatter("%g")  # 20 instead of 2x10^1 on log axes
TEST_SET_KEYS = ("n_test", "n_experience", "n_target_test")
REQUIRED = {"": ("seed", "source_robot", "target_robot"),
            "lpa": ("n_min", "c_min", "cluster_dims", "n_init"), "learner": ("n_neighbors",),
            "size_sweep": ("sizes", "runs", "n_ground_truth") + TEST_SET_KEYS,
            "link_sweep": ("length_start", "length_stop", "length_step", "n_train", "runs")
            + TEST_SET_KEYS}


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
    cfg["source"] = load_robot_params(path.parent / cfg["source_robot"])
    cfg["target"] = load_robot_params(path.parent / cfg["target_robot"])
    if cfg["source"].n_joints != cfg["target"].n_joints:
        raise ValueError(f"{path}: source and target robots must have the same number of "
                         "joints (correspondences pair equal joint angles)")
    return cfg


def link_lengths_grid(sweep):
    """Target link lengths of experiment 2 (§3.6: 0.1 m to 1.5 m in 0.1 m steps)."""
    count = int(round((sweep["length_stop"] - sweep["length_start"]) / sweep["length_step"])) + 1
    return np.round(sweep["length_start"] + sweep["length_step"] * np.arange(count), 10)


# --------------------------------------------------------------------------- one run
def draw_correspondences(n, source, target, rng):
    """N correspondences (§3.6): both robots' domain points at the same uniform joint angles."""
    limits = np.column_stack((np.maximum(source.joint_limits[:, 0], target.joint_limits[:, 0]),
                              np.minimum(source.joint_limits[:, 1], target.joint_limits[:, 1])))
    q = sample_joint_uniform(n, limits, rng)
    return domain_data(q, source.link_lengths), domain_data(q, target.link_lengths)


def draw_test_sets(source, target, sizes, rng):
    """Uniform source test points, source experience, and target test joint angles."""
    return {"test_q": sample_joint_uniform(sizes["n_test"], source.joint_limits, rng),
            "experience": domain_data(sample_joint_uniform(sizes["n_experience"],
                                                           source.joint_limits, rng),
                                      source.link_lengths),
            "target_test_q": sample_joint_uniform(sizes["n_target_test"], target.joint_limits,
                                                  rng)}


def model_error(train_q, train_x, test_q, target, cfg):
    """RMSE (m) on the target test set of a forward-kinematics model trained on (q, x)."""
    model = LocallyWeightedRegression(**cfg["learner"]).fit(train_q, train_x)
    return end_effector_rmse(model.predict(test_q),
                             planar_forward_kinematics(test_q, target.link_lengths))


def transfer_scores(mapping, source, target, tests, cfg):
    """Mapping RMSE and model RMSE (m) of a fitted mapping (Fig. 3-6 a/b, Fig. 3-8)."""
    n_joints = source.n_joints
    transferred = mapping.transfer(domain_data(tests["test_q"], source.link_lengths))
    mapping_rmse = end_effector_rmse(
        transferred[:, n_joints:], planar_forward_kinematics(tests["test_q"], target.link_lengths))
    experience = mapping.transfer(tests["experience"])
    return mapping_rmse, model_error(experience[:, :n_joints], experience[:, n_joints:],
                                     tests["target_test_q"], target, cfg)


def child_seed(seed_seq, i):
    """``seed_seq.spawn(2)[i]`` without advancing its spawn counter, so a run can be repeated."""
    return np.random.SeedSequence(seed_seq.entropy, spawn_key=(*seed_seq.spawn_key, i),
                                  pool_size=seed_seq.pool_size)


def make_mapping(method, seed_seq, cfg):
    if method == "PA":
        return ProcrustesAnalysis()
    return LocalProcrustesAnalysis(**cfg["lpa"],
                                   random_state=int(seed_seq.generate_state(1)[0] >> 1))


def run_transfer(n, source, target, seed_seq, cfg, sizes):
    """Fit PA and LPA on n correspondences and score them.

    Returns ({method: (mapping RMSE, model RMSE, K)}, target training data, test sets, rng).
    """
    data_seq, model_seq = (child_seed(seed_seq, i) for i in range(2))
    rng = np.random.default_rng(data_seq)
    train_source, train_target = draw_correspondences(n, source, target, rng)
    tests = draw_test_sets(source, target, sizes, rng)
    scores = {}
    for method in TRANSFER_METHODS:
        mapping = make_mapping(method, model_seq, cfg).fit(train_source, train_target)
        scores[method] = (*transfer_scores(mapping, source, target, tests, cfg),
                          getattr(mapping, "n_clusters_", 1))
    return scores, train_target, tests, rng


def run_size_point(n, run, seed_seq, cfg):
    """Experiment 1 (Fig. 3-6) for one training size and run: rows for PA, LPA and baselines."""
    source, target, sweep = cfg["source"], cfg["target"], cfg["size_sweep"]
    scores, train_target, tests, rng = run_transfer(n, source, target, seed_seq, cfg, sweep)
    n_joints = source.n_joints
    truth_q = sample_joint_uniform(sweep["n_ground_truth"], target.joint_limits, rng)
    baselines = {
        "no_transfer": model_error(train_target[:, :n_joints], train_target[:, n_joints:],
                                   tests["target_test_q"], target, cfg),
        "ground_truth": model_error(truth_q, planar_forward_kinematics(truth_q,
                                                                      target.link_lengths),
                                    tests["target_test_q"], target, cfg)}
    rows = [dict(method=m, n_train=n, run=run, mapping_rmse_m=mapping, model_rmse_m=model,
                 n_clusters=k) for m, (mapping, model, k) in scores.items()]
    rows += [dict(method=m, n_train=n, run=run, mapping_rmse_m=math.nan, model_rmse_m=model,
                  n_clusters="") for m, model in baselines.items()]
    return rows


def run_link_point(lengths, run, seed_seq, cfg):
    """Experiment 2 (Fig. 3-8) for one pair of target link lengths and run."""
    source, sweep = cfg["source"], cfg["link_sweep"]
    target = dataclasses.replace(cfg["target"], link_lengths=lengths)
    scores, *_ = run_transfer(sweep["n_train"], source, target, seed_seq, cfg, sweep)
    delta = np.asarray(lengths) - source.link_lengths
    return [dict(method=m, target_link1_m=lengths[0], target_link2_m=lengths[1],
                 delta_link1_m=round(delta[0], 10), delta_link2_m=round(delta[1], 10), run=run,
                 mapping_rmse_m=mapping, model_rmse_m=model, n_clusters=k)
            for m, (mapping, model, k) in scores.items()]


def build_tasks(cfg, seed):
    """All runs as (function, args) with seeds spawned from one SeedSequence(seed)."""
    size_seq, link_seq = np.random.SeedSequence(seed).spawn(2)
    size_sweep, link_sweep = cfg["size_sweep"], cfg["link_sweep"]
    sizes = size_sweep["sizes"]
    lengths = link_lengths_grid(link_sweep)
    grid = [(l1, l2) for l1 in lengths for l2 in lengths]
    size_tasks = [(run_size_point, (n, run, run_seq, cfg))
                  for n, n_seq in zip(sizes, size_seq.spawn(len(sizes)))
                  for run, run_seq in enumerate(n_seq.spawn(size_sweep["runs"]))]
    link_tasks = [(run_link_point, ((float(l1), float(l2)), run, run_seq, cfg))
                  for (l1, l2), cell_seq in zip(grid, link_seq.spawn(len(grid)))
                  for run, run_seq in enumerate(cell_seq.spawn(link_sweep["runs"]))]
    return size_tasks, link_tasks


def _call(task):
    function, args = task
    return function(*args)


def run_all(tasks, jobs):
    """Run the tasks in order (optionally in ``jobs`` processes) with a progress bar."""
    results = []
    with (concurrent.futures.ProcessPoolExecutor(jobs) if jobs > 1 else contextlib.nullcontext()) \
            as pool, tqdm(total=len(tasks), desc="runs", unit="run", file=sys.stderr) as bar:
        for rows in (pool.map(_call, tasks, chunksize=4) if pool else map(_call, tasks)):
            results.append(rows)
            bar.update()
    return results


# --------------------------------------------------------------------------- outputs
def write_csv(path, fields, rows):
    with open(path, "w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=fields)
        writer.writeheader()
        for row in rows:
            writer.writerow({key: _cell(value) for key, value in row.items()})


def _cell(value):
    """CSV text of a value: floats at full precision (round-trip), NaN as an empty cell."""
    if isinstance(value, (float, np.floating)):
        return "" if math.isnan(value) else repr(float(value))
    return int(value) if isinstance(value, np.integer) else value


def grouped(rows, key, field):
    """{key value: values of ``field``} for the rows (e.g. per training size)."""
    groups = {}
    for row in rows:
        groups.setdefault(row[key], []).append(row[field])
    return {k: np.asarray(v, dtype=float) for k, v in groups.items()}


def select(rows, method):
    return [row for row in rows if row["method"] == method]


def plot_size_sweep(rows, cfg, path):
    """Fig. 3-6: (a) mapping RMSE and (b) model RMSE against N; mean ± std bands, mm."""
    fig, axes = plt.subplots(1, 2, figsize=(12, 5.4), constrained_layout=True)
    panels = ((axes[0], "mapping_rmse_m", TRANSFER_METHODS, "(a) mapping error"),
              (axes[1], "model_rmse_m", TRANSFER_METHODS + ("no_transfer", "ground_truth"),
               "(b) target forward-kinematics model error"))
    labels = {"PA": "PA", "LPA": "LPA", "no_transfer": "no transfer (target data only)",
              "ground_truth": "ground truth (%d true target samples)"
              % cfg["size_sweep"]["n_ground_truth"]}
    for ax, field, methods, title in panels:
        for method in methods:
            stats = grouped(select(rows, method), "n_train", field)
            sizes = np.array(sorted(stats))
            mean = np.array([stats[n].mean() for n in sizes]) * 1e3
            std = np.array([stats[n].std() for n in sizes]) * 1e3
            line, = ax.plot(sizes, mean, marker="o", label=labels[method])
            ax.fill_between(sizes, np.maximum(mean - std, mean * 1e-2), mean + std,
                            color=line.get_color(), alpha=0.2)
        ax.set(xscale="log", yscale="log", xlabel="training correspondences N",
               ylabel="end-effector RMSE (mm)", title=title)
        ax.set_xticks(sizes, [str(n) for n in sizes], rotation=45)
        ax.xaxis.set_minor_locator(NullLocator())
        ax.yaxis.set_major_locator(LogLocator(subs=(1, 2, 5)))
        ax.yaxis.set_major_formatter(PLAIN_NUMBERS)
        ax.yaxis.set_minor_formatter(NullFormatter())
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.2), ncol=2)
    fig.suptitle(f"Thesis Fig. 3-6: 2-link transfer {_robots_label(cfg)}, mean ± std of "
                 f"{cfg['size_sweep']['runs']} runs")
    fig.savefig(path, dpi=120)
    plt.close(fig)


def _robots_label(cfg):
    lengths = [", ".join(f"{v:g}" for v in robot.link_lengths)
               for robot in (cfg["source"], cfg["target"])]
    return f"source ({lengths[0]}) m → target ({lengths[1]}) m"


def cell_means(rows, field):
    """Mean of ``field`` per (ΔL1, ΔL2) cell: sorted axes and a (len ΔL2, len ΔL1) grid."""
    stats = {}
    for row in rows:
        stats.setdefault((row["delta_link1_m"], row["delta_link2_m"]), []).append(row[field])
    d1 = sorted({key[0] for key in stats})
    d2 = sorted({key[1] for key in stats})
    grid = np.array([[np.mean(stats[(a, b)]) for a in d1] for b in d2])
    return np.array(d1), np.array(d2), grid


def _cell_edges(centres):
    step = centres[1] - centres[0] if len(centres) > 1 else 0.1
    return np.append(centres - step / 2, centres[-1] + step / 2)


def plot_link_sweep(rows, cfg, path):
    """Fig. 3-8: heat maps of PA/LPA mapping and model RMSE over the link-length differences."""
    fig, axes = plt.subplots(2, 2, figsize=(11, 9), constrained_layout=True)
    source = cfg["source"].link_lengths
    for col, (field, what) in enumerate((("mapping_rmse_m", "mapping"),
                                         ("model_rmse_m", "model"))):
        grids = {m: cell_means(select(rows, m), field) for m in TRANSFER_METHODS}
        values = np.concatenate([g[2].ravel() for g in grids.values()]) * 1e3
        norm = LogNorm(vmin=max(values.min(), 1e-2), vmax=values.max())
        for row, method in enumerate(TRANSFER_METHODS):
            ax = axes[row, col]
            d1, d2, grid = grids[method]
            mesh = ax.pcolormesh(_cell_edges(d1), _cell_edges(d2),
                                 np.maximum(grid * 1e3, norm.vmin), norm=norm, cmap="viridis")
            ax.plot(d1, d1 * source[1] / source[0], "w--", lw=1.5,
                    label="equal link ratio $L_1/L_2$")
            ax.set(xlim=_cell_edges(d1)[[0, -1]], ylim=_cell_edges(d2)[[0, -1]],
                   xlabel="$L_1^t - L_1^s$ (m)", ylabel="$L_2^t - L_2^s$ (m)",
                   title=f"{method}: {what} RMSE")
            ax.legend(loc="upper left", fontsize=8)
            fig.colorbar(mesh, ax=ax, label=f"{what} RMSE (mm)", format=PLAIN_NUMBERS)
    fig.suptitle(f"Thesis Fig. 3-8: source links ({source[0]:g}, {source[1]:g}) m, "
                 f"N = {cfg['link_sweep']['n_train']}, mean of {cfg['link_sweep']['runs']} "
                 "run(s) per cell")
    fig.savefig(path, dpi=110)
    plt.close(fig)


def summary_text(size_rows, link_rows, cfg, seed, seconds):
    """Means per method and N, the LPA/PA mapping ratio, and link-sweep aggregates."""
    lines = [f"Thesis §3.6 two-link example, seed {seed}, {_robots_label(cfg)}, "
             f"runtime {seconds:.1f} s", "",
             "Experiment 1 (Fig. 3-6): mean ± std over "
             f"{cfg['size_sweep']['runs']} runs, RMSE in mm",
             f"{'N':>6} {'PA map':>15} {'LPA map':>15} {'LPA/PA':>7} {'LPA K':>6} "
             f"{'PA model':>9} {'LPA model':>9} {'no transfer':>11} {'ground truth':>12}"]
    stats = {(m, f): grouped(select(size_rows, m), "n_train", f)
             for m in TRANSFER_METHODS + ("no_transfer", "ground_truth")
             for f in ("mapping_rmse_m", "model_rmse_m")}
    clusters = grouped(select(size_rows, "LPA"), "n_train", "n_clusters")
    for n in cfg["size_sweep"]["sizes"]:
        pa, lpa = stats["PA", "mapping_rmse_m"][n] * 1e3, stats["LPA", "mapping_rmse_m"][n] * 1e3
        models = [stats[m, "model_rmse_m"][n].mean() * 1e3
                  for m in TRANSFER_METHODS + ("no_transfer", "ground_truth")]
        lines.append(f"{n:>6} {pa.mean():8.3f} ±{pa.std():5.2f} {lpa.mean():8.3f} ±"
                     f"{lpa.std():5.2f} {lpa.mean() / pa.mean():7.3f} "
                     f"{clusters[n].mean():6.1f} {models[0]:9.3f} {models[1]:9.3f} "
                     f"{models[2]:11.3f} {models[3]:12.3f}")
    lines += ["", f"Experiment 2 (Fig. 3-8): N = {cfg['link_sweep']['n_train']}, "
              f"{cfg['link_sweep']['runs']} run(s) per cell, cell means"]
    grids = {(m, f): cell_means(select(link_rows, m), f)[2] * 1e3
             for m in TRANSFER_METHODS for f in ("mapping_rmse_m", "model_rmse_m")}
    for field in ("mapping_rmse_m", "model_rmse_m"):
        pa, lpa = grids["PA", field], grids["LPA", field]
        lines.append(f"  {field[:-2]} (mm): median PA {np.median(pa):.3f}, median LPA "
                     f"{np.median(lpa):.3f}; LPA < PA in {np.mean(lpa < pa):.0%} of cells; "
                     f"LPA < 10 mm in {np.mean(lpa < 10):.0%} of cells")
    return "\n".join(lines) + "\n"


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
    size_tasks, link_tasks = build_tasks(cfg, seed)
    results = run_all(size_tasks + link_tasks, args.jobs)
    size_rows = [row for rows in results[:len(size_tasks)] for row in rows]
    link_rows = [row for rows in results[len(size_tasks):] for row in rows]
    write_csv(args.out / "size_sweep.csv", SIZE_FIELDS, size_rows)
    write_csv(args.out / "link_sweep.csv", LINK_FIELDS, link_rows)
    plot_size_sweep(size_rows, cfg, args.out / "fig3_6_mapping_and_model_error.png")
    plot_link_sweep(link_rows, cfg, args.out / "fig3_8_link_sweep.png")
    config_text = Path(args.config).read_text()
    if args.seed is not None:
        config_text = f"# run with --seed {args.seed} (overrides 'seed' below)\n" + config_text
    (args.out / "config_used.toml").write_text(config_text)
    summary = summary_text(size_rows, link_rows, cfg, seed, time.perf_counter() - start)
    (args.out / "summary.txt").write_text(summary)
    print(summary, end="")
    print(f"outputs written to {args.out}")


if __name__ == "__main__":
    main()
