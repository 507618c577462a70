"""Planar serial-chain kinematics and domain data for the thesis' 2-link example (§3.6).

In the illustrative example (§3.6, Table 3.1) each robot is a planar chain with its base at
the origin; a domain point is z = (x, y) = (q, end-effector position), i.e. joint angles as
inputs and the end-effector position as outputs of the forward kinematics, and source and
target points correspond when they share the same joint angles q.
Pure numpy; ``q`` holds relative joint angles in rad, lengths are in m.
"""
import dataclasses
from dataclasses import dataclass
from typing import Callable

import numpy as np

from lpa_transfer import _validation as check
from lpa_transfer.robots.serial_chain import forward_kinematics


def _joint_matrix(q, n_joints, name="q"):
    q = np.asarray(q, dtype=np.float64)
    if q.ndim != 2 or q.shape[1] != n_joints:
        raise ValueError(f"{name} must have shape (N, {n_joints}) (one row of {n_joints} joint "
                         f"angles per sample), got shape {q.shape}")
    if not np.isfinite(q).all():
        raise ValueError(f"{name} contains NaN or infinite values")
    return q


def _link_lengths(link_lengths):
    lengths = np.asarray(link_lengths, dtype=np.float64)
    if lengths.ndim != 1 or lengths.size == 0:
        raise ValueError(f"link_lengths must be a non-empty 1-D sequence, got shape "
                         f"{lengths.shape}")
    if not (np.isfinite(lengths).all() and (lengths > 0).all()):
        raise ValueError(f"link_lengths must be finite and positive, got {lengths}")
    return lengths


def planar_forward_kinematics(q, link_lengths):
    """End-effector positions (N, 2) of a planar serial chain with its base at the origin.

    Link i points along the absolute angle q[:, 0] + ... + q[:, i] (relative joint angles),
    so q = 0 stretches the chain along +x. This is the forward kinematics the source and
    target robots of §3.6 (Table 3.1) learn.
    """
    lengths = _link_lengths(link_lengths)
    absolute = np.cumsum(_joint_matrix(q, lengths.size), axis=1)
    return np.column_stack((np.cos(absolute) @ lengths, np.sin(absolute) @ lengths))


def home_pose(joint_limits, positions=None, name="home pose"):
    """The given pose (checked: one finite value per joint, within the limits) or, when none
    is given, zero clipped into the limits — the pose a robot starts from (simulator, babbling).
    ``name`` says in error messages whose pose it is."""
    limits = np.asarray(joint_limits, dtype=np.float64)
    if positions is None or len(positions) == 0:
        return np.clip(np.zeros(len(limits)), limits[:, 0], limits[:, 1])
    home = np.asarray(positions, dtype=np.float64)
    if home.shape != (len(limits),) or not np.isfinite(home).all():
        raise ValueError(f"{name} needs {len(limits)} finite joint values, got {positions}")
    if ((home < limits[:, 0]) | (home > limits[:, 1])).any():
        raise ValueError(f"{name} {home.tolist()} lies outside the joint limits "
                         f"{limits.tolist()}")
    return home


def overlapping_limits(limits_a, limits_b, joints="the joints"):
    """(n, 2) intersection of two robots' (n, 2) ranges of corresponding joints; ValueError
    naming ``joints`` when a range is empty."""
    limits_a, limits_b = (np.asarray(limits, dtype=np.float64) for limits in (limits_a, limits_b))
    lower = np.maximum(limits_a[:, 0], limits_b[:, 0])
    upper = np.minimum(limits_a[:, 1], limits_b[:, 1])
    if (lower > upper).any():
        raise ValueError(f"{joints}' ranges do not overlap (lower {lower.tolist()}, upper "
                         f"{upper.tolist()})")
    return np.column_stack((lower, upper))


