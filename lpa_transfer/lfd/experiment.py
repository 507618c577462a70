"""Chapter 4's experiments in process: demonstrations of letters, their transfer from the
demonstrator to a robot by LPA, and the mapping error (thesis §4.5, §4.5.1).

* The scenario (:func:`load_setup`): the demonstrator's and the robots' parameter files, each
  robot's joint map (Table 4.2) and task frame T_R^H, as scenarios/lfd/frames.yaml holds them.
* Demonstrations (:func:`demonstrations`): handwriting shapes placed in the demonstrator's
  task space (Fig. 4-9) and traced with its IK ("we used an IK solver on the left arm of the
  human kinematic model to trace the letters and obtained the tasks in joint space", §4.5).
  The demonstrations of one shape share one placement, so their differences stay those the
  writer made.
* Correspondences to a count (:func:`collect_pairs`, motor babbling on the robot, §4.4.2)
  and the mapping error (:func:`executed_errors`): transferred robot joints executed
  (forward kinematics) against the task point they should reach, T_R^H x_H. The sweeps of
  Fig. 4-10/4-12 are in :mod:`lpa_transfer.lfd.skills`.
"""
from pathlib import Path
from typing import NamedTuple

import numpy as np
import yaml

from lpa_transfer import _validation as check
from lpa_transfer.lfd.demonstrations import letter_layout, load_lasa, place_in_task_space
from lpa_transfer.robots.inverse_kinematics import solve_path
from lpa_transfer.lfd.correspondences import (JointMap, TaskFrame,
                                              collect_demonstrator_correspondences)
from lpa_transfer.robots.kinematics import arm_kinematics
from lpa_transfer.robots.params import load_robot_params

#: Babbling batches :func:`collect_pairs` may draw before it gives up on a robot that the
#: demonstrator hardly reaches.
MAX_BATCHES = 50


class Learner(NamedTuple):
    """One robot learner of the scenario: its parameters, Table 4.2 row and T_R^H."""
    robot: object            # RobotParams
    joint_map: JointMap
    task_frame: TaskFrame


class Setup(NamedTuple):
    demonstrator: object     # RobotParams
    learners: dict           # name -> Learner


def load_setup(path, root=None):
    """The demonstrator and robot learners of a frames file (scenarios/lfd/frames.yaml);
    robot paths in it are relative to ``root`` (default: the file's grandparent's parent,
    i.e. the repository for scenarios/lfd/frames.yaml)."""
    path = Path(path)
    root = Path(root) if root is not None else path.resolve().parents[2]
    spec = yaml.safe_load(path.read_text())
    if not isinstance(spec, dict) or "demonstrator" not in spec or "robots" not in spec:
        raise ValueError(f"{path}: needs 'demonstrator' (a robot file) and 'robots'")
    learners = {}
    for name, entry in spec["robots"].items():
        if not isinstance(entry, dict) or set(entry) != {"robot", "joint_map", "task_frame"}:
            raise ValueError(f"{path}: robot {name!r} needs exactly 'robot', 'joint_map' and "
                             f"'task_frame'")
        learners[name] = Learner(load_robot_params(root / entry["robot"]),
                                 JointMap.from_spec(entry["joint_map"]),
                                 TaskFrame.from_spec(entry["task_frame"]))
    return Setup(load_robot_params(root / spec["demonstrator"]), learners)


class Demonstration(NamedTuple):
    """One demonstration in the demonstrator's domain: joints q (T, n), tool points x (T, 3)
    in its world frame, sample times (T,) s from 0."""
    shape: str
    times: np.ndarray
    q: np.ndarray
    x: np.ndarray

    @property
    def rows(self):
        """The domain rows z = (q, x), (T, n + 3), as LPA maps them."""
        return np.hstack((self.q, self.x))


