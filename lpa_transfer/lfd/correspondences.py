"""Correspondences between a demonstrator and a robot learner for goal-directed imitation
(thesis §4.4.2-4.5).

Two poses correspond when they put the end effectors at the *same* task point, the
demonstrator's point seen through the task frame T_R^H (§4.4.2, Fig. 4-5):
x_R = T_R^H x_H. They are collected by motor babbling on the robot (step 1 of Fig. 4-4):
random joint samples q_R, their end-effector points x_R, then x_H = (T_R^H)⁻¹ x_R and the
demonstrator's inverse kinematics for x_H (steps 2-3). The demonstrator is redundant for a
point, so the IK starts from the robot's joints carried over to the demonstrator by the joint
correspondence of Table 4.2 (:class:`JointMap`): neighbouring robot poses then give
neighbouring demonstrator poses (redundancy resolution, Fig. 4-6b).

As in §4.5, only the first ``joint_map.n_joints`` (4) joints of each arm move; the others are
held at home, and a domain row is z = (q, x) with q those joints (rad) and x the
end-effector position (m) in the arm's own world frame: 7-D for 4 joints.
"""
from typing import NamedTuple

import numpy as np

from lpa_transfer import _validation as check
from lpa_transfer.lfd.demonstrations import as_rotation
from lpa_transfer.robots.inverse_kinematics import solve_many
from lpa_transfer.robots.kinematics import arm_kinematics, sample_joint_uniform
from lpa_transfer.robots.params import RobotParams
from lpa_transfer.robots.serial_chain import reach_sphere

#: Keys of one joint of a :meth:`JointMap.from_spec` list given as a dict.
SPEC_KEYS = ("joint", "sign", "offset")