def sample_joint_uniform(n_samples, joint_limits, rng):
    """``n_samples`` joint vectors (N, n) drawn uniformly in the box ``joint_limits`` (n, 2).

    The thesis generates its training, test and ground-truth sets this way (§3.6: "10 000
    uniformly generated points"). ``rng`` is a ``numpy.random.Generator``.
    """
    if isinstance(n_samples, bool) or not isinstance(n_samples, (int, np.integer)) \
            or n_samples < 0:
        raise ValueError(f"n_samples must be a non-negative integer, got {n_samples!r}")
    limits = np.asarray(joint_limits, dtype=np.float64)
    if limits.ndim != 2 or limits.shape[1] != 2 or limits.shape[0] == 0:
        raise ValueError(f"joint_limits must have shape (n_joints, 2) of (lower, upper), got "
                         f"shape {limits.shape}")
    if not np.isfinite(limits).all() or (limits[:, 0] > limits[:, 1]).any():
        raise ValueError(f"joint_limits must be finite with lower <= upper, got {limits}")
    if not isinstance(rng, np.random.Generator):
        raise ValueError(f"rng must be a numpy.random.Generator, got {type(rng).__name__}")
    return rng.uniform(limits[:, 0], limits[:, 1], size=(int(n_samples), len(limits)))


def domain_data(q, link_lengths):
    """Domain points z = (x, y) = (q, fk(q)), shape (N, n + 2) (§3.6: d = m = 2 for 2 links).

    Calling it with the same ``q`` for the source and the target robot yields the
    correspondences of §3.6 (pairs that share a joint-space position).
    """
    return np.hstack((np.asarray(q, dtype=np.float64), planar_forward_kinematics(q, link_lengths)))


def end_effector_rmse(predicted, true):
    """RMSE of positions (m): sqrt(mean over points of ||predicted − true||²).

    The error measure of Fig. 3-6 and Fig. 3-8, for both the mapping error (transferred vs.
    true target end-effector) and the model error (forward-kinematics predictions).
    """
    predicted, true = np.asarray(predicted, dtype=np.float64), np.asarray(true, dtype=np.float64)
    if predicted.ndim != 2 or predicted.shape != true.shape or len(true) == 0:
        raise ValueError(f"predicted and true must be non-empty (N, D) arrays of the same "
                         f"shape, got {predicted.shape} and {true.shape}")
    return float(np.sqrt(np.mean(np.sum((predicted - true) ** 2, axis=1))))


@dataclass(frozen=True)
class Kinematics:
    """What a babbling program needs to know of a robot.

    ``joint_limits`` (n, 2) rad, ``home`` (n,) the pose babbling starts from, ``forward``
    maps joint vectors (N, n) to task points (N, m). ``task_box`` ((low), (high)), if set, is
    where this robot's task-space babbling happens (robots of different sizes babble in their
    own boxes, §5.4.1); it replaces the program's ``task_low``/``task_high``.
    ``execute`` (Q) -> (Q_observed, X), if set, runs commands on a robot that may not reach
    them exactly (:func:`lpa_transfer.robots.environment.stepped_environment`); see
    :func:`execute`.
    """

    joint_limits: np.ndarray
    home: np.ndarray
    forward: Callable[[np.ndarray], np.ndarray]
    task_box: tuple = None
    execute: Callable = None

    @property
    def n_joints(self):
        return len(self.joint_limits)


def execute(environment, commands):
    """Run joint commands (N, n) on ``environment``: (observed joint positions (N, n),
    observed task points (N, m)). A kinematic environment (no ``execute``) reaches every
    command exactly, so the positions are the commands and the points their ``forward``."""
    commands = np.atleast_2d(np.asarray(commands, dtype=np.float64))
    if environment.execute is None:
        return commands, np.asarray(environment.forward(commands), dtype=np.float64)
    positions, points = environment.execute(commands)
    return np.asarray(positions, dtype=np.float64), np.asarray(points, dtype=np.float64)


def planar_kinematics(robot, home=None):
    """:class:`Kinematics` of a planar chain (``RobotParams``): task space (x, y)."""
    lengths = np.array(robot.link_lengths, dtype=np.float64)
    return Kinematics(np.array(robot.joint_limits, dtype=np.float64),
                      home_pose(robot.joint_limits, home),
                      lambda q: planar_forward_kinematics(q, lengths))


def robot_kinematics(robot, home=None):
    """:class:`Kinematics` of any robot file: planar chains in (x, y)
    (:func:`planar_kinematics`), serial chains in world (x, y, z)
    (:func:`lpa_transfer.robots.serial_chain.forward_kinematics`)."""
    if robot.kind == "planar":
        return planar_kinematics(robot, home)
    return Kinematics(np.array(robot.joint_limits, dtype=np.float64),
                      home_pose(robot.joint_limits, home),
                      lambda q: forward_kinematics(robot, q))


