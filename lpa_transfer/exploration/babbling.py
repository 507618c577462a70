"""Motor babbling programs: seeded random straight lines in joint or task space.

The thesis collects correspondences by driving robots through the same random exploration:
joint-space positions (§3.6), straight task-space segments tracked by both robots (§5.4.1),
random joint samples (§4.4.2), joint commands executed on both bodies (§6.4.2). A
:class:`BabblingProgram` is that exploration as hyperparameters; what it commands depends on
the robot's :class:`Kinematics`:

* ``"joint_lines"``: straight lines in joint space between random waypoints drawn uniformly
  in the unit box and scaled to the robot's joint limits. Waypoint coordinate j depends only
  on (seed, j), so robots babbling with one seed move their common joints alike, each in
  proportion to its own range — straight lines stay straight under this scaling.
* ``"task_lines"``: straight lines in task space between random waypoints drawn uniformly in
  the box ``task_low``..``task_high``; each robot follows them with its own inverse
  kinematics (:mod:`lpa_transfer.robots.inverse_kinematics`), warm-started along the path.

Every line starts where the last ended (the first at the robot's home) and holds
``samples_per_segment`` commands, the last one at the waypoint. Along a line the commands
follow a time law: ``"linear"`` (evenly spaced: constant speed, which jumps at every
waypoint) or ``"minimum_jerk"`` (the star tasks' profile, :func:`lpa_transfer.robots.trajectories.minimum_jerk`:
each line starts and ends at rest). §5.4.1 leaves it open; for inverse-dynamics
correspondences it decides which accelerations the babbling holds.
"""
from dataclasses import dataclass

import numpy as np

from lpa_transfer._validation import check_box, check_int
from lpa_transfer.robots import inverse_kinematics
from lpa_transfer.robots.trajectories import minimum_jerk

PROGRAMS = ("joint_lines", "task_lines")
TIME_LAWS = ("linear", "minimum_jerk")
_TASK_STREAM = 2 ** 20   # seed-sequence key of the task-space waypoints (joints use 0..n-1)


def check_task_box(low, high):
    """(low, high) as float arrays; ValueError unless finite, low <= high, one length."""
    return check_box(low, high, "task_lines needs finite task_low <= task_high of one length")


def box_around(kinematics, halfwidth):
    """The task box (low, high) centred on the end effector at ``kinematics.home``, reaching
    ``halfwidth`` (m, one value per task coordinate; 0 keeps a coordinate fixed) either side:
    babbling "in the vicinity" of a task (§5.5.3), e.g. around a star's centre. Robots of
    different sizes babbling with one seed in boxes scaled like their tasks move through
    corresponding places of their tasks."""
    centre = kinematics.forward(kinematics.home[None])[0]
    halfwidth = np.asarray(halfwidth, dtype=np.float64)
    if halfwidth.shape != centre.shape or not np.isfinite(halfwidth).all() \
            or (halfwidth < 0).any():
        raise ValueError(f"the half-width needs {len(centre)} finite values >= 0 (one per "
                         f"task coordinate), got {halfwidth.tolist()}")
    return tuple(centre - halfwidth), tuple(centre + halfwidth)


def polyline(start, waypoints, samples_per_segment, time_law="linear"):
    """Points on the straight lines start → waypoints[0] → waypoints[1] → …:
    ``samples_per_segment`` per line, spaced by ``time_law`` (module docstring), each
    line's end included."""
    if time_law not in TIME_LAWS:
        raise ValueError(f"time_law must be one of {TIME_LAWS}, got {time_law!r}")
    waypoints = np.asarray(waypoints, dtype=np.float64)
    starts = np.vstack((start, waypoints[:-1]))
    fractions = minimum_jerk(samples_per_segment) if time_law == "minimum_jerk" else \
        np.arange(1, samples_per_segment + 1) / samples_per_segment
    points = starts[:, None] + fractions[None, :, None] * (waypoints - starts)[:, None]
    return points.reshape(-1, waypoints.shape[1])


@dataclass(frozen=True)
class BabblingProgram:
    """Seeded straight-line babbling (module docstring); the fields are its hyperparameters.

    ``task_low``/``task_high`` bound the task-space waypoints of ``"task_lines"``;
    ``time_law`` spaces the commands along each line.
    """

    program: str = "joint_lines"
    n_segments: int = 20
    samples_per_segment: int = 10
    seed: int = 0
    task_low: tuple = ()
    task_high: tuple = ()
    time_law: str = "linear"

    def __post_init__(self):
        if self.program not in PROGRAMS:
            raise ValueError(f"program must be one of {PROGRAMS}, got {self.program!r}")
        if self.time_law not in TIME_LAWS:
            raise ValueError(f"time_law must be one of {TIME_LAWS}, got {self.time_law!r}")
        check_int(self.n_segments, "n_segments", 1)
        check_int(self.samples_per_segment, "samples_per_segment", 1)
        if self.program == "task_lines" and (len(self.task_low) or len(self.task_high)):
            check_task_box(self.task_low, self.task_high)

    @property
    def n_samples(self):
        return self.n_segments * self.samples_per_segment

    def unit_waypoints(self, n_joints):
        """(n_segments, n_joints) waypoints in the unit box; column j depends on (seed, j)."""
        return np.column_stack([np.random.default_rng([self.seed, j]).uniform(
            size=self.n_segments) for j in range(n_joints)])

    def task_waypoints(self, task_box=None):
        """(n_segments, m) waypoints uniform in ``task_box`` (default: the program's box); the
        same seed puts them at the same relative place in any box."""
        low, high = check_task_box(*(task_box or (self.task_low, self.task_high)))
        rng = np.random.default_rng([self.seed, _TASK_STREAM])
        return rng.uniform(low, high, size=(self.n_segments, len(low)))

    def joint_commands(self, joint_limits, start):
        """The joint-space lines scaled to ``joint_limits`` (n, 2), starting at ``start``."""
        limits = np.asarray(joint_limits, dtype=np.float64)
        waypoints = limits[:, 0] + self.unit_waypoints(len(limits)) * (limits[:, 1] - limits[:, 0])
        return polyline(start, waypoints, self.samples_per_segment, self.time_law)

    def task_points(self, start_point, task_box=None):
        """The task-space lines from ``start_point``: (n_samples, m)."""
        waypoints = self.task_waypoints(task_box)
        if len(start_point) != waypoints.shape[1]:
            raise ValueError(f"task_low/task_high have {waypoints.shape[1]} coordinates but the "
                             f"robot's task space has {len(start_point)}")
        return polyline(start_point, waypoints, self.samples_per_segment, self.time_law)

    def commands(self, kinematics):
        """The robot's joint commands (n_samples, n) for this program."""
        if self.program == "joint_lines":
            return self.joint_commands(kinematics.joint_limits, kinematics.home)
        start = kinematics.forward(kinematics.home[None])[0]
        commands, _ = inverse_kinematics.solve_path(
            kinematics.forward, self.task_points(start, kinematics.task_box), kinematics.home,
            kinematics.joint_limits)
        return commands
