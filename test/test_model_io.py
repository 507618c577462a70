"""The versioned model file format: bit-identical round trips, clear errors, no pickle."""
import json
import zipfile

import numpy as np
import pytest

from lpa_transfer import LocalProcrustesAnalysis, ProcrustesAnalysis, load_model
from two_link import correspondences


@pytest.mark.parametrize("model", [
    ProcrustesAnalysis(),
    LocalProcrustesAnalysis(n_min=7, c_min=1e-7, cluster_dims=[0, 1], random_state=3),
])
def test_round_trip_transfers_bit_identically(model, tmp_path):
    source, target = correspondences(300, seed=1)
    model.fit(source, target)
    path = model.save(tmp_path / "model.npz")
    loaded = type(model).load(path)
    queries = correspondences(2000, seed=2)[0]
    assert np.array_equal(loaded.transfer(queries), model.transfer(queries))
    assert loaded.get_params() == json.loads(json.dumps(model.get_params()))
    for name in model._learned:
        assert np.array_equal(np.asarray(getattr(loaded, name)), np.asarray(getattr(model, name)))
    assert type(load_model(path)) is type(model)


def test_file_is_plain_npz_without_pickles(tmp_path):
    path = ProcrustesAnalysis().fit(*correspondences(50, seed=0)).save(tmp_path / "pa.npz")
    with np.load(path, allow_pickle=False) as archive:
        assert archive["format"].item() == "lpa_transfer-model"
        assert archive["format_version"].item() == 1
        assert archive["model_class"].item() == "ProcrustesAnalysis"
    assert not list(tmp_path.glob(".tmp-*"))


def test_unknown_version_wrong_class_and_garbage_are_rejected(tmp_path):
    pa = ProcrustesAnalysis().fit(*correspondences(50, seed=0))
    path = pa.save(tmp_path / "pa.npz")
    with pytest.raises(ValueError, match="holds a ProcrustesAnalysis, not a LocalProcrustes"):
        LocalProcrustesAnalysis.load(path)
    with np.load(path) as archive:
        entries = dict(archive)
    entries["format_version"] = np.array(99)
    np.savez(tmp_path / "future.npz", **entries)
    with pytest.raises(ValueError, match="format version 99"):
        load_model(tmp_path / "future.npz")
    (tmp_path / "junk.npz").write_bytes(b"not a zip")
    with pytest.raises(ValueError, match="not an lpa_transfer model file") as refused:
        load_model(tmp_path / "junk.npz")
    assert "pickle" not in str(refused.value)   # numpy's reason would invite unsafe loading
    (tmp_path / "short.npz").write_bytes(b"PK")
    with pytest.raises(ValueError, match="not a zip archive"):
        load_model(tmp_path / "short.npz")
    with zipfile.ZipFile(tmp_path / "empty.npz", "w"):
        pass
    with pytest.raises(ValueError, match="not an lpa_transfer model file"):
        load_model(tmp_path / "empty.npz")


def test_unfitted_model_cannot_be_saved(tmp_path):
    with pytest.raises(ValueError, match="not fitted"):
        ProcrustesAnalysis().save(tmp_path / "x.npz")
