"""ListModels names the model files quarantined at start (a damaged file must not stop the
service), on a node in its own process, which serves the other models as before."""
import os

import numpy as np

from lpa_transfer import LocalProcrustesAnalysis
from lpa_transfer.transfer.model_store import file_name
from ros_harness import NodeProcess, ros_params, unique_domain_id
from test_lpa_mapping_node import MappingClient, matrix, points
from two_link import correspondences


def model_dir(tmp_path, model_id):
    """(model_dir holding one good LPA model ``model_id``, the model, test source points)."""
    models = tmp_path / "models"
    models.mkdir()
    (source, target), test = correspondences(200, seed=1), correspondences(50, seed=2)[0]
    good = LocalProcrustesAnalysis(n_min=10).fit(source, target)
    good.save(models / file_name(model_id))
    return models, good, test


def serving(tmp_path, models):
    """(an lpa_mapping node in its own process on ``models``, a client on its domain)."""
    domain_id = unique_domain_id()
    node = NodeProcess("lpa_mapping", domain_id, tmp_path / "log", ros_params(model_dir=models))
    return node, MappingClient(domain_id)


def test_corrupt_files_at_start_are_listed_as_quarantined_and_the_rest_served(tmp_path):
    models, good, test = model_dir(tmp_path, "good/lpa")
    good.save(models / file_name("truncated"))
    truncated = models / file_name("truncated")
    truncated.write_bytes(truncated.read_bytes()[:300])
    (models / file_name("not a model")).write_bytes(b"hello")
    node, client = serving(tmp_path, models)
    try:
        listed = client.call("list")
        assert listed.success, listed.message
        assert list(listed.model_ids) == ["good/lpa"]
        assert sorted(listed.quarantined_ids) == ["not a model", "truncated"]
        assert "2 quarantined" in listed.message, listed.message
        answer = client.call("transfer", model_id="good/lpa", source=matrix(test))
        assert np.array_equal(points(answer.target), good.transfer(test))
        refused = client.call("transfer", model_id="truncated", source=matrix(test))
        assert not refused.success and "unknown model id 'truncated'" in refused.message
    finally:
        client.close()
        assert node.stop() == 0, node.log()
    assert sorted(p.name for p in (models / "quarantine").iterdir()) == sorted(
        [file_name("truncated"), file_name("not a model")])


def test_a_clean_start_lists_no_quarantined_ids(tmp_path):
    domain_id = unique_domain_id()
    node = NodeProcess("lpa_mapping", domain_id, tmp_path / "log",
                       ros_params(model_dir=tmp_path / "models"))
    client = MappingClient(domain_id)
    try:
        listed = client.call("list")
        assert listed.success and list(listed.quarantined_ids) == [], listed
    finally:
        client.close()
        assert node.stop() == 0, node.log()


def test_a_fifo_model_and_a_quarantine_file_do_not_stop_the_start(tmp_path):
    """Entries that are not regular files: a FIFO named x.npz once kept the node from ever
    serving (deaf to SIGINT), a plain file named quarantine stopped it with FATAL
    "File exists"."""
    models, good, test = model_dir(tmp_path, "good")
    os.mkfifo(models / file_name("x"))
    (models / "quarantine").write_text("a file, not a folder")
    node, client = serving(tmp_path, models)
    try:
        listed = client.call("list")
        assert listed.success, listed.message + node.log()
        assert list(listed.model_ids) == ["good"] and list(listed.quarantined_ids) == ["x"]
        answer = client.call("transfer", model_id="good", source=matrix(test))
        assert np.array_equal(points(answer.target), good.transfer(test))
    finally:
        client.close()
        assert node.stop() == 0, node.log()
    log = node.log()
    assert log.count("skipped a model file") == 1, log
    assert f"{file_name('x')} moved to quarantine.1/ (quarantine in {models} is not a " \
           "directory)" in log and "is not a regular file (a FIFO)" in log, log
    assert (models / "quarantine.1" / file_name("x")).exists()
