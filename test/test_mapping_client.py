"""The public MappingClient (numpy in, numpy out) against a live lpa_mapping process: fit,
transfer, describe, list and delete on numpy arrays, the model's metadata, and the errors."""
import math

import numpy as np
import pytest
import rclpy

from lpa_transfer import LocalProcrustesAnalysis, ProcrustesAnalysis
from lpa_transfer.transfer.model_store import file_name
from lpa_transfer_nodes.mapping_client import MappingClient, ModelList
from ros_harness import NodeProcess, ros_params, unique_domain_id
from two_link import correspondences

LPA = dict(n_min=10, c_min=1e-3, random_state=0)
FEATURES = ["position[0]", "position[1]", "ee_x", "ee_y"]


@pytest.fixture(scope="module")
def mapping(tmp_path_factory):
    """A service with one good and one quarantined model file, and a MappingClient on a node
    of rclpy's default context (as a user's node would be)."""
    root = tmp_path_factory.mktemp("mapping_client")
    (root / "models").mkdir()
    (root / "models" / file_name("broken")).write_bytes(b"not a model")
    (root / "correspondences").mkdir()
    domain_id = unique_domain_id()
    service = NodeProcess("lpa_mapping", domain_id, root / "log",
                          ros_params(model_dir=root / "models"))
    rclpy.init(domain_id=domain_id)
    node = rclpy.create_node("mapping_client_test")
    try:
        yield MappingClient(node, timeout=60.0), root
    finally:
        node.destroy_node()
        rclpy.shutdown()
        assert service.stop() == 0, service.log()


def test_fit_transfer_describe_list_delete(mapping):
    client, _ = mapping
    source, target = correspondences(300, seed=1)
    test = correspondences(100, seed=2)[0]
    answer = client.fit("small->large", source, target, source_robot="small",
                        target_robot="large", source_features=FEATURES,
                        target_features=("q1", "q2", "x", "y"), **LPA)
    library = LocalProcrustesAnalysis(**LPA).fit(source, target)
    assert answer.n_clusters == library.n_clusters_ and answer.n_points == 300
    assert np.array_equal(client.transfer("small->large", test), library.transfer(test))
    info = client.describe("small->large")
    assert info["method"] == "lpa" and (info["source_dim"], info["target_dim"]) == (4, 4)
    assert (info["n_clusters"], info["n_points"]) == (library.n_clusters_, 300)
    assert (info["source_robot"], info["target_robot"]) == ("small", "large")
    assert info["source_features"] == FEATURES
    assert info["target_features"] == ["q1", "q2", "x", "y"]
    assert info["training_rmse"] == answer.training_rmse
    assert info["correspondences"] == "request"
    assert info["hyperparameters"]["n_min"] == 10 and info["hyperparameters"]["k_max"] == 2000
    listed = client.list()
    assert isinstance(listed, ModelList)
    assert "small->large" in listed.model_ids and listed.quarantined_ids == ["broken"]
    assert "deleted" in client.delete("small->large")
    assert "small->large" not in client.list().model_ids
    with pytest.raises(RuntimeError, match="unknown model id 'small->large'"):
        client.describe("small->large")


def test_a_pa_fit_without_metadata_describes_empty_metadata(mapping):
    client, _ = mapping
    source, target = correspondences(50, seed=1)
    client.fit("pa", source, target, method="pa", latent_dim=3)
    info = client.describe("pa")
    assert (info["method"], info["n_clusters"], info["source_robot"]) == ("pa", 1, "")
    assert info["source_features"] == [] and info["hyperparameters"]["latent_dim"] == 3
    expected = ProcrustesAnalysis(latent_dim=3).fit(source, target).transfer(source)
    assert np.array_equal(client.transfer("pa", source), expected)
    client.delete("pa")


def test_fit_from_a_correspondence_file_takes_its_metadata(mapping):
    client, root = mapping
    source, target = correspondences(80, seed=3)
    np.savez(root / "correspondences" / "pairs.npz", source=source, target=target,
             source_robot="two_link_source", target_robot="two_link_target",
             features=np.array(["position", "ee_x", "ee_y"]))
    answer = client.fit("from-file", method="pa", correspondence_file="pairs.npz")
    assert answer.n_points == 80
    info = client.describe("from-file")
    assert (info["source_robot"], info["target_robot"]) == ("two_link_source",
                                                            "two_link_target")
    assert info["source_features"] == info["target_features"] == FEATURES
    assert info["correspondences"].startswith("file ") and \
        info["correspondences"].endswith("pairs.npz")
    assert not math.isnan(info["training_rmse"])
    client.fit("from-file", method="pa", correspondence_file="pairs.npz",
               source_robot="given")                   # the request's metadata wins
    assert client.describe("from-file")["source_robot"] == "given"
    client.delete("from-file")


def test_bad_calls_raise_and_name_the_problem(mapping):
    client, _ = mapping
    source, target = correspondences(50, seed=1)
    with pytest.raises(ValueError, match=r"unknown fit fields \['nmin'\]"):
        client.fit("x", source, target, nmin=3)
    with pytest.raises(ValueError, match="no correspondences"):
        client.fit("x")
    with pytest.raises(ValueError, match="both source and target"):
        client.fit("x", source)
    with pytest.raises(ValueError, match="2-D array"):
        client.transfer("x", source[0])
    with pytest.raises(RuntimeError, match="source_features names 2 columns but the source "
                                           "has 4"):
        client.fit("x", source, target, method="pa", source_features=["a", "b"])
    with pytest.raises(RuntimeError, match="outside the data directory"):
        client.fit("x", method="pa", correspondence_file="/etc/passwd")
    assert "x" not in client.list().model_ids


def test_a_missing_service_is_a_clear_error(mapping):
    client = MappingClient(mapping[0].node, service="/nobody", timeout=0.5)
    with pytest.raises(RuntimeError, match="/nobody/list is not available"):
        client.list()


def test_a_nul_in_a_string_is_refused_before_it_is_sent(mapping):
    """A NUL in a string: rclpy cuts a string at its first NUL, so fitting "a\\0b" overwrote
    the model "a" (and deleting "a\\0b" would delete "a"); the client now refuses it."""
    client, _ = mapping
    source, target = correspondences(60, seed=1)
    client.fit("a", source, target, method="pa")
    model = ProcrustesAnalysis().fit(source, target)
    for call in (lambda: client.fit("a\0b", source[:50], target[:50], method="pa"),
                 lambda: client.delete("a\0b"),
                 lambda: client.transfer("a\0b", source),
                 lambda: client.describe("a\0b"),
                 lambda: client.fit("c", source, target, method="pa",
                                    source_robot="x\0y")):
        with pytest.raises(ValueError, match=r"contains a NUL character"):
            call()
    for control in ("a\x01b", "a\nb", "a\x7fb"):       # the service refuses the others
        with pytest.raises(RuntimeError, match="contains control characters"):
            client.fit(control, source, target, method="pa")
    assert client.describe("a")["n_points"] == 60
    assert np.array_equal(client.transfer("a", source), model.transfer(source))
    assert "c" not in client.list().model_ids
    client.delete("a")
