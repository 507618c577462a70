"""How much of Poppy's test grid Nao's experience can teach at all (thesis §6.5.2, Nao -> Poppy,
in process on the analytic arms): ceilings on the reaching rate that data confined to some
poses can give, next to what transfer reaches right after guided exploration.

    nice -n 10 python -m studies.goal_babbling.nao_poppy_coverage --seeds 0 1 2

The setting is nao_poppy.yaml's, built by nao_poppy_rates.py (4 movements a simulated
second). Printed, as shares of the test points within the reaching threshold (0.015 m):

- Poppy with all 5 joints, and with its torso at home (Poppy's own ranges of the 4 shared
  joints), and with its torso at home and the shared joints in the ranges both robots have
  (all four, all but one, only one: which range binds): estimated from 400 000 uniform
  joint samples (seed 0) each;
- per seed, Nao's experience from 600 s to 5000 s transferred by LPA: where Poppy's
  kinematics put the transferred commands (what a perfect k-NN over the transferred data
  could reach), where LPA says they are, and the reaching rate of the k-NN model holding the
  guided pairs and the transferred data (the "LPA" condition at 600 s). Not run in CI: a seed
  takes ~30 s.
"""
import argparse
import dataclasses

from studies.goal_babbling.nao_poppy_rates import model_after_guided, prepare

import numpy as np  # noqa: E402

from lpa_transfer.robots import hold_at_home  # noqa: E402
from lpa_transfer.exploration import shared_limits  # noqa: E402
from lpa_transfer.goal_babbling import coverage, evaluate_reaching, reachable_share  # noqa: E402

N_JOINT_SAMPLES = 400000


def ceilings(setup):
    """(label, share) of the test points Poppy reaches with all joints, torso at home, and
    torso at home within the shared joints' common ranges — all of them, all but one, and
    only one (which range binds)."""
    target, source = setup.arms["target"], setup.arms["source"]
    joints = setup.shared["target"]
    torso_home = hold_at_home(target, joints)
    own = np.array(torso_home.joint_limits)
    common = own.copy()
    common[joints] = shared_limits(source, target, setup.shared["source"], joints)

    def within(limits):
        return dataclasses.replace(torso_home, joint_limits=limits)

    arms = [("all 5 joints", target), ("torso at home", torso_home),
            ("torso at home, common ranges", within(common))]
    for joint in joints:
        all_but, only = common.copy(), own.copy()
        all_but[joint], only[joint] = own[joint], common[joint]
        arms += [(f"  common ranges but joint {joint}'s own", within(all_but)),
                 (f"  own ranges but joint {joint}'s common", within(only))]
    return [(label, reachable_share(arm, setup.points, setup.threshold, N_JOINT_SAMPLES))
            for label, arm in arms]


def transferred(setup):
    """(label, share) for the transferred data of one seed (module docstring)."""
    target = setup.arms["target"]
    rate = evaluate_reaching(model_after_guided(setup, "LPA").inverse, target, setup.points,
                             setup.threshold).rate
    return [("transferred commands executed", coverage(
                setup.points, target.forward(setup.commands), setup.threshold)),
            ("transferred points as mapped", coverage(
                setup.points, setup.task_points, setup.threshold)),
            ("LPA model at 600 s (reaching rate)", rate)]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[0])
    args = parser.parse_args()
    first = True
    for seed in args.seeds:
        setup = prepare(4.0, seed)
        if first:
            print(f"{len(setup.points)} test points, threshold {setup.threshold} m")
            for label, share in ceilings(setup):
                print(f"  {label:<38}{share:6.3f}")
            first = False
        print(f"seed {seed}: {len(setup.commands)} transferred samples")
        for label, share in transferred(setup):
            print(f"  {label:<38}{share:6.3f}")


if __name__ == "__main__":
    main()
