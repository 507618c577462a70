"""Skills from transferred demonstrations, and transfer between robots (thesis §4.4.4-4.4.5,
§4.5.2-4.5.3).

* Accuracy sweep (:func:`accuracy_sweep`, Fig. 4-10 and 4-12): LPA fitted on a growing
  number of correspondences for several N_min; every demonstration transferred point by
  point (Alg. 4), its mapping and encoding errors measured.
* Encoding (Fig. 4-12): the 5 demonstrations of a letter, in the robot's joint space, become
  one joint-space DMP (:meth:`~lpa_transfer.lfd.dmp.JointDMP.fit_many`); the DMP reproduces the
  first demonstration, the reproduction is executed (forward kinematics) and compared with
  that demonstration's task points T_R^H x_H. The joint trajectories come from LPA
  (transferred) or from the robot's own IK (the thesis' "IK method", which uses the robot's
  kinematic model: :func:`robot_ik_demonstrations`).
* Multi-robot (Table 4.3, :func:`multi_robot_transfer`): the human teaches the learner
  directly; or a teacher robot learned from the human and passes it on, its skills
  "unrefined" (the human -> teacher and teacher -> learner mappings cascaded) or "refined"
  (the teacher traces the letters with its own IK first, as the thesis models a teacher that
  has mastered them).
"""
from typing import NamedTuple

import numpy as np

from lpa_transfer import _validation as check
from lpa_transfer._estimator import clone
from lpa_transfer.lfd.dmp import JointDMP
from lpa_transfer.robots.inverse_kinematics import solve_path
from lpa_transfer.lfd.correspondences import JointMap, TaskFrame
from lpa_transfer.robots.kinematics import arm_kinematics
from lpa_transfer.lfd.experiment import Demonstration, Learner, collect_pairs, executed_errors
from lpa_transfer.transfer.local_procrustes import LocalProcrustesAnalysis

#: Conditions of :func:`multi_robot_transfer`, in Table 4.3's order.
CONDITIONS = ("direct", "refined", "unrefined")
#: Table 4.3 (to the Meka, m): (mapping, encoding) error, each (mean, standard deviation).
THESIS_TABLE = {"direct": ((0.0045, 0.0008), (0.0140, 0.0013)),
                "refined": ((0.0062, 0.0041), (0.0138, 0.0005)),
                "unrefined": ((0.0152, 0.0035), (0.0192, 0.0012))}


def robot_ik_demonstrations(learner, demos, ik_tolerance=1e-5):
    """The demonstrations traced by the robot itself: its IK along T_R^H x_H of each, started
    from the first demonstrated pose carried over by the joint map (clipped into the robot's
    limits) and warm-started along the path. Returns :class:`Demonstration` rows in the
    robot's domain (q_R, x_R). Raises if the robot does not reach a point."""
    n = learner.joint_map.n_joints
    arm = arm_kinematics(learner.robot, n, name="robot")
    limits = arm.joint_limits
    out = []
    for d in demos:
        x_robot = learner.task_frame.to_robot(d.x)
        start = np.clip(learner.joint_map.to_robot(d.q[:1])[0], limits[:, 0], limits[:, 1])
        q, residuals = solve_path(arm.forward, x_robot, start, limits, tolerance=1e-7)
        if residuals.max() > ik_tolerance:
            raise ValueError(f"the robot misses a point of a {d.shape} demonstration by "
                             f"{residuals.max():.3g} m")
        out.append(Demonstration(d.shape, d.times, q, x_robot))
    return out


def by_shape(demos):
    """Indices of ``demos`` grouped by shape, in first-seen order: {shape: [i, ...]}."""
    groups = {}
    for i, d in enumerate(demos):
        groups.setdefault(d.shape, []).append(i)
    return groups


def encoding_errors(learner, demos, robot_joints, dmp=None):
    """Fig. 4-12: per shape, the mean task-space error (m) of the DMP reproduction of its
    first demonstration against that demonstration's T_R^H x_H. ``robot_joints[i]`` (T_i, n)
    are demonstration i's joints on the robot (transferred or from its IK); one ``dmp``
    (a :class:`~lpa_transfer.lfd.dmp.JointDMP`, default hyperparameters if None) per shape is
    fitted on all of the shape's demonstrations. Returns {shape: error}."""
    errors = {}
    for shape, members in by_shape(demos).items():
        model = JointDMP() if dmp is None else clone(dmp)
        model.fit_many([demos[i].times for i in members], [robot_joints[i] for i in members])
        first = demos[members[0]]
        reproduced = np.hstack((model.reproduce(), np.zeros((len(first.times), 3))))
        errors[shape] = float(executed_errors(learner, reproduced, first.x).mean())
    return errors


class TransferErrors(NamedTuple):
    """Errors (m) of one way of reaching the learner: the mapping error over every
    demonstrated point (mean) and the encoding error (mean over shapes)."""
    mapping: float
    encoding: float


def _split(rows, demos):
    return np.split(rows, np.cumsum([len(d.times) for d in demos])[:-1])