def check_joints(joints, n_joints, name="shared_joints"):
    """``joints`` as an int array of distinct indices in [0, n_joints); ValueError if not."""
    indices = np.asarray(joints)
    if indices.ndim != 1 or indices.size == 0 or not np.issubdtype(indices.dtype, np.integer):
        raise ValueError(f"{name} must be a non-empty 1-D sequence of joint indices, got "
                         f"{joints!r}")
    if len(np.unique(indices)) != len(indices) or indices.min() < 0 or indices.max() >= n_joints:
        raise ValueError(f"{name} must hold distinct joint indices in [0, {n_joints}), got "
                         f"{indices.tolist()}")
    return indices


def pad_transferred(q_shared, home, shared_joints):
    """Commands (N, d_t) for all the target's joints: ``q_shared`` (N, d_c) in the columns
    ``shared_joints``, the target's ``home`` (d_t,) values in the others (§6.4.1)."""
    home = np.asarray(home, dtype=np.float64)
    if home.ndim != 1 or not np.isfinite(home).all():
        raise ValueError(f"home must be a 1-D array of finite joint values, got {home.tolist()}")
    shared_joints = check_joints(shared_joints, len(home))
    q_shared = check.as_matrix(q_shared, "q_shared")
    if q_shared.shape[1] != len(shared_joints):
        raise ValueError(f"q_shared has {q_shared.shape[1]} columns but {len(shared_joints)} "
                         f"shared joints are given")
    full = np.tile(home, (len(q_shared), 1))
    full[:, shared_joints] = q_shared
    return full


def restrict(robot, joints, joint_limits=None):
    """The robot (a Kinematics) seen through its ``joints`` only: commands (N, len(joints)),
    the other joints held at home. ``joint_limits`` (len(joints), 2) narrows the ranges
    (default: the robot's own); the home is clipped into them."""
    joints = check_joints(joints, robot.n_joints, "joints")
    limits = np.asarray(robot.joint_limits, dtype=np.float64)[joints]
    if joint_limits is not None:
        given = np.asarray(joint_limits, dtype=np.float64)
        if given.shape != limits.shape or not np.isfinite(given).all() \
                or (given[:, 0] > given[:, 1]).any():
            raise ValueError(f"joint_limits must be {len(joints)} finite (lower, upper) pairs "
                             f"with lower <= upper, got {given.tolist()}")
        limits = given
    home = np.asarray(robot.home, dtype=np.float64)
    run = None
    if robot.execute is not None:            # a robot: observe the shared joints it reached
        def run(q):
            positions, points = robot.execute(pad_transferred(q, home, joints))
            return np.asarray(positions)[:, joints], points
    return Kinematics(limits, np.clip(home[joints], limits[:, 0], limits[:, 1]),
                      lambda q: robot.forward(pad_transferred(q, home, joints)), robot.task_box,
                      run)


def hold_at_home(robot, joints):
    """The robot (a Kinematics) with only ``joints`` free: the other joints' ranges shrink to
    their home values, so every command, clipped into the ranges as goal babbling does
    (Alg. 6), holds them at home. Unlike :func:`restrict`, commands and observations keep all
    d joints. §6.5.2 transfers "Nao data generated by the 4 joints it has in common with
    Poppy": the source explores like this, so that its experience lies where guided
    exploration (which holds those joints at home too) paired its poses."""
    joints = check_joints(joints, robot.n_joints, "joints")
    limits = np.array(robot.joint_limits, dtype=np.float64)
    home = np.asarray(robot.home, dtype=np.float64)
    held = np.setdiff1d(np.arange(robot.n_joints), joints)
    limits[held] = home[held, None]
    return dataclasses.replace(robot, joint_limits=limits)


def arm_kinematics(arm, n_joints, home=None, name="arm"):
    """A RobotParams or :class:`~lpa_transfer.robots.kinematics.Kinematics` seen through its first
    ``n_joints`` joints, the others held at ``home`` (default: the Kinematics' own home, or
    zero clipped into a robot file's limits)."""
    if isinstance(arm, Kinematics):
        if home is not None:
            arm = dataclasses.replace(arm, home=home_pose(arm.joint_limits, home, f"{name} home"))
    else:
        arm = robot_kinematics(arm, home_pose(arm.joint_limits, home, f"{name} home"))
    if arm.n_joints < n_joints:
        raise ValueError(f"the {name} has {arm.n_joints} joints, fewer than the "
                         f"{n_joints} of the joint map")
    return restrict(arm, np.arange(n_joints))
