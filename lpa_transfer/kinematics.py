"""Planar serial-chain kinematics and domain data for the thesis' 2-link example (§3.6).

In the illustrative example (§3.6, Table 3.1) each robot is a planar chain with its base at
the origin; a domain point is z = (x, y) = (q, end-effector position), i.e. joint angles as
inputs and the end-effector position as outputs of the forward kinematics, and source and
target points correspond when they share the same joint angles q.
Pure numpy; ``q`` holds relative joint angles in rad, lengths are in m.
"""
import numpy as np


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
