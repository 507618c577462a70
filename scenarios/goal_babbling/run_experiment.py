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

For every seed (its babbling seeds: :func:`lpa_transfer.goal_babbling.seeds.derived_seeds`):

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
import sys
import time
from pathlib import Path

import matplotlib
matplotlib.use("Agg")
import numpy as np  # noqa: E402
from rclpy.executors import SingleThreadedExecutor  # noqa: E402
from rclpy.node import Node  # noqa: E402

from lpa_transfer.exploration import load_guided_exploration  # noqa: E402
from lpa_transfer.goal_babbling import derived_seeds, padded_rows  # noqa: E402
from lpa_transfer.goal_babbling.report import write_outputs  # noqa: E402
from lpa_transfer.robots import load_robot_params  # noqa: E402
from lpa_transfer_interfaces.action import GoalBabble  # noqa: E402
from lpa_transfer_interfaces.srv import InitialiseSensorimotor  # noqa: E402
from lpa_transfer_nodes.calls import ServiceCalls, wait_for_services  # noqa: E402
from lpa_transfer_nodes.conversions import from_matrix, to_matrix  # noqa: E402
from lpa_transfer_nodes.entry import run_job  # noqa: E402
from lpa_transfer_nodes.params import declare, describe_use_sim_time  # noqa: E402
from lpa_transfer_nodes.mapping_client import MappingClient  # noqa: E402

THESIS = ("thesis §6.5.1 (Fig. 6-6/6-7, read from the text): transfer boosts learning at "
          "once; LPA helps the final performance when applied at 180 s and beyond, and "
          "transfers negatively from 60 s of guided exploration; PA transfers negatively")


