#!/usr/bin/env python3
"""Thesis §5.5.3 over the node graph: does transfer accelerate online inverse-dynamics learning?

Part of run.sh, as the ROS node ``experiment`` (parameters in the scenario YAML); the robot
simulators, one ``inverse_dynamics_learner`` per robot and star, ``lpa_mapping`` and the
recorder are running, and correspondence_collector has saved the pairs of every seed (source
= the first robot of ``robots``): one file per star, babbled in the star's vicinity, given
seed by seed in the order of ``seeds``; a seed's files are joined.

For every seed: PA and LPA models in both directions from that seed's correspondences, fitted
by the mapping service. For every target robot and star, the conditions of §5.5.3, each a
fresh learner run for ``n_trials`` trials (parameter ``conditions``: which of them run,
default all; learning from scratch always runs, as every other condition is measured against
it):

* ``uninitialised``: learning from scratch. The simulation is deterministic, so with
  ``start_noise`` 0 this curve is the same for every seed: it is run once and reused. With
  ``start_noise`` > 0 (rad) every seed's runs start from the rest pose moved by N(0,
  start_noise) per joint (drawn from the seed, the robot and the star; the same start for all
  conditions of that seed), and learning from scratch runs for every seed too, so that its
  run-to-run spread is measured like the other conditions' (one scratch run is one draw: a
  1 mrad change of the start moves the youBot's final Star 1 error between 2.30 and 2.77 mm,
  bench/README.md);
* ``random``: initialised with the target's own babbling data (its side of the pairs);
* ``transfer-PA`` / ``transfer-LPA``: initialised with the other robot's experience of the
  same star from scratch (its first ``n_source_trials`` trials), transferred through the
  mapping service;
* ``own+transfer-PA`` / ``own+transfer-LPA`` (beyond the thesis): the transferred experience
  and then the target's own babbling data, which it has anyway (it babbled for the
  correspondences, and that time is charged to every initialised condition). Set beside
  ``random`` it measures what the transferred knowledge adds to the target's own data.

The outputs are rewritten after every seed, so an interrupted run keeps what it finished.

Writes into ``output_dir``: ``results.json`` (every curve), ``learning_curves.csv``,
``fig5_7_5_8_learning_curves.png`` (mean ± std per condition, like Fig. 5-7/5-8),
``fig5_6_traces.png`` (first and last trial from scratch on Star 2, like Fig. 5-6) and
``report.txt`` (trials to convergence and training time saved, beside the thesis' numbers).
"""
import csv
import json
import sys
import time
from pathlib import Path

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.ticker import ScalarFormatter  # noqa: E402
import numpy as np  # noqa: E402
from rclpy.executors import SingleThreadedExecutor  # noqa: E402
from rclpy.node import Node  # noqa: E402

from lpa_transfer.correspondences import load_correspondences  # noqa: E402
from lpa_transfer.learning_curves import paired_comparison  # noqa: E402
from lpa_transfer.robot_params import load_robot_params  # noqa: E402
from lpa_transfer_interfaces.msg import TrialResult  # noqa: E402
from lpa_transfer_interfaces.srv import (FitModel, InitialiseLearner, RunTrials,  # noqa: E402
                                         TransferPoints)
from lpa_transfer_nodes._ros_util import (ServiceCalls, from_matrix, run_job,  # noqa: E402
                                          to_matrix, wait_for_services)

CONDITIONS = ("uninitialised", "random", "transfer-PA", "transfer-LPA", "own+transfer-PA",
              "own+transfer-LPA")
SETTINGS = ("robots", "stars", "n_trials", "tolerance", "babbling_seconds",  # in results.json
            "start_noise")
TRIAL_SECONDS = 8.4
BOOTSTRAP_RESAMPLES = 2000
OTHER_TOLERANCES = (0.05, 0.2)   # the report's check of how the verdict depends on it
THESIS = {"youbot": "Star 1: 9 trials from scratch, 4 with transfer; Star 2: > 20 and 5; "
                    "63% of training time saved (random init: 4.6%)",
          "pincher": "58.7% of training time saved (random init: 15.8%)"}


