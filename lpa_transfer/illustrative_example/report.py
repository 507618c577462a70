"""The §3.6 outputs: CSVs of every run, Fig. 3-6 (errors against training size), Fig. 3-8
(errors against the difference in link lengths), the from-scratch learning curve beside the
transferred model (the §3.6 claim "Without transfer, this would not have happened until well
over 1000 points") and a text summary beside the thesis'.
"""
import csv
import math

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.colors import LogNorm
from matplotlib.ticker import FormatStrFormatter, LogLocator, NullFormatter, NullLocator

from lpa_transfer.illustrative_example.experiment import TRANSFER_METHODS


PLAIN_NUMBERS = FormatStrFormatter("%g")  # 20 instead of 2x10^1 on log axes


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
    fig.suptitle(f"Thesis Fig. 3-6: 2-link transfer {_robots_label(cfg)}, models "
                 f"{_learner_label(cfg)}, mean ± std of {cfg['size_sweep']['runs']} runs")
    fig.savefig(path, dpi=120)
    plt.close(fig)


def _learner_label(cfg, name=None):
    """'lwpr (LWPR)': a [learners.<name>] entry and its kind."""
    name = cfg["target_model"]["learner"] if name is None else name
    return f"{name} ({cfg['learners'][name]['kind']})"


def points_needed(scratch_means, level):
    """Smallest swept N whose from-scratch mean error is at or below ``level`` (None if none)."""
    return next((n for n in sorted(scratch_means) if scratch_means[n] <= level), None)


def scratch_comparison(scratch_rows, cfg):
    """Per learner: mean from-scratch error (m) per N, and the mean error of the same learner
    trained on LPA-transferred experience from compare_n correspondences."""
    means, levels = {}, {}
    for name in cfg["scratch_sweep"]["learners"]:
        rows = [r for r in scratch_rows if r["learner"] == name]
        means[name] = {n: v.mean() for n, v in
                       grouped(select(rows, "no_transfer"), "n_train", "model_rmse_m").items()}
        levels[name] = np.mean([r["model_rmse_m"] for r in select(rows, "LPA")])
    return means, levels


def plot_scratch_sweep(scratch_rows, cfg, path):
    """From-scratch model error against the target's own N, per learner (solid), beside the
    same learner on LPA-transferred data from compare_n correspondences (dotted): §3.6,
    convergence at about 200 points with transfer, "well over 1000" without."""
    means, levels = scratch_comparison(scratch_rows, cfg)
    n_cmp = cfg["scratch_sweep"]["compare_n"]
    fig, ax = plt.subplots(figsize=(8, 5.4), constrained_layout=True)
    for name, curve in means.items():
        sizes = np.array(sorted(curve))
        line, = ax.plot(sizes, [curve[n] * 1e3 for n in sizes], marker="o",
                        label=f"no transfer: {_learner_label(cfg, name)}")
        ax.axhline(levels[name] * 1e3, color=line.get_color(), ls=":",
                   label=f"LPA transfer, N = {n_cmp}: {name}")
    ax.set(xscale="log", yscale="log", xlabel="target's own training points N",
           ylabel="forward-kinematics model RMSE (mm)",
           title=f"Learning from scratch vs transfer, mean of {cfg['scratch_sweep']['runs']} "
                 "runs")
    ax.set_xticks(sizes, [str(n) for n in sizes])
    ax.xaxis.set_minor_locator(NullLocator())
    ax.yaxis.set_major_locator(LogLocator(subs=(1, 2, 5)))
    ax.yaxis.set_major_formatter(PLAIN_NUMBERS)
    ax.yaxis.set_minor_formatter(NullFormatter())
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    fig.savefig(path, dpi=110)
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


def summary_text(size_rows, link_rows, scratch_rows, cfg, seed, seconds):
    """Means per method and N, the LPA/PA mapping ratio, link-sweep aggregates, and the
    from-scratch errors with the points needed to reach the transferred model."""
    lines = [f"Thesis §3.6 two-link example, seed {seed}, {_robots_label(cfg)}, "
             f"runtime {seconds:.1f} s", f"Forward-kinematics models: {_learner_label(cfg)}",
             "",
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
    return "\n".join(lines + [""] + scratch_lines(scratch_rows, cfg)) + "\n"


def scratch_lines(scratch_rows, cfg):
    """The from-scratch table (mm), the same learners on LPA-transferred data from compare_n
    correspondences, and per learner the smallest swept N that reaches that level."""
    sweep = cfg["scratch_sweep"]
    means, levels = scratch_comparison(scratch_rows, cfg)
    n_cmp = sweep["compare_n"]
    width = max(len(name) for name in means) + 1
    lines = [f"No transfer (target learns from N own samples) vs LPA transfer from N = {n_cmp}"
             f", mean of {sweep['runs']} runs, RMSE in mm",
             f"{'N':>6} " + " ".join(f"{name:>{width}}" for name in means)]
    for n in sweep["sizes"]:
        lines.append(f"{n:>6} " + " ".join(f"{means[name][n] * 1e3:>{width}.3f}"
                                           for name in means))
    lines.append(f"{'LPA':>6} " + " ".join(f"{levels[name] * 1e3:>{width}.3f}" for name in means))
    for name, curve in means.items():
        needed = points_needed(curve, levels[name])
        lines.append(f"  {name}: from scratch reaches its LPA transfer level of N = {n_cmp} "
                     + (f"at N = {needed}" if needed else f"beyond N = {max(curve)} (the sweep)"))
    return lines
