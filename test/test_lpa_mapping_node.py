"""The lpa_mapping node as a separate process over real DDS: fit, transfer, errors, restart."""
import itertools
import json
import signal

import numpy as np
import pytest

from lpa_transfer import LocalProcrustesAnalysis
from lpa_transfer.transfer.model_store import file_name
from ros_harness import ClientNode, NodeProcess, ros_params, unique_domain_id
from two_link import correspondences


from lpa_transfer_interfaces.msg import Matrix
from lpa_transfer_nodes.conversions import to_matrix
from lpa_transfer_interfaces.srv import (DeleteModel, DescribeModel, FitModel,
                                         ListModels, TransferPoints)

SERVICES = {"fit": FitModel, "transfer": TransferPoints, "list": ListModels,
            "describe": DescribeModel, "delete": DeleteModel}
LPA = dict(n_min=7, c_min=1e-3, n_init=3, random_state=0)
ID = "pincher->youbot"
_CLIENTS = itertools.count()


class MappingClient(ClientNode):
    """A client node in this process, on its own context, with one client per service."""

    def __init__(self, domain_id):
        super().__init__(domain_id, f"mapping_test_client_{next(_CLIENTS)}")
        self.clients = {name: self.node.create_client(srv, f"/lpa_mapping/{name}")
                        for name, srv in SERVICES.items()}

    def call(self, name, **fields):
        return super().call(self.clients[name], SERVICES[name].Request(**fields))


def matrix(values):
    return to_matrix(np.asarray(values, dtype=np.float64))


def points(msg):
    return np.frombuffer(msg.data).reshape(msg.rows, msg.cols)


def fit(client, model_id, source, target, method="lpa", **fields):
    return client.call("fit", model_id=model_id, method=method, source=matrix(source),
                       target=matrix(target), **{**LPA, **fields})


def start_node(domain_id, log_dir, model_dir):
    return NodeProcess("lpa_mapping", domain_id, log_dir, ros_params(model_dir=model_dir))


@pytest.fixture(scope="module")
def data():
    return correspondences(300, seed=1), correspondences(200, seed=2)[0]


@pytest.fixture(scope="module")
def service(tmp_path_factory, data):
    """One mapping node and a client; the model ``ID`` is fitted once for all tests."""
    root = tmp_path_factory.mktemp("lpa_mapping")
    domain_id = unique_domain_id()
    node = start_node(domain_id, root / "log", root / "models")
    client = MappingClient(domain_id)
    (source, target), _ = data
    answer = fit(client, ID, source, target)
    assert answer.success, answer.message + node.log()
    yield client, root / "models", node
    client.close()
    assert node.stop() == 0, node.log()


def test_round_trip_equals_the_library(service, data):
    client, _, _ = service
    (source, target), test = data
    library = LocalProcrustesAnalysis(**LPA).fit(source, target)
    answer = client.call("transfer", model_id=ID, source=matrix(test))
    assert answer.success, answer.message
    assert np.array_equal(points(answer.target), library.transfer(test))
    info = client.call("describe", model_id=ID)
    assert (info.method, info.source_dim, info.target_dim) == ("lpa", 4, 4)
    assert (info.n_clusters, info.n_points) == (library.n_clusters_, 300)
    assert json.loads(info.hyperparameters_json)["n_min"] == LPA["n_min"]
    assert ID in client.call("list").model_ids


def test_minimal_lpa_request_uses_the_library_defaults(service, data):
    client, _, _ = service
    (source, target), test = data
    answer = client.call("fit", model_id="minimal", method="lpa", source=matrix(source),
                         target=matrix(target))          # n_min, n_init, c_min left at 0
    assert answer.success, answer.message
    info = json.loads(client.call("describe", model_id="minimal").hyperparameters_json)
    assert (info["n_min"], info["n_init"], info["c_min"]) == (7, 3, 0.0)
    library = LocalProcrustesAnalysis(c_min=0.0).fit(source, target)
    transferred = client.call("transfer", model_id="minimal", source=matrix(test))
    assert np.array_equal(points(transferred.target), library.transfer(test))
    assert client.call("delete", model_id="minimal").success


