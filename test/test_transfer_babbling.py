"""lpa_transfer.goal_babbling.transfer: transfer of goal-babbling experience (§6.4-§6.5) and the
negative-transfer guard (§6.6)."""
import numpy as np
import pytest

from lpa_transfer.transfer.procrustes import ProcrustesAnalysis
from lpa_transfer.learners.sensorimotor import make_sensorimotor_model
from lpa_transfer.goal_babbling.experiment import Experiment1, run_condition
from lpa_transfer.goal_babbling.negative_transfer import (COVERED, DISAGREED, GuardedModel,
                                                          chain_lipschitz)
from lpa_transfer.goal_babbling.transfer import initialise_with_transfer, transfer_experience
from two_link import GB_TARGET_LINKS

SMALL = Experiment1(source_seconds=150, total_seconds=120, guided_seconds=30, interval=30,
                    eval_spacing=0.1)


def linear_pairs(n=50, seed=0):
    """(q̄, x_s) rows and their images (q̄, A x_s + b) under a known affine map."""
    rows = np.random.default_rng(seed).uniform(-1, 1, (n, 4))
    image = rows.copy()
    image[:, 2:] = rows[:, 2:] @ np.array([[0.5, 0.2], [-0.1, 1.5]]).T + [0.3, -0.2]
    return rows, image


# -- transfer_experience (§6.4.1) ---------------------------------------------------------------
def test_pa_transfer_of_a_linear_relation_is_exact_and_padded_to_the_target():
    source, target = linear_pairs()
    mapping = ProcrustesAnalysis().fit(source, target)
    experience, expected = linear_pairs(20, seed=1)
    home = np.array([7.0, 8.0, 9.0])
    commands, points = transfer_experience(mapping, experience, home, [2, 0])
    assert commands.shape == (20, 3) and points.shape == (20, 2)
    np.testing.assert_array_equal(commands[:, 1], 8.0)          # the joint the source lacks
    np.testing.assert_allclose(commands[:, [2, 0]], experience[:, :2], atol=1e-12)
    np.testing.assert_allclose(points, expected[:, 2:], atol=1e-12)


def test_transfer_experience_rejects_bad_input():
    mapping = ProcrustesAnalysis().fit(*linear_pairs())
    with pytest.raises(ValueError, match="3 columns but the model was fitted on 4"):
        transfer_experience(mapping, np.zeros((3, 3)), [0.0, 0.0], [0, 1])
    with pytest.raises(ValueError, match="NaN"):
        transfer_experience(mapping, np.full((3, 4), np.nan), [0.0, 0.0], [0, 1])
    with pytest.raises(ValueError, match="too few for 4 shared joints"):
        transfer_experience(mapping, np.zeros((3, 4)), np.zeros(5), [0, 1, 2, 3])


def test_plain_initialisation_gives_transferred_samples_weight_one():
    model = make_sensorimotor_model(forward=False)
    initialise_with_transfer(model, np.ones((4, 2)), np.zeros((4, 2)))
    np.testing.assert_array_equal(model.inverse.sample_weight_, np.ones(4))


# -- GuardedModel (§6.6) ------------------------------------------------------------------------
def guarded(**hyperparameters):
    model = GuardedModel(**hyperparameters)
    model.update([[1.0, 1.0]], [[1.0, 0.0]])          # own: x = (1, 0) -> q = (1, 1)
    return model


def test_transferred_samples_count_less_than_own_ones_at_equal_distance():
    model = guarded(transferred_weight=0.25).transfer([[3.0, 3.0]], [[-1.0, 0.0]])
    # own and transferred sample both 1 from the query: weights 1 and 0.25
    np.testing.assert_allclose(model.infer_command([[0.0, 0.0]]), [[1.4, 1.4]])
    assert model.n_active_ == 1
    with pytest.raises(ValueError, match="transferred_weight must lie in"):
        GuardedModel(transferred_weight=1.5)


def test_transferred_samples_decide_alone_where_the_robot_has_no_own_data():
    model = guarded(lipschitz=100.0).transfer([[3.0, 3.0]], [[5.0, 5.0]])
    np.testing.assert_allclose(model.infer_command([[5.0, 5.0]]), [[3.0, 3.0]])


def test_a_transferred_sample_is_retired_once_own_data_cover_it():
    model = guarded(coverage_radius=0.1, coverage_count=2, lipschitz=100.0)
    model.transfer([[3.0, 3.0], [4.0, 4.0]], [[-1.0, 0.0], [5.0, 5.0]])
    model.update([[2.0, 2.0]], [[-1.05, 0.0]])
    assert model.n_active_ == 2                          # one own sample: not yet covered
    assert model.infer_command([[-1.0, 0.0]])[0, 0] > 2.2   # (3, 3) still counts
    model.update([[2.0, 2.0]], [[-0.95, 0.0]])
    np.testing.assert_array_equal(model.status_, [COVERED, 0])
    own_only = model.model.inverse.predict([[-1.0, 0.0]])    # (3, 3) no longer counts
    np.testing.assert_array_equal(model.infer_command([[-1.0, 0.0]]), own_only)