def demonstrations(demonstrator, shapes, task_box, seed, n_demos=5, n_samples=100,
                   n_joints=4, start=None, ik_tolerance=1e-5):
    """Demonstrations of the LASA ``shapes`` by the ``demonstrator`` (RobotParams), placed
    with :func:`~lpa_transfer.lfd.demonstrations.letter_layout` in ``task_box`` (low, high) of
    its world frame (m), ``n_demos`` per shape, each cut to ``n_samples`` evenly spaced
    samples, traced by its first ``n_joints`` joints (the others at home) with
    :func:`~lpa_transfer.robots.inverse_kinematics.solve_path` from ``start`` (default: the middle
    of those joints' ranges). Raises if a letter leaves the demonstrator's reach (residual
    above ``ik_tolerance`` m). Returns a list of :class:`Demonstration`, shape by shape.
    """
    check.check_int(n_samples, "n_samples", minimum=3)
    arm = arm_kinematics(demonstrator, n_joints, name="demonstrator")
    limits = arm.joint_limits
    start = limits.mean(axis=1) if start is None else np.asarray(start, dtype=np.float64)
    placements = letter_layout(len(shapes), task_box, seed)
    out = []
    for shape, placement in zip(shapes, placements):
        positions, times = load_lasa(shape, n_demos)
        picks = [np.linspace(0, len(p) - 1, n_samples).round().astype(int) for p in positions]
        placed = place_in_task_space(np.vstack([p[k] for p, k in zip(positions, picks)]),
                                     *placement)
        for k, (points, t) in enumerate(zip(np.split(placed, len(picks)), times)):
            q, residuals = solve_path(arm.forward, points, start, limits, tolerance=1e-7)
            if residuals.max() > ik_tolerance:
                raise ValueError(f"{shape} demonstration {k} leaves the demonstrator's reach "
                                 f"by {residuals.max():.3g} m: choose a task_box it reaches")
            time = t[picks[k]]
            out.append(Demonstration(shape, time - time[0], q, points))
    return out


def collect_pairs(learner, demonstrator, n_pairs, seed, batch=None):
    """At least ``n_pairs`` correspondences demonstrator -> ``learner`` (a :class:`Learner`):
    :func:`~lpa_transfer.lfd.correspondences.collect_demonstrator_correspondences` in batches of
    ``batch`` babbled poses (default ``n_pairs``) with seeds ``seed * MAX_BATCHES + b``,
    until enough are kept. Returns (demonstrator rows, robot rows), ``n_pairs`` each, and the
    number of poses babbled."""
    check.check_int(n_pairs, "n_pairs", minimum=1)
    check.check_int(seed, "seed", minimum=0)
    batch = n_pairs if batch is None else batch
    demo_rows, robot_rows, tried = [], [], 0
    for b in range(MAX_BATCHES):
        c = collect_demonstrator_correspondences(learner.robot, demonstrator, learner.joint_map,
                                    learner.task_frame, batch, seed * MAX_BATCHES + b)
        demo_rows.append(c.demonstrator)
        robot_rows.append(c.robot)
        tried += c.n_tried
        if sum(map(len, demo_rows)) >= n_pairs:
            return (np.vstack(demo_rows)[:n_pairs], np.vstack(robot_rows)[:n_pairs], tried)
    raise ValueError(f"the demonstrator reached only {sum(map(len, demo_rows))} of {tried} "
                     f"babbled robot poses, fewer than the {n_pairs} pairs asked for")


class RememberedPairs:
    """:func:`collect_pairs` that keeps its answers: asked again for the same learner and
    demonstrator objects, ``n_pairs`` and ``seed``, it returns the pairs it collected instead
    of babbling and solving the IK again. Fig. 4-10's sweep and Table 4.3 both pair the human
    with each robot on a seed's babbling, the same pairs when the sizes agree. Keys are the
    objects' identities, which it keeps alive (so no later object can take a stored id); the
    returned arrays are shared between callers, which only read them."""

    def __init__(self):
        self._kept = {}

    def __call__(self, learner, demonstrator, n_pairs, seed):
        key = (id(learner), id(demonstrator), n_pairs, seed)
        if key not in self._kept:
            self._kept[key] = (learner, demonstrator,
                               collect_pairs(learner, demonstrator, n_pairs, seed))
        return self._kept[key][2]


def executed_errors(learner, mapped_rows, x_demonstrator):
    """Per-point task-space errors (m) of mapped robot rows (q̂_R, x̂_R) (T, n + 3): the
    mapped joints executed (forward kinematics, other joints at home) against where the
    demonstrated point lies for the robot, T_R^H x_H (§4.5: "computing forward kinematics
    on the simulated robots, to obtain the adapted trajectories in task space")."""
    n = learner.joint_map.n_joints
    forward = arm_kinematics(learner.robot, n, name="robot").forward
    x_target = learner.task_frame.to_robot(x_demonstrator)
    return np.linalg.norm(forward(np.asarray(mapped_rows)[:, :n]) - x_target, axis=1)
