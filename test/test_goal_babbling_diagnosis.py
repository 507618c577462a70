"""Fast checks of lpa_transfer.goal_babbling.diagnosis, which explains the chapter 6
set-up's reaching rates (thesis §6.5.1)."""
import numpy as np
import pytest

from lpa_transfer.goal_babbling import diagnosis as dx
from lpa_transfer.goal_babbling.experiment import Experiment1
from lpa_transfer.learners.sensorimotor import make_sensorimotor_model

SMALL = Experiment1(source_seconds=60.0, total_seconds=120.0)


def test_transfer_accuracy_counts_shares_against_true_kinematics():
    config = Experiment1()
    target = config.arm(config.target_links)
    q = np.array([[-0.5, 1.0], [-1.0, 2.0], [-0.2, 0.8], [-1.2, 1.5]])
    x = np.asarray(target.forward(q))
    offsets = np.array([[0.0, 0.0], [0.003, 0.0], [0.0, 0.007], [0.02, 0.0]])
    errors, shares = dx.transfer_accuracy(config, q, x + offsets)
    np.testing.assert_allclose(errors, [0.0, 0.003, 0.007, 0.02], atol=1e-12)
    assert shares == {1.0: 0.25, 5.0: 0.5, 10.0: 0.75}


def test_neighbour_log_splits_own_and_transferred_neighbours():
    model = make_sensorimotor_model(forward=False)
    own_x = np.array([[0.0, 0.0], [0.01, 0.0], [0.0, 0.01]])
    far_x = np.array([[1.0, 1.0], [1.01, 1.0], [1.0, 1.01]])
    model.update(np.zeros((3, 2)), own_x)
    model.update(np.ones((3, 2)), far_x)
    log = dx.NeighbourLog(model.inverse, 3, 6, errors=[0.0, 0.02, 0.0])
    model.infer_command(np.array([[1.0, 1.0]]))
    model.infer_command(np.array([[0.0, 0.0]]))
    assert log.babble == [1.0, 0.0]
    log.mode = "eval"
    model.inverse.predict(np.array([[0.0, 0.0], [1.0, 1.0]]))
    split = log.eval_split(np.array([0.0, 0.05]), threshold=0.01)
    assert split["eval_neighbours_transferred"] == 0.5
    assert split["rate_all_own"] == (1.0, 1)
    assert split["rate_transferred_inaccurate"] == (0.0, 1)   # the 20 mm transferred neighbour
    assert split["rate_transferred_accurate"][1] == 0


def test_density_counts_transferred_against_own():
    config = Experiment1()
    points = dx._test_points(config)
    own = points[:10]
    transferred = np.repeat(points[:10], 3, axis=0)
    d = dx.density(config, own, transferred, radius=0.001)
    # 10 grid points with 1 own and 3 transferred each, the rest with none (share 0)
    assert d["density_share_transferred"] == pytest.approx(10 * 0.75 / len(points))
    assert d["density_points_transferred_majority"] == pytest.approx(10 / len(points))


def test_transferred_rows_variants():
    plain = dx.transferred_rows(SMALL, 0, 30.0, guided_longest=30.0)
    commands, points, weights, errors, info = plain
    assert info["n_correspondences"] == 300   # same limits: every command is a pair
    assert len(commands) == 600 and np.all(weights == 1)
    assert 0 <= info["within_1mm"] <= info["within_5mm"] <= info["within_10mm"] <= 1
    _, exact_points, _, exact_errors, _ = dx.transferred_rows(SMALL, 0, 30.0, "oracle_exact",
                                                              guided_longest=30.0)
    target = SMALL.arm(SMALL.target_links)
    np.testing.assert_allclose(exact_points, target.forward(commands), atol=1e-12)
    assert not exact_errors.any()
    _, _, _, kept_errors, kept = dx.transferred_rows(SMALL, 0, 30.0, "oracle_filter_5",
                                                     guided_longest=30.0)
    assert kept["n_transferred"] == int(np.sum(errors <= 0.005)) < len(commands)
    assert kept_errors.max() <= 0.005
    _, _, w, _, _ = dx.transferred_rows(SMALL, 0, 30.0, "weighted_0.3", guided_longest=30.0)
    assert np.all(w == 0.3)


def test_matched_pairs_keeps_only_agreeing_correspondences():
    # analytic arms reach every command: every pair agrees exactly, none is dropped
    *_, info = dx.transferred_rows(SMALL, 0, 30.0, "matched_pairs_0.0", guided_longest=30.0)
    assert info["n_correspondences"] == 300


def test_physics_arms_lag_and_pair_residuals_appear():
    from conftest import ROOT
    physics = tuple(str(ROOT / f"scenarios/robots/goal_babbling_{side}.toml")
                    for side in ("source", "target"))
    config = Experiment1(source_seconds=5.0, total_seconds=10.0)
    pairs = dx.guided_rows(config, 0, 5.0, physics)
    residual = np.abs(pairs.source[:, :2] - pairs.target[:, :2]).max(axis=1)
    assert len(residual) == 50 and residual.max() > 1e-3   # the arms lag differently
    *_, info = dx.transferred_rows(config, 0, 5.0, "matched_pairs_0.001", guided_longest=5.0,
                                   physics=physics)
    assert info["n_correspondences"] == int(np.sum(residual <= 0.001)) < 50


def test_reached_variant_settles_the_source_on_the_targets_postures():
    """The collector's default (source_follows reached): the source settles on what the
    target reached, so the pairs agree within PairCheck's tolerance where the command pairs
    did not; the rows mapped are the same source experience."""
    from conftest import ROOT
    physics = tuple(str(ROOT / f"scenarios/robots/goal_babbling_{side}.toml")
                    for side in ("source", "target"))
    config = Experiment1(source_seconds=5.0, total_seconds=10.0)
    pairs = dx.guided_rows(config, 0, 5.0, physics, "reached")
    source, target = pairs.correspondences()
    assert len(source) >= 48                                  # of 50 movements
    assert np.abs(source[:, :2] - target[:, :2]).max() <= 1e-3
    np.testing.assert_array_equal(pairs.target, dx.guided_rows(config, 0, 5.0, physics).target)
    *_, info = dx.transferred_rows(config, 0, 5.0, "reached", guided_longest=5.0,
                                   physics=physics)
    assert info["n_correspondences"] == len(source)
