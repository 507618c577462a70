"""The §3.6 robots (thesis Table 3.1) as a test fixture: correspondences by joint angles."""
from functools import lru_cache
from pathlib import Path

import numpy as np

from lpa_transfer.robots.kinematics import Kinematics
from lpa_transfer.robots.kinematics import (domain_data, planar_forward_kinematics,
                                            sample_joint_uniform)

SOURCE_LINKS, TARGET_LINKS = (0.3, 0.25), (0.6, 0.2)
JOINT_LIMITS = [(0.0, np.pi / 2), (0.0, np.pi)]
ROBOTS_DIR = Path(__file__).resolve().parents[1] / "scenarios" / "robots"


@lru_cache(maxsize=None)
def robot(name):
    """The RobotParams of ``scenarios/robots/<name>.toml`` (e.g. "two_link_source")."""
    from lpa_transfer.robots.params import load_robot_params

    return load_robot_params(ROBOTS_DIR / f"{name}.toml")


def correspondences(n, seed, target_links=TARGET_LINKS):
    q = sample_joint_uniform(n, JOINT_LIMITS, np.random.default_rng(seed))
    return domain_data(q, SOURCE_LINKS), domain_data(q, target_links)


def mapping_rmse_mm(model, source_test, target_test):
    """RMSE (mm) of the transferred end-effector positions (columns 2-3)."""
    error = model.transfer(source_test)[:, 2:] - target_test[:, 2:]
    return 1000 * np.sqrt((error ** 2).sum(axis=1).mean())


def elbow_ik(points, links, joint_limits=JOINT_LIMITS):
    """Closed-form inverse kinematics of a planar 2-link arm with elbow angle q2 in [0, π]:
    ``(q, reachable)``, ``reachable`` where the distance lies in the annulus of the links and
    q lies within ``joint_limits`` (q is NaN off the annulus)."""
    points = np.atleast_2d(np.asarray(points, dtype=np.float64))
    (l1, l2), limits = links, np.asarray(joint_limits, dtype=np.float64)
    r2 = (points ** 2).sum(axis=1)
    cos_q2 = (r2 - l1 ** 2 - l2 ** 2) / (2 * l1 * l2)
    with np.errstate(invalid="ignore"):
        q2 = np.arccos(cos_q2)
    q1 = np.arctan2(points[:, 1], points[:, 0]) - np.arctan2(l2 * np.sin(q2),
                                                             l1 + l2 * np.cos(q2))
    q = np.column_stack(((q1 + np.pi) % (2 * np.pi) - np.pi, q2))   # q1 in [-π, π)
    tolerance = 1e-9
    with np.errstate(invalid="ignore"):
        reachable = (np.abs(cos_q2) <= 1) & ((q >= limits[:, 0] - tolerance)
                                             & (q <= limits[:, 1] + tolerance)).all(axis=1)
    return q, reachable


# -- the 2-link arms of the goal-babbling experiment (thesis Table 6.1) -------------------------
#: Table 6.1: link lengths (m) and the joint limits (rad) both arms share.
GB_SOURCE_LINKS, GB_TARGET_LINKS = (0.5, 0.5), (0.7, 0.4)
TABLE_6_1_LIMITS = np.array([(-np.pi / 2, 0.0), (0.4, 2.9)])
GB_HOME = TABLE_6_1_LIMITS.mean(axis=1)   # our choice: the middle of the ranges
#: the target's task box (bounding box of its workspace, rounded out)
GB_TARGET_BOUNDS = ((0.1, -1.1), (1.1, 0.4))


def table_6_1_arm(links, home=GB_HOME):
    """A Table 6.1 arm as a Kinematics (the environment goal babbling explores)."""
    return Kinematics(TABLE_6_1_LIMITS, np.asarray(home, dtype=np.float64),
                      lambda q: planar_forward_kinematics(q, links))
