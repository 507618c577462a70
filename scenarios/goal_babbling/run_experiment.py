#!/usr/bin/env python3
"""Thesis §6.5.1 and §6.5.2 over the node graph: does transfer accelerate goal babbling?

The robots, boxes and times come from the scenario YAML: config.yaml is experiment 1 (two
2-link arms, Table 6.1), nao_poppy.yaml experiment 2 (Nao -> Poppy). Part of run.sh, as the
ROS node ``experiment`` (parameters in the scenario YAML). Running: two robot_sim nodes in
position mode (``/source``, ``/target``), a goal_babbling_learner for the source
(``/source/learner``), two for the target (``/target/learner`` as the thesis, and
``/target/guarded_learner`` with the guard against negative transfer), ``lpa_mapping`` and the
recorder; correspondence_collector has run guided exploration (Alg. 7) for every seed, for the
longest T_guided, and saved the pairs (one file per seed, in the order of ``seeds``). A
shorter T_guided uses the first T_guided · steps_per_second commands: with the same seed and
the robots reset to home the collection is deterministic, so that prefix is what a shorter
run would have collected. (With the collector's ``target_range: own`` the file also holds
the target's rows of the commands the source could not follow: they are the target's own
experience but not correspondences.)

For every seed (its babbling seeds: :func:`lpa_transfer.goal_babbling_experiment.derived_seeds`):

1. The source goal-babbles for ``source_seconds`` from scratch; its experience ξ_s is kept.
2. ``scratch``: the target goal-babbles for ``total_seconds``, evaluated every ``interval`` s.
3. For every T_guided and method (PA, LPA): the mapping service fits the method on the first
   T_guided s of guided-exploration correspondences (q̄, x_s) -> (q̄, x_t); ξ_s is
   transferred through it (with ``transfer_from_guided``, only the part the source babbled
   after T_guided, as §6.5.2 transfers Nao's data from 600 s to 5000 s) and padded with the
   target's home for joints the source lacks (§6.4.1); the target learner is reset and
   initialised with its own guided samples (every command's) and the transferred ones, its
   clock at T_guided, and goal-babbles for the rest of ``total_seconds`` (with a seed of its own: the
   learner restarts its babbler, and the guided exploration's goals should not repeat).
   With ``guarded``, the same again on the guarded learner.

Writes into ``output_dir`` after every seed: ``results.json``, ``learning_curves.csv``,
``fig6_5_task_spaces.png`` (Fig. 6-5; for 3-D robots such as Nao -> Poppy, Fig. 6-9 in three
projections), ``fig6_6_7_learning_curves.png`` (reaching error and rate, mean ± std over seeds,
one column per method; Fig. 6-10 for Nao -> Poppy) and ``report.txt`` (time to reach the
scratch learner's final reaching rate, time saved).
"""
import csv
import json
import sys
import time
from pathlib import Path

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from rclpy.executors import SingleThreadedExecutor  # noqa: E402
from rclpy.node import Node  # noqa: E402

from lpa_transfer.babbling import robot_kinematics  # noqa: E402
from lpa_transfer.correspondences import load_guided_exploration  # noqa: E402
from lpa_transfer.goal_babbling_experiment import derived_seeds  # noqa: E402
from lpa_transfer.kinematics import sample_joint_uniform  # noqa: E402
from lpa_transfer.learning_curves import rank_sum_comparison, time_saved  # noqa: E402
from lpa_transfer.reaching import evaluation_points  # noqa: E402
from lpa_transfer.robot_params import load_robot_params  # noqa: E402
from lpa_transfer.transfer_babbling import padded_rows  # noqa: E402
from lpa_transfer_interfaces.srv import (FitModel, GoalBabble,  # noqa: E402
                                         InitialiseSensorimotor, TransferPoints)
from lpa_transfer_nodes._ros_util import (ServiceCalls, from_matrix, run_job,  # noqa: E402
                                          to_matrix, wait_for_services)

SETTINGS = ("seeds_done", "source_seconds", "total_seconds", "guided_seconds", "interval",
            "methods", "guarded", "reaching_threshold", "transfer_from_guided", "robot_files",
            "target_home", "x_bounds", "eval_spacing", "eval_joint_samples", "steps_per_second",
            "thesis")
THESIS = ("thesis §6.5.1 (Fig. 6-6/6-7, read from the text): transfer boosts learning at "
          "once; LPA helps the final performance when applied at 180 s and beyond, and "
          "transfers negatively from 60 s of guided exploration; PA transfers negatively")


