"""Pairing residuals of every scenario's correspondence collection, before and after the
pairing check.

Runs each collection in process, as its node runs it over the graph (the tests check that the
two give the same pairs bit for bit), once the way the collector worked before the pairing
check ("before": a fixed ``steps_per_sample`` a sample, no settling; guided exploration's
source sent the target's commands) and once with today's defaults ("after": settling by state,
:class:`~lpa_transfer.exploration.correspondences.PairCheck`; the guided source takes the
target's reached postures). Both are measured with the check's residual, the check off for
"before" (tolerance inf), so that the table says how far apart the pairs were and how many the
check would have dropped.

* §3.6 arms (two_link_graph/config.yaml) and the user pair (user_pair.yaml):
  ``same_command``, residual = largest difference of the common joints (rad);
* chapter 6 guided exploration: experiment 1 (config.yaml, seed 0's babbling) and Nao -> Poppy
  (nao_poppy.yaml), residual the same, over the movements whose command the source could follow;
* chapter 4 (lfd): ``same_task_point`` through the demonstrator's inverse kinematics (a
  kinematic collection, no physics): residual = ||FK_H(q_H) − x_H|| (m), the poses whose
  point the demonstrator does not reach within ``ik_tolerance`` dropped (unchanged by the
  check, one row: "before" = "after").

Chapter 5 pairs by ``same_time_index`` with 10 steps a sample on both robots: 0 s by
construction (its smoke test asserts it). Usage: ``python -m studies.transfer.pairing_residuals
[--only NAME ...] [--guided-seconds S]``.
"""
import argparse
import time
from pathlib import Path

import numpy as np

from studies.scenario_params import node_params
from lpa_transfer.exploration import (BabblingProgram, PairCheck, SettlingStep,
                                      collect_correspondences, collect_guided_correspondences)
from lpa_transfer.goal_babbling import GoalBabbling, derived_seeds
from lpa_transfer.lfd import (MAX_BATCHES, collect_demonstrator_correspondences, load_setup,
                              task_point_residuals)
from lpa_transfer.robots import (RobotSimulator, load_robot_params, robot_kinematics, robot_urdf,
                                 stepped_environment)

ROOT = Path(__file__).resolve().parents[2]
SCENARIOS = ROOT / "scenarios"
BEFORE = PairCheck(max_settle_steps=0, tolerance=np.inf)     # the collector before the check
AFTER = PairCheck()


def simulators(params, sim_params):
    """side -> (robot params, RobotSimulator) as the scenario's robot_sim nodes build them."""
    out = {}
    for side in ("source", "target"):
        robot = load_robot_params(ROOT / params[f"{side}_robot"])
        sim = sim_params[side]
        out[side] = (robot, RobotSimulator(robot_urdf(robot), control_mode="position",
                                           physics_step=sim.get("physics_step", 1e-3),
                                           initial_positions=sim.get("initial_positions")))
    return out


def summary(metadata, n_pairs, seconds):
    keys = ("pairs_checked", "pairs_dropped", "worst_residual", "residual_unit")
    row = {key: metadata[key] for key in keys}
    row.update(n_pairs=n_pairs, wall_s=seconds)
    return row


def two_link(*files):
    """A ``same_command`` joint_lines collection of the two_link_graph scenario."""
    params = node_params("correspondence_collector", *files)
    sims_params = {side: node_params(f"/{side}/robot_sim", *files) for side in ("source",
                                                                               "target")}
    rows = {}
    for name, check in (("before", BEFORE), ("after", AFTER)):
        sims = simulators(params, sims_params)
        try:
            start = time.perf_counter()
            pairs = collect_correspondences(
                BabblingProgram(params["program"], params["n_segments"],
                                params["samples_per_segment"], params["seed"]),
                params["pairing_rule"], robot_kinematics(sims["source"][0]),
                robot_kinematics(sims["target"][0]), sims["source"][1].step,
                sims["target"][1].step, params["steps_per_sample"],
                tuple(params["features"]), pair_check=check)
            rows[name] = summary(pairs.metadata, len(pairs), time.perf_counter() - start)
        finally:
            for _, sim in sims.values():
                sim.close()
    return rows