class JointMap:
    """Joint correspondence of Table 4.2 as data: q_R[j] = sign_j · q_H[index_j] + offset_j.

    ``index[j]`` is the demonstrator's joint that robot joint j follows, ``sign[j]`` ±1 and
    ``offset[j]`` (rad) how it converts (e.g. the Meka's first joint is π/2 − J1: index 0,
    sign −1, offset π/2). The indices are a permutation of 0..n−1: the first n joints of each
    arm correspond one to one (§4.4.2, found with the T- and U-poses of Fig. 4-7).
    """

    def __init__(self, index, sign, offset):
        index, sign, offset = (np.asarray(v) for v in (index, sign, offset))
        if index.ndim != 1 or index.size == 0 or not np.issubdtype(index.dtype, np.integer):
            raise ValueError(f"joint map: index must be a non-empty 1-D sequence of joint "
                             f"indices, got {index.tolist()}")
        n = len(index)
        if sorted(index.tolist()) != list(range(n)):
            raise ValueError(f"joint map: the demonstrator joints must be distinct indices in "
                             f"[0, {n}) (one per robot joint), got {index.tolist()}")
        try:
            sign, offset = sign.astype(np.float64), offset.astype(np.float64)
        except (TypeError, ValueError):
            raise ValueError("joint map: signs and offsets must be numbers") from None
        if sign.shape != (n,) or not np.isin(sign, (-1.0, 1.0)).all():
            raise ValueError(f"joint map: need {n} signs, each +1 or -1, got {sign.tolist()}")
        if offset.shape != (n,) or not np.isfinite(offset).all():
            raise ValueError(f"joint map: need {n} finite offsets (rad), got {offset.tolist()}")
        self.index, self.sign, self.offset = index.astype(np.intp), sign, offset
        for array in (self.index, self.sign, self.offset):
            array.setflags(write=False)

    @classmethod
    def from_spec(cls, spec):
        """A map from a list, one entry per robot joint: ``(joint, sign, offset)`` or
        ``{"joint": i, "sign": ±1, "offset": rad}`` (sign defaults to 1, offset to 0), e.g.
        as read from a scenario YAML file (scenarios/lfd/frames.yaml)."""
        if not isinstance(spec, (list, tuple)) or not spec:
            raise ValueError(f"joint map spec must be a non-empty list, got {spec!r}")
        rows = []
        for j, entry in enumerate(spec):
            if isinstance(entry, dict):
                unknown = set(entry) - set(SPEC_KEYS)
                if unknown or "joint" not in entry:
                    raise ValueError(f"joint map spec entry {j} needs the key 'joint' and only "
                                     f"keys {SPEC_KEYS}, got {sorted(entry)}")
                entry = (entry["joint"], entry.get("sign", 1), entry.get("offset", 0.0))
            if not isinstance(entry, (list, tuple)) or len(entry) != 3:
                raise ValueError(f"joint map spec entry {j} must be (joint, sign, offset) or a "
                                 f"dict with those keys, got {entry!r}")
            if isinstance(entry[0], bool) or not isinstance(entry[0], (int, np.integer)):
                raise ValueError(f"joint map spec entry {j}: joint must be an integer index, "
                                 f"got {entry[0]!r}")
            rows.append(entry)
        index, sign, offset = zip(*rows)
        return cls(np.array(index, dtype=np.intp), sign, offset)

    def to_spec(self):
        """The map as :meth:`from_spec` reads it (a list of dicts)."""
        return [dict(joint=int(i), sign=int(s), offset=float(o))
                for i, s, o in zip(self.index, self.sign, self.offset)]

    @property
    def n_joints(self):
        return len(self.index)

    def _rows(self, q, name):
        q = check.as_matrix(q, name)
        if q.shape[1] != self.n_joints:
            raise ValueError(f"{name} must have {self.n_joints} columns (the mapped joints), "
                             f"got {q.shape[1]}")
        return q

    def to_robot(self, q_demonstrator):
        """Robot joints (N, n) for demonstrator joints (N, n) (Table 4.2)."""
        q = self._rows(q_demonstrator, "q_demonstrator")
        return self.sign * q[:, self.index] + self.offset

    def to_demonstrator(self, q_robot):
        """Demonstrator joints (N, n) for robot joints (N, n): the inverse of :meth:`to_robot`
        (used to initialise the demonstrator's IK, §4.4.2)."""
        q = self._rows(q_robot, "q_robot")
        out = np.empty_like(q)
        out[:, self.index] = self.sign * (q - self.offset)
        return out

    def robot_range(self, demonstrator_limits):
        """Where the demonstrator's joint ranges (n, 2) land in robot joint space: (n, 2)
        (lower, upper) of ``sign_j · q_H[index_j] + offset_j`` over the demonstrator's range of
        joint index_j."""
        limits = check.as_matrix(demonstrator_limits, "demonstrator_limits")
        if limits.shape != (self.n_joints, 2):
            raise ValueError(f"demonstrator_limits must have shape ({self.n_joints}, 2), got "
                             f"{limits.shape}")
        return np.sort(self.sign[:, None] * limits[self.index] + self.offset[:, None], axis=1)

    @classmethod
    def between(cls, teacher, learner):
        """The map from a teacher robot's joints to a learner robot's, both given by their
        maps from one demonstrator (§4.4.5: the PR2 teaches the Meka what the human taught
        it): q_L = learner.to_robot(teacher.to_demonstrator(q_T)), itself a joint map."""
        if teacher.n_joints != learner.n_joints:
            raise ValueError(f"the teacher's map has {teacher.n_joints} joints, the "
                             f"learner's {learner.n_joints}")
        where = np.argsort(teacher.index)       # teacher joint that follows demonstrator i
        index = where[learner.index]
        sign = learner.sign * teacher.sign[index]
        return cls(index, sign, learner.offset - sign * teacher.offset[index])

    def __repr__(self):
        return f"JointMap.from_spec({self.to_spec()!r})"


