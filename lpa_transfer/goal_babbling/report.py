"""Chapter 6's run outputs (thesis §6.5): results.json, learning_curves.csv, the task-space
figure (Fig. 6-5/6-9), the reaching curves (Fig. 6-6/6-7/6-10) and report.txt with the time
to reach scratch's final reaching rate and the time saved; and joining runs that each ran a
share of the seeds.

``curves`` map a condition (``scratch``, ``lpa/240s``, ...) to one run per seed, each a dict of
``times``, ``mean_error``, ``rate`` and ``n_transferred`` per evaluation; ``experiment`` is
anything with the attributes of :data:`SETTINGS` plus ``robots`` (``source``/``target``
:class:`~lpa_transfer.robots.params.RobotParams`).
"""
import csv
import json
from pathlib import Path
from types import SimpleNamespace

import matplotlib.pyplot as plt
import numpy as np

from lpa_transfer.evaluation.learning_curves import rank_sum_comparison, time_saved
from lpa_transfer._validation import check_x_bounds
from lpa_transfer.goal_babbling.reaching import evaluation_points, grid
from lpa_transfer.robots.kinematics import robot_kinematics, sample_joint_uniform
from lpa_transfer.robots.params import load_robot_params


SETTINGS = ("seeds_done", "source_seconds", "total_seconds", "guided_seconds", "interval",
            "methods", "guarded", "yielding", "reaching_threshold", "transfer_from_guided",
            "robot_files", "target_home", "x_bounds", "eval_spacing", "eval_joint_samples", "steps_per_second",
            "thesis")


def mean_curve(runs, key):
    """(times, mean, std) over the runs of one condition (all share the times)."""
    values = np.array([run[key] for run in runs], dtype=np.float64)
    return np.asarray(runs[0]["times"]), values.mean(axis=0), values.std(axis=0)


def report_lines(curves, experiment):
    times, scratch_rate, _ = mean_curve(curves["scratch"], "rate")
    lines = [f"Thesis ch. 6 over the node graph ({experiment.robots['source'].name} -> "
             f"{experiment.robots['target'].name}): {len(experiment.seeds_done)} seed(s) "
             f"({', '.join(map(str, experiment.seeds_done))}); target learns for "
             f"{experiment.total_seconds:g} s ({experiment.steps_per_second:g} movements a "
             f"simulated second), reaching threshold {1e3 * experiment.reaching_threshold:g} mm",
             f"the thesis' measure, read off the mean curves over the seeds: the time a "
             f"condition takes to reach scratch's final reaching rate against scratch's; "
             f"scratch reaches its final rate {scratch_rate[-1]:.3f} first at "
             f"{time_saved(times, scratch_rate, times, scratch_rate)[1]:g} s", "",
             f"{'condition':<22} {'rate after transfer':>19} {'(scratch then)':>14} "
             f"{'final rate':>11} {'final error (mm)':>16} {'reaches scratch final':>22} "
             f"{'time saved':>10}"]
    every_evaluation = []   # the mean rate of each condition at each of scratch's times
    for name, runs in curves.items():
        t, rate, rate_std = mean_curve(runs, "rate")
        _, error, error_std = mean_curve(runs, "mean_error")
        level, _, reach, saved = time_saved(times, scratch_rate, t, rate)
        scratch_then = np.interp(t[0], times, scratch_rate, left=0.0)
        cells = {round(float(x), 6): f"{r:5.2f}" for x, r in zip(t, rate)}
        every_evaluation.append(f"{name:<22} " + " ".join(
            cells.get(round(float(x), 6), "    -") for x in times))
        lines.append(f"{name:<22} {rate[0]:>19.3f} {scratch_then:>14.3f} "
                     f"{rate[-1]:>5.3f} ± {rate_std[-1]:.3f} "
                     f"{1e3 * error[-1]:>8.1f} ± {1e3 * error_std[-1]:4.1f} "
                     f"{'never' if np.isinf(reach) else f'{reach:g} s':>22} "
                     f"{'-' if name == 'scratch' or np.isinf(saved) else f'{saved:.0%}':>10}")
    lines += [""] + final_rate_lines(curves)
    lines += ["", "'rate after transfer': the first evaluation (right after the transfer; for "
              "scratch, after one interval); '(scratch then)': the scratch learner's mean rate "
              "at that time (0 before its first evaluation)", "",
              "mean reaching rate at every evaluation (learning time in s):",
              f"{'':<22} " + " ".join(f"{x:>5g}" for x in times)]
    lines += every_evaluation + [""] + level_lines(curves, times, scratch_rate) + [""] + \
        comparison_lines(curves, times) + [""] + grid_lines(curves, experiment) + \
        ["", experiment.thesis]
    return lines