class Experiment(Node):
    def __init__(self, stop):
        super().__init__("experiment")
        self.stop = stop
        declare = lambda name, default: self.declare_parameter(name, default).value  # noqa: E731
        self.robot_files = {side: declare(f"{side}_robot", "") for side in ("source", "target")}
        self.robots = {side: load_robot_params(path) for side, path in self.robot_files.items()}
        self.target_home = list(declare("target_home", [0.0]))
        self.joints = {side: list(declare(f"{side}_joints", [0, 1]))
                       for side in ("source", "target")}
        self.seeds = list(declare("seeds", [0]))
        self.source_seconds = float(declare("source_seconds", 1000.0))
        self.total_seconds = float(declare("total_seconds", 1000.0))
        self.guided_seconds = [float(t) for t in declare("guided_seconds", [60.0])]
        self.interval = float(declare("interval", 60.0))
        self.steps_per_second = float(declare("steps_per_second", 10.0))
        self.methods = list(declare("methods", ["pa", "lpa"]))
        self.guarded = bool(declare("guarded", True))
        self.reaching_threshold = float(declare("reaching_threshold", 0.01))
        self.transfer_from_guided = bool(declare("transfer_from_guided", False))
        self.thesis = declare("thesis", THESIS)
        self.fit = dict(latent_dim=declare("latent_dim", 0), n_min=declare("n_min", 7),
                        c_min=declare("c_min", 1e-7))
        self.x_bounds = (list(declare("x_low", [0.0])), list(declare("x_high", [0.0])))
        self.eval_spacing = float(declare("eval_spacing", 0.05))
        self.eval_joint_samples = declare("eval_joint_samples", 20000)
        self.output_dir = Path(declare("output_dir", "."))
        if not 0 < max(self.guided_seconds) <= self.total_seconds:
            raise ValueError(f"guided_seconds must lie in (0, total_seconds], got "
                             f"{self.guided_seconds}")
        self.spinner = SingleThreadedExecutor()
        self.spinner.add_node(self)
        self.calls = ServiceCalls(self, self.spinner, float(declare("call_timeout", 1800.0)),
                                     stop)
        self.call = self.calls.call
        self.seeds_done = []

    # -- one learner run ---------------------------------------------------------------------
    def learn(self, learner, seed, seconds, own=None, transferred=None, elapsed=0.0):
        """Reset ``learner``, initialise it, babble: (times, errors, rates, experience)."""
        width = self.robots["source" if learner.startswith("/source") else "target"].n_joints + 2
        empty = np.zeros((0, width))
        answer = self.call(InitialiseSensorimotor, f"{learner}/initialise", reset=True,
                           seed=seed, elapsed=float(elapsed),
                           own=to_matrix(empty if own is None else own),
                           transferred=to_matrix(empty if transferred is None else transferred))
        evaluations = [answer.evaluation] if own is not None else []
        babbled = self.call(GoalBabble, f"{learner}/babble", seconds=float(seconds),
                            evaluation_interval=self.interval)
        evaluations += list(babbled.evaluations)
        return ([e.learning_time for e in evaluations], [e.mean_error for e in evaluations],
                [e.reaching_rate for e in evaluations], [e.n_transferred_samples
                                                         for e in evaluations],
                from_matrix(babbled.experience, "experience"))

    def transferred(self, model_id, source_experience):
        """ξ̂_t: the source's (q̄, x_s) through the model, padded with the target's home."""
        n_source = self.robots["source"].n_joints
        rows = np.hstack((source_experience[:, self.joints["source"]],
                          source_experience[:, n_source:]))
        mapped = from_matrix(self.call(TransferPoints, "/lpa_mapping/transfer",
                                       model_id=model_id, source=to_matrix(rows)).target,
                             "target")
        return self.padded(mapped)

    def padded(self, rows):
        """Rows (q̄, x) of the target as (q, x): the joints outside q̄ at the target's home."""
        return np.hstack(padded_rows(rows, self.target_home, self.joints["target"]))

    def run(self, pair_files):
        services = ["/source/learner/babble", "/target/learner/babble", "/lpa_mapping/fit"]
        services += ["/target/guarded_learner/babble"] if self.guarded else []
        wait_for_services([self.calls.client(FitModel if s.endswith("fit") else GoalBabble, s)
                           for s in services], 60, self.stop)
        curves = {}
        for seed, pair_file in zip(self.seeds, pair_files):
            source_seed, target_seed, lpa_seed, after_transfer_seed = derived_seeds(seed)
            *_, source_experience = self.learn("/source/learner", source_seed,
                                               self.source_seconds)
            self.get_logger().info(f"seed {seed}: the source babbled {len(source_experience)} "
                                   f"samples")
            self.record(curves, "scratch", self.learn("/target/learner", target_seed,
                                                      self.total_seconds))
            all_source_pairs, all_target_pairs, guided_experience, followed = \
                load_guided_exploration(pair_file)
            for guided in self.guided_seconds:
                n_commands = int(round(guided * self.steps_per_second))
                if n_commands > len(guided_experience):
                    raise ValueError(f"{pair_file} holds {len(guided_experience)} commands, "
                                     f"fewer than T_guided = {guided:g} s needs ({n_commands})")
                n_pairs = int(followed[:n_commands].sum())    # the correspondences among them
                source_pairs, target_pairs = (all_source_pairs[:n_pairs],
                                              all_target_pairs[:n_pairs])
                own = guided_experience[:n_commands]
                experience = source_experience[n_commands if self.transfer_from_guided else 0:]
                for method in self.methods:
                    model_id = f"seed{seed}/T{guided:g}/{method}"
                    fields = dict(self.fit, random_state=lpa_seed) if method == "lpa" else {}
                    self.call(FitModel, "/lpa_mapping/fit", model_id=model_id, method=method,
                              latent_dim=self.fit["latent_dim"], source=to_matrix(source_pairs),
                              target=to_matrix(target_pairs),
                              **{k: v for k, v in fields.items() if k != "latent_dim"})
                    transferred = self.transferred(model_id, experience)
                    for guarded in (False, True) if self.guarded else (False,):
                        learner = "/target/guarded_learner" if guarded else "/target/learner"
                        name = f"{method.upper()}{'-guarded' if guarded else ''}/T{guided:g}"
                        self.record(curves, name, self.learn(
                            learner, after_transfer_seed, self.total_seconds - guided,
                            own=self.padded(own), transferred=transferred,
                            elapsed=guided))
            self.seeds_done.append(seed)
            write_outputs(curves, self, self.output_dir)
        return curves

    def record(self, curves, name, run):
        times, errors, rates, n_transferred, _ = run
        curves.setdefault(name, []).append(dict(times=times, mean_error=errors, rate=rates,
                                                n_transferred=n_transferred))
        self.get_logger().info(f"{name}: reaching rate " + " ".join(f"{r:.2f}" for r in rates)
                               + f" (final mean error {1e3 * errors[-1]:.1f} mm)")