def mean_mapping_error(learner, demos, mapped_rows):
    """The mapping error (m): the mean of :func:`executed_errors` over every point of the
    demonstrations, ``mapped_rows`` their mapped rows stacked in order (sum T_i, n + 3)."""
    return float(executed_errors(learner, mapped_rows, np.vstack([d.x for d in demos])).mean())


def _errors(learner, demos, mapped_rows, dmp):
    mapping = mean_mapping_error(learner, demos, mapped_rows)
    joints = [r[:, :learner.joint_map.n_joints] for r in _split(mapped_rows, demos)]
    encoding = float(np.mean(list(encoding_errors(learner, demos, joints, dmp).values())))
    return TransferErrors(mapping, encoding)


def between(teacher, learner):
    """The teacher robot as the learner's demonstrator: the learner with the joint map and
    task frame from the teacher (both composed through the human, §4.5.3)."""
    return Learner(learner.robot, JointMap.between(teacher.joint_map, learner.joint_map),
                   TaskFrame.between(teacher.task_frame, learner.task_frame))


def multi_robot_transfer(demonstrator, teacher, learner, demos, n_pairs, n_min, seed,
                         c_min=1e-7, dmp=None, pairs=collect_pairs):
    """Table 4.3 for one seed: {condition: :class:`TransferErrors`} for ``CONDITIONS``.

    Every mapping is an LPA (``n_min``, ``c_min``) on ``n_pairs`` correspondences collected
    by babbling on the robot it maps to (:func:`~lpa_transfer.lfd.experiment.collect_pairs`,
    ``seed``): human -> learner, human -> teacher, teacher -> learner (the teacher's IK
    started from the learner's poses carried over by the composed joint map). The errors
    are measured on the learner against where its own task frame puts the demonstrated
    points, for every condition. ``pairs`` collects them (``collect_pairs``' signature; a
    :class:`~lpa_transfer.lfd.experiment.RememberedPairs` reuses the sweep's).
    """
    relay = between(teacher, learner)

    def fit(target, source_body):
        source_rows, target_rows, _ = pairs(target, source_body, n_pairs, seed)
        return LocalProcrustesAnalysis(n_min=n_min, c_min=c_min).fit(source_rows, target_rows)

    rows = np.vstack([d.rows for d in demos])
    human_to_learner = fit(learner, demonstrator)
    human_to_teacher = fit(teacher, demonstrator)
    teacher_to_learner = fit(relay, teacher.robot)
    taught = np.vstack([d.rows for d in robot_ik_demonstrations(teacher, demos)])
    mapped = {"direct": human_to_learner.transfer(rows),
              "refined": teacher_to_learner.transfer(taught),
              "unrefined": teacher_to_learner.transfer(human_to_teacher.transfer(rows))}
    return {c: _errors(learner, demos, mapped[c], dmp) for c in CONDITIONS}


class SweepErrors(NamedTuple):
    """Arrays (seeds, N_min values, training sizes) of :class:`TransferErrors`' fields (m)."""
    mapping: np.ndarray
    encoding: np.ndarray


def accuracy_sweep(learner, demonstrator, demos, sizes, n_mins, seeds, c_min=1e-7, dmp=None,
                   random_state=0, pairs=collect_pairs):
    """Fig. 4-10 and 4-12: mapping and encoding errors (:class:`SweepErrors`) of LPA
    (``c_min``, each of ``n_mins``, the mixture in the demonstrator's (q, x) space, latent_dim
    the full 7-D, §4.4.3) for each training size and seed.

    Per seed the correspondences are collected once (max(sizes) pairs, by ``pairs``,
    :func:`collect_pairs`' signature) and each size uses its first pairs, so a curve shows
    more data, not other data.
    """
    for size in sizes:
        check.check_int(size, "training size", minimum=1)
    rows = np.vstack([d.rows for d in demos])
    shape = (len(seeds), len(n_mins), len(sizes))
    out = SweepErrors(np.empty(shape), np.empty(shape))
    for i, seed in enumerate(seeds):
        demo_pairs, robot_pairs, _ = pairs(learner, demonstrator, max(sizes), seed)
        for j, n_min in enumerate(n_mins):
            for k, size in enumerate(sizes):
                lpa = LocalProcrustesAnalysis(n_min=n_min, c_min=c_min,
                                              random_state=random_state)
                lpa.fit(demo_pairs[:size], robot_pairs[:size])
                errors = _errors(learner, demos, lpa.transfer(rows), dmp)
                out.mapping[i, j, k], out.encoding[i, j, k] = errors
    return out


def ik_method_errors(learner, demos, dmp=None):
    """The thesis' baseline (the black dashed line of Fig. 4-12): the robot's own IK
    trajectories encoded the same way. Returns :class:`TransferErrors` (mapping error 0 up
    to the IK's tolerance)."""
    traced = robot_ik_demonstrations(learner, demos)
    return _errors(learner, demos, np.vstack([d.rows for d in traced]), dmp)