class TaskFrame:
    """The task frame T_R^H (§4.4.2, Fig. 4-5b): where the demonstrator's task space sits in
    the robot's, x_R = R x_H + t.

    ``translation`` t (3,) m; ``rotation`` R a (3, 3) rotation matrix or (roll, pitch, yaw)
    rad (URDF convention), identity by default (the thesis' choice, §4.5). Both points are
    in their arm's own world frame.
    """

    def __init__(self, translation, rotation=None):
        t = np.asarray(translation, dtype=np.float64)
        if t.shape != (3,) or not np.isfinite(t).all():
            raise ValueError(f"task frame translation must be 3 finite numbers (m), got "
                             f"{t.tolist()}")
        self.translation = t
        self.rotation = np.eye(3) if rotation is None else as_rotation(rotation)
        for array in (self.translation, self.rotation):
            array.setflags(write=False)

    @classmethod
    def from_spec(cls, spec):
        """A frame from ``{"translation": [x, y, z], "rpy": [r, p, y]}`` (or ``"rotation"``,
        a 3×3 matrix; neither: identity), e.g. from scenarios/lfd/frames.yaml."""
        if not isinstance(spec, dict) or "translation" not in spec \
                or set(spec) - {"translation", "rpy", "rotation"} \
                or {"rpy", "rotation"} <= set(spec):
            raise ValueError(f"task frame spec needs 'translation' and at most one of 'rpy', "
                             f"'rotation', got {spec!r}")
        return cls(spec["translation"], spec.get("rpy", spec.get("rotation")))

    def _points(self, x, name):
        x = check.as_matrix(x, name)
        if x.shape[1] != 3:
            raise ValueError(f"{name} must have 3 columns (task-space x, y, z), got "
                             f"{x.shape[1]}")
        return x

    def to_robot(self, x_demonstrator):
        """Robot task points (N, 3) for demonstrator points (N, 3): T_R^H x_H."""
        return self._points(x_demonstrator, "x_demonstrator") @ self.rotation.T \
            + self.translation

    def to_demonstrator(self, x_robot):
        """Demonstrator task points (N, 3) for robot points (N, 3): (T_R^H)⁻¹ x_R."""
        return (self._points(x_robot, "x_robot") - self.translation) @ self.rotation

    @classmethod
    def between(cls, teacher, learner):
        """The task frame from a teacher robot to a learner robot, both placed relative to
        one demonstrator (T_learner^teacher of §4.5.3): x_L = R_L R_Tᵀ (x_T − t_T) + t_L, so
        a demonstrated point lands where the learner's own frame puts it."""
        rotation = learner.rotation @ teacher.rotation.T
        return cls(learner.translation - rotation @ teacher.translation, rotation)

    def __repr__(self):
        return f"TaskFrame({self.translation.tolist()}, {self.rotation.tolist()})"


class LfdCorrespondences(NamedTuple):
    """Kept correspondences: row i of ``demonstrator`` (q_H, x_H) and of ``robot`` (q_R, x_R)
    reach the same task point (x_R = T_R^H x_H); ``n_tried`` babbled robot samples, of which
    ``n_kept`` the demonstrator reached."""
    demonstrator: np.ndarray   # (n_kept, n + 3)
    robot: np.ndarray          # (n_kept, n + 3)
    n_tried: int
    n_kept: int


#: ``babble_range`` values of :func:`collect_demonstrator_correspondences`.
BABBLE_RANGES = ("shared", "robot")