def test_fit_from_a_correspondence_file(service, data):
    """In the default data_dir, the folder 'correspondences' beside model_dir."""
    client, model_dir, _ = service
    (source, target), test = data
    (model_dir.parent / "correspondences").mkdir(exist_ok=True)
    np.savez(model_dir.parent / "correspondences" / "pairs.npz", source=source, target=target)
    answer = client.call("fit", model_id="from-file", method="pa",
                         correspondence_file="pairs.npz")
    assert answer.success and answer.n_points == 300 and answer.n_clusters == 1, answer.message
    assert answer.training_rmse > 0
    client.call("delete", model_id="from-file")


def _bad(width=4, rows=10, nan=False):
    values = np.ones((rows, width))
    if nan:
        values[3, 1] = np.nan
    return matrix(values)


BAD_REQUESTS = {
    "unknown id": ("transfer", dict(model_id="nao", source=_bad()), "unknown model id 'nao'"),
    "transfer width": ("transfer", dict(model_id=ID, source=_bad(width=3)), "3 columns"),
    "NaN in source": ("transfer", dict(model_id=ID, source=_bad(nan=True)), "NaN"),
    "rows*cols != len(data)": ("transfer", dict(
        model_id=ID, source=Matrix(rows=4, cols=4, data=[1.0] * 15)), "rows*cols"),
    "too few points": ("fit", dict(model_id="x", method="lpa", source=_bad(rows=5),
                                   target=_bad(rows=5), **LPA), "too few correspondences"),
    "row mismatch": ("fit", dict(model_id="x", method="pa", source=_bad(rows=10),
                                 target=_bad(rows=9)), "same number of rows"),
    "unknown method": ("fit", dict(model_id="x", method="gp", source=_bad(), target=_bad()),
                       "unknown method 'gp'"),
    "empty id": ("fit", dict(model_id="", method="pa", source=_bad(), target=_bad()),
                 "non-empty"),
    "describe unknown": ("describe", dict(model_id="nao"), "unknown model id"),
    "no correspondences": ("fit", dict(model_id="x", method="pa"), "no correspondences"),
    "pair never received": ("fit", dict(model_id="x", method="pa", received_pair="a->b"),
                            "no correspondences received for the robot pair 'a->b'"),
}


@pytest.mark.parametrize("case", BAD_REQUESTS)
def test_bad_request_fails_and_the_service_keeps_answering(service, data, case):
    client, _, node = service
    name, fields, problem = BAD_REQUESTS[case]
    answer = client.call(name, **fields)
    assert not answer.success and problem in answer.message, answer.message
    good = client.call("transfer", model_id=ID, source=matrix(data[1][:5]))
    assert good.success and good.target.rows == 5 and node.alive()
    assert "x" not in client.call("list").model_ids


def test_delete_removes_the_model(service, data):
    client, model_dir, _ = service
    (source, target), _ = data
    assert fit(client, "to/delete", source, target, method="pa").success
    assert (model_dir / file_name("to/delete")).is_file()
    answer = client.call("delete", model_id="to/delete")
    assert answer.success, answer.message
    assert "to/delete" not in client.call("list").model_ids
    assert not (model_dir / file_name("to/delete")).exists()
    assert not client.call("delete", model_id="to/delete").success


def test_killed_and_restarted_service_transfers_identically(tmp_path, data):
    """A fresh client after the restart: the old one would still see the killed server's
    endpoints (SIGKILL sends no goodbye) and send its request there."""
    (source, target), test = data
    domain_id, models = unique_domain_id(), tmp_path / "models"
    answers = []
    for phase in ("first", "restarted"):
        node = start_node(domain_id, tmp_path / phase, models)
        client = MappingClient(domain_id)
        try:
            if phase == "first":
                assert fit(client, ID, source, target).success, node.log()
            assert client.call("list").model_ids == [ID], node.log()
            answers.append(client.call("transfer", model_id=ID, source=matrix(test)))
        finally:
            client.close()
        # the first is killed; the restarted one must stop cleanly on SIGINT (a stop() that
        # falls back to SIGKILL would return -9)
        expected = -signal.SIGKILL if phase == "first" else 0
        assert node.stop(signal.SIGKILL if phase == "first" else signal.SIGINT) == expected, \
            node.log()
    assert all(answer.success for answer in answers)
    assert np.array_equal(*(points(answer.target) for answer in answers))