#: Evaluations at the end of a run whose mean is its final reaching rate.
FINAL_EVALUATIONS = 3


def final_rate_lines(curves, last=FINAL_EVALUATIONS):
    """Each condition's final reaching rate, the mean of a run's last ``last`` evaluations,
    against scratch's over the seeds: the difference of the means, the share of (run, scratch
    run) pairs in which the run ends higher and the Mann-Whitney p
    (:func:`lpa_transfer.evaluation.learning_curves.rank_sum_comparison`; unpaired, as in
    :func:`comparison_lines`). Does transfer end where learning from scratch ends?"""
    def finals(runs):
        return np.array([np.mean(run["rate"][-last:]) for run in runs])

    scratch = finals(curves["scratch"])
    lines = [f"final reaching rate (mean of the last {last} evaluations; mean ± std over the "
             f"seeds) against scratch's: the difference of the means, the share of (run, "
             f"scratch run) pairs ending higher and the two-sided Mann-Whitney p (unpaired: a "
             f"seed's scratch run and its transfer runs babble with different derived seeds)",
             f"{'scratch':<22} {scratch.mean():5.3f} ± {scratch.std():5.3f}"]
    for name, runs in curves.items():
        if name == "scratch":
            continue
        ours = finals(runs)
        share, p = rank_sum_comparison(ours, scratch)
        lines.append(f"{name:<22} {ours.mean():5.3f} ± {ours.std():5.3f}  "
                     f"{ours.mean() - scratch.mean():+6.3f}  {share:4.2f} (p {p:.3f})")
    return lines


def grid_lines(curves, experiment):
    """The final mean rates over every point of the grid over X_bounds, not only the points the
    target can reach (the test points): §6.5 does not say which of the two it counted."""
    target = robot_kinematics(experiment.robots["target"], experiment.target_home)
    n_points = len(evaluation_points(target, experiment.x_bounds,
                                     spacing=experiment.eval_spacing,
                                     n_joint_samples=experiment.eval_joint_samples))
    n_grid = len(grid(check_x_bounds(experiment.x_bounds, len(experiment.x_bounds[0])),
                      experiment.eval_spacing))
    share = n_points / n_grid
    lines = [f"over all {n_grid} points of the {experiment.eval_spacing:g} m grid over X_bounds "
             f"(the test points are the {n_points} the target reaches, {share:.3f} of them): "
             f"final mean rate over the test points -> over the whole grid"]
    for name, runs in curves.items():
        _, rate, _ = mean_curve(runs, "rate")
        lines.append(f"{name:<22} {rate[-1]:5.3f} -> {rate[-1] * share:5.3f}")
    return lines


def comparison_lines(curves, times):
    """Each condition against scratch at each of scratch's evaluations, over the seeds: the
    share of (run, scratch run) pairs in which the run's reaching rate is higher, and the
    Mann-Whitney p (:func:`lpa_transfer.evaluation.learning_curves.rank_sum_comparison`; unpaired: a
    seed's scratch run and its transfer runs babble with different derived seeds). Says
    whether a lead or a lag of the mean curves is more than the seeds' spread."""
    lines = ["against scratch over the seeds: share of (run, scratch run) pairs with a higher "
             "reaching rate, and the two-sided Mann-Whitney p, at every evaluation (learning "
             "time in s):", f"{'':<22} " + " ".join(f"{x:>5g}" for x in times)]
    keys = [round(float(x), 6) for x in times]
    scratch = {key: [run["rate"][i] for run in curves["scratch"]] for i, key in enumerate(keys)}
    for name, runs in curves.items():
        if name == "scratch":
            continue
        rates = {round(float(x), 6): [run["rate"][i] for run in runs]
                 for i, x in enumerate(runs[0]["times"])}
        cells = {key: rank_sum_comparison(rates[key], scratch[key])
                 for key in keys if key in rates}
        for label, column, digits in ((name, 0, 2), ("  p", 1, 3)):
            lines.append(f"{label:<22} " + " ".join(
                f"{cells[key][column]:5.{digits}f}" if key in cells else "    -"
                for key in keys))
    return lines


#: Shares of the scratch learner's final rate at which the report also reads time saved.
LEVEL_SHARES = (0.5, 0.75, 0.9, 1.0)


