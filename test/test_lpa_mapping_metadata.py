"""Model metadata over the graph (which robots and columns a model maps): two robot_sims,
lpa_mapping and the correspondence_collector. The collector's fit stores the robots' and the
columns' names; a fit from its saved file in data_dir or from the pairs the service received on
its topics takes them from there when the request leaves them empty."""
import pytest

from lpa_transfer_nodes.mapping_client import MappingClient
from ros_harness import NodeProcess, ros_params, run_to_end, start_robot_sims, unique_domain_id
from test_correspondence_collector_node import ROBOTS

PAIR = "two_link_source->two_link_target"
COLUMNS = ["position[0]", "position[1]", "ee_x", "ee_y"]


@pytest.fixture(scope="module")
def graph(tmp_path_factory):
    import rclpy

    work = tmp_path_factory.mktemp("metadata_graph")
    domain_id = unique_domain_id()
    nodes = start_robot_sims(domain_id, work, ROBOTS) + [NodeProcess(
        "lpa_mapping", domain_id, work, ros_params(model_dir=work / "models",
                                                   data_dir=work / "data"))]
    (work / "data").mkdir()
    collector = NodeProcess("correspondence_collector", domain_id, work, ros_params(
        source_robot=ROBOTS["source"], target_robot=ROBOTS["target"], steps_per_sample=200,
        wait_timeout=20.0, program="joint_lines", n_segments=4, samples_per_segment=3, seed=7,
        method="pa", output=work / "data" / "pairs.npz", model_id="collected",
        wait_for_subscribers=1))
    rclpy.init(domain_id=domain_id)
    node = rclpy.create_node("metadata_test_client")
    try:
        assert run_to_end(collector) == 0, collector.log()
        yield MappingClient(node)
    finally:
        node.destroy_node()
        rclpy.shutdown()
        for process in nodes:
            assert process.stop() == 0, process.log()


def test_the_collectors_fit_stores_robot_and_column_names(graph):
    info = graph.describe("collected")
    assert (info["source_robot"], info["target_robot"]) == ("two_link_source",
                                                            "two_link_target")
    assert info["source_features"] == info["target_features"] == COLUMNS
    assert (info["correspondences"], info["n_points"]) == ("request", 12)


def test_a_fit_from_the_saved_file_takes_its_names(graph):
    graph.fit("from-file", method="pa", correspondence_file="pairs.npz")
    info = graph.describe("from-file")
    assert (info["source_robot"], info["source_features"]) == ("two_link_source", COLUMNS)
    assert info["correspondences"].endswith("data/pairs.npz")


def test_a_fit_from_the_received_pairs_takes_the_robot_names(graph):
    graph.fit("received", method="pa", received_pair=PAIR)
    info = graph.describe("received")
    assert (info["source_robot"], info["target_robot"]) == ("two_link_source",
                                                            "two_link_target")
    assert info["source_features"] == [] and info["n_points"] == 12
    assert info["correspondences"] == f"received {PAIR}"
