"""The seeds of one chapter 6 run, apart from the experiment so that a shell script or node
can derive them without importing the learners (scenarios/goal_babbling/run.sh does, once
per seed, to seed guided exploration)."""
import numpy as np

from lpa_transfer import _validation as check


def derived_seeds(seed):
    """Independent integer seeds from one run seed: source babbling, target babbling, LPA,
    and the target's babbling after a transfer where it cannot continue the guided
    exploration's babbling (over the node graph the learner restarts its babbler)."""
    check.check_int(seed, "seed", 0)
    return [int(s.generate_state(1)[0]) for s in np.random.SeedSequence(seed).spawn(4)]
