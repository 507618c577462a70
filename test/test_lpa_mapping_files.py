"""lpa_mapping reads correspondence files only inside its data_dir (a request names no other
file of the host), on a node in its own process: relative names are taken in it; absolute paths,
'..' and symbolic links that lead outside it are refused naming data_dir, and the service keeps
serving."""
import os

import numpy as np
import pytest

from ros_harness import NodeProcess, ros_params, unique_domain_id
from test_lpa_mapping_node import MappingClient
from two_link import correspondences


@pytest.fixture(scope="module")
def service(tmp_path_factory):
    root = tmp_path_factory.mktemp("lpa_mapping_files")
    data_dir, outside = root / "data", root / "outside"
    (data_dir / "run1").mkdir(parents=True)
    outside.mkdir()
    source, target = correspondences(100, seed=1)
    for folder in (data_dir, data_dir / "run1", outside):
        np.savez(folder / "pairs.npz", source=source, target=target)
    os.symlink(outside / "pairs.npz", data_dir / "link_out.npz")
    os.symlink(outside, data_dir / "dir_out")
    os.symlink(data_dir / "run1" / "pairs.npz", data_dir / "link_in.npz")
    os.mkfifo(data_dir / "fifo.npz")
    domain_id = unique_domain_id()
    node = NodeProcess("lpa_mapping", domain_id, root / "log",
                       ros_params(model_dir=root / "models", data_dir=data_dir))
    client = MappingClient(domain_id)
    yield client, node, data_dir.resolve(), outside
    client.close()
    assert node.stop() == 0, node.log()


def fit_file(client, name):
    return client.call("fit", model_id="from-file", method="pa", correspondence_file=name)


@pytest.mark.parametrize("name", ["pairs.npz", "run1/pairs.npz", "./run1/../pairs.npz",
                                  "link_in.npz"])
def test_files_inside_data_dir_are_read(service, name):
    client, _, _, _ = service
    answer = fit_file(client, name)
    assert answer.success and answer.n_points == 100, answer.message


def test_an_absolute_path_inside_data_dir_is_read(service):
    client, _, data_dir, _ = service
    assert fit_file(client, str(data_dir / "run1" / "pairs.npz")).success


@pytest.mark.parametrize("name", ["../outside/pairs.npz", "run1/../../outside/pairs.npz",
                                  "link_out.npz", "dir_out/pairs.npz", "/etc/passwd",
                                  "OUTSIDE"])
def test_paths_that_lead_outside_data_dir_are_refused(service, name):
    client, node, data_dir, outside = service
    name = str(outside / "pairs.npz") if name == "OUTSIDE" else name
    answer = fit_file(client, name)
    assert not answer.success, answer.message
    assert f"is outside the data directory {data_dir} (the parameter data_dir)" in \
        answer.message, answer.message
    assert client.call("list").success and node.alive()


def test_a_missing_file_inside_data_dir_is_a_bad_request(service):
    client, node, _, _ = service
    answer = fit_file(client, "nothing.npz")
    assert not answer.success and "nothing.npz" in answer.message, answer.message
    assert node.alive()


def test_a_fifo_as_correspondence_file_is_refused_and_later_fits_run(service):
    """A FIFO as correspondence_file is refused: opening it once blocked every later fit."""
    client, node, data_dir, _ = service
    answer = fit_file(client, "fifo.npz")
    assert not answer.success, answer.message
    assert f"correspondence file {data_dir / 'fifo.npz'} is not a regular file (a FIFO)" in \
        answer.message, answer.message
    assert fit_file(client, "pairs.npz").success and node.alive()