class Experiment(Node):
    def __init__(self, stop):
        super().__init__("experiment")
        self.stop = stop
        seconds = dict(range=(0.0, None), finite=True)
        self.robot_files = {side: declare(self, f"{side}_robot", "", f"the {side} robot's "
                                          f"parameter file; required")
                            for side in ("source", "target")}
        self.robots = {side: load_robot_params(path) for side, path in self.robot_files.items()}
        self.target_home = list(declare(self, "target_home", [0.0], "the target's q_home "
                                        "(rad): transferred rows are padded with it for the "
                                        "joints the source lacks"))
        self.joints = {side: list(declare(self, f"{side}_joints", [0, 1], "the shared joints "
                                          "(source_joints[i] is target_joints[i]): the "
                                          f"{side}'s joint columns in the transferred rows"))
                       for side in ("source", "target")}
        self.seeds = list(declare(self, "seeds", [0], "experiment seeds (each derives its "
                                  "babbling seeds); one guided-exploration .npz argument each, "
                                  "in this order"))
        self.source_seconds = declare(self, "source_seconds", 1000.0, "simulated s the source "
                                      "goal-babbles from scratch: its experience", **seconds)
        self.total_seconds = declare(self, "total_seconds", 1000.0, "the target's learning "
                                     "time in every condition (simulated s)", **seconds)
        self.guided_seconds = [float(t) for t in declare(
            self, "guided_seconds", [60.0], "T_guided values (simulated s of guided "
            "exploration before transfer)", additional_constraints="each in (0, total_seconds]")]
        self.interval = declare(self, "interval", 60.0, "simulated s between evaluations of "
                                "the learners", **seconds)
        self.steps_per_second = declare(self, "steps_per_second", 10.0, "movement steps a "
                                        "simulated second: T_guided uses the first T_guided * "
                                        "steps_per_second commands of guided exploration",
                                        positive=True, finite=True)
        self.methods = list(declare(self, "methods", ["pa", "lpa"], "the transfer methods",
                                    additional_constraints="from pa, lpa"))
        self.guarded = declare(self, "guarded", True, "also run every transfer condition on "
                               "/target/guarded_learner (the guard against negative transfer)")
        self.yielding = declare(self, "yielding", False, "also run every transfer condition on "
                                "/target/yielding_learner (transferred samples yield to the "
                                "own ones)")
        self.reaching_threshold = declare(self, "reaching_threshold", 0.01, "the learners' "
                                          "reaching threshold (m), for the report",
                                          range=(0.0, None), finite=True)
        self.transfer_from_guided = declare(self, "transfer_from_guided", False, "transfer "
                                            "only the source experience babbled after "
                                            "T_guided (as thesis §6.5.2 does)")
        self.thesis = declare(self, "thesis", THESIS, "the thesis' result, quoted in the report")
        self.fit = dict(
            latent_dim=declare(self, "latent_dim", 0, "the mapping's latent dimension (0: "
                               "all)", range=(0, None)),
            n_min=declare(self, "n_min", 7, "LPA's N_min (0: the service's default)",
                          range=(0, None)),
            c_min=declare(self, "c_min", 1e-7, "LPA's c_min", range=(0.0, None)))
        self.x_bounds = tuple(list(declare(self, f"x_{end}", [0.0], f"X_bounds' {end} corner "
                                           "(m): the target's task box, for the report's "
                                           "figures and test points"))
                              for end in ("low", "high"))
        self.eval_spacing = declare(self, "eval_spacing", 0.05, "the test points' grid "
                                    "spacing (m), for the report", positive=True, finite=True)
        self.eval_joint_samples = declare(self, "eval_joint_samples", 20000, "the joint "
                                          "samples that find the reachable grid points, for "
                                          "the report", range=(1, None))
        self.output_dir = Path(declare(self, "output_dir", ".", "where results.json, "
                                       "learning_curves.csv, the figures and report.txt go"))
        call_timeout = declare(self, "call_timeout", 1800.0, "s a single service call may "
                               "take (a babble call runs for minutes)", range=(0.0, None))
        describe_use_sim_time(self)
        if not 0 < max(self.guided_seconds) <= self.total_seconds:
            raise ValueError(f"guided_seconds must lie in (0, total_seconds], got "
                             f"{self.guided_seconds}")
        self.spinner = SingleThreadedExecutor()
        self.spinner.add_node(self)
        self.calls = ServiceCalls(self, self.spinner, call_timeout, stop)
        self.call = self.calls.call
        self.mapping = MappingClient(self, timeout=call_timeout, executor=self.spinner,
                                     stop=stop)
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
        babbled = self.calls.run(GoalBabble, f"{learner}/babble", self.on_feedback(learner),
                                 seconds=float(seconds), evaluation_interval=self.interval)
        evaluations += list(babbled.evaluations)
        return ([e.learning_time for e in evaluations], [e.mean_error for e in evaluations],
                [e.reaching_rate for e in evaluations], [e.n_transferred_samples
                                                         for e in evaluations],
                from_matrix(babbled.experience, "experience"))

    def on_feedback(self, learner):
        """Progress: the babble action's feedback at every evaluation, logged."""
        def log(feedback):
            e = feedback.evaluation
            self.get_logger().info(
                f"{learner}: t = {e.learning_time:g} s ({feedback.steps_done}/"
                f"{feedback.n_steps} steps), reaching rate {100 * e.reaching_rate:.1f} %, "
                f"mean error {1e3 * e.mean_error:.1f} mm")
        return log

    def transferred(self, model_id, source_experience):
        """ξ̂_t: the source's (q̄, x_s) through the model, padded with the target's home."""
        n_source = self.robots["source"].n_joints
        rows = np.hstack((source_experience[:, self.joints["source"]],
                          source_experience[:, n_source:]))
        return self.padded(self.mapping.transfer(model_id, rows))

    def padded(self, rows):
        """Rows (q̄, x) of the target as (q, x): the joints outside q̄ at the target's home."""
        return np.hstack(padded_rows(rows, self.target_home, self.joints["target"]))

    def run(self, pair_files):
        services = ["/source/learner/babble", "/target/learner/babble", "/lpa_mapping/fit"]
        services += [f"/target/{variant}_learner/babble" for variant in self.variants()[1:]]
        wait_for_services([self.mapping.client("fit") if s.endswith("fit")
                           else self.calls.action_client(GoalBabble, s) for s in services],
                          60, self.stop, self.spinner)
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
                    self.mapping.fit(model_id, source_pairs, target_pairs, method=method,
                                     latent_dim=self.fit["latent_dim"],
                                     source_robot=self.robots["source"].name,
                                     target_robot=self.robots["target"].name,
                                     **{k: v for k, v in fields.items() if k != "latent_dim"})
                    transferred = self.transferred(model_id, experience)
                    for variant in self.variants():
                        learner = f"/target/{variant + '_' if variant else ''}learner"
                        name = f"{method.upper()}{'-' + variant if variant else ''}/T{guided:g}"
                        self.record(curves, name, self.learn(
                            learner, after_transfer_seed, self.total_seconds - guided,
                            own=self.padded(own), transferred=transferred,
                            elapsed=guided))
            self.seeds_done.append(seed)
            write_outputs(curves, self, self.output_dir)
        return curves

    def variants(self):
        """The target's learners of the transfer conditions: "" (the thesis'), "guarded",
        "yielding"."""
        return [""] + ["guarded"] * self.guarded + ["yielding"] * self.yielding

    def record(self, curves, name, run):
        times, errors, rates, n_transferred, _ = run
        curves.setdefault(name, []).append(dict(times=times, mean_error=errors, rate=rates,
                                                n_transferred=n_transferred))
        self.get_logger().info(f"{name}: reaching rate " + " ".join(f"{r:.2f}" for r in rates)
                               + f" (final mean error {1e3 * errors[-1]:.1f} mm)")


# --------------------------------------------------------------------------- analysis


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
