"""Reaching evaluation of a learned inverse model (thesis §6.5).

The thesis tests the learned L⁻¹ at evenly spaced times "on some test data evenly distributed
in the target robot's task space" with two measures: the average error of reaching all test
points, and the reaching rate, the share of points reached within a threshold (0.01 m for
the 2-link arms, §6.5.1; 0.015 m for Poppy, §6.5.2).

Test points (:func:`evaluation_points`): a regular grid over a task box, kept only where the
robot can reach. Reachability is decided in two steps: the joint space is sampled uniformly
(seeded) and mapped by the forward kinematics; a grid point within ``tolerance`` of such a
sample is a candidate, and it is kept if damped-least-squares inverse kinematics
(:mod:`lpa_transfer.robots.inverse_kinematics`), started at that sample's joints, reaches it within
``ik_tolerance``. Every kept point is thus reachable within the joint limits, and a perfect
inverse model reaches all of them.
"""
from typing import NamedTuple

import numpy as np
from scipy.spatial import cKDTree

from lpa_transfer import _validation as check
from lpa_transfer.robots import inverse_kinematics
from lpa_transfer._validation import check_x_bounds
from lpa_transfer.robots.kinematics import sample_joint_uniform


class Reaching(NamedTuple):
    """The two measures of progress of §6.5."""

    mean_error: float   # m, mean distance between the test points and the positions reached
    rate: float         # share of test points reached within the threshold, in [0, 1]


def grid(x_bounds, spacing):
    """Points (N, m) of a regular grid with step ``spacing`` (m) filling the box x_bounds,
    centred in it (equal margins, each below ``spacing``)."""
    low, high = check_x_bounds(x_bounds)
    check.check_float(spacing, "spacing", 0)
    if spacing == 0:
        raise ValueError("spacing must be > 0")
    counts = np.floor((high - low) / spacing + 1e-9).astype(int) + 1
    starts = low + (high - low - (counts - 1) * spacing) / 2
    axes = [start + spacing * np.arange(count) for start, count in zip(starts, counts)]
    return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, len(low))


def evaluation_points(environment, x_bounds=None, spacing=0.05, tolerance=0.01,
                      n_joint_samples=20000, seed=0, ik_tolerance=1e-6):
    """Test points (N, m) evenly spread through the reachable part of a task box (module
    docstring): the grid of ``spacing`` over ``x_bounds`` (default: the bounding box of the
    sampled reachable positions) kept where ``environment`` (a Kinematics) reaches them.
    The same arguments give the same points."""
    check.check_int(n_joint_samples, "n_joint_samples", 1)
    check.check_float(tolerance, "tolerance", 0)
    check.check_float(ik_tolerance, "ik_tolerance", 0)
    limits = np.asarray(environment.joint_limits, dtype=np.float64)
    joints = sample_joint_uniform(n_joint_samples, limits, np.random.default_rng(seed))
    reached = np.asarray(environment.forward(joints), dtype=np.float64)
    if x_bounds is None:
        x_bounds = (reached.min(axis=0), reached.max(axis=0))
    candidates = grid(check_x_bounds(x_bounds, reached.shape[1]), spacing)
    distance, nearest = cKDTree(reached).query(candidates)
    kept = []
    for point, start in zip(candidates[distance <= tolerance],
                            joints[nearest[distance <= tolerance]]):
        _, residual = inverse_kinematics.solve(environment.forward, point, start, limits)
        if residual <= ik_tolerance:
            kept.append(point)
    return np.reshape(kept, (len(kept), reached.shape[1]))


def coverage(points, reached, radius):
    """Share of the test ``points`` (N, m) within ``radius`` of some ``reached`` position
    (M, m): the reaching rate at threshold ``radius`` that an inverse model could at best
    attain if it only ever commanded the poses that gave ``reached`` (a ceiling on what data
    confined to those positions can teach)."""
    points, reached = check.as_matrix(points, "points"), check.as_matrix(reached, "reached")
    check.check_float(radius, "radius", 0)
    if not len(points) or not len(reached) or points.shape[1] != reached.shape[1]:
        raise ValueError(f"points and reached must be non-empty with the same width, got "
                         f"shapes {points.shape} and {reached.shape}")
    distance, _ = cKDTree(reached).query(points)
    return float(np.mean(distance <= radius))


def reachable_share(environment, points, radius, n_joint_samples=200000, seed=0):
    """:func:`coverage` of ``points`` by ``environment`` (a Kinematics) within its joint
    limits, estimated from ``n_joint_samples`` uniform joint samples (seeded): the share of
    the points it reaches within ``radius`` (from below: a finite sample may miss a point)."""
    check.check_int(n_joint_samples, "n_joint_samples", 1)
    joints = sample_joint_uniform(n_joint_samples, np.asarray(environment.joint_limits),
                                  np.random.default_rng(seed))
    return coverage(points, np.asarray(environment.forward(joints), dtype=np.float64), radius)


def reaching_errors(inverse_model, environment, points):
    """Distances (N,) between test points (N, m) and where ``environment`` (a Kinematics)
    puts its end effector when executing the commands ``inverse_model.predict(points)``
    (clipped into the joint limits, as the robot would)."""
    points = check.as_matrix(points, "points")
    if not len(points):
        raise ValueError("points holds no test points")
    limits = np.asarray(environment.joint_limits, dtype=np.float64)
    commands = np.clip(np.asarray(inverse_model.predict(points), dtype=np.float64),
                       limits[:, 0], limits[:, 1])
    reached = np.asarray(environment.forward(commands), dtype=np.float64)
    return np.linalg.norm(reached - points, axis=1)


def reaching_rate(errors, threshold=0.01):
    """Share of errors <= ``threshold`` (m): the reaching rate of §6.5, in [0, 1]."""
    errors = np.asarray(errors, dtype=np.float64)
    check.check_float(threshold, "threshold", 0)
    if errors.ndim != 1 or errors.size == 0 or not np.isfinite(errors).all():
        raise ValueError(f"errors must be a non-empty 1-D array of finite distances, got shape "
                         f"{errors.shape}")
    return float(np.mean(errors <= threshold))


def evaluate_reaching(inverse_model, environment, points, threshold=0.01):
    """:class:`Reaching` (mean error, reaching rate) of ``inverse_model`` on the test points."""
    errors = reaching_errors(inverse_model, environment, points)
    return Reaching(float(errors.mean()), reaching_rate(errors, threshold))
