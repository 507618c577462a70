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
  studies/inverse_dynamics/README.md);
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
import sys
import time
from pathlib import Path
from types import SimpleNamespace

import matplotlib
matplotlib.use("Agg")
import numpy as np  # noqa: E402
from rclpy.executors import SingleThreadedExecutor  # noqa: E402
from rclpy.node import Node  # noqa: E402

from lpa_transfer.exploration import load_correspondences, read_correspondences  # noqa: E402
from lpa_transfer.inverse_dynamics.analysis import CONDITIONS  # noqa: E402
from lpa_transfer.inverse_dynamics import INTERPOLATIONS, interpolated, summary_lines  # noqa: E402
from lpa_transfer.inverse_dynamics.report import SETTINGS, write_outputs  # noqa: E402
from lpa_transfer.robots import load_robot_params  # noqa: E402
from lpa_transfer_interfaces.msg import TrialResult  # noqa: E402
from lpa_transfer_interfaces.action import RunTrials  # noqa: E402
from lpa_transfer_interfaces.srv import InitialiseLearner  # noqa: E402
from lpa_transfer_nodes.calls import ServiceCalls, wait_for_services  # noqa: E402
from lpa_transfer_nodes.conversions import from_matrix, to_matrix  # noqa: E402
from lpa_transfer_nodes.entry import run_job  # noqa: E402
from lpa_transfer_nodes.params import declare, describe_use_sim_time  # noqa: E402
from lpa_transfer_nodes.mapping_client import MappingClient  # noqa: E402