def level_lines(curves, times, scratch_rate):
    """When each condition's mean rate first reaches shares of scratch's final rate, and the
    time saved to get there: where in learning transfer helps, not only at the end."""
    levels = [share * scratch_rate[-1] for share in LEVEL_SHARES]
    lines = ["first time (s) the mean rate reaches a share of scratch's final rate, and the "
             "time saved against scratch:",
             f"{'':<22} " + " ".join(f"{f'{share:.0%} ({level:.2f})':>15}"
                                     for share, level in zip(LEVEL_SHARES, levels))]
    for name, runs in curves.items():
        t, rate, _ = mean_curve(runs, "rate")
        cells = []
        for level in levels:
            _, _, reach, saved = time_saved(times, scratch_rate, t, rate, level=level)
            text = "never" if np.isinf(reach) else f"{reach:g}"
            if name != "scratch" and np.isfinite(saved):
                text += f" ({saved:+.0%})"
            cells.append(f"{text:>15}")
        lines.append(f"{name:<22} " + " ".join(cells))
    return lines


def write_outputs(curves, experiment, out):
    out.mkdir(parents=True, exist_ok=True)
    (out / "results.json").write_text(json.dumps({
        "settings": {key: getattr(experiment, key) for key in SETTINGS},
        "curves": curves}) + "\n")
    with open(out / "learning_curves.csv", "w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(["condition", "seed", "learning_time_s", "mean_error_m",
                         "reaching_rate", "n_transferred_active"])
        for name, runs in curves.items():
            for seed, run in zip(experiment.seeds_done, runs):
                writer.writerows([name, seed, t, repr(e), repr(r), n] for t, e, r, n in zip(
                    run["times"], run["mean_error"], run["rate"], run["n_transferred"]))
    plot_curves(curves, experiment, out / "fig6_6_7_learning_curves.png")
    plot_task_spaces(experiment, out / "fig6_5_task_spaces.png")
    text = "\n".join(report_lines(curves, experiment)) + "\n"
    (out / "report.txt").write_text(text)
    return text


def plot_curves(curves, experiment, path):
    columns = [name for name in dict.fromkeys(n.split("/")[0] for n in curves)
               if name != "scratch"]
    fig, axes = plt.subplots(2, max(1, len(columns)), squeeze=False, sharex=True,
                             figsize=(4.5 * max(1, len(columns)), 7), constrained_layout=True)
    for col, method in enumerate(columns or ["scratch"]):
        for row, (key, label, scale) in enumerate((("mean_error", "mean reaching error (mm)",
                                                    1e3), ("rate", "reaching rate", 1))):
            ax = axes[row, col]
            for name in ["scratch"] + [n for n in curves if n.split("/")[0] == method]:
                t, mean, std = mean_curve(curves[name], key)
                style = dict(color="k", lw=2) if name == "scratch" else dict(lw=1.2)
                line, = ax.plot(t, scale * mean, marker="o", ms=2.5, label=name.split("/")[-1]
                                if name != "scratch" else "scratch", **style)
                ax.fill_between(t, scale * (mean - std), scale * (mean + std),
                                color=line.get_color(), alpha=0.15)
            ax.set(ylabel=label, title=f"{method}" if row == 0 else None)
            ax.grid(True, alpha=0.3)
            if row == 1:
                ax.set(xlabel="learning time (s of simulated babbling)", ylim=(0, 1.02))
                ax.legend(title="T_guided", fontsize=8)
    figure = "6-6/6-7" if len(experiment.x_bounds[0]) == 2 else "6-10"
    fig.suptitle(f"Thesis Fig. {figure}: {experiment.robots['target'].name} learning from "
                 f"scratch (black) and after transfer\nfrom {experiment.robots['source'].name}; "
                 f"mean ± std over {len(experiment.seeds_done)} seed(s)")
    fig.savefig(path, dpi=110)
    plt.close(fig)


#: Views of a task space: planar arms (x, y); 3-D ones front (x, y), side (z, y), top (x, z).
VIEWS = {2: ((0, 1),), 3: ((0, 1), (2, 1), (0, 2))}