def test_existing_own_data_cover_transferred_samples_at_transfer():
    model = guarded(coverage_radius=0.1, coverage_count=1, lipschitz=100.0)
    model.transfer([[3.0, 3.0], [4.0, 4.0]], [[1.05, 0.0], [5.0, 5.0]])
    np.testing.assert_array_equal(model.status_, [COVERED, 0])


def test_a_transferred_sample_contradicted_by_an_observation_is_retired():
    # claim: q = (0, 0) reaches (0.5, 0); with L = 1 an observation at q' = (0.01, 0)
    # must lie within 0.01 m of it (+ the 0.01 m threshold)
    model = guarded(lipschitz=1.0, disagreement_threshold=0.01, coverage_radius=0.001)
    model.transfer([[0.0, 0.0]], [[0.5, 0.0]])
    model.update([[0.01, 0.0]], [[0.515, 0.0]])          # 0.015 <= 0.02: consistent
    assert model.n_active_ == 1
    model.update([[0.01, 0.0]], [[0.5, 0.025]])          # 0.025 > 0.02: contradicted
    assert model.status_[0] == DISAGREED and model.n_active_ == 0


def test_own_data_contradicting_a_sample_retire_it_at_transfer():
    model = guarded(lipschitz=1.0, coverage_radius=0.001)   # own: q (1, 1) -> x (1, 0)
    model.transfer([[1.0, 1.01], [1.0, 1.01]], [[1.005, 0.0], [1.1, 0.0]])
    np.testing.assert_array_equal(model.status_, [0, DISAGREED])


def test_the_lipschitz_bound_of_a_planar_arm_holds_for_the_target():
    links, rng = GB_TARGET_LINKS, np.random.default_rng(0)
    bound = chain_lipschitz(links)
    assert bound == pytest.approx(np.hypot(1.1, 0.4))
    from lpa_transfer.robots.kinematics import planar_forward_kinematics
    q = rng.uniform(-3, 3, (500, 2))
    step = rng.normal(0, 1e-4, (500, 2))
    ratio = np.linalg.norm(planar_forward_kinematics(q + step, links)
                           - planar_forward_kinematics(q, links), axis=1) \
        / np.linalg.norm(step, axis=1)
    assert ratio.max() <= bound and ratio.max() > 0.8 * bound


def test_the_lipschitz_bound_holds_for_a_serial_chain():
    """The youBot (5 joints, offsets in 3-D): finite-difference slopes of its forward
    kinematics stay below chain_lipschitz of its link offsets."""
    from conftest import ROOT
    from lpa_transfer.robots.params import load_robot_params
    from lpa_transfer.robots.serial_chain import forward_kinematics
    robot = load_robot_params(ROOT / "scenarios" / "robots" / "youbot_arm.toml")
    bound, rng = chain_lipschitz(robot.link_lengths), np.random.default_rng(1)
    q = rng.uniform(robot.joint_limits[:, 0], robot.joint_limits[:, 1], (2000, 5))
    step = rng.normal(0, 1e-5, (2000, 5))
    ratio = np.linalg.norm(forward_kinematics(robot, q + step) - forward_kinematics(robot, q),
                           axis=1) / np.linalg.norm(step, axis=1)
    assert ratio.max() <= bound and ratio.max() > 0.5 * bound


# -- experiment 1 runner (§6.5.1) ---------------------------------------------------------------
def test_runner_is_reproducible_and_seeded():
    first, again = run_condition("PA-guarded", 3, SMALL), run_condition("PA-guarded", 3, SMALL)
    np.testing.assert_array_equal(first.times, [30, 60, 90, 120])
    for a, b in zip(first, again):
        np.testing.assert_array_equal(a, b)
    other = run_condition("PA-guarded", 4, SMALL)
    assert not np.array_equal(first.mean_error, other.mean_error)
    assert first.n_transferred[0] > 0 and (np.diff(first.n_transferred) <= 0).all()


def test_transfer_between_identical_arms_beats_scratch_early():
    same = Experiment1(source_links=GB_TARGET_LINKS, source_seconds=150, total_seconds=60,
                       guided_seconds=30, interval=15, eval_spacing=0.1)
    scratch, transfer = run_condition("scratch", 0, same), run_condition("PA", 0, same)
    # before the transfer both are the same goal babbling (same seed): the same model
    assert transfer.mean_error[0] == scratch.mean_error[0] and transfer.n_transferred[0] == 0
    assert transfer.mean_error[1] < 0.5 * scratch.mean_error[1]
    assert transfer.rate[1] > scratch.rate[1] + 0.1
    assert (transfer.n_transferred[1:] == 1500).all() and (scratch.n_transferred == 0).all()


def test_runner_rejects_bad_conditions_and_times():
    with pytest.raises(ValueError, match="condition must be one of"):
        run_condition("LWPR", 0, SMALL)
    with pytest.raises(ValueError, match="guided_seconds <= total_seconds"):
        run_condition("PA", 0, Experiment1(total_seconds=60, guided_seconds=90, interval=30))