class Experiment(Node):
    def __init__(self, stop):
        super().__init__("experiment")
        self.stop = stop
        describe_use_sim_time(self)
        d = lambda *args, **kwargs: declare(self, *args, **kwargs)  # noqa: E731
        self.robots = list(d("robots", ["youbot", "pincher"], "the two robots' names (their "
                             "namespaces); the first is the babbling's source"))
        files = list(d("robot_files", [""], "their robot parameter files, in that order"))
        self.n_joints = {robot: load_robot_params(path).n_joints
                         for robot, path in zip(self.robots, files)}
        self.targets = list(d("targets", self.robots, "the robots that learn with transfer "
                              "(the other gives its experience); default: both"))
        if not self.targets or set(self.targets) - set(self.robots):
            raise ValueError(f"the parameter targets must name some of the robots "
                             f"{self.robots}, got {self.targets}")
        self.stars = list(d("stars", ["star1", "star2"], "the stars (learner nodes /<robot>/"
                            "<star>)"))
        self.seeds = list(d("seeds", [0], "the experiment seeds, one pair file per star each"))
        self.conditions = list(d("conditions", list(CONDITIONS), "the initialisations run "
                                 f"beside learning from scratch, of {list(CONDITIONS)}"))
        unknown = sorted(set(self.conditions) - set(CONDITIONS))
        if unknown:
            raise ValueError(f"unknown conditions {unknown}; known: {list(CONDITIONS)}")
        self.n_trials = d("n_trials", 20, "trials of each condition", range=(1, None))
        self.n_source_trials = d("n_source_trials", 15, "trials of the source's experience "
                                 "from scratch that are transferred", range=(1, None))
        self.fit = dict(
            latent_dim=d("latent_dim", 16, "PA/LPA latent dimensions", range=(1, None)),
            n_min=d("n_min", 40, "LPA's n_min (Alg. 3)", range=(1, None)),
            c_min=d("c_min", 1e-7, "LPA's c_min (Alg. 3)", positive=True, finite=True))
        self.tolerance = d("convergence_tolerance", 0.1, "converged: within this share of "
                           "learning from scratch's final error", positive=True, finite=True)
        self.babbling_seconds = d("babbling_seconds", 14.4, "babbling time (s) charged to "
                                  "every initialised condition", range=(0.0, None), finite=True)
        self.start_noise = float(d("start_noise", 0.0, "rad; > 0: each seed's runs start from "
                                   "the rest pose moved by N(0, start_noise) per joint",
                                   range=(0.0, None), finite=True))
        # §5.4.1: 'spline' reads q̇, τ and q̈ off smoothing splines per babbling line (pairs)
        # and per trial (the source's experience) before the fit and the transfer
        # (lpa_transfer.inverse_dynamics.interpolation; reference_results/ablation, Factor 4)
        self.interpolation = d("interpolation", "none", "none: the pairs and the experience "
                               "as sampled; spline: read off smoothing cubic splines (§5.4.1)",
                               choices=list(INTERPOLATIONS))
        self.line_samples = d("babbling_line_samples", 60, "samples of one babbling line "
                              "(/babbling/* samples_per_segment): one spline each",
                              range=(1, None))
        self.control_period = 1.0 / d("control_rate", 100.0, "the learners' control rate "
                                      "(Hz): the splines' sample period", positive=True,
                                      finite=True)
        self.output_dir = Path(d("output_dir", ".", "where the results, figures and report "
                                 "go"))
        self.timeout = float(d("call_timeout", 600.0, "seconds for each service call (a "
                               "run_trials call lasts minutes)", positive=True))
        self.spinner = SingleThreadedExecutor()
        self.spinner.add_node(self)
        self.calls = ServiceCalls(self, self.spinner, self.timeout, stop)
        self.mapping = MappingClient(self, timeout=self.timeout, executor=self.spinner,
                                     stop=stop)
        self.client, self.call = self.calls.client, self.calls.call
        self.traces = {}
        self.recording = {}            # robot -> its trial results while one of it runs
        for robot in self.robots:
            self.create_subscription(TrialResult, f"/{robot}/trial_result",
                                     lambda msg, robot=robot: self.on_trial(robot, msg), 50)
        self.done_seeds = []

    def on_trial(self, robot, msg):
        if robot in self.recording:
            self.recording[robot].append(msg)

    @staticmethod
    def progress(label):
        """Progress of the run ``label``: the run_trials action's feedback after every trial."""
        def show(feedback):
            print(f"  {label}: trial {feedback.trial}/{feedback.n_trials} tracking error "
                  f"{1e3 * feedback.tracking_error:.2f} mm", flush=True)
        return show

    # -- learner runs -----------------------------------------------------------------------
    def learn(self, runs):
        """Learner runs ``(robot, star, initial_data, start_offset, yielding, label)`` of
        different robots at once (each robot has its own simulator, so they run in parallel):
        reset and initialise each learner (``yielding``: InitialiseLearner's), run its trials
        from the centre pose plus ``start_offset``; one (errors, experience, messages) per
        run."""
        robots = [robot for robot, *_ in runs]
        assert len(set(robots)) == len(robots), "one run per robot at a time"
        for robot, star, initial_data, _, yielding, _ in runs:
            self.call(InitialiseLearner, f"/{robot}/{star}/initialise",
                      samples=to_matrix(initial_data), reset=True, yielding=yielding)
        self.recording = {robot: [] for robot in robots}
        answers = self.calls.run_many(RunTrials, [
            (f"/{robot}/{star}/run_trials", self.progress(label),
             dict(n_trials=self.n_trials, start_offset=[float(v) for v in offset]))
            for robot, star, _, offset, _, label in runs])
        deadline = time.monotonic() + 5
        while (any(len(m) < self.n_trials for m in self.recording.values())
               and time.monotonic() < deadline):
            self.spinner.spin_once(timeout_sec=0.05)
        recorded, self.recording = self.recording, {}
        return [(list(answer.tracking_errors), from_matrix(answer.experience, "experience"),
                 recorded[robot]) for answer, robot in zip(answers, robots)]

    def transfer(self, model_id, points):
        return self.mapping.transfer(model_id, points)

    def fit_models(self, seed, pairs, methods):
        """PA and/or LPA (``methods``) towards every target robot; model ids like
        'youbot->pincher/lpa/seed0'."""
        for source, target in (self.robots, self.robots[::-1]):
            if target not in self.targets:
                continue
            for method in methods:
                model_id = f"{source}->{target}/{method}/seed{seed}"
                fields = dict(latent_dim=self.fit["latent_dim"], random_state=seed)
                if method == "lpa":
                    fields.update(n_min=self.fit["n_min"], c_min=self.fit["c_min"],
                                  cluster_dims=list(range(2 * self.n_joints[source])))
                answer = self.mapping.fit(model_id, pairs[source], pairs[target],
                                          method=method, source_robot=source,
                                          target_robot=target, **fields)
                self.get_logger().info(answer.message)

    def run(self, pair_files):
        wait_for_services([self.calls.action_client(RunTrials, f"/{r}/{s}/run_trials")
                           for r in self.robots for s in self.stars]
                          + [self.mapping.client("fit")], 60, self.stop,
                          self.spinner)
        run = [c for c in CONDITIONS if c == "uninitialised" or c in self.conditions]
        curves = {f"{r}/{s}/{c}": [] for r in self.targets for s in self.stars for c in run}
        tasks = [(robot, star) for robot in self.robots for star in self.stars]
        scratch = {}
        per_seed = len(pair_files) // len(self.seeds)
        for index, seed in enumerate(self.seeds):
            offsets = {task: self.start_offset(seed, *task) for task in tasks}
            if self.start_noise > 0 or index == 0:   # else deterministic: the same every seed
                for star in self.stars:                     # the robots side by side
                    scratch.update(self.from_scratch(seed, star, offsets))
            files = pair_files[index * per_seed:(index + 1) * per_seed]
            if self.interpolation != "none":
                self.check_whole_lines(files)
            sides = [load_correspondences(path) for path in files]
            pairs = {robot: interpolated(np.vstack([side[k] for side in sides]),
                                         self.interpolation, self.line_samples,
                                         self.control_period)
                     for k, robot in enumerate(self.robots)}
            methods = [m for m in ("pa", "lpa") if any(f"transfer-{m.upper()}" in c
                                                         for c in run)]
            self.fit_models(seed, pairs, methods)
            data = {}
            for target in self.targets:
                source = next(r for r in self.robots if r != target)
                for star in self.stars:
                    data[target, star] = {"random": pairs[target]}
                    for method in ("PA", "LPA"):
                        if not {f"transfer-{method}", f"own+transfer-{method}",
                                f"transfer-{method}-yielding"} & set(run):
                            continue
                        experience = scratch[source, star][1]
                        transferred = self.transfer(
                            f"{source}->{target}/{method.lower()}/seed{seed}",
                            interpolated(experience, self.interpolation,
                                         len(experience) // self.n_source_trials,
                                         self.control_period))
                        data[target, star][f"transfer-{method}"] = transferred
                        data[target, star][f"own+transfer-{method}"] = np.vstack(
                            (transferred, pairs[target]))                  # own babbling last
                        # the same data as a prior that yields to the own experience
                        data[target, star][f"transfer-{method}-yielding"] = transferred
            # every learner meets its conditions in the same order as alone; the targets'
            # runs of a star and condition go side by side
            for star in self.stars:
                for condition in run[1:]:
                    batch = [(target, star, data[target, star][condition],
                              offsets[target, star], condition.endswith("-yielding"),
                              f"seed {seed} {target} {star} {condition}")
                             for target in self.targets]
                    for (target, *_, label), (errors, _, _) in zip(batch, self.learn(batch)):
                        curves[f"{target}/{star}/{condition}"].append(errors)
                        self.get_logger().info(f"{label}: {_mm(errors)}")
            self.done_seeds.append(seed)
            for robot, star in tasks:
                if robot in self.targets:
                    curves[f"{robot}/{star}/uninitialised"].append(scratch[robot, star][0])
            write_outputs(curves, self.traces, self.reported(), self.output_dir)   # so far
        return curves

    def check_whole_lines(self, files):
        """Splines run per babbling line: refuse pair files whose rows are not whole lines
        of ``babbling_line_samples`` (a dropped pair would shift every line after it)."""
        for path in files:
            pairs = read_correspondences(path)
            dropped, rows = int(pairs.metadata.get("pairs_dropped", 0)), len(pairs)
            if dropped or rows % self.line_samples:
                raise ValueError(f"{path}: {rows} pairs, {dropped} dropped: not whole babbling "
                                 f"lines of {self.line_samples} samples, which interpolation "
                                 f"{self.interpolation!r} needs")

    def reported(self):
        """The settings the outputs describe: the target robots only (a source that only
        gives its experience has no conditions of its own to report)."""
        if self.targets == self.robots:
            return self
        return SimpleNamespace(**{key: getattr(self, key) for key in SETTINGS
                                  if key != "robots"},
                               robots=self.targets, done_seeds=self.done_seeds)

    def start_offset(self, seed, robot, star):
        """The seed's joint offsets of the start pose (empty with ``start_noise`` 0)."""
        if self.start_noise == 0:
            return np.zeros(0)
        rng = np.random.default_rng([seed, self.robots.index(robot), self.stars.index(star)])
        return rng.normal(0.0, self.start_noise, self.n_joints[robot])

    def from_scratch(self, seed, star, offsets):
        """Every robot learning ``star`` from scratch, side by side: {(robot, star): (errors,
        its first ``n_source_trials`` trials' experience)}; the traces of the first seed's
        run are kept for Fig. 5-6."""
        batch = [(robot, star, np.zeros((0, 4 * self.n_joints[robot])), offsets[robot, star],
                  False, f"seed {seed} {robot} {star} from scratch") for robot in self.robots]
        done = {}
        for (robot, *_, label), (errors, experience, messages) in zip(batch, self.learn(batch)):
            self.traces.setdefault((robot, star), [_trace(messages[0]), _trace(messages[-1])])
            self.get_logger().info(f"{label}: {_mm(errors)}")
            done[robot, star] = (errors, experience[:self.n_source_trials * len(experience)
                                                     // self.n_trials])
        return done


def _mm(errors):
    return " ".join(f"{1e3 * e:.1f}" for e in errors) + " mm"


def _trace(msg):
    return {"trial": msg.trial, "desired": from_matrix(msg.desired, "desired").tolist(),
            "actual": from_matrix(msg.actual, "actual").tolist()}


# --------------------------------------------------------------------------- analysis


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
    text = write_outputs(curves, node.traces, node.reported(), node.output_dir)
    text += f"\nexperiment wall time {time.perf_counter() - start:.0f} s\n"
    (node.output_dir / "report.txt").write_text(text)
    print("\n".join(summary_lines(curves, node.reported())), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
