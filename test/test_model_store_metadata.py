"""Model metadata (which robots and columns a model maps): saved in the model file, reloaded,
checked; files without it (written before it existed) still load."""
import json
import math

import numpy as np
import pytest

from lpa_transfer import LocalProcrustesAnalysis
from lpa_transfer.transfer.model_io import load_model, load_model_and_metadata
from lpa_transfer.transfer.model_store import METADATA, ModelStore, file_name, training_rmse
from two_link import correspondences

META = dict(source_robot="pincher", target_robot="youbot",
            source_features=["position[0]", "position[1]", "ee_x", "ee_y"],
            target_features=["q1", "q2", "x", "y"], correspondences="request")


@pytest.fixture(scope="module")
def data():
    return correspondences(200, seed=1)


def test_metadata_is_saved_reloaded_and_described(tmp_path, data):
    source, target = data
    store = ModelStore(tmp_path)
    model = store.fit("a->b", "lpa", source, target, META, n_min=10)
    expected = dict(META, training_rmse=training_rmse(model, source, target))
    assert store.metadata("a->b") == expected
    again = ModelStore(tmp_path)
    assert again.metadata("a->b") == expected
    info = again.describe("a->b")
    assert {key: info[key] for key in METADATA} == expected
    assert (info["n_points"], info["source_dim"], info["hyperparameters"]["n_min"]) == \
        (200, 4, 10)
    model, metadata = load_model_and_metadata(tmp_path / file_name("a->b"))
    assert metadata == expected and isinstance(model, LocalProcrustesAnalysis)


def test_a_file_without_metadata_loads_with_the_defaults(tmp_path, data):
    source, target = data
    model = LocalProcrustesAnalysis(n_min=10).fit(source, target)
    model.save(tmp_path / file_name("old"))             # as files were written before
    with np.load(tmp_path / file_name("old")) as archive:
        assert "metadata" not in archive.files
    store = ModelStore(tmp_path)
    assert store.ids() == ["old"] and store.quarantined == []
    metadata = store.metadata("old")
    assert math.isnan(metadata.pop("training_rmse"))
    assert metadata == {key: value for key, value in METADATA.items()
                        if key != "training_rmse"}
    assert np.array_equal(store.transfer("old", source), model.transfer(source))


def test_partial_metadata_keeps_the_defaults_for_the_rest(tmp_path, data):
    store = ModelStore(tmp_path)
    store.fit("p", "pa", *data, dict(source_robot="nao"))
    metadata = store.metadata("p")
    assert (metadata["source_robot"], metadata["target_robot"]) == ("nao", "")
    assert metadata["source_features"] == [] and metadata["training_rmse"] > 0


@pytest.mark.parametrize("metadata, problem", [
    (dict(source_features=["a", "b"]), "source_features names 2 columns but the source has 4"),
    (dict(target_features=["a"] * 5), "target_features names 5 columns but the target has 4"),
    (dict(robot="x"), "unknown metadata ['robot']"),
    (dict(source_robot=3), "source_robot must be a string"),
    (dict(source_features=[1, 2, 3, 4]), "source_features must be strings"),
])
def test_bad_metadata_is_refused_before_the_fit(tmp_path, data, metadata, problem):
    store = ModelStore(tmp_path)
    with pytest.raises(ValueError) as error:
        store.fit("bad", "pa", *data, metadata)
    assert problem in str(error.value)
    assert store.ids() == [] and not list(tmp_path.glob("*.npz"))


def test_a_file_whose_metadata_is_not_an_object_is_quarantined(tmp_path, data):
    store = ModelStore(tmp_path)
    store.fit("good", "pa", *data, META)
    store.fit("bad", "pa", *data, META)
    bad = tmp_path / file_name("bad")
    with np.load(bad) as archive:
        entries = {key: archive[key] for key in archive.files}
    entries["metadata"] = np.array(json.dumps(["not", "an", "object"]))
    np.savez(bad, **entries)
    again = ModelStore(tmp_path)
    assert again.ids() == ["good"] and again.quarantined == ["bad"]
    assert "metadata that is not a JSON object" in again.load_errors[0]
    assert load_model(tmp_path / file_name("good")).n_features_in_ == 4


def test_metadata_must_be_a_json_object_to_save(tmp_path, data):
    model = LocalProcrustesAnalysis(n_min=10).fit(*data)
    with pytest.raises(ValueError, match="metadata must be a dict"):
        model.save(tmp_path / "m.npz", ["x"])
    with pytest.raises(ValueError, match="JSON-serialisable"):
        model.save(tmp_path / "m.npz", dict(x=object()))
    assert not list(tmp_path.iterdir())