def plot_task_spaces(experiment, path):
    """Fig. 6-5 / 6-9: the two robots' reachable task spaces (world frame, y up), the target's
    X_bounds and its test points; a 3-D task space is drawn in three projections."""
    rng = np.random.default_rng(0)
    reached = {}
    for side in ("source", "target"):
        kinematics = robot_kinematics(experiment.robots[side])
        reached[side] = kinematics.forward(sample_joint_uniform(4000, kinematics.joint_limits,
                                                                rng))
    target = robot_kinematics(experiment.robots["target"], experiment.target_home)
    points = evaluation_points(target, experiment.x_bounds, spacing=experiment.eval_spacing,
                               n_joint_samples=experiment.eval_joint_samples)
    low, high = (np.asarray(b, dtype=np.float64) for b in experiment.x_bounds)
    views = VIEWS[points.shape[1]]
    fig, axes = plt.subplots(1, len(views), figsize=(6 * len(views), 6), squeeze=False,
                             constrained_layout=True)
    for ax, (h, v) in zip(axes[0], views):
        for side, colour in (("source", "tab:blue"), ("target", "tab:orange")):
            ax.scatter(reached[side][:, h], reached[side][:, v], s=1, color=colour, alpha=0.4,
                       label=f"{side}: {experiment.robots[side].name}")
        ax.scatter(points[:, h], points[:, v], s=8, marker="x", color="k",
                   label=f"target test points ({len(points)})")
        ax.plot([low[h], high[h], high[h], low[h], low[h]],
                [low[v], low[v], high[v], high[v], low[v]], "k--", lw=1,
                label="target X_bounds")
        ax.set(xlabel="xyz"[h] + " (m)", ylabel="xyz"[v] + " (m)", aspect="equal")
        ax.legend(markerscale=4, fontsize=8, loc="lower left")
    fig.suptitle(f"Thesis Fig. {'6-5' if len(views) == 1 else '6-9'}: task spaces of the two "
                 f"robots (world frame, gravity along -y)")
    fig.savefig(path, dpi=110)
    plt.close(fig)


PER_SHARE = ("seeds_done",)


def read_curves(run_dir):
    """({condition: [run per seed]}, seeds) from a run's learning_curves.csv."""
    curves, seeds = {}, []
    with open(Path(run_dir) / "learning_curves.csv", newline="") as handle:
        for row in csv.DictReader(handle):
            seed = int(row["seed"])
            seeds += [] if seed in seeds else [seed]
            runs = curves.setdefault(row["condition"], {})
            run = runs.setdefault(seed, dict(times=[], mean_error=[], rate=[], n_transferred=[]))
            run["times"].append(float(row["learning_time_s"]))
            run["mean_error"].append(float(row["mean_error_m"]))
            run["rate"].append(float(row["reaching_rate"]))
            run["n_transferred"].append(int(row["n_transferred_active"]))
    for name, runs in curves.items():
        if sorted(runs) != sorted(seeds):
            raise ValueError(f"{run_dir}: condition {name} has seeds {sorted(runs)}, the run "
                             f"has {sorted(seeds)}")
    return {name: [runs[seed] for seed in seeds] for name, runs in curves.items()}, seeds


def settings_of(run_dirs):
    """The shared settings (without the seeds) of the runs that wrote a results.json."""
    found = {}
    for run_dir in run_dirs:
        path = Path(run_dir) / "results.json"
        if path.exists():
            settings = json.loads(path.read_text())["settings"]
            found[run_dir] = {k: v for k, v in settings.items() if k not in PER_SHARE}
    if not found:
        raise ValueError(f"none of {list(run_dirs)} holds a results.json with the settings")
    first_dir, first = next(iter(found.items()))
    for run_dir, settings in found.items():
        if settings != first:
            differing = sorted(k for k in set(first) | set(settings)
                               if first.get(k) != settings.get(k))
            raise ValueError(f"{run_dir} ran other settings than {first_dir}: {differing}")
    return first


def merge(run_dirs):
    """(curves, experiment-like settings) of the runs in ``run_dirs`` together."""
    settings = settings_of(run_dirs)
    curves, seeds = {}, []
    for run_dir in run_dirs:
        run_curves, run_seeds = read_curves(run_dir)
        if curves and sorted(run_curves) != sorted(curves):
            raise ValueError(f"{run_dir} holds conditions {sorted(run_curves)}, not "
                             f"{sorted(curves)}")
        repeated = set(run_seeds) & set(seeds)
        if repeated:
            raise ValueError(f"seeds {sorted(repeated)} appear in more than one run")
        seeds += run_seeds
        for name, runs in run_curves.items():
            curves.setdefault(name, []).extend(runs)
    robots = {side: load_robot_params(path) for side, path in settings["robot_files"].items()}
    return curves, SimpleNamespace(seeds_done=seeds, robots=robots, **settings)
