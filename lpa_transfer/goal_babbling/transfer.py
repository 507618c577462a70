"""Transfer of goal-babbling experience between robots (thesis ch. 6, §6.4-§6.5).

The pipeline of §6.4 (Fig. 6-3): guided exploration (Alg. 7,
:mod:`lpa_transfer.exploration.guided`) gives correspondences (q̄, x_s) ~ (q̄, x_t); a domain
mapping f (PA, Alg. 1-2, or LPA, Alg. 3-4) is fitted on them; the source's experience
ξ_s = {(q̄, x_s)} is mapped through f and padded with the target's home values for the joints
the source lacks (§6.4.1, :func:`transfer_experience`); the estimate ξ̂_t initialises the
target's sensorimotor model (:func:`initialise_with_transfer`), and the target goes on with
goal babbling (Alg. 6).

:class:`lpa_transfer.goal_babbling.negative_transfer.GuardedModel` takes the transferred samples with lower
weight and retires them; :mod:`lpa_transfer.goal_babbling.experiment` runs experiment 1.
"""
import numpy as np

from lpa_transfer import _validation as check
from lpa_transfer.goal_babbling.negative_transfer import GuardedModel
from lpa_transfer.goal_babbling.yielding import YieldingModel
from lpa_transfer.learners.sensorimotor import make_sensorimotor_model
from lpa_transfer.robots.kinematics import check_joints, pad_transferred


def transfer_experience(mapping, source_experience, target_home, shared_joints):
    """ξ̂_t = pad(f(ξ_s)) (§6.4.1): the source's experience in the target's domain.

    ``mapping`` is a PA or LPA fitted on guided-exploration pairs (q̄, x_s) -> (q̄, x_t);
    ``source_experience`` (N, d_c + m) holds rows (q̄, x_s) in that layout (the source's
    shared joints, then its task point). Each row is mapped (Alg. 2 or 4) and the mapped q̄
    are padded with the target's ``target_home`` (d_t,) in the joints not in
    ``shared_joints`` (the target's indices of the d_c shared joints, in q̄'s order).
    Returns ``(commands (N, d_t), points (N, m))``.
    """
    shared_joints = check_joints(shared_joints, len(np.atleast_1d(target_home)))
    mapped = mapping.transfer(check.as_matrix(source_experience, "source_experience"))
    if mapped.shape[1] <= len(shared_joints):
        raise ValueError(f"the mapping yields {mapped.shape[1]} columns, too few for "
                         f"{len(shared_joints)} shared joints and a task point")
    return padded_rows(mapped, target_home, shared_joints)


def padded_rows(rows, target_home, shared_joints):
    """Rows (q̄, x) of the target's domain (e.g. mapped ones, or its guided-exploration
    pairs) as ``(commands (N, d_t), points (N, m))``: q̄ padded with ``target_home`` in the
    joints not in ``shared_joints`` (§6.4.1)."""
    n_shared = len(shared_joints)
    return pad_transferred(rows[:, :n_shared], target_home, shared_joints), rows[:, n_shared:]


def initialise_with_transfer(model, commands, points):
    """Add transferred samples to a target's model: a :class:`GuardedModel` (low weight,
    retirable) or a :class:`lpa_transfer.goal_babbling.yielding.YieldingModel` (overridden by
    own samples) keeps them apart, through its ``transfer``; a plain SensorimotorModel learns
    them with weight 1, exactly like its own data, as the thesis does (§6.4, §6.5.1)."""
    if hasattr(model, "transfer"):
        return model.transfer(commands, points)
    return model.update(commands, points)



def inverse_knn_model(n_neighbors, guard=None, yielding=False, gate_radius=0.01):
    """A target's inverse K-NN model knowing nothing yet: a :class:`GuardedModel` with the
    hyperparameters ``guard`` (a dict; None: no guard), a
    :class:`~lpa_transfer.goal_babbling.yielding.YieldingModel` gating at ``gate_radius`` (m)
    when ``yielding``, or a plain SensorimotorModel."""
    model = make_sensorimotor_model("knn", forward=False, n_neighbors=n_neighbors)
    if yielding and guard is not None:
        raise ValueError("guard and yielding exclude each other: set one of them")
    if yielding:
        return YieldingModel(model, gate_radius=gate_radius)
    return model if guard is None else GuardedModel(model, **guard)


def finite_experience(values, n_joints, n_task, name):
    """(finite rows (N, n_joints + n_task), number of rejected rows) of experience rows (q, x);
    ValueError for a wrong number of columns (a matrix without rows may have any)."""
    width = n_joints + n_task
    if not len(values):
        return values.reshape(0, width), 0
    if values.shape[1] != width:
        raise ValueError(f"{name} needs {n_joints} joint + {n_task} task = "
                         f"{width} columns (q, x), got {values.shape[1]}")
    finite = np.isfinite(values).all(axis=1)
    return values[finite], int(np.count_nonzero(~finite))
