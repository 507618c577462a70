"""Chapter 4's accuracy sweeps in process (thesis §4.5.1-4.5.3): their CSV files (written,
and read back to join shares of the seeds), Fig. 4-10/4-12 (mapping and encoding error
against the training size for several N_min, beside the IK method) and the report with
Table 4.3.
"""
import csv
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from lpa_transfer.lfd.skills import CONDITIONS, THESIS_TABLE, SweepErrors, TransferErrors


THESIS_SWEEP = ("thesis §4.5.1-4.5.2 (Fig. 4-10/4-12, 5 runs): the mapping improves with more "
                "data and degrades as N_min decreases (N_min 8 overfits the PR2, 10 the Meka, "
                "for small samples); mapping errors on average below 0.01 m; the PR2 maps more "
                "accurately and with less data than the Meka; encoding errors comparable with "
                "the IK method's")


def write_csvs(out, params, sweeps, ik_method, table):
    with open(out / "ik_method.csv", "w", newline="") as f:
        rows = csv.writer(f)
        rows.writerow(["robot", "mapping_error_mm", "encoding_error_mm"])
        for name, e in ik_method.items():
            rows.writerow([name, f"{e.mapping * 1e3:.4f}", f"{e.encoding * 1e3:.4f}"])
    with open(out / "sweep.csv", "w", newline="") as f:
        rows = csv.writer(f)
        rows.writerow(["robot", "seed", "n_min", "training_size", "mapping_error_mm",
                       "encoding_error_mm"])
        for name, sweep in sweeps.items():
            for index in np.ndindex(sweep.mapping.shape):
                i, j, k = index
                rows.writerow([name, params["seeds"][i], params["n_mins"][j],
                               params["training_sizes"][k], f"{sweep.mapping[index] * 1e3:.4f}",
                               f"{sweep.encoding[index] * 1e3:.4f}"])
    with open(out / "multi_robot.csv", "w", newline="") as f:
        rows = csv.writer(f)
        rows.writerow(["seed", "condition", "mapping_error_mm", "encoding_error_mm"])
        for seed, result in zip(params["seeds"], table):
            for condition in CONDITIONS:
                e = result[condition]
                rows.writerow([seed, condition, f"{e.mapping * 1e3:.4f}",
                               f"{e.encoding * 1e3:.4f}"])


def read_csvs(run_dirs, params):
    """Join runs that each swept a share of the seeds (same config otherwise): (seeds,
    sweeps, ik_method, table) as :func:`run` and ``params["seeds"]`` give them."""
    rows = {name: [r for d in run_dirs if (Path(d) / name).exists()
                   for r in csv.DictReader(open(Path(d) / name))]
            for name in ("sweep.csv", "multi_robot.csv", "ik_method.csv")}
    seeds = sorted({int(r["seed"]) for r in rows["multi_robot.csv"]})
    shares = [sorted({int(r["seed"]) for r in csv.DictReader(open(Path(d) / "multi_robot.csv"))})
              for d in run_dirs]
    if sum(map(len, shares)) != len(seeds):
        raise ValueError(f"the runs repeat a seed: {shares}")
    sizes, n_mins = params["training_sizes"], params["n_mins"]
    sweeps = {}
    for r in rows["sweep.csv"]:
        sweep = sweeps.setdefault(r["robot"], SweepErrors(
            *(np.full((len(seeds), len(n_mins), len(sizes)), np.nan) for _ in range(2))))
        index = (seeds.index(int(r["seed"])), n_mins.index(int(r["n_min"])),
                 sizes.index(int(r["training_size"])))
        sweep.mapping[index] = float(r["mapping_error_mm"]) / 1e3
        sweep.encoding[index] = float(r["encoding_error_mm"]) / 1e3
    if any(np.isnan(s.mapping).any() for s in sweeps.values()):
        raise ValueError("the runs' sweeps do not cover every seed, N_min and size")
    # the IK method has no seed: every share that wrote it must agree (one is enough)
    ik_method = {r["robot"]: TransferErrors(float(r["mapping_error_mm"]) / 1e3,
                                            float(r["encoding_error_mm"]) / 1e3)
                 for r in rows["ik_method.csv"]}
    if set(ik_method) != set(sweeps) or len({tuple(r.values()) for r in rows["ik_method.csv"]}) \
            != len(ik_method):
        raise ValueError("the runs' ik_method.csv files are missing or disagree")
    table = [{r["condition"]: TransferErrors(float(r["mapping_error_mm"]) / 1e3,
                                             float(r["encoding_error_mm"]) / 1e3)
              for r in rows["multi_robot.csv"] if int(r["seed"]) == seed} for seed in seeds]
    return seeds, sweeps, ik_method, table