def guided(files, seed, seconds):
    """Guided exploration (Alg. 7) of the chapter 6 collector for ``seconds``."""
    params = node_params("guided_exploration", *files)
    sims_params = {side: node_params(f"/{side}/robot_sim", *files) for side in ("source",
                                                                               "target")}
    rows = {}
    for name, check, follows in (("before", BEFORE, "command"), ("after", AFTER, "reached")):
        sims = simulators(params, sims_params)
        try:
            kinematics = {side: robot_kinematics(robot, params.get(f"{side}_home"))
                          for side, (robot, _) in sims.items()}
            settling = SettlingStep(sims["source"][1].step, check)
            babbling = GoalBabbling((tuple(params["x_low"]), tuple(params["x_high"])),
                                    seed=seed, steps_per_second=params["steps_per_second"])
            joints = {side: params.get(f"{side}_joints",
                                       list(range(min(k.n_joints for k in kinematics.values()))))
                      for side in kinematics}
            start = time.perf_counter()
            pairs = collect_guided_correspondences(
                babbling,
                stepped_environment(kinematics["source"], settling, params["steps_per_sample"]),
                stepped_environment(kinematics["target"], sims["target"][1].step,
                                    params["steps_per_sample"]),
                joints["source"], joints["target"], seconds,
                target_range=params.get("target_range", "shared"), source_follows=follows,
                pair_check=check, source_settling=settling)
            rows[name] = summary(pairs.metadata, len(pairs), time.perf_counter() - start)
            rows[name]["median_residual"] = pairs.metadata["median_residual"]
        finally:
            for _, sim in sims.values():
                sim.close()
    return rows


def lfd(n_poses=20000, seed=0):
    """Chapter 4: the demonstrator -> each robot, one babbling batch of ``n_poses`` robot poses
    as run_experiment.py's first batch (collect_pairs' seed ``seed * MAX_BATCHES``):
    the poses whose point the demonstrator's IK reaches within IK_TOLERANCE are the pairs."""
    setup = load_setup(SCENARIOS / "lfd" / "frames.yaml")
    rows = {}
    for name, learner in setup.learners.items():
        start = time.perf_counter()
        pairs = collect_demonstrator_correspondences(
            learner.robot, setup.demonstrator, learner.joint_map, learner.task_frame, n_poses,
            seed * MAX_BATCHES)
        residual = task_point_residuals(setup.demonstrator, pairs.demonstrator,
                                        learner.joint_map.n_joints)
        rows[name] = dict(pairs_checked=pairs.n_tried, pairs_dropped=pairs.n_tried - pairs.n_kept,
                          worst_residual=float(residual.max()), residual_unit="m",
                          n_pairs=pairs.n_kept, wall_s=time.perf_counter() - start)
    return rows


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", nargs="*", default=None)
    parser.add_argument("--guided-seconds", type=float, default=240.0,
                        help="experiment 1's longest T_guided (Nao -> Poppy: 600 s as §6.5.2)")
    parser.add_argument("--lfd-poses", type=int, default=20000)
    args = parser.parse_args()
    gb = SCENARIOS / "goal_babbling"
    jobs = {
        "two_link (thesis arms)": lambda: two_link(SCENARIOS / "two_link_graph" / "config.yaml"),
        "two_link (user pair)": lambda: two_link(SCENARIOS / "two_link_graph" / "config.yaml",
                                                 SCENARIOS / "two_link_graph" / "user_pair.yaml"),
        "ch6 exp1 guided (seed 0)": lambda: guided([gb / "config.yaml"], derived_seeds(0)[1],
                                                   args.guided_seconds),
        "ch6 Nao->Poppy guided (seed 0)": lambda: guided(
            [gb / "nao_poppy.yaml"], derived_seeds(0)[1], 2.5 * args.guided_seconds),
        "ch4 lfd (seed 0, 20 000 poses)": lambda: lfd(args.lfd_poses),
    }
    for name, job in jobs.items():
        if args.only and not any(word in name for word in args.only):
            continue
        for variant, row in job().items():
            print(f"{name:32s} {variant:8s} " + ", ".join(
                f"{k} {v:.3g}" if isinstance(v, float) else f"{k} {v}" for k, v in row.items()),
                flush=True)


if __name__ == "__main__":
    main()
