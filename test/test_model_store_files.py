"""Model and correspondence files that are not regular files (opening one could block): a
FIFO, a device or a socket in model_dir is quarantined without being opened for reading (a FIFO
once blocked the start for ever), a ``quarantine`` entry that is not a directory does not stop
the start, and a FIFO read as a correspondence file is a ValueError, not a hang."""
import os
import socket
import threading

import numpy as np
import pytest

from lpa_transfer import ProcrustesAnalysis
from lpa_transfer.exploration.correspondences import read_correspondences
from lpa_transfer.transfer.model_io import load_model
from lpa_transfer.transfer.model_store import ModelStore, file_name
from two_link import correspondences


def in_thread(action, timeout=10.0):
    """``action()``'s result or exception, failing the test if it blocks."""
    outcome = {}

    def run():
        try:
            outcome["result"] = action()
        except Exception as exc:   # handed to the test
            outcome["error"] = exc
    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    thread.join(timeout)
    assert not thread.is_alive(), f"blocked for more than {timeout} s"
    if "error" in outcome:
        raise outcome["error"]
    return outcome["result"]


@pytest.fixture
def good(tmp_path):
    source, target = correspondences(100, seed=1)
    model = ProcrustesAnalysis().fit(source, target)
    model.save(tmp_path / file_name("good"))
    return model


def test_a_fifo_device_and_socket_are_quarantined_without_blocking(tmp_path, good):
    os.mkfifo(tmp_path / file_name("fifo"))
    os.symlink("/dev/zero", tmp_path / file_name("device"))
    server = socket.socket(socket.AF_UNIX)
    server.bind(str(tmp_path / file_name("sock")))
    try:
        store = in_thread(lambda: ModelStore(tmp_path))
    finally:
        server.close()
    assert store.ids() == ["good"]
    assert sorted(store.quarantined) == ["device", "fifo", "sock"]
    errors = "\n".join(store.load_errors)
    for kind in ("a FIFO", "a character device", "a socket"):
        assert f"is not a regular file ({kind})" in errors, errors
    assert len(store.load_errors) == 3, errors
    assert sorted(p.name for p in (tmp_path / "quarantine").iterdir()) == sorted(
        file_name(model_id) for model_id in ("device", "fifo", "sock"))
    assert ModelStore(tmp_path).load_errors == []       # the next start is clean


@pytest.mark.parametrize("squatter", ["file", "fifo"])
def test_a_quarantine_that_is_not_a_directory_does_not_stop_the_start(tmp_path, good,
                                                                     squatter):
    quarantine = tmp_path / "quarantine"
    if squatter == "file":
        quarantine.write_text("not a folder")
    else:
        os.mkfifo(quarantine)
    (tmp_path / file_name("bad")).write_bytes(b"hello")
    store = in_thread(lambda: ModelStore(tmp_path))
    assert store.ids() == ["good"] and store.quarantined == ["bad"]
    assert store.load_errors[0].startswith(
        f"{file_name('bad')} moved to quarantine.1/ (quarantine in {tmp_path} is not a "
        f"directory): "), store.load_errors
    assert (tmp_path / "quarantine.1" / file_name("bad")).exists()
    assert quarantine.exists() and not quarantine.is_dir()


def test_a_file_that_cannot_be_moved_aside_is_left_in_place_and_not_served(tmp_path, good):
    for name in ["quarantine"] + [f"quarantine.{n}" for n in range(1, 100)]:
        (tmp_path / name).write_text("")
    (tmp_path / file_name("bad")).write_bytes(b"hello")
    store = ModelStore(tmp_path)
    assert store.ids() == ["good"] and store.quarantined == ["bad"]
    assert "left in place, not served" in store.load_errors[0], store.load_errors


def test_load_model_of_a_fifo_is_a_value_error(tmp_path):
    os.mkfifo(tmp_path / "m.npz")
    with pytest.raises(ValueError, match=r"m.npz is not a regular file \(a FIFO\)"):
        in_thread(lambda: load_model(tmp_path / "m.npz"))


def test_a_fifo_as_correspondence_file_is_a_value_error(tmp_path):
    os.mkfifo(tmp_path / "pairs.npz")
    with pytest.raises(ValueError, match=r"correspondence file .*pairs.npz is not a regular "
                                         r"file \(a FIFO\)"):
        in_thread(lambda: read_correspondences(tmp_path / "pairs.npz"))
    (tmp_path / "good.npz").unlink(missing_ok=True)
    source, target = correspondences(20, seed=1)
    np.savez(tmp_path / "good.npz", source=source, target=target)
    assert np.array_equal(read_correspondences(tmp_path / "good.npz").source, source)
