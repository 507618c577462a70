"""A transfer that yields to the robot's own experience (FeedForwardLearner's ``yielding``):
after the initial data, the robot's own samples make receptive fields of their own above
``own_w_gen`` (LWPR.set_w_gen)."""
import copy

import numpy as np
import pytest

from lpa_transfer.inverse_dynamics.online_learning import FeedForwardLearner
from lpa_transfer.learners.locally_weighted import LocallyWeightedRegression
from lpa_transfer.learners.lwpr import LWPR
from lpa_transfer.robots.control import PID


def truth(X):
    return np.column_stack((np.sin(3 * X[:, 0]), X[:, 0] ** 2))


def lwpr():
    return LWPR(init_D=20.0, init_alpha=1.0, norm_in=1.0, empty_prediction="zero")


def test_raising_w_gen_keeps_the_model_and_makes_fields_where_old_ones_answer_weakly():
    rng = np.random.default_rng(0)
    transferred = rng.uniform(-1, 1, (400, 1)) + 0.25          # another robot's states, shifted
    plain = lwpr().partial_fit(transferred, truth(transferred) + 0.3)
    raised = copy.deepcopy(plain).set_w_gen(0.6)
    queries = rng.uniform(-1, 1, (50, 1))
    assert np.array_equal(raised.predict(queries), plain.predict(queries))   # model kept
    assert raised.w_gen == 0.6 and raised.get_params()["w_gen"] == 0.6
    own = rng.uniform(-1, 1, (300, 1))
    for model in (plain, raised):
        for x in own:
            model.partial_fit(x[None], truth(x[None]))
    made = {name: int(m.n_receptive_fields_.sum()) for name, m in (("plain", plain),
                                                                   ("raised", raised))}
    assert made["raised"] > made["plain"], made
    error = {name: np.abs(m.predict(queries) - truth(queries)).mean()
             for name, m in (("plain", plain), ("raised", raised))}
    assert error["raised"] < error["plain"], error
    with pytest.raises(ValueError, match="w_gen"):
        raised.set_w_gen(1.5)


def test_a_yielding_learner_raises_w_gen_after_its_initial_data_only():
    pid = PID.from_gains([1.0, 0.0, 0.0])
    samples = np.random.default_rng(1).normal(size=(60, 4))
    plain = FeedForwardLearner(lwpr(), pid)
    yielding = FeedForwardLearner(lwpr(), pid, yielding=True, own_w_gen=0.4)
    for learner in (plain, yielding):
        assert learner.initialise(samples) == 60
    assert plain.regressor.w_gen == 0.1 and yielding.regressor.w_gen == 0.4
    # the initial data were learned the same way: the same model so far
    assert np.array_equal(plain.regressor.predict(samples[:5, :3]),
                          yielding.regressor.predict(samples[:5, :3]))
    assert yielding.observe(samples[0]) and yielding.regressor.w_gen == 0.4
    assert not yielding.observe(np.full(4, np.nan)) and yielding.n_rejected_ == 1


def test_bad_settings_are_refused():
    pid = PID.from_gains([1.0, 0.0, 0.0])
    with pytest.raises(ValueError, match="own_w_gen"):
        FeedForwardLearner(lwpr(), pid, yielding=True, own_w_gen=1.5)
    with pytest.raises(ValueError, match="LWPR"):
        FeedForwardLearner(LocallyWeightedRegression(), pid, yielding=True)
