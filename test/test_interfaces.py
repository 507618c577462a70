"""The interface package msg_schemas/ as built and installed into the venv by tools/setup.sh."""
import re
from pathlib import Path

import pytest

from conftest import ROOT

MSG_SCHEMAS = ROOT / "msg_schemas"
INTERFACE_FILES = sorted([*MSG_SCHEMAS.glob("msg/*.msg"), *MSG_SCHEMAS.glob("srv/*.srv")])


def test_transfer_points_request_round_trips(project_venv):
    from rclpy.serialization import deserialize_message, serialize_message

    from lpa_transfer_interfaces.msg import Matrix
    from lpa_transfer_interfaces.srv import TransferPoints

    request = TransferPoints.Request(
        model_id="two_link", source=Matrix(rows=3, cols=2, data=[0.1, 0.2, 1.5, -2.0, 3.25, 1e-9]))
    back = deserialize_message(serialize_message(request), TransferPoints.Request)
    assert back == request
    assert list(back.source.data) == [0.1, 0.2, 1.5, -2.0, 3.25, 1e-9]


def test_all_interfaces_import(project_venv):
    import lpa_transfer_interfaces.msg as msg
    import lpa_transfer_interfaces.srv as srv

    for path in INTERFACE_FILES:
        module = msg if path.suffix == ".msg" else srv
        assert hasattr(module, path.stem), path.name


def test_installed_interface_files(project_venv):
    share = project_venv / "share" / "lpa_transfer_interfaces"
    for path in INTERFACE_FILES:
        installed = share / path.parent.name / path.name
        assert installed.read_text() == path.read_text()


def test_ament_index_finds_both_packages(project_venv, monkeypatch):
    from ament_index_python.packages import get_package_share_directory

    monkeypatch.setenv("AMENT_PREFIX_PATH", str(project_venv))
    for package in ("lpa_transfer", "lpa_transfer_interfaces"):
        assert (Path(get_package_share_directory(package)) / "package.xml").is_file()


@pytest.mark.parametrize("path", INTERFACE_FILES, ids=lambda p: p.name)
def test_every_field_is_documented(path):
    """Each field line must follow a comment line (the files are the API documentation)."""
    previous = ""
    for line in path.read_text().splitlines():
        if line and not line.startswith("#") and line != "---":
            assert previous.startswith("#"), f"{path.name}: undocumented field {line!r}"
        previous = line
    assert re.search(r"^\w", path.read_text(), re.M), "no fields"


def test_matrix_from_rows():
    import array

    import numpy as np

    from lpa_transfer_nodes.conversions import matrix_from_rows
    values = array.array("d", [1, 2, 3, 4, 5, 6])
    assert np.array_equal(matrix_from_rows(2, 3, values, "source"), [[1, 2, 3], [4, 5, 6]])
    assert matrix_from_rows(3, 2, [1, 2, 3, 4, 5, 6], "source").shape == (3, 2)
    with pytest.raises(ValueError, match=r"source: rows\*cols = 2\*2 = 4 does not match the 6"):
        matrix_from_rows(2, 2, values, "source")
