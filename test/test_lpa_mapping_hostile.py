"""lpa_mapping checks a request's sizes before it allocates anything (a hostile request must
not exhaust the host's memory), on a node in its own process over DDS: a Matrix of 50,000,000
rows and no columns (``rows*cols == len(data)`` holds) once took the service to a 1.78 GB peak
before it answered "source has no columns", and ``rows = 4294967295`` answered "internal error:
MemoryError()". Now each is refused from its shape, the service's peak RSS grows by less than
50 MiB, a transfer beyond the memory budget ``max_transfer_mib`` is refused naming it, and the
service keeps serving."""
from pathlib import Path

import numpy as np
import pytest

from lpa_transfer import ProcrustesAnalysis
from lpa_transfer.transfer.requests import check_transfer, transfer_bytes
from lpa_transfer_interfaces.msg import CorrespondenceBatch, Matrix
from lpa_transfer_nodes.qos import BATCH_QOS
from ros_harness import NodeProcess, ros_params, unique_domain_id
from test_lpa_mapping_node import MappingClient, fit, matrix, points
from two_link import correspondences

BUDGET_MIB = 4
#: The goal: a refused request grows the service's peak RSS by less than this.
MAX_PEAK_GROWTH_MIB = 50


@pytest.fixture(scope="module")
def service(tmp_path_factory):
    root = tmp_path_factory.mktemp("lpa_mapping_hostile")
    domain_id = unique_domain_id()
    node = NodeProcess("lpa_mapping", domain_id, root / "log",
                       ros_params(model_dir=root / "models", max_transfer_mib=BUDGET_MIB))
    client = MappingClient(domain_id)
    source, target = correspondences(200, seed=1)
    assert fit(client, "pa", source, target, method="pa").success, node.log()
    yield client, node, ProcrustesAnalysis().fit(source, target)
    client.close()
    assert node.stop() == 0, node.log()


def status_kib(pid, field):
    line = next(line for line in Path(f"/proc/{pid}/status").read_text().splitlines()
                if line.startswith(field + ":"))
    return int(line.split()[1])


def peak_growth_mib(node, action):
    """``action()``'s result and how far the node's peak RSS rose above its RSS before it
    (the peak reset through /proc/PID/clear_refs)."""
    pid = node.process.pid
    Path(f"/proc/{pid}/clear_refs").write_text("5")
    before = status_kib(pid, "VmRSS")
    result = action()
    return result, (status_kib(pid, "VmHWM") - before) / 1024


def assert_serving(client, node, model):
    test = correspondences(20, seed=3)[0]
    answer = client.call("transfer", model_id="pa", source=matrix(test))
    assert answer.success and np.array_equal(points(answer.target), model.transfer(test))
    assert node.alive(), node.log()


@pytest.mark.parametrize("rows, cols, data, message", [
    (50_000_000, 0, [], "source has no columns"),
    (4294967295, 0, [], "source has no columns"),
    (4294967295, 2, [1.0, 2.0], "rows*cols = 4294967295*2 = 8589934590 does not match the 2 "
                                "values in data"),
    (2, 3, [0.0] * 6, "source has 3 columns but the model was fitted on"),
])
def test_a_hostile_transfer_is_refused_before_anything_is_allocated(service, rows, cols,
                                                                     data, message):
    client, node, model = service
    answer, growth = peak_growth_mib(node, lambda: client.call(
        "transfer", model_id="pa", source=Matrix(rows=rows, cols=cols, data=data)))
    print(f"rows={rows} cols={cols}: peak RSS growth {growth:.1f} MiB; {answer.message!r}")
    assert not answer.success and message in answer.message, answer.message
    assert growth < MAX_PEAK_GROWTH_MIB, growth
    assert_serving(client, node, model)


def test_a_transfer_beyond_the_memory_budget_is_refused_naming_it(service):
    client, node, model = service
    width = model.n_features_in_
    too_many = BUDGET_MIB * 2 ** 20 // (2 * 8 * model.n_features_out_) + 1
    within = np.zeros((too_many - 1, width))
    answer = client.call("transfer", model_id="pa", source=matrix(np.zeros((too_many, width))))
    assert not answer.success, answer.message
    assert f"beyond the limit max_transfer_mib = {BUDGET_MIB}" in answer.message, answer.message
    answer = client.call("transfer", model_id="pa", source=matrix(within))
    assert answer.success and np.array_equal(points(answer.target), model.transfer(within))
    assert_serving(client, node, model)


def test_a_hostile_correspondence_batch_is_ignored_with_a_warning(service):
    client, node, model = service
    publisher = client.node.create_publisher(CorrespondenceBatch, "/correspondence_batch",
                                             BATCH_QOS)
    hostile = Matrix(rows=50_000_000, cols=0, data=[])
    client.spin_until(lambda: publisher.get_subscription_count() > 0, what="the service")
    _, growth = peak_growth_mib(node, lambda: (
        publisher.publish(CorrespondenceBatch(source_robot="a", target_robot="b",
                                              source=hostile, target=hostile)),
        client.spin_until(lambda: "ignoring a correspondence batch" in node.log(),
                          what="the warning")))
    print(f"hostile batch: peak RSS growth {growth:.1f} MiB")
    assert "source has no columns" in node.log()
    assert growth < MAX_PEAK_GROWTH_MIB, growth
    answer = client.call("fit", model_id="b", method="pa", received_pair="a->b")
    assert not answer.success and "no correspondences received" in answer.message
    assert_serving(client, node, model)


def test_the_budget_is_checked_from_the_shape_alone():
    source, target = correspondences(50, seed=1)
    model = ProcrustesAnalysis().fit(source, target)
    rows = 10 ** 12                               # 10^12 points: nothing is allocated
    assert transfer_bytes(model, rows) == 2 * rows * model.n_features_out_ * 8
    with pytest.raises(ValueError, match="max_transfer_mib = 1024"):
        check_transfer(model, (rows, model.n_features_in_), None, 1024)
    assert check_transfer(model, (7, model.n_features_in_), None, 1) == (
        7, model.n_features_out_)
