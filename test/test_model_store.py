"""ModelStore: models keyed by id, persisted to a directory and reloaded bit for bit."""

import numpy as np
import pytest

from lpa_transfer import LocalProcrustesAnalysis
from lpa_transfer.transfer.model_store import ModelStore, file_name, training_rmse
from two_link import correspondences

ID = "pincher->youbot/left arm"


@pytest.fixture(scope="module")
def data():
    return correspondences(300, seed=1), correspondences(50, seed=2)[0]


def test_fit_transfer_equals_the_library(tmp_path, data):
    (source, target), test = data
    store = ModelStore(tmp_path)
    store.fit(ID, "lpa", source, target, n_min=10)
    expected = LocalProcrustesAnalysis(n_min=10).fit(source, target).transfer(test)
    assert np.array_equal(store.transfer(ID, test), expected)
    assert store.ids() == [ID]
    assert (tmp_path / file_name(ID)).is_file()


def test_restart_reloads_bit_identical(tmp_path, data):
    (source, target), test = data
    first = ModelStore(tmp_path)
    first.fit(ID, "lpa", source, target)
    first.fit("two.link", "pa", source, target, latent_dim=3)
    again = ModelStore(tmp_path)
    assert again.ids() == sorted([ID, "two.link"]) and again.load_errors == []
    for model_id in again.ids():
        assert np.array_equal(again.transfer(model_id, test), first.transfer(model_id, test))
        assert again.describe(model_id) == first.describe(model_id)


def test_describe(tmp_path, data):
    (source, target), _ = data
    store = ModelStore(tmp_path)
    model = store.fit(ID, "lpa", source, target, k_max=4)
    info = store.describe(ID)
    assert info["method"] == "lpa" and (info["source_dim"], info["target_dim"]) == (4, 4)
    assert info["n_clusters"] == model.n_clusters_ <= 4 and info["n_points"] == 300
    assert info["hyperparameters"]["k_max"] == 4
    store.fit("global", "pa", source, target)
    assert store.describe("global")["n_clusters"] == 1
    assert training_rmse(model, source, target) < training_rmse(
        store.get("global"), source, target)


def test_unknown_id_names_the_known_ones(tmp_path, data):
    (source, target), test = data
    store = ModelStore(tmp_path)
    store.fit(ID, "pa", source, target)
    for call in (lambda: store.transfer("nao", test), lambda: store.describe("nao"),
                 lambda: store.delete("nao")):
        with pytest.raises(ValueError, match=r"unknown model id 'nao'; known: \['pincher"):
            call()


@pytest.mark.parametrize("model_id, problem", [
    ("", "non-empty"), ("a\nb", "control"), ("tab\there", "control"), (None, "string"),
    ("x" * 300, "too long")])
def test_bad_ids_are_refused(tmp_path, data, model_id, problem):
    (source, target), _ = data
    store = ModelStore(tmp_path)
    with pytest.raises(ValueError, match=problem):
        store.fit(model_id, "pa", source, target)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("model_id", ["..", ".hidden", "a/../../b", "../escape", "%41"])
def test_awkward_ids_stay_inside_the_directory(tmp_path, data, model_id):
    (source, target), _ = data
    store = ModelStore(tmp_path / "models")
    store.fit(model_id, "pa", source, target)
    [path] = (tmp_path / "models").iterdir()
    assert not path.name.startswith(".")
    assert ModelStore(tmp_path / "models").ids() == [model_id]


def test_bad_method_and_hyperparameters(tmp_path, data):
    (source, target), _ = data
    store = ModelStore(tmp_path)
    with pytest.raises(ValueError, match=r"unknown method 'gp'; known: \['lpa', 'pa'\]"):
        store.fit(ID, "gp", source, target)
    with pytest.raises(ValueError, match=r"'pa' has no hyperparameters \['n_min'\]"):
        store.fit(ID, "pa", source, target, n_min=7)
    with pytest.raises(ValueError, match="too few correspondences"):
        store.fit(ID, "lpa", source[:5], target[:5])
    assert store.ids() == []