def plot_accuracy(path, params, sweeps, ik_method):
    sizes = np.asarray(params["training_sizes"])
    fig, axes = plt.subplots(2, len(sweeps), figsize=(5.5 * len(sweeps), 8.0), sharex=True,
                             squeeze=False)
    for col, (name, sweep) in enumerate(sweeps.items()):
        for row, (what, errors) in enumerate((("mapping", sweep.mapping),
                                              ("encoding", sweep.encoding))):
            ax = axes[row, col]
            for j, n_min in enumerate(params["n_mins"]):
                ax.errorbar(sizes, errors[:, j].mean(axis=0) * 1e3,
                            yerr=errors[:, j].std(axis=0) * 1e3, marker="o", capsize=3,
                            label=f"N_min = {n_min}")
            if what == "encoding":
                ax.axhline(ik_method[name].encoding * 1e3, color="black", linestyle="--",
                           label="IK method")
            ax.axhline(10, color="grey", linestyle=":", label="10 mm")
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.set_ylabel(f"{what} error (mm)")
            ax.set_title(f"{name}: {what} ({len(params['seeds'])} seed(s))")
            ax.grid(True, which="both", alpha=0.3)
            ax.legend(fontsize=8)
        axes[1, col].set_xlabel("training size (correspondences)")
    fig.suptitle("Letters transferred from the human by LPA (like thesis Fig. 4-10 and 4-12)")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def _cells(errors):
    return "".join(f"{m:8.1f} ±{s:5.1f}" for m, s in
                   zip(errors.mean(axis=0) * 1e3, errors.std(axis=0) * 1e3))


def accuracy_report(params, sweeps, ik_method, table, wall):
    lines = [f"Thesis §4.5 in process: {len(params['shapes']) * params['n_demos']} "
             f"demonstrations "
             f"({len(params['shapes'])} shapes x {params['n_demos']}, "
             f"{params['n_samples']} points each), LPA c_min {params['c_min']:g}, "
             f"{len(params['seeds'])} seed(s), DMPs with {params['dmp_weights_per_joint']} "
             f"weights a joint", "mapping error = mean ||FK_R(q̂_R) - T_R^H x_H|| over every "
             "demonstrated point; encoding error = the same for the DMP reproduction of each "
             "shape's first demonstration, mean over shapes; mm, mean ± std over the seeds", ""]
    for what in ("mapping", "encoding"):
        lines.append(f"{what} error      N_min " +
                     "".join(f"{s:>14d}" for s in params["training_sizes"]))
        for name, sweep in sweeps.items():
            for j, n_min in enumerate(params["n_mins"]):
                lines.append(f"{name:16s} {n_min:5d} {_cells(getattr(sweep, what)[:, j])}")
        lines.append("")
    for name, sweep in sweeps.items():
        mean = sweep.mapping.mean(axis=0)
        j, k = np.unravel_index(np.argmin(mean), mean.shape)
        lines.append(f"{name}: lowest mean mapping error {mean[j, k] * 1e3:.1f} ± "
                     f"{sweep.mapping[:, j, k].std() * 1e3:.1f} mm at N_min "
                     f"{params['n_mins'][j]}, {params['training_sizes'][k]} correspondences "
                     f"(encoding there {sweep.encoding[:, j, k].mean() * 1e3:.1f} mm; IK "
                     f"method's encoding {ik_method[name].encoding * 1e3:.1f} mm)")
    lines += ["", THESIS_SWEEP, "",
              f"Table 4.3 ({params['learner']} taught by the human directly or via "
              f"{params['teacher']}; every mapping LPA N_min {params['multi_robot_n_min']} on "
              f"{params['multi_robot_pairs']} correspondences; mm, mean ± std over the seeds):",
              f"{'':22s}{'mapping':>16s}{'thesis':>16s}{'encoding':>16s}{'thesis':>16s}"]
    for condition in CONDITIONS:
        ours = [np.array([getattr(r[condition], f) for r in table]) * 1e3
                for f in ("mapping", "encoding")]
        theirs = THESIS_TABLE[condition]
        lines.append(f"{condition:22s}" + "".join(
            f"{o.mean():9.1f} ±{o.std():5.1f}{t[0] * 1e3:10.1f} ({t[1] * 1e3:.1f})"
            for o, t in zip(ours, theirs)))
    lines += ["", f"wall time {wall:.0f} s"]
    return "\n".join(lines) + "\n"
