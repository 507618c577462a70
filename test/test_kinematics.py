"""Planar forward kinematics and domain data of the §3.6 example (lpa_transfer.robots.kinematics)."""
import numpy as np
import pytest

from lpa_transfer.robots.kinematics import (domain_data, end_effector_rmse,
                                            planar_forward_kinematics, sample_joint_uniform)

LENGTHS = (0.6, 0.2)  # target robot of Table 3.1


@pytest.mark.parametrize("q, expected", [
    ((0.0, 0.0), (0.8, 0.0)),                       # stretched along +x
    ((np.pi / 2, 0.0), (0.0, 0.8)),                 # stretched along +y
    ((0.0, np.pi / 2), (0.6, 0.2)),                 # elbow bent up
    ((np.pi / 2, np.pi), (0.0, 0.4)),               # folded back on link 1
])
def test_fk_at_known_angles(q, expected):
    np.testing.assert_allclose(planar_forward_kinematics([q], LENGTHS)[0], expected, atol=1e-12)


def test_fk_three_links_and_batch():
    q = np.array([[0.0, 0.0, 0.0], [np.pi / 2, -np.pi / 2, -np.pi / 2]])
    np.testing.assert_allclose(planar_forward_kinematics(q, [1.0, 2.0, 3.0]),
                               [[6.0, 0.0], [2.0, -2.0]], atol=1e-12)


@pytest.mark.parametrize("q", [np.zeros(2), np.zeros((3, 3)), np.zeros((1, 2, 2)),
                               [[np.nan, 0.0]]])
def test_fk_rejects_bad_joint_arrays(q):
    with pytest.raises(ValueError, match="q"):
        planar_forward_kinematics(q, LENGTHS)


@pytest.mark.parametrize("lengths", [[], [[0.3, 0.2]], [0.3, -0.2], [0.3, np.inf]])
def test_fk_rejects_bad_link_lengths(lengths):
    with pytest.raises(ValueError, match="link_lengths"):
        planar_forward_kinematics(np.zeros((1, 2)), lengths)


def test_sample_joint_uniform_stays_in_box_and_is_seeded():
    limits = [[0.0, np.pi / 2], [-1.0, np.pi]]
    q = sample_joint_uniform(5000, limits, np.random.default_rng(3))
    assert q.shape == (5000, 2)
    assert (q >= np.array(limits)[:, 0]).all() and (q <= np.array(limits)[:, 1]).all()
    np.testing.assert_allclose(q.mean(axis=0), np.mean(limits, axis=1), atol=0.05)
    np.testing.assert_array_equal(q, sample_joint_uniform(5000, limits, np.random.default_rng(3)))


@pytest.mark.parametrize("n, limits, rng", [
    (-1, [[0, 1]], np.random.default_rng()), (2.5, [[0, 1]], np.random.default_rng()),
    (3, [0, 1], np.random.default_rng()), (3, [[1, 0]], np.random.default_rng()),
    (3, [[0, 1]], 0)])
def test_sample_joint_uniform_rejects_bad_input(n, limits, rng):
    with pytest.raises(ValueError):
        sample_joint_uniform(n, limits, rng)


def test_domain_data_is_joints_then_end_effector():
    q = np.array([[0.0, 0.0], [np.pi / 2, 0.0]])
    np.testing.assert_allclose(domain_data(q, LENGTHS), [[0, 0, 0.8, 0], [np.pi / 2, 0, 0, 0.8]],
                               atol=1e-12)


def test_end_effector_rmse():
    assert end_effector_rmse([[3.0, 4.0], [0.0, 0.0]], [[0.0, 0.0], [0.0, 0.0]]) \
        == pytest.approx(np.sqrt(12.5))
    with pytest.raises(ValueError):
        end_effector_rmse(np.zeros((2, 2)), np.zeros((3, 2)))