def test_delete_removes_the_file(tmp_path, data):
    (source, target), _ = data
    store = ModelStore(tmp_path)
    store.fit(ID, "pa", source, target)
    store.delete(ID)
    assert store.ids() == [] and list(tmp_path.iterdir()) == []
    assert ModelStore(tmp_path).ids() == []


def test_unreadable_files_are_skipped(tmp_path, data):
    (source, target), _ = data
    ModelStore(tmp_path).fit(ID, "pa", source, target)
    (tmp_path / "junk.npz").write_bytes(b"not a model")
    (tmp_path / ".tmp-left-by-a-crash.npz").write_bytes(b"half")
    store = ModelStore(tmp_path)
    assert store.ids() == [ID]
    assert len(store.load_errors) == 1 and "junk.npz" in store.load_errors[0]


def damaged_store(tmp_path, data):
    """A store with two good models and one damaged file of each kind (a damaged file is set
    aside, the others are served)."""
    (source, target), _ = data
    store = ModelStore(tmp_path)
    for model_id in ("good/lpa", "good.pa", "truncated", "empty", "crc", "wrong arrays"):
        store.fit(model_id, "lpa" if "lpa" in model_id else "pa", source, target)
    truncated = tmp_path / file_name("truncated")
    truncated.write_bytes(truncated.read_bytes()[:300])
    (tmp_path / file_name("empty")).write_bytes(b"")
    crc = tmp_path / file_name("crc")
    raw = bytearray(crc.read_bytes())
    with np.load(crc) as archive:
        stored = archive["coef_"].tobytes()
    raw[raw.index(stored) + len(stored) // 2] ^= 0x40   # one bit inside a stored array
    crc.write_bytes(bytes(raw))
    wrong = tmp_path / file_name("wrong arrays")
    with np.load(wrong) as archive:
        entries = {key: archive[key] for key in archive.files}
    entries["coef_"] = entries["coef_"][:1, :1]        # arrays that do not fit together
    np.savez(wrong, **entries)
    (tmp_path / ".tmp-abc123.npz").write_bytes(b"half a save")
    return store


def test_one_bad_file_of_any_kind_is_quarantined_and_the_rest_served(tmp_path, data):
    (source, target), test = data
    before = damaged_store(tmp_path, data)
    store = ModelStore(tmp_path)
    assert store.ids() == ["good.pa", "good/lpa"]
    assert sorted(store.quarantined) == ["crc", "empty", "truncated", "wrong arrays"]
    for model_id in store.quarantined:
        assert (tmp_path / "quarantine" / file_name(model_id)).is_file()
        assert any(file_name(model_id) in error for error in store.load_errors)
    assert not list(tmp_path.glob(".tmp-*"))           # the killed save's leftover is gone
    for model_id in store.ids():
        assert np.array_equal(store.transfer(model_id, test), before.transfer(model_id, test))
    assert ModelStore(tmp_path).quarantined == []      # quarantined files stay out


def test_a_hand_named_file_is_its_ids_one_file_and_delete_removes_it(tmp_path, data):
    (source, target), test = data
    ModelStore(tmp_path).fit("pa.v2", "pa", source, target)
    (tmp_path / file_name("pa.v2")).rename(tmp_path / "pa.v2.npz")   # placed by hand
    store = ModelStore(tmp_path)
    assert store.ids() == ["pa.v2"] and (tmp_path / file_name("pa.v2")).is_file()
    store.delete("pa.v2")
    assert ModelStore(tmp_path).ids() == [] and not list(tmp_path.glob("*.npz"))
    # beside the id's own file, a second one is quarantined instead of shadowing it
    ModelStore(tmp_path).fit("pa.v2", "pa", source, target)
    ModelStore(tmp_path).fit("other", "pa", source, target)
    (tmp_path / file_name("other")).rename(tmp_path / "pa.v2.npz")
    store = ModelStore(tmp_path)
    assert store.ids() == ["pa.v2"] and store.quarantined == ["pa.v2"]
