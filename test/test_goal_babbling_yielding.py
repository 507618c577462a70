"""YieldingModel: transferred goal-babbling samples as a prior the own samples override."""
import numpy as np
import pytest

from lpa_transfer.goal_babbling.goal_babbling import GoalBabbling
from lpa_transfer.goal_babbling.transfer import initialise_with_transfer
from lpa_transfer.goal_babbling.yielding import YieldingModel
from lpa_transfer.learners.sensorimotor import KNNRegressor, make_sensorimotor_model
from lpa_transfer.robots.kinematics import Kinematics, planar_forward_kinematics

LINKS = np.array([0.7, 0.4])
LIMITS = np.array([[-np.pi / 2, 0.0], [0.4, 2.9]])


def arm():
    return Kinematics(LIMITS, LIMITS.mean(axis=1),
                      lambda q: planar_forward_kinematics(q, LINKS), ((-0.2, -1.2), (1.2, 0.6)))


def samples(n, seed):
    rng = np.random.default_rng(seed)
    q = rng.uniform(LIMITS[:, 0], LIMITS[:, 1], (n, 2))
    return q, planar_forward_kinematics(q, LINKS)


def model_with(own, transferred, **kw):
    model = YieldingModel(**kw)
    model.update(*own)
    return initialise_with_transfer(model, *transferred)


def test_own_samples_alone_answer_within_the_gate_and_the_thesis_mixing_elsewhere():
    own, transferred = samples(40, 0), samples(300, 1)
    model = model_with(own, transferred, gate_radius=0.05)
    queries = samples(200, 2)[1]
    plain_own = KNNRegressor().fit(own[1], own[0])
    mixed = KNNRegressor().fit(np.vstack((own[1], transferred[1])),
                               np.vstack((own[0], transferred[0])))
    near = plain_own.kneighbors(queries)[0][:, 0] <= 0.05
    assert 0 < near.sum() < len(queries)   # both kinds of query occur
    answer = model.inverse.predict(queries)
    np.testing.assert_allclose(answer[near], plain_own.predict(queries[near]), rtol=0,
                               atol=1e-12)
    np.testing.assert_allclose(answer[~near], mixed.predict(queries[~near]), rtol=0,
                               atol=1e-12)
    assert model.n_active_ == 300


def test_exploration_asks_the_own_samples_alone_or_the_gated_model():
    own, transferred = samples(40, 0), samples(300, 1)
    queries = samples(50, 3)[1]
    by_own = model_with(own, transferred, gate_radius=0.05, explore="own")
    gated = model_with(own, transferred, gate_radius=0.05, explore="gated")
    np.testing.assert_array_equal(by_own.infer_command(queries),
                                  KNNRegressor().fit(own[1], own[0]).predict(queries))
    np.testing.assert_array_equal(gated.infer_command(queries),
                                  gated.inverse.predict(queries))
    assert not np.allclose(by_own.infer_command(queries), gated.infer_command(queries))


def test_before_any_own_sample_the_transferred_samples_answer():
    transferred = samples(100, 1)
    model = initialise_with_transfer(YieldingModel(), *transferred)
    queries = samples(20, 4)[1]
    expected = KNNRegressor().fit(transferred[1], transferred[0]).predict(queries)
    np.testing.assert_allclose(model.infer_command(queries), expected, rtol=0, atol=1e-12)


def test_own_exploration_collects_what_babbling_without_transfer_collects():
    """explore="own": the transferred samples never steer what the robot collects."""
    plain = GoalBabbling(arm().task_box, seed=5).start(arm(), make_sensorimotor_model(
        forward=False))
    yielding = YieldingModel(explore="own")
    yielding.transfer(*samples(500, 6))
    guided = GoalBabbling(arm().task_box, seed=5).start(arm(), yielding)
    np.testing.assert_array_equal(plain.run(300)[0], guided.run(300)[0])
    gated = YieldingModel(explore="gated")
    gated.transfer(*samples(500, 6))
    steered = GoalBabbling(arm().task_box, seed=5).start(arm(), gated)
    assert not np.array_equal(plain.run(300)[0], steered.run(300)[0])


@pytest.mark.parametrize("kw", [{"gate_radius": -0.1}, {"gate_radius": float("nan")},
                                {"explore": "both"}])
def test_bad_hyperparameters_are_refused(kw):
    with pytest.raises(ValueError):
        YieldingModel(**kw)


def test_transfer_checks_its_rows():
    with pytest.raises(ValueError):
        YieldingModel().transfer(np.zeros((3, 2)), np.zeros((4, 2)))


def test_experiment_1_runs_the_yielding_conditions_beside_the_thesis_ones():
    """run_condition's "-yielding" conditions: the same transfer as plain LPA (same
    transferred count), answered through the gate; the same seed gives the same curves."""
    from lpa_transfer.goal_babbling.experiment import Experiment1, run_condition
    small = Experiment1(source_seconds=60.0, total_seconds=120.0)
    plain = run_condition("LPA", 0, small)
    yielding = run_condition("LPA-yielding", 0, small)
    assert yielding.n_transferred[-1] == plain.n_transferred[-1] > 0
    np.testing.assert_array_equal(yielding.rate, run_condition("LPA-yielding", 0, small).rate)
    assert ((yielding.rate >= 0) & (yielding.rate <= 1)).all()


def test_diagnosis_keeps_the_transferred_rows_apart_in_a_yielding_model():
    from lpa_transfer.goal_babbling import diagnosis
    from lpa_transfer.goal_babbling.experiment import Experiment1
    small = Experiment1(source_seconds=60.0, total_seconds=120.0)
    run = diagnosis.run_transfer_condition(small, 0, 60.0, guided_longest=60.0,
                                           yielding=dict(gate_radius=0.01))
    plain = diagnosis.run_transfer_condition(small, 0, 60.0, guided_longest=60.0)
    assert run["info"]["n_transferred"] == plain["info"]["n_transferred"] > 0
    assert np.isnan(run["curve"][-1]["eval_neighbours_transferred"])
    assert run["density_end"]["n_transferred_total"] == plain["density_end"][
        "n_transferred_total"]