def babbling_limits(robot, demonstrator, joint_map, babble_range="shared"):
    """The joint box (n, 2) the robot babbles in (:func:`collect_demonstrator_correspondences`):
    ``"robot"``, its own limits (the thesis: "randomly sampling the 4-dimensional joint
    space of the robot", §4.5); ``"shared"``, those limits intersected with
    :meth:`JointMap.robot_range` of the demonstrator's. ``robot`` and ``demonstrator`` are
    restricted Kinematics (:func:`arm_kinematics`).

    Why "shared" is our default: the redundancy resolution starts the demonstrator's IK at
    the joint-mapped robot pose, clipped into the demonstrator's limits. Where the robot's
    range is wider, clipping breaks that start's continuity and neighbouring robot poses get
    far-apart demonstrator poses. On the PR2, whose upper-arm roll spans 4.7 rad against the
    human's 2.8, babbling the full box gives held-out LPA mapping errors several times those
    of the shared box (docs/history.md); the Meka's box lies almost inside the shared one.
    """
    if babble_range not in BABBLE_RANGES:
        raise ValueError(f"babble_range must be one of {BABBLE_RANGES}, got {babble_range!r}")
    limits = np.array(robot.joint_limits, dtype=np.float64)
    if babble_range == "shared":
        image = joint_map.robot_range(demonstrator.joint_limits)
        limits = np.column_stack((np.maximum(limits[:, 0], image[:, 0]),
                                  np.minimum(limits[:, 1], image[:, 1])))
        if (limits[:, 0] > limits[:, 1]).any():
            empty = np.flatnonzero(limits[:, 0] > limits[:, 1]).tolist()
            raise ValueError(f"the robot's joints {empty} share no range with the "
                             f"demonstrator's through the joint map")
    return limits


#: Default ``ik_tolerance`` (m) of :func:`collect_demonstrator_correspondences`: the pairing
#: check of the chapter 4 collection (same_task_point).
IK_TOLERANCE = 1e-4


def task_point_residuals(body, rows, n_joints):
    """(N,) ||FK(q) − x|| (m) of rows (q, x) of ``body`` (RobotParams or Kinematics; its first
    ``n_joints`` joints, the others at home): how far each pair's inverse-kinematics pose is
    from the task point it pairs at (same_task_point, §4.4.2) — the residual
    :func:`collect_demonstrator_correspondences` keeps at most ``ik_tolerance``."""
    rows = check.as_matrix(rows, "rows")
    forward = arm_kinematics(body, n_joints, name="body").forward
    return np.linalg.norm(np.asarray(forward(rows[:, :n_joints])) - rows[:, n_joints:], axis=1)


def collect_demonstrator_correspondences(robot, demonstrator, joint_map, task_frame, n, seed,
                            robot_home=None, demonstrator_home=None, ik_tolerance=IK_TOLERANCE,
                            babble_range="shared"):
    """Correspondences by motor babbling on the robot (§4.4.2, Fig. 4-4 steps 1-3).

    ``n`` robot poses uniform within the robot's first ``joint_map.n_joints`` joints'
    :func:`babbling_limits` for ``babble_range`` (the others at ``robot_home``), their
    end-effector points x_R, x_H =
    ``task_frame.to_demonstrator(x_R)``, then the demonstrator's IK for x_H on its first
    joints (the others at ``demonstrator_home``), started from
    ``joint_map.to_demonstrator(q_R)`` clipped into its limits (redundancy resolution).
    Pairs whose IK residual exceeds ``ik_tolerance`` (m) are dropped: the demonstrator does
    not reach that point. ``robot`` and ``demonstrator`` are RobotParams or Kinematics; the
    same ``seed`` gives the same pairs. The IK runs for all points at once
    (:func:`~lpa_transfer.robots.inverse_kinematics.solve_many`), except for points a serial
    chain demonstrator (RobotParams) cannot reach within ``ik_tolerance`` whatever its pose
    (outside its :func:`~lpa_transfer.robots.serial_chain.reach_sphere`): they are dropped
    without it. Returns :class:`LfdCorrespondences`.
    """
    check.check_int(n, "n", minimum=1)
    check.check_int(seed, "seed", minimum=0)
    check.check_float(ik_tolerance, "ik_tolerance", minimum=0.0)
    if ik_tolerance <= 0:
        raise ValueError(f"ik_tolerance must be > 0 (m), got {ik_tolerance}")
    k = joint_map.n_joints
    robot = arm_kinematics(robot, k, robot_home, "robot")
    demonstrator_params = demonstrator
    demonstrator = arm_kinematics(demonstrator, k, demonstrator_home, "demonstrator")
    q_robot = sample_joint_uniform(n, babbling_limits(robot, demonstrator, joint_map,
                                                      babble_range),
                                   np.random.default_rng(seed))
    x_robot = np.asarray(robot.forward(q_robot), dtype=np.float64)
    x_demo = task_frame.to_demonstrator(x_robot)
    limits = demonstrator.joint_limits
    starts = np.clip(joint_map.to_demonstrator(q_robot), limits[:, 0], limits[:, 1])
    # points beyond the demonstrator's reach by more than the tolerance are dropped without
    # their IK, which each would run to its last iteration (most of the PR2's babbled points
    # for the human, docs/history.md); the other rows' IK does not depend on them (bit for bit)
    tried = _within_reach(demonstrator_params, x_demo, ik_tolerance)
    q_demo, residuals = starts.copy(), np.full(n, np.inf)
    q_demo[tried], residuals[tried] = solve_many(demonstrator.forward, x_demo[tried],
                                                 starts[tried], limits,
                                                 tolerance=min(1e-7, ik_tolerance / 10))
    kept = residuals <= ik_tolerance
    return LfdCorrespondences(np.hstack((q_demo, x_demo))[kept],
                              np.hstack((q_robot, x_robot))[kept], n, int(kept.sum()))


