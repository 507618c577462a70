"""lpa_transfer._estimator: PA, LPA, the k-NN model and the DMP follow scikit-learn's estimator
protocol without importing scikit-learn, so that the nodes built on them start without it.
LWPR stays a scikit-learn BaseEstimator (test_lwpr.py runs scikit-learn's checks on it)."""
import subprocess
import sys

import numpy as np
import pytest
from sklearn.base import clone as sklearn_clone
from sklearn.exceptions import NotFittedError

from lpa_transfer import LWPR, LocalProcrustesAnalysis, ProcrustesAnalysis
from lpa_transfer._estimator import Estimator, clone
from lpa_transfer.learners.sensorimotor import KNNRegressor
from lpa_transfer.lfd.dmp import JointDMP


@pytest.mark.parametrize("make", [lambda: LocalProcrustesAnalysis(n_min=9, cluster_dims=[0, 1]),
                                  lambda: ProcrustesAnalysis(latent_dim=2),
                                  lambda: KNNRegressor(n_neighbors=5),
                                  lambda: JointDMP(n_weights_per_dim=12),
                                  lambda: LWPR(init_D=np.eye(2), meta=True)])
def test_scikit_learns_clone_and_ours_give_unfitted_equal_copies(make):
    model = make()
    for copy in (sklearn_clone(model), clone(model)):
        assert type(copy) is type(model) and copy is not model
        assert repr(copy) == repr(model)
        assert {k: str(v) for k, v in copy.get_params().items()} == \
            {k: str(v) for k, v in model.get_params().items()}


def test_fitted_state_is_not_cloned_and_parameters_are_set_by_name():
    rng = np.random.default_rng(0)
    source, target = rng.normal(size=(60, 2)), rng.normal(size=(60, 2))
    model = ProcrustesAnalysis(latent_dim=2).fit(source, target)
    assert not hasattr(clone(model), "coef_")
    assert model.set_params(latent_dim=1) is model and model.latent_dim == 1
    with pytest.raises(ValueError, match="invalid parameter 'latent' for ProcrustesAnalysis"):
        model.set_params(latent=1)
    assert repr(LocalProcrustesAnalysis(n_min=9)) == "LocalProcrustesAnalysis(n_min=9)"


def test_nested_estimators_are_reached_as_scikit_learn_names_them():
    class Holder(Estimator):
        def __init__(self, model=None, scale=1.0):
            self.model, self.scale = model, scale

    holder = Holder(model=LWPR(init_D=2.0))
    assert holder.get_params()["model__init_D"] == 2.0
    holder.set_params(model__init_D=5.0, scale=2.0)
    assert holder.model.init_D == 5.0 and holder.scale == 2.0
    copy = clone(holder)
    assert copy.model is not holder.model and copy.model.init_D == 5.0


def test_not_fitted_is_scikit_learns_error():
    with pytest.raises(NotFittedError, match="no samples yet"):
        KNNRegressor().predict(np.zeros((1, 2)))
    with pytest.raises(NotFittedError, match="LWPR instance is not fitted yet"):
        LWPR().predict(np.zeros((1, 2)))


@pytest.mark.parametrize("node", ["lpa_mapping", "goal_babbling_learner", "skill_learner",
                                  "correspondence_collector", "robot_sim"])
def test_nodes_start_without_importing_scikit_learn(node):
    """scikit-learn's import (scipy.stats through sklearn.base) would lengthen each node's
    start (measured in docs/history.md)."""
    code = (f"import sys, lpa_transfer_nodes.{node}\n"
            "print(sorted({k.split('.')[0] for k in sys.modules} & {'sklearn'}))\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout
    assert out.strip() == "[]"
