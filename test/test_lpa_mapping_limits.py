"""lpa_mapping's limits on one request's work (so no request holds the service for long), on a
node in its own process: a fit past max_fit_points, max_n_init or max_k_max is refused naming
the parameter and its value, k_max = 0 stays within max_k_max, and a transfer in blocks equals
one block."""
import json

import numpy as np
import pytest

from lpa_transfer import LocalProcrustesAnalysis
from lpa_transfer.transfer.model_store import block_rows, transfer_in_blocks
from ros_harness import NodeProcess, ros_params, unique_domain_id
from test_lpa_mapping_node import MappingClient, matrix, points
from two_link import correspondences

LIMITS = dict(max_fit_points=250, max_n_init=5, max_k_max=10, transfer_block_elements=200)
LPA = dict(n_min=7, c_min=0.0, n_init=3, random_state=0)


@pytest.fixture(scope="module")
def service(tmp_path_factory):
    root = tmp_path_factory.mktemp("lpa_mapping_limits")
    domain_id = unique_domain_id()
    node = NodeProcess("lpa_mapping", domain_id, root / "log",
                       ros_params(model_dir=root / "models", **LIMITS))
    client = MappingClient(domain_id)
    yield client, node
    client.close()
    assert node.stop() == 0, node.log()


def fit(client, model_id, source, target, **fields):
    return client.call("fit", model_id=model_id, method="lpa", source=matrix(source),
                       target=matrix(target), **{**LPA, **fields})


def assert_refused(answer, text, client, node):
    assert not answer.success and text in answer.message, answer.message
    assert client.call("list").success and node.alive(), node.log()


def test_more_points_than_max_fit_points_is_refused(service):
    client, node = service
    source, target = correspondences(251, seed=1)
    answer = fit(client, "too-many", source, target)
    assert_refused(answer, "251 correspondences exceeds the limit max_fit_points = 250",
                   client, node)
    answer = client.call("fit", model_id="too-many", method="pa", source=matrix(source),
                         target=matrix(target))
    assert_refused(answer, "max_fit_points = 250", client, node)
    assert "too-many" not in client.call("list").model_ids
    assert fit(client, "just-enough", *correspondences(250, seed=1)).success


def test_n_init_past_max_n_init_is_refused(service):
    client, node = service
    source, target = correspondences(200, seed=1)
    assert_refused(fit(client, "x", source, target, n_init=6),
                   "n_init = 6 exceeds the limit max_n_init = 5", client, node)
    assert fit(client, "x", source, target, n_init=5).success


def test_k_max_past_max_k_max_is_refused_and_zero_means_max_k_max(service):
    client, node = service
    source, target = correspondences(240, seed=1)
    assert_refused(fit(client, "k", source, target, k_max=11),
                   "k_max = 11 exceeds the limit max_k_max = 10", client, node)
    unbounded = LocalProcrustesAnalysis(**LPA).fit(source, target)
    assert unbounded.n_clusters_ > 10          # so that the limit does bound this fit
    answer = fit(client, "k", source, target, k_max=0)
    assert answer.success and answer.n_clusters == 10, answer.message
    info = client.call("describe", model_id="k")
    assert json.loads(info.hyperparameters_json)["k_max"] == 10


def test_k_max_zero_below_the_limit_is_the_unbounded_model(service):
    client, _ = service
    source, target = correspondences(240, seed=1)
    fields = dict(LPA, n_min=30)
    unbounded = LocalProcrustesAnalysis(**fields).fit(source, target)
    assert unbounded.n_clusters_ < 10
    assert fit(client, "few", source, target, **fields).success
    test = correspondences(100, seed=3)[0]
    answer = client.call("transfer", model_id="few", source=matrix(test))
    assert np.array_equal(points(answer.target), unbounded.transfer(test))


def test_a_transfer_in_blocks_equals_one_block(service):
    """With transfer_block_elements = 200 the node transfers 30,000 points in blocks (of the
    rows of one of the library's responsibility blocks, the smallest): the same values as the
    library in one call (within 1e-12), and bit for bit what the blocked library call
    gives."""
    client, _ = service
    source, target = correspondences(240, seed=1)
    assert fit(client, "blocks", source, target).success       # k_max = 0: max_k_max
    model = LocalProcrustesAnalysis(**LPA, k_max=LIMITS["max_k_max"]).fit(source, target)
    test = correspondences(30_000, seed=4)[0]
    assert block_rows(model, LIMITS["transfer_block_elements"]) < len(test) // 2
    answer = client.call("transfer", model_id="blocks", source=matrix(test))
    assert answer.success, answer.message
    served = points(answer.target)
    np.testing.assert_allclose(served, model.transfer(test), rtol=1e-12, atol=1e-12)
    assert np.array_equal(served, transfer_in_blocks(model, test,
                                                     LIMITS["transfer_block_elements"]))
    bad = test.copy()
    bad[29_500, 1] = np.nan
    refused = client.call("transfer", model_id="blocks", source=matrix(bad))
    assert not refused.success and "first in row 29500" in refused.message, refused.message


def test_out_of_range_limits_stop_the_node_with_the_reason(tmp_path):
    node = NodeProcess("lpa_mapping", unique_domain_id(), tmp_path,
                       ros_params(model_dir=tmp_path / "models", max_k_max=0))
    node.process.wait(60)
    assert node.stop() == 1
    assert "max_k_max must be an integer >= 1, got 0" in node.log(), node.log()
