"""Benchmark data sets: correspondences between a source and a target robot.

(a) The thesis' illustrative 2-link pair (§3.6, Table 3.1): source links 0.3/0.25 m, target
    0.6/0.2 m, q1 ∈ [0, π/2], q2 ∈ [0, π] drawn uniformly, correspondences share q; a domain
    point is z = (q, end-effector xy) (4-D on both sides).
(b) Inverse dynamics (ch. 5): a 5-link source chain (z = (q, q̇, q̈, τ), 20-D) and a 4-link
    target chain (16-D) run the same seeded babbling program at 100 Hz and are paired by time
    index (§5.4.1). The first 14.64 s give the 1464 training correspondences (ICRA 2018: 1464
    pairs from ~14 s of babbling); the following 168 s of the same session give 16,800
    held-out pairs (the size of the thesis' 20-trial source task data, §5.5.3), used both for
    the transfer-throughput test and for the held-out τ error. What the robots record
    carries 1 % Gaussian measurement noise (σ = 1 % of each column's standard deviation over
    the session); the held-out target is kept noise-free as ground truth. Without noise each
    local cluster of a smooth trajectory is nearly rank-deficient in 20-D, so a 16-D local
    PCA whitening divides by ~0 and extrapolation to the held-out states blows up (the plain
    reference more than the library, whose whitening drops eigenvalues < 1e-10·λ_max).

The chains are synthetic (thin uniform rods in a vertical plane, joints ±π/2), not models of
the youBot and the Pincher; only the proportions echo them: a heavier, longer 5-link source
and a light, short 4-link target (see ``SOURCE_CHAIN`` and ``TARGET_CHAIN``).
"""
import numpy as np

from lpa_transfer.robots.kinematics import domain_data, sample_joint_uniform
from lpa_transfer.robots.planar_chain import inverse_dynamics_babbling

TWO_LINK_SOURCE, TWO_LINK_TARGET = (0.3, 0.25), (0.6, 0.2)               # m, Table 3.1
TWO_LINK_JOINT_LIMITS = [(0.0, np.pi / 2), (0.0, np.pi)]
#: (link lengths in m, link masses in kg)
SOURCE_CHAIN = ((0.16, 0.155, 0.135, 0.11, 0.05), (1.4, 1.2, 0.9, 0.5, 0.3))
TARGET_CHAIN = ((0.04, 0.105, 0.105, 0.11), (0.10, 0.12, 0.10, 0.06))
RATE_HZ, N_TRAIN, N_HELD_OUT = 100, 1464, 16_800
MEASUREMENT_NOISE = 0.01


def two_link(n, seed):
    """``n`` correspondences (source (n, 4), target (n, 4)) of the §3.6 pair."""
    q = sample_joint_uniform(n, TWO_LINK_JOINT_LIMITS, np.random.default_rng(seed))
    return domain_data(q, TWO_LINK_SOURCE), domain_data(q, TWO_LINK_TARGET)


def _babbling_points(chain, n_samples, seed):
    data = inverse_dynamics_babbling(*chain, n_samples / RATE_HZ, RATE_HZ, seed)
    return np.hstack([data[key] for key in ("q", "qd", "qdd", "tau")])


def inverse_dynamics(seed=0, n_train=N_TRAIN, n_held_out=N_HELD_OUT):
    """Babbling correspondences 20-D -> 16-D, split in time: dict of (N, D) arrays.

    Keys ``source``/``target`` (the first ``n_train`` samples, noisy), ``source_held_out``
    (the next ``n_held_out``, noisy) and ``target_held_out`` (their noise-free target
    counterparts). Columns are (q, q̇, q̈, τ): the torques are the last 5 (source) and 4
    (target) columns.
    """
    source = _babbling_points(SOURCE_CHAIN, n_train + n_held_out, seed)
    target = _babbling_points(TARGET_CHAIN, n_train + n_held_out, seed)
    rng = np.random.default_rng([seed, 1])
    noisy_source, noisy_target = (
        z + MEASUREMENT_NOISE * z.std(axis=0) * rng.standard_normal(z.shape)
        for z in (source, target))
    return dict(source=noisy_source[:n_train], target=noisy_target[:n_train],
                source_held_out=noisy_source[n_train:], target_held_out=target[n_train:])
