"""Planar chains in pybullet and their inverse-dynamics babbling data (thesis ch. 5, eq. 5.1)."""
import os
import tempfile

import numpy as np
import pytest

import pybullet as p

from lpa_transfer.robots.planar_chain import (GRAVITY, babbling_trajectory, inverse_dynamics,
                                              inverse_dynamics_babbling, planar_chain_urdf)

LENGTHS, MASSES = (0.3, 0.25, 0.2), (1.5, 1.0, 0.5)


def load(urdf):
    """Load URDF text into a fresh DIRECT client; returns (client, body)."""
    handle, path = tempfile.mkstemp(suffix=".urdf")
    with os.fdopen(handle, "w") as f:
        f.write(urdf)
    client = p.connect(p.DIRECT)
    try:
        body = p.loadURDF(path, useFixedBase=True, flags=p.URDF_USE_INERTIA_FROM_FILE,
                          physicsClientId=client)
    finally:
        os.remove(path)
    return client, body


def test_urdf_parses_with_the_declared_joints_masses_and_geometry():
    limits = [(-1.0, 1.0), (-2.0, 0.5), (0.0, 3.0)]
    client, body = load(planar_chain_urdf(LENGTHS, MASSES, limits, effort_limits=(40, 20, 5)))
    try:
        assert p.getNumJoints(body, physicsClientId=client) == 4        # 3 revolute + tool
        for j, (lower, upper) in enumerate(limits):
            info = p.getJointInfo(body, j, physicsClientId=client)
            assert info[2] == p.JOINT_REVOLUTE
            assert info[8:11] == pytest.approx((lower, upper, (40, 20, 5)[j]))
            assert info[13] == pytest.approx((0, 0, 1))                 # axis z
            dyn = p.getDynamicsInfo(body, j, physicsClientId=client)
            assert dyn[0] == pytest.approx(MASSES[j])
            assert dyn[2][2] == pytest.approx(MASSES[j] * LENGTHS[j] ** 2 / 12)
        assert p.getJointInfo(body, 3, physicsClientId=client)[2] == p.JOINT_FIXED
        # q = 0 stretches the chain along +x: the tool sits at the summed link lengths.
        tool = p.getLinkState(body, 3, computeForwardKinematics=True,
                              physicsClientId=client)[4]
        assert tool == pytest.approx((sum(LENGTHS), 0, 0))
    finally:
        p.disconnect(physicsClientId=client)


def test_one_link_pendulum_matches_the_analytic_torque():
    """Uniform rod about its end, gravity in the plane: τ = m g (L/2) cos q + (m L²/3) q̈."""
    length, mass = 0.7, 2.3
    rng = np.random.default_rng(0)
    q, qd, qdd = (rng.uniform(-3, 3, (50, 1)) for _ in range(3))
    tau = inverse_dynamics([length], [mass], q, qd, qdd, joint_limits=[(-np.pi, np.pi)])
    expected = mass * GRAVITY * length / 2 * np.cos(q) + mass * length ** 2 / 3 * qdd
    np.testing.assert_allclose(tau, expected, atol=1e-6)


def test_babbling_shapes_limits_and_derivatives():
    limits = [(-1.0, 1.0), (0.0, 2.0), (-0.5, 0.2)]
    data = inverse_dynamics_babbling(LENGTHS, MASSES, duration_s=2.0, rate_hz=100, seed=3,
                                     joint_limits=limits)
    assert set(data) == {"q", "qd", "qdd", "tau"}
    assert all(v.shape == (200, 3) for v in data.values())
    limits = np.array(limits)
    assert (data["q"] >= limits[:, 0]).all() and (data["q"] <= limits[:, 1]).all()
    # q̇ and q̈ are the time derivatives of q (central differences of the analytic motion).
    dt = 1e-5
    t = np.array([0.5 - dt, 0.5, 0.5 + dt])
    q, qd, qdd = babbling_trajectory(3, t, seed=3, joint_limits=limits)
    np.testing.assert_allclose((q[2] - q[0]) / (2 * dt), qd[1], rtol=1e-6, atol=1e-8)
    np.testing.assert_allclose((qd[2] - qd[0]) / (2 * dt), qdd[1], rtol=1e-6, atol=1e-8)


def test_babbling_is_deterministic_for_a_seed_and_differs_between_seeds():
    first = inverse_dynamics_babbling(LENGTHS, MASSES, 1.0, 50, seed=7)
    again = inverse_dynamics_babbling(LENGTHS, MASSES, 1.0, 50, seed=7)
    other = inverse_dynamics_babbling(LENGTHS, MASSES, 1.0, 50, seed=8)
    for key in first:
        np.testing.assert_array_equal(first[key], again[key])
        assert not np.allclose(first[key], other[key])


def test_chains_of_different_length_share_the_babbling_of_common_joints():
    """Same seed, same program: joint j moves alike on both chains (correspondences, §5.4.1)."""
    t = np.linspace(0, 3, 31)
    five, four = babbling_trajectory(5, t, seed=2), babbling_trajectory(4, t, seed=2)
    for a, b in zip(five, four):
        np.testing.assert_array_equal(a[:, :4], b)


@pytest.mark.parametrize("bad", [dict(link_lengths=[0.3, -0.1], link_masses=[1, 1]),
                                 dict(link_lengths=[0.3], link_masses=[1, 1]),
                                 dict(link_lengths=[0.3], link_masses=[1],
                                      joint_limits=[(1.0, -1.0)])])
def test_invalid_chains_are_rejected(bad):
    with pytest.raises(ValueError):
        planar_chain_urdf(**bad)