class Experiment(Node):
    def __init__(self, stop):
        super().__init__("experiment")
        self.stop = stop
        declare = lambda name, default: self.declare_parameter(name, default).value  # noqa: E731
        self.robots = list(declare("robots", ["youbot", "pincher"]))
        files = list(declare("robot_files", [""]))
        self.n_joints = {robot: load_robot_params(path).n_joints
                         for robot, path in zip(self.robots, files)}
        self.stars = list(declare("stars", ["star1", "star2"]))
        self.seeds = list(declare("seeds", [0]))
        self.conditions = list(declare("conditions", list(CONDITIONS)))
        unknown = sorted(set(self.conditions) - set(CONDITIONS))
        if unknown:
            raise ValueError(f"unknown conditions {unknown}; known: {list(CONDITIONS)}")
        self.n_trials = declare("n_trials", 20)
        self.n_source_trials = declare("n_source_trials", 15)
        self.fit = dict(latent_dim=declare("latent_dim", 16), n_min=declare("n_min", 40),
                        c_min=declare("c_min", 1e-7))
        self.tolerance = declare("convergence_tolerance", 0.1)
        self.babbling_seconds = declare("babbling_seconds", 14.4)
        self.start_noise = float(declare("start_noise", 0.0))
        if not (np.isfinite(self.start_noise) and self.start_noise >= 0):
            raise ValueError(f"start_noise must be a finite angle >= 0 (rad), got "
                             f"{self.start_noise}")
        self.output_dir = Path(declare("output_dir", "."))
        self.timeout = float(declare("call_timeout", 600.0))
        self.spinner = SingleThreadedExecutor()
        self.spinner.add_node(self)
        self.calls = ServiceCalls(self, self.spinner, self.timeout, stop)
        self.client, self.call = self.calls.client, self.calls.call
        self.traces = {}
        for robot in self.robots:
            self.create_subscription(TrialResult, f"/{robot}/trial_result", self.on_trial, 50)
        self.recording = None
        self.done_seeds = []

    def on_trial(self, msg):
        if self.recording is not None:
            self.recording.append(msg)

    # -- one learner run --------------------------------------------------------------------
    def learn(self, robot, star, initial_data, start_offset=()):
        """Reset the learner, initialise it, run the trials from the centre pose plus
        ``start_offset``: (errors, experience, messages)."""
        learner = f"/{robot}/{star}"
        self.call(InitialiseLearner, f"{learner}/initialise", samples=to_matrix(initial_data),
                  reset=True)
        self.recording = []
        answer = self.call(RunTrials, f"{learner}/run_trials", n_trials=self.n_trials,
                           start_offset=[float(v) for v in start_offset])
        deadline = time.monotonic() + 5
        while len(self.recording) < self.n_trials and time.monotonic() < deadline:
            self.spinner.spin_once(timeout_sec=0.05)
        messages, self.recording = self.recording, None
        return (list(answer.tracking_errors), from_matrix(answer.experience, "experience"),
                messages)

    def transfer(self, model_id, points):
        answer = self.call(TransferPoints, "/lpa_mapping/transfer", model_id=model_id,
                           source=to_matrix(points))
        return from_matrix(answer.target, "target")

    def fit_models(self, seed, pairs):
        """PA and LPA in both directions; model ids like 'youbot->pincher/lpa/seed0'."""
        for source, target in (self.robots, self.robots[::-1]):
            for method in ("pa", "lpa"):
                model_id = f"{source}->{target}/{method}/seed{seed}"
                fields = dict(latent_dim=self.fit["latent_dim"], random_state=seed)
                if method == "lpa":
                    fields.update(n_min=self.fit["n_min"], c_min=self.fit["c_min"],
                                  cluster_dims=list(range(2 * self.n_joints[source])))
                answer = self.call(FitModel, "/lpa_mapping/fit", model_id=model_id,
                                   method=method, source=to_matrix(pairs[source]),
                                   target=to_matrix(pairs[target]), **fields)
                self.get_logger().info(answer.message)

    def run(self, pair_files):
        wait_for_services([self.client(RunTrials, f"/{r}/{s}/run_trials")
                           for r in self.robots for s in self.stars]
                          + [self.client(FitModel, "/lpa_mapping/fit")], 60, self.stop)
        run = [c for c in CONDITIONS if c == "uninitialised" or c in self.conditions]
        curves = {f"{r}/{s}/{c}": [] for r in self.robots for s in self.stars for c in run}
        tasks = [(robot, star) for robot in self.robots for star in self.stars]
        scratch = {}
        per_seed = len(pair_files) // len(self.seeds)
        for index, seed in enumerate(self.seeds):
            offsets = {task: self.start_offset(seed, *task) for task in tasks}
            if self.start_noise > 0 or index == 0:   # else deterministic: the same every seed
                for task in tasks:
                    scratch[task] = self.from_scratch(seed, *task, offsets[task])
            sides = [load_correspondences(path)
                     for path in pair_files[index * per_seed:(index + 1) * per_seed]]
            pairs = {robot: np.vstack([side[k] for side in sides])
                     for k, robot in enumerate(self.robots)}
            self.fit_models(seed, pairs)
            for target in self.robots:
                source = next(r for r in self.robots if r != target)
                for star in self.stars:
                    data = {"random": pairs[target]}
                    for method in ("PA", "LPA"):
                        if not {f"transfer-{method}", f"own+transfer-{method}"} & set(run):
                            continue
                        transferred = self.transfer(
                            f"{source}->{target}/{method.lower()}/seed{seed}",
                            scratch[source, star][1])
                        data[f"transfer-{method}"] = transferred
                        data[f"own+transfer-{method}"] = np.vstack(   # own babbling last
                            (transferred, pairs[target]))
                    for condition in run[1:]:
                        initial = data[condition]
                        errors, _, _ = self.learn(target, star, initial,
                                                  offsets[target, star])
                        curves[f"{target}/{star}/{condition}"].append(errors)
                        self.get_logger().info(f"seed {seed} {target} {star} {condition}: "
                                               f"{_mm(errors)}")
            self.done_seeds.append(seed)
            for robot, star in tasks:
                curves[f"{robot}/{star}/uninitialised"].append(scratch[robot, star][0])
            write_outputs(curves, self.traces, self, self.output_dir)   # results so far
        return curves

    def start_offset(self, seed, robot, star):
        """The seed's joint offsets of the start pose (empty with ``start_noise`` 0)."""
        if self.start_noise == 0:
            return np.zeros(0)
        rng = np.random.default_rng([seed, self.robots.index(robot), self.stars.index(star)])
        return rng.normal(0.0, self.start_noise, self.n_joints[robot])

    def from_scratch(self, seed, robot, star, offset):
        """Learning from scratch: (errors, its first ``n_source_trials`` trials' experience);
        the traces of the first seed's run are kept for Fig. 5-6."""
        empty = np.zeros((0, 4 * self.n_joints[robot]))
        errors, experience, messages = self.learn(robot, star, empty, offset)
        self.traces.setdefault((robot, star), [_trace(messages[0]), _trace(messages[-1])])
        self.get_logger().info(f"seed {seed} {robot} {star} from scratch: {_mm(errors)}")
        return errors, experience[:self.n_source_trials * len(experience) // self.n_trials]


def _mm(errors):
    return " ".join(f"{1e3 * e:.1f}" for e in errors) + " mm"


def _trace(msg):
    return {"trial": msg.trial, "desired": from_matrix(msg.desired, "desired").tolist(),
            "actual": from_matrix(msg.actual, "actual").tolist()}


# --------------------------------------------------------------------------- analysis
def trials_to_convergence(curve, reference_final, tolerance, stay=True):
    """First trial (1-based) from which the error stays within (1 + tolerance) of the scratch
    learner's final error (``stay=False``: the first trial within it); len(curve) + 1 when
    there is none."""
    threshold = (1 + tolerance) * reference_final
    curve = np.asarray(curve)
    if not stay:
        within = np.flatnonzero(curve <= threshold)
        return int(within[0]) + 1 if len(within) else len(curve) + 1
    above = np.flatnonzero(curve > threshold)
    return 1 if len(above) == 0 else int(above[-1]) + 2


def conditions_in(curves):
    """The CONDITIONS that ``curves`` holds, in their order (results written before a
    condition existed lack it)."""
    present = {key.rsplit("/", 1)[1] for key in curves}
    return [c for c in CONDITIONS if c in present]


def convergence_table(curves, robots, stars, tolerance, babbling_seconds, stay=True):
    """Per target robot: trials to convergence per star and condition (mean curves; ``stay``
    as in :func:`trials_to_convergence`), and the training time saved against learning from
    scratch, as §5.5.3 computes it."""
    rows, savings, conditions = [], {}, conditions_in(curves)
    for robot in robots:
        seconds = {c: 0.0 for c in conditions}
        for star in stars:
            mean = {c: np.mean(curves[f"{robot}/{star}/{c}"], axis=0) for c in conditions}
            final = mean["uninitialised"][-1]
            for condition in conditions:
                k = trials_to_convergence(mean[condition], final, tolerance, stay)
                rows.append((robot, star, condition, k, len(mean[condition])))
                seconds[condition] += k * TRIAL_SECONDS
        for condition in conditions[1:]:
            seconds[condition] += babbling_seconds
        savings[robot] = {c: 1 - seconds[c] / seconds["uninitialised"] for c in conditions[1:]}
    return rows, savings


def bootstrap_savings(curves, robots, stars, tolerance, babbling_seconds, n_resamples=2000,
                      seed=0, reference="random"):
    """How sure the time saved is, given the seeds: :func:`convergence_table`'s savings over
    ``n_resamples`` resamples of the seeds (drawn with replacement, the same seeds for every
    condition, as every seed ran all of them). Per target robot and initialised condition:
    ``(low, high, beats)``, the 2.5 and 97.5 percentiles of its saving and the share of
    resamples in which it saves more than, as much as and less than ``reference`` (nan for
    ``reference`` itself)."""
    n_seeds = len(next(iter(curves.values())))
    rng = np.random.default_rng(seed)
    draws = {}
    for _ in range(n_resamples):
        picks = rng.integers(n_seeds, size=n_seeds)
        _, savings = convergence_table({key: np.asarray(runs)[picks] for key, runs in
                                        curves.items()}, robots, stars, tolerance,
                                       babbling_seconds)
        for robot, saved in savings.items():
            for condition, value in saved.items():
                draws.setdefault(robot, {}).setdefault(condition, []).append(value)
    summary = {}
    for robot, by_condition in draws.items():
        base = np.asarray(by_condition.get(reference, np.nan))
        summary[robot] = {c: (*np.percentile(v, [2.5, 97.5]), *(
            (np.mean(np.asarray(v) > base), np.mean(np.asarray(v) == base),
             np.mean(np.asarray(v) < base)) if c != reference and reference in by_condition
            else 3 * (float("nan"),))) for c, v in by_condition.items()}
    return summary


def paired_against(curves, robots, stars, early_trials=5, reference="random"):
    """Each initialised condition against ``reference`` seed by seed (a seed's conditions
    share its start and its babbling, so they pair): per robot, star and condition, for the
    mean error over the first ``early_trials`` trials and over all trials, ``(lower, n, p)``:
    in how many of the ``n`` seeds the condition's error is below the reference's, and
    :func:`lpa_transfer.learning_curves.paired_comparison`'s p (Wilcoxon signed-rank)."""
    def compare(ours, theirs):
        _, lower, n, p = paired_comparison(ours, theirs)
        return lower, n, p

    table = {}
    for robot in robots:
        for star in stars:
            base = np.asarray(curves[f"{robot}/{star}/{reference}"])
            for condition in conditions_in(curves)[1:]:
                if condition == reference:
                    continue
                runs = np.asarray(curves[f"{robot}/{star}/{condition}"])
                table[robot, star, condition] = (
                    compare(runs[:, :early_trials].mean(1), base[:, :early_trials].mean(1)),
                    compare(runs.mean(1), base.mean(1)))
    return table


def paired_lines(curves, robots, stars, early_trials=5, reference="random"):
    """The report's lines of :func:`paired_against`."""
    lines = [f"paired over seeds against {reference}: seeds in which the condition's mean error "
             f"is lower / seeds (Wilcoxon signed-rank p), over trials 1-{early_trials} and over "
             f"all trials"]
    for (robot, star, condition), (early, whole) in paired_against(
            curves, robots, stars, early_trials, reference).items():
        lines.append(f"  {robot:<9} {star:<6} {condition:<16} " + ",  ".join(
            f"{lower:>2}/{n} (p {p:.3f})" for lower, n, p in (early, whole)))
    return lines


def simulated_seconds(curves, experiment):
    """Simulated time per robot: its trials (learning from scratch runs once, whatever the
    number of seeds, unless ``start_noise`` > 0) and the babbling of every seed."""
    once = experiment.start_noise == 0
    trials = sum(len(runs[0]) if once and key.endswith("/uninitialised")
                 else sum(map(len, runs)) for key, runs in curves.items() if runs)
    return (trials * TRIAL_SECONDS / len(experiment.robots)
            + len(experiment.done_seeds) * experiment.babbling_seconds)


def write_outputs(curves, traces, experiment, out):
    out.mkdir(parents=True, exist_ok=True)
    (out / "results.json").write_text(json.dumps({
        "settings": {key: getattr(experiment, key) for key in SETTINGS},
        "curves_m": curves, "seeds": experiment.done_seeds,
        "traces": {f"{r}/{s}": t for (r, s), t in traces.items()}}) + "\n")
    with open(out / "learning_curves.csv", "w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(["target", "star", "condition", "seed", "trial", "tracking_error_m"])
        for key, runs in curves.items():
            robot, star, condition = key.split("/")
            for seed, errors in zip(experiment.done_seeds, runs):
                writer.writerows([robot, star, condition, seed, trial + 1, repr(error)]
                                 for trial, error in enumerate(errors))
    plot_curves(curves, experiment, out / "fig5_7_5_8_learning_curves.png")
    plot_traces(traces, experiment, out / "fig5_6_traces.png")
    args = (curves, experiment.robots, experiment.stars, experiment.tolerance,
            experiment.babbling_seconds)
    rows, savings = convergence_table(*args)
    first_rows, first_savings = convergence_table(*args, stay=False)
    intervals = bootstrap_savings(*args, n_resamples=BOOTSTRAP_RESAMPLES)
    other = {t: convergence_table(curves, experiment.robots, experiment.stars, t,
                                  experiment.babbling_seconds)[1] for t in OTHER_TOLERANCES}
    lines = [f"Thesis §5.5.3 over the node graph: {len(experiment.done_seeds)} seed(s) "
             f"({', '.join(map(str, experiment.done_seeds))}), "
             f"{experiment.n_trials} trials a condition. Converged: the mean error stays within "
             f"{experiment.tolerance:.0%} of learning from scratch's final error; 'first "
             f"within': the first trial within it", "",
             f"{'target':<9} {'star':<6} {'condition':<16} {'converged':>9} {'first within':>12}"
             f"   tracking error (mm, mean ± std over seeds): trial 1, trials 1-5, all, last"]
    for (r, s, c, k, n), (*_, first, _) in zip(rows, first_rows):
        runs = 1e3 * np.asarray(curves[f"{r}/{s}/{c}"])
        early, whole = runs[:, :5].mean(axis=1), runs.mean(axis=1)
        lines.append(f"{r:<9} {s:<6} {c:<16} {k if k <= n else f'> {n}':>9} "
                     f"{first if first <= n else f'> {n}':>12}   "
                     f"{runs[:, 0].mean():5.2f} ± {runs[:, 0].std():4.2f}, "
                     f"{early.mean():5.2f} ± {early.std():4.2f}, "
                     f"{whole.mean():5.2f} ± {whole.std():4.2f}, "
                     f"{runs[:, -1].mean():5.2f} ± {runs[:, -1].std():4.2f}")
    lines.append("")
    for robot in savings:
        lines.append(f"{robot} as target, training time saved (trials x 8.4 s, + "
                     f"{experiment.babbling_seconds:g} s babbling for initialised runs), "
                     f"converged: " + ", ".join(f"{c} {100 * v:.1f}%"
                                                for c, v in savings[robot].items()))
        lines.append("  first within: " + ", ".join(f"{c} {100 * v:.1f}%"
                                                    for c, v in first_savings[robot].items()))
        lines.append(f"  converged within {' / '.join(f'{t:.0%}' for t in OTHER_TOLERANCES)} "
                     f"of scratch's final error instead: " + ", ".join(
                         f"{c} " + " / ".join(f"{100 * other[t][robot][c]:.1f}"
                                              for t in OTHER_TOLERANCES) + "%"
                         for c in savings[robot]))
        lines.append(f"  95% interval over seeds (bootstrap, {BOOTSTRAP_RESAMPLES} resamples of "
                     f"the seeds), converged: " + ", ".join(
                         f"{c} [{100 * low:.1f}, {100 * high:.1f}]%"
                         for c, (low, high, *_) in intervals[robot].items()))
        lines.append("  share of resamples saving more / as much / less than random: "
                     + ", ".join(f"{c} {100 * more:.0f}/{100 * same:.0f}/{100 * less:.0f}%"
                                 for c, (_, _, more, same, less) in intervals[robot].items()
                                 if c != "random"))
        lines.append(f"  thesis: {THESIS.get(robot, '-')}")
    lines.append("")
    if "random" in conditions_in(curves):
        lines += paired_lines(curves, experiment.robots, experiment.stars) + [""]
    lines.append(f"simulated: {simulated_seconds(curves, experiment):.0f} s per robot (trials of "
                 f"{TRIAL_SECONDS} s, learning from scratch "
                 f"{'for every seed' if experiment.start_noise else 'once'}, plus the babbling)")
    text = "\n".join(lines) + "\n"
    (out / "report.txt").write_text(text)
    return text


def plot_curves(curves, experiment, path):
    fig, axes = plt.subplots(len(experiment.robots), len(experiment.stars), squeeze=False,
                             figsize=(6 * len(experiment.stars), 4.2 * len(experiment.robots)),
                             constrained_layout=True)
    for row, robot in enumerate(experiment.robots):
        for col, star in enumerate(experiment.stars):
            ax = axes[row, col]
            for condition in conditions_in(curves):
                runs = np.asarray(curves[f"{robot}/{star}/{condition}"]) * 1e3
                trials = np.arange(1, runs.shape[1] + 1)
                mean, std = runs.mean(axis=0), runs.std(axis=0)
                line, = ax.plot(trials, mean, marker="o", ms=3, label=condition,
                                linestyle="--" if condition.startswith("own+") else "-")
                ax.fill_between(trials, mean - std, mean + std, color=line.get_color(),
                                alpha=0.15)
            final = np.mean(curves[f"{robot}/{star}/uninitialised"], axis=0)[-1] * 1e3
            ax.axhline((1 + experiment.tolerance) * final, color="black", linewidth=0.8,
                       linestyle=":", label=f"converged: within {experiment.tolerance:.0%} "
                                            f"of scratch's final")
            ax.set(title=f"{robot} learning {star}", xlabel="trial",
                   ylabel="tracking error (mm, log scale)", yscale="log")
            ax.yaxis.set_major_formatter(ScalarFormatter())   # 2, 3, 5 mm, not 2×10⁰
            ax.yaxis.set_minor_formatter(ScalarFormatter())
            ax.grid(True, which="both", alpha=0.3)
            ax.legend()
    fig.suptitle(f"Thesis Fig. 5-7/5-8: mean ± std over {len(experiment.done_seeds)} seed(s) "
                 f"(a trial is 8.4 s)")
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_traces(traces, experiment, path):
    star = experiment.stars[-1]
    fig, axes = plt.subplots(1, len(experiment.robots), squeeze=False,
                             figsize=(6 * len(experiment.robots), 5), constrained_layout=True)
    for ax, robot in zip(axes[0], experiment.robots):
        first, last = traces[robot, star]
        desired = np.asarray(first["desired"])
        ax.plot(desired[:, 0], desired[:, 1], "k--", lw=1, label="desired")
        for trace, style in ((first, "tab:red"), (last, "tab:blue")):
            actual = np.asarray(trace["actual"])
            ax.plot(actual[:, 0], actual[:, 1], color=style, lw=1,
                    label=f"trial {trace['trial']}")
        ax.set(title=f"{robot}, {star}, learning from scratch", xlabel="x (m)",
               ylabel="y (m)", aspect="equal")
        ax.legend()
    fig.suptitle("Thesis Fig. 5-6: end effector in the first and last trial")
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(args=None):
    argv = sys.argv if args is None else args
    pair_files = [a for a in argv[1:] if a.endswith(".npz")]
    start = time.perf_counter()

    def experiment(node):
        if not pair_files or len(pair_files) % len(node.seeds):
            raise ValueError(f"give the same number of correspondence files for every seed "
                             f"({node.seeds}), got {pair_files}")
        return node.run(pair_files)

    node, curves = run_job("experiment", Experiment, experiment,
                           [a for a in argv if not a.endswith(".npz")])
    text = write_outputs(curves, node.traces, node, node.output_dir)
    text += f"\nexperiment wall time {time.perf_counter() - start:.0f} s\n"
    (node.output_dir / "report.txt").write_text(text)
    print(text, end="")
    return 0


if __name__ == "__main__":
    sys.exit(main())
