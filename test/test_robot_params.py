"""Robot parameter files (scenarios/robots/*.toml) and their loader."""
from pathlib import Path

import numpy as np
import pytest

from lpa_transfer.robot_params import load_robot_params

ROBOTS = Path(__file__).resolve().parents[1] / "scenarios" / "robots"
VALID = """name = "arm"
source = "test"
[[links]]
length = 0.3
[[links]]
length = 0.25
[[joints]]
lower = 0.0
upper = 1.0
[[joints]]
lower = -1.0
upper = 1.0
"""


@pytest.mark.parametrize("stem, lengths", [("two_link_source", [0.3, 0.25]),
                                           ("two_link_target", [0.6, 0.2])])
def test_loads_table_3_1_robots(stem, lengths):
    robot = load_robot_params(ROBOTS / f"{stem}.toml")
    assert robot.name == stem and "Table 3.1" in robot.source
    np.testing.assert_array_equal(robot.link_lengths, lengths)
    np.testing.assert_allclose(robot.joint_limits, [[0, np.pi / 2], [0, np.pi]], rtol=1e-15)
    assert robot.n_joints == 2
    with pytest.raises(ValueError):
        robot.link_lengths[0] = 1.0   # read-only


def write(tmp_path, text):
    path = tmp_path / "robot.toml"
    path.write_text(text)
    return path


def test_valid_file_and_extra_keys_are_accepted(tmp_path):
    robot = load_robot_params(write(tmp_path, VALID.replace("length = 0.3",
                                                            "length = 0.3\nmass = 1.0")))
    np.testing.assert_array_equal(robot.joint_limits, [[0, 1], [-1, 1]])


@pytest.mark.parametrize("old, new, message", [
    ('name = "arm"\n', "", "'name'"),
    ('source = "test"\n', "", "'source'"),
    ("length = 0.25", "mass = 1.0", r"links\[1\]: missing key 'length'"),
    ("length = 0.25", "length = 0.0", r"links\[1\]: key 'length' must be positive"),
    ("length = 0.25", 'length = "long"', r"links\[1\]: key 'length' must be a finite number"),
    ("upper = 1.0\n[[joints]]", "[[joints]]", r"joints\[0\]: missing key 'upper'"),
    ("lower = -1.0\nupper = 1.0", "lower = 2.0\nupper = 1.0",
     r"joints\[1\]: key 'lower' \(2.0\) is greater than 'upper'"),
    ("[[links]]\nlength = 0.25\n", "", r"1 \[\[links\]\] but 2 \[\[joints\]\]"),
    ("name = ", "name = = ", "not valid TOML"),
])
def test_broken_file_names_file_and_key(tmp_path, old, new, message):
    assert old in VALID
    path = write(tmp_path, VALID.replace(old, new, 1))
    with pytest.raises(ValueError, match=message) as info:
        load_robot_params(path)
    assert str(path) in str(info.value)


def test_masses_and_effort_limits_are_optional_with_defaults(tmp_path):
    from lpa_transfer.robot_params import DEFAULT_EFFORT_LIMIT, DEFAULT_LINK_MASS

    robot = load_robot_params(write(tmp_path, VALID.replace("length = 0.3",
                                                            "length = 0.3\nmass = 0.7")
                                    .replace("upper = 1.0\n[[joints]]",
                                             "upper = 1.0\neffort = 12.5\n[[joints]]")))
    np.testing.assert_array_equal(robot.link_masses, [0.7, DEFAULT_LINK_MASS])
    np.testing.assert_array_equal(robot.effort_limits, [12.5, DEFAULT_EFFORT_LIMIT])
    with pytest.raises(ValueError, match=r"links\[0\]: key 'mass' must be positive"):
        load_robot_params(write(tmp_path, VALID.replace("length = 0.3", "length = 0.3\nmass = 0")))
