"""Tracking tasks of thesis ch. 5: the 'star' figures, as task- and joint-space trajectories.

§5.5.1: each star is 7 straight lines from a centre; a trial follows every line out from the
centre and back, 0.6 s each way (1.2 s a line, 8.4 s a trial). The thesis does not give the
time law along a line (``time_law``): by default each leg uses the minimum-jerk profile
s(τ) = 10τ³ − 15τ⁴ + 6τ⁵ (τ = t / 0.6 s), which starts and ends at rest, so the desired joint
accelerations stay finite while still peaking high mid-leg; ``"linear"`` runs each leg at
constant speed, as a straight reading of "each line 0.6 s out and 0.6 s back" with
"components of high acceleration" suggests (the velocity jumps at the centre and the tips).

The task is placed in a robot's workspace by its centre, the plane it lies in (two
orthonormal directions ``u``, ``v``) and its radius; the 7 line directions are spread evenly
over ``spread`` radians starting at ``start_angle``. Joint trajectories come from the robot's
inverse kinematics, warm-started along the path, differentiated numerically.
"""
import numpy as np

from lpa_transfer.robots import inverse_kinematics
from lpa_transfer.robots.trajectories import minimum_jerk

N_LINES = 7
LEG_DURATION = 0.6


def star_tips(centre, u, v, radius, n_lines=N_LINES, spread=2 * np.pi, start_angle=0.0):
    """(n_lines, m) end points of the star's lines around ``centre`` in the plane (u, v)."""
    centre, u, v = (np.asarray(a, dtype=np.float64) for a in (centre, u, v))
    if not (centre.shape == u.shape == v.shape) or centre.ndim != 1:
        raise ValueError(f"centre, u and v must be vectors of one length, got shapes "
                         f"{centre.shape}, {u.shape}, {v.shape}")
    if not radius > 0:
        raise ValueError(f"radius must be positive, got {radius}")
    full_turn = np.isclose(spread, 2 * np.pi)
    angles = start_angle + spread * np.arange(n_lines) / (n_lines if full_turn else n_lines - 1)
    return centre + radius * (np.cos(angles)[:, None] * u + np.sin(angles)[:, None] * v)


TIME_LAWS = ("minimum_jerk", "linear")


def leg_profile(n_samples, time_law="minimum_jerk"):
    """s(τ) ∈ (0, 1] at τ = 1/n … 1 along a leg: ``"minimum_jerk"`` or ``"linear"`` (constant
    speed)."""
    if time_law == "minimum_jerk":
        return minimum_jerk(n_samples)
    if time_law == "linear":
        return np.arange(1, n_samples + 1) / n_samples
    raise ValueError(f"time_law must be one of {TIME_LAWS}, got {time_law!r}")


def star_trajectory(centre, u, v, radius, dt, n_lines=N_LINES, spread=2 * np.pi,
                    start_angle=0.0, leg_duration=LEG_DURATION, time_law="minimum_jerk"):
    """Desired task-space positions of one trial, one row per control period ``dt``, starting
    one period after the centre: (n_lines · 2 · leg_duration / dt, m)."""
    n_leg = int(round(leg_duration / dt))
    if n_leg < 1:
        raise ValueError(f"dt = {dt} s is longer than a leg ({leg_duration} s)")
    centre = np.asarray(centre, dtype=np.float64)
    s = leg_profile(n_leg, time_law)[:, None]
    legs = []
    for tip in star_tips(centre, u, v, radius, n_lines, spread, start_angle):
        legs += [centre + s * (tip - centre), tip + s * (centre - tip)]
    return np.vstack(legs)


def joint_trajectory(kinematics, task_points, q_start, dt):
    """(q, q̇, q̈, residuals) following ``task_points`` (T, m) from the pose ``q_start``.

    Positions by inverse kinematics warm-started along the path; velocities and accelerations
    by central differences (np.gradient) at the control period ``dt``.
    """
    q, residuals = inverse_kinematics.solve_path(kinematics.forward, task_points, q_start,
                                                 kinematics.joint_limits)
    qd = np.gradient(q, dt, axis=0)
    return q, qd, np.gradient(qd, dt, axis=0), residuals


def tracking_error(desired, actual):
    """Mean task-space distance between desired and actual end-effector positions (§5.5.2)."""
    desired, actual = np.asarray(desired, dtype=np.float64), np.asarray(actual, dtype=np.float64)
    if desired.shape != actual.shape or desired.ndim != 2 or len(desired) == 0:
        raise ValueError(f"desired and actual must be non-empty (T, m) arrays of one shape, "
                         f"got {desired.shape} and {actual.shape}")
    return float(np.linalg.norm(desired - actual, axis=1).mean())


def star_task(kinematics, radius, dt, u=None, v=None, spread=2 * np.pi, start_angle=0.0,
              tolerance=1e-3, time_law="minimum_jerk"):
    """One trial of a star (§5.5.1) around the end effector at ``kinematics.home``, from rest
    there: ``(q_d, q̇_d, q̈_d, x_d)``, T rows each (the centre itself not included).

    ``u``, ``v``: the star's plane (default world x and y); ``time_law``: along each leg
    (:func:`leg_profile`). ValueError when the inverse
    kinematics misses a star point by more than ``tolerance`` (m): the star leaves the
    workspace.
    """
    centre = kinematics.forward(kinematics.home[None])[0]
    dims = len(centre)
    u = np.eye(dims)[0] if u is None or not len(u) else u
    v = np.eye(dims)[1] if v is None or not len(v) else v
    x_d = star_trajectory(centre, u, v, radius, dt, spread=spread, start_angle=start_angle,
                          time_law=time_law)
    q, qd, qdd, residuals = joint_trajectory(kinematics, np.vstack((centre, x_d)),
                                             kinematics.home, dt)
    if residuals.max() > tolerance:
        raise ValueError(f"the star leaves the robot's workspace: inverse kinematics misses "
                         f"it by up to {residuals.max():.4f} m (move the centre pose inwards "
                         f"or shrink the radius)")
    return q[1:], qd[1:], qdd[1:], x_d