# --------------------------------------------------------------------------- analysis
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
             f"scratch reaches its final reaching rate {scratch_rate[-1]:.3f} first at "
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
    lines += ["", "'rate after transfer': the first evaluation (right after the transfer; for "
              "scratch, after one interval); '(scratch then)': the scratch learner's mean rate "
              "at that time (0 before its first evaluation)", "",
              "mean reaching rate at every evaluation (learning time in s):",
              f"{'':<22} " + " ".join(f"{x:>5g}" for x in times)]
    lines += every_evaluation + [""] + level_lines(curves, times, scratch_rate) + [""] + \
        comparison_lines(curves, times) + ["", experiment.thesis]
    return lines


def comparison_lines(curves, times):
    """Each condition against scratch at each of scratch's evaluations, over the seeds: the
    share of (run, scratch run) pairs in which the run's reaching rate is higher, and the
    Mann-Whitney p (:func:`lpa_transfer.learning_curves.rank_sum_comparison`; unpaired: a
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


def main(args=None):
    argv = sys.argv if args is None else args
    pair_files = [a for a in argv[1:] if a.endswith(".npz")]
    start = time.perf_counter()

    def experiment(node):
        if len(pair_files) != len(node.seeds):
            raise ValueError(f"give one guided-exploration file per seed ({node.seeds}), got "
                             f"{pair_files}")
        return node.run(pair_files)

    node, curves = run_job("experiment", Experiment, experiment,
                           [a for a in argv if not a.endswith(".npz")])
    text = write_outputs(curves, node, node.output_dir)
    text += f"\nexperiment wall time {time.perf_counter() - start:.0f} s\n"
    (node.output_dir / "report.txt").write_text(text)
    print(text, end="")
    return 0


if __name__ == "__main__":
    sys.exit(main())
