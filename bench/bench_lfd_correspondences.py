"""Collecting human -> robot correspondences (thesis §4.4.2): the demonstrator's IK for every
babbled robot point, solved one point at a time (inverse_kinematics.solve) or all at once
(inverse_kinematics.solve_many, what collect_demonstrator_correspondences uses), on the Meka and the PR2
of scenarios/lfd/frames.yaml; then the whole collect_pairs for 20 000 pairs.

    python -m bench.bench_lfd_correspondences [--points 1000] [--pairs 20000]
"""
import argparse
import time
from pathlib import Path

import numpy as np

from lpa_transfer.robots.inverse_kinematics import solve, solve_many
from lpa_transfer.robots.kinematics import sample_joint_uniform
from lpa_transfer.robots.kinematics import arm_kinematics
from lpa_transfer.lfd.correspondences import babbling_limits
from lpa_transfer.lfd.experiment import collect_pairs, load_setup

ROOT = Path(__file__).resolve().parents[1]


def ik_problem(learner, demonstrator, n, seed=0):
    """The demonstrator's IK problems of n babbled robot poses: (forward, targets, starts,
    limits)."""
    robot = arm_kinematics(learner.robot, 4)
    human = arm_kinematics(demonstrator, 4)
    q = sample_joint_uniform(n, babbling_limits(robot, human, learner.joint_map),
                             np.random.default_rng(seed))
    limits = human.joint_limits
    starts = np.clip(learner.joint_map.to_demonstrator(q), limits[:, 0], limits[:, 1])
    return human.forward, learner.task_frame.to_demonstrator(robot.forward(q)), starts, limits


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--points", type=int, default=1000)
    parser.add_argument("--pairs", type=int, default=20000)
    args = parser.parse_args()
    setup = load_setup(ROOT / "scenarios" / "lfd" / "frames.yaml", ROOT)
    for name, learner in setup.learners.items():
        forward, targets, starts, limits = ik_problem(learner, setup.demonstrator, args.points)
        started = time.perf_counter()
        one = [solve(forward, x, q, limits) for x, q in zip(targets, starts)]
        single = time.perf_counter() - started
        started = time.perf_counter()
        _, residuals = solve_many(forward, targets, starts, limits)
        batched = time.perf_counter() - started
        single_residuals = np.array([r for _, r in one])
        kept = single_residuals <= 1e-4      # collect_demonstrator_correspondences' default ik_tolerance
        same = np.abs(single_residuals - residuals)[kept].max(initial=0.0)
        flipped = int((kept != (residuals <= 1e-4)).sum())
        started = time.perf_counter()
        _, _, tried = collect_pairs(learner, setup.demonstrator, args.pairs, seed=0)
        pairs = time.perf_counter() - started
        print(f"{name}: IK of {args.points} points: solve {single:.2f} s "
              f"({1e3 * single / args.points:.2f} ms/point), solve_many {batched:.2f} s "
              f"({single / batched:.1f}x; on the {kept.sum()} reached points residuals agree "
              f"to {same:.1e} m, {flipped} kept/dropped decisions differ); "
              f"collect_pairs({args.pairs}): {pairs:.1f} s ({tried} poses babbled)")


if __name__ == "__main__":
    main()
