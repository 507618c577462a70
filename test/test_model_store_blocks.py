"""transfer_in_blocks: an LPA transfer block of rows by block of rows, so a large transfer
needs bounded memory and equals one block."""
import numpy as np
import pytest

from lpa_transfer import LocalProcrustesAnalysis, ProcrustesAnalysis
from lpa_transfer.transfer import gmm
from lpa_transfer.transfer.model_store import ModelStore, block_rows, transfer_in_blocks
from two_link import correspondences


@pytest.fixture(scope="module")
def model():
    model = LocalProcrustesAnalysis(n_min=5, c_min=0.0).fit(*correspondences(3000, seed=1))
    assert model.n_clusters_ > 100
    return model


@pytest.fixture(scope="module")
def test_points():
    return correspondences(20_000, seed=2)[0]


@pytest.mark.parametrize("block_elements", [1, 10_000, 200_000, 2_000_000])
def test_blocks_give_the_values_of_one_call(model, test_points, block_elements):
    rows = block_rows(model, block_elements)
    assert rows < len(test_points)           # more than one block
    whole = model.transfer(test_points)
    blocked = transfer_in_blocks(model, test_points, block_elements)
    np.testing.assert_allclose(blocked, whole, rtol=1e-12, atol=1e-12)
    assert np.array_equal(blocked, transfer_in_blocks(model, test_points, block_elements))


def test_block_rows_follow_the_elements_and_the_responsibility_blocks(model):
    step = gmm.row_blocks(10 ** 6, model.n_clusters_)[0].stop
    for block_elements in (1, 10_000, 200_000, 2_000_000):
        rows = block_rows(model, block_elements)
        assert rows % step == 0 and rows >= step
        assert rows <= max(step, block_elements // model.n_clusters_)
    assert block_rows(model, None) is None
    assert block_rows(ProcrustesAnalysis().fit(*correspondences(50, seed=1)), 10) is None


def test_one_block_is_the_library_call_bit_for_bit(model, test_points):
    few = test_points[:block_rows(model, 2_000_000)]
    assert np.array_equal(transfer_in_blocks(model, few, 2_000_000), model.transfer(few))


def test_bad_rows_are_named_in_the_whole_source(model, test_points):
    bad = test_points.copy()
    bad[12_345, 2] = np.inf
    with pytest.raises(ValueError, match=r"NaN or infinite values \(first in row 12345\)"):
        transfer_in_blocks(model, bad, 10_000)
    with pytest.raises(ValueError, match="3 columns but the model was fitted on 4"):
        transfer_in_blocks(model, test_points[:, :3], 10_000)


def test_the_store_transfers_in_blocks(tmp_path, test_points):
    store = ModelStore(tmp_path)
    fitted = store.fit("a->b", "lpa", *correspondences(3000, seed=1), n_min=5, c_min=0.0)
    np.testing.assert_allclose(store.transfer("a->b", test_points, 10_000),
                               fitted.transfer(test_points), rtol=1e-12, atol=1e-12)
    assert np.array_equal(store.transfer("a->b", test_points), fitted.transfer(test_points))


def test_the_result_can_go_into_a_given_array(model, test_points):
    out = np.full((len(test_points), 4), np.nan)
    assert transfer_in_blocks(model, test_points, 10_000, out=out) is out
    assert np.array_equal(out, transfer_in_blocks(model, test_points, 10_000))
    pa = ProcrustesAnalysis().fit(*correspondences(50, seed=1))
    out = np.empty((100, 4))
    transfer_in_blocks(pa, test_points[:100], 10_000, out=out)
    assert np.array_equal(out, pa.transfer(test_points[:100]))
