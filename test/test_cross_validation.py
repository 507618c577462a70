"""lpa_transfer.transfer.cross_validation: the held-out error the collector reports."""
import numpy as np
import pytest

from lpa_transfer.transfer import LocalProcrustesAnalysis, ProcrustesAnalysis
from lpa_transfer.transfer.cross_validation import held_out_nmse
from two_link import correspondences


def test_a_linear_map_is_held_out_exactly_and_noise_is_not():
    rng = np.random.default_rng(0)
    source = rng.normal(size=(200, 3))
    rotation, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    target = 2.0 * source @ rotation + [1.0, -2.0, 0.5]
    assert held_out_nmse(ProcrustesAnalysis(), source, target) < 1e-20
    unrelated = rng.normal(size=(200, 3))
    assert held_out_nmse(ProcrustesAnalysis(), source, unrelated) > 0.9


def test_lpa_beats_pa_held_out_on_the_2_link_arms_and_is_seeded():
    """§3.6's pair: LPA's local maps fit the nonlinear relation PA cannot."""
    source, target = correspondences(400, 1)
    lpa = LocalProcrustesAnalysis(n_min=7, c_min=1e-7, cluster_dims=[0, 1], n_init=1)
    lpa_score = held_out_nmse(lpa, source, target, random_state=3)
    assert lpa_score < 0.2 * held_out_nmse(ProcrustesAnalysis(), source, target)
    assert held_out_nmse(lpa, source, target, random_state=3) == lpa_score
    assert held_out_nmse(lpa, source, target, random_state=4) != lpa_score


@pytest.mark.parametrize("args, message", [
    ((np.zeros((3, 2)), np.zeros((3, 2))), "at least 5"),
    ((np.zeros((10, 2)), np.zeros((9, 2))), "as many source as target rows"),
    ((np.ones((10, 2)), np.ones((10, 2))), "constant"),
])
def test_bad_input_is_refused(args, message):
    with pytest.raises(ValueError, match=message):
        held_out_nmse(ProcrustesAnalysis(), *args)


def test_bad_fold_count_is_refused():
    with pytest.raises(ValueError, match="n_folds must be an integer >= 2"):
        held_out_nmse(ProcrustesAnalysis(), np.zeros((10, 2)), np.zeros((10, 2)), n_folds=1)