def _within_reach(arm, x, tolerance):
    """Rows of ``x`` (N, 3) that a serial chain's RobotParams ``arm`` may reach within
    ``tolerance`` (m): inside :func:`~lpa_transfer.robots.serial_chain.reach_sphere` grown by
    it. Every row for anything else (a Kinematics has no chain to bound)."""
    if not isinstance(arm, RobotParams) or arm.kind != "serial":
        return np.ones(len(x), dtype=bool)
    centre, radius = reach_sphere(arm)
    return np.linalg.norm(x - centre, axis=1) <= radius + tolerance


class MappingErrors(NamedTuple):
    """Per-row task-space errors (m) of demonstrator rows mapped onto the robot."""
    executed: np.ndarray   # ||FK_R(q̂_R) − x_R||: the thesis' mapping error (§4.5.1)
    estimated: np.ndarray  # ||x̂_R − x_R||: the mapped task coordinates themselves


def mapping_error(model, demonstrator_rows, robot_rows, robot, robot_home=None):
    """Errors (m) of mapping held-out demonstrator rows (q_H, x_H) onto the robot through a
    fitted PA/LPA ``model`` (§4.4.3, Alg. 4), against the true robot rows (q_R, x_R).

    §4.5 evaluates the mapped joints by executing them: "computing forward kinematics on the
    simulated robots" gives the adapted trajectories in task space, and the mapping error
    (Fig. 4-10, Table 4.3, "less than 0.01 m") is their distance to the ground-truth task
    points. That is ``executed``, ||FK_R(q̂_R) − x_R|| with the robot's other joints at
    ``robot_home`` (q̂_R as mapped, not clipped into the limits); ``estimated`` is
    ||x̂_R − x_R||, the model's own task coordinates. Both are per row, in metres: take
    ``.mean()`` for Fig. 4-10's average.
    """
    robot_rows = check.as_matrix(robot_rows, "robot_rows")
    n_joints = robot_rows.shape[1] - 3
    if n_joints < 1:
        raise ValueError(f"robot_rows must hold (q_R, x_R): joints then 3 task coordinates, "
                         f"got {robot_rows.shape[1]} columns")
    mapped = model.transfer(demonstrator_rows)
    if mapped.shape != robot_rows.shape:
        raise ValueError(f"the model maps demonstrator_rows to shape {mapped.shape} but "
                         f"robot_rows has shape {robot_rows.shape}")
    forward = arm_kinematics(robot, n_joints, robot_home, "robot").forward
    x_true = robot_rows[:, n_joints:]
    executed = np.linalg.norm(forward(mapped[:, :n_joints]) - x_true, axis=1)
    return MappingErrors(executed, np.linalg.norm(mapped[:, n_joints:] - x_true, axis=1))
