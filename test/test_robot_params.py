"""Robot parameter files (scenarios/robots/*.toml) and their loader."""
from pathlib import Path

import numpy as np
import pytest

from lpa_transfer.robots.params import load_robot_params

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
    assert_broken(tmp_path, VALID, old, new, message)


def assert_broken(tmp_path, text, old, new, message):
    """``text`` with ``old`` replaced by ``new`` fails to load with ``message`` and its path."""
    assert old in text
    path = write(tmp_path, text.replace(old, new, 1))
    with pytest.raises(ValueError, match=message) as info:
        load_robot_params(path)
    assert str(path) in str(info.value)


def test_masses_and_effort_limits_are_optional_with_defaults(tmp_path):
    from lpa_transfer.robots.params import DEFAULT_EFFORT_LIMIT, DEFAULT_LINK_MASS

    robot = load_robot_params(write(tmp_path, VALID.replace("length = 0.3",
                                                            "length = 0.3\nmass = 0.7")
                                    .replace("upper = 1.0\n[[joints]]",
                                             "upper = 1.0\neffort = 12.5\n[[joints]]")))
    np.testing.assert_array_equal(robot.link_masses, [0.7, DEFAULT_LINK_MASS])
    np.testing.assert_array_equal(robot.effort_limits, [12.5, DEFAULT_EFFORT_LIMIT])
    with pytest.raises(ValueError, match=r"links\[0\]: key 'mass' must be positive"):
        load_robot_params(write(tmp_path, VALID.replace("length = 0.3", "length = 0.3\nmass = 0")))


# -- general serial chains (kind = "serial") -----------------------------------------------
SERIAL = """name = "arm"
source = "test"
kind = "serial"
[base]
xyz = [0.0, 0.0, 0.1]
[[joints]]
xyz = [0.0, 0.0, 0.05]
axis = [0.0, 0.0, 2.0]
lower = -1.0
upper = 1.0
effort = 10.0
velocity = 2.0
[[joints]]
xyz = [0.0, 0.0, 0.3]
rpy = [0.0, 0.5, 0.0]
axis = [0.0, 1.0, 0.0]
lower = -2.0
upper = 2.0
effort = 5.0
velocity = 3.0
[[links]]
mass = 1.0
com = [0.0, 0.0, 0.1]
inertia = { ixx = 0.01, ixy = 0.0, ixz = 0.0, iyy = 0.01, iyz = 0.0, izz = 0.005 }
[[links]]
mass = 0.5
com = [0.1, 0.0, 0.0]
inertia = { ixx = 0.0005, ixy = 0.0001, ixz = 0.0, iyy = 0.002, iyz = 0.0, izz = 0.002 }
[tool]
xyz = [0.2, 0.0, 0.0]
"""


def test_serial_file_fills_the_general_fields(tmp_path):
    robot = load_robot_params(write(tmp_path, SERIAL))
    assert robot.kind == "serial" and robot.n_joints == 2
    np.testing.assert_array_equal(robot.joint_xyz, [[0, 0, 0.05], [0, 0, 0.3]])
    np.testing.assert_array_equal(robot.joint_rpy, [[0, 0, 0], [0, 0.5, 0]])   # rpy optional
    np.testing.assert_array_equal(robot.joint_axes, [[0, 0, 1], [0, 1, 0]])     # normalised
    np.testing.assert_array_equal(robot.velocity_limits, [2.0, 3.0])
    np.testing.assert_array_equal(robot.link_inertias[1][0], [0.0005, 0.0001, 0.0])
    np.testing.assert_array_equal(robot.base_xyz, [0, 0, 0.1])
    np.testing.assert_array_equal(robot.base_rpy, [0, 0, 0])
    np.testing.assert_array_equal(robot.tool_rpy, [0, 0, 0])
    # link i reaches from joint i to joint i + 1 (the tool for the last joint)
    np.testing.assert_allclose(robot.link_lengths, [0.3, 0.2])
    with pytest.raises(ValueError):
        robot.link_inertias[0, 0, 0] = 1.0   # read-only


def test_planar_file_is_the_planar_special_case(tmp_path):
    """Derived general fields: joints about z at the previous link's end, rods along x."""
    from lpa_transfer.robots.params import DEFAULT_VELOCITY_LIMIT, ROD_AXIAL_SHARE

    robot = load_robot_params(ROBOTS / "two_link_source.toml")
    assert robot.kind == "planar"
    np.testing.assert_array_equal(robot.joint_xyz, [[0, 0, 0], [0.3, 0, 0]])
    np.testing.assert_array_equal(robot.joint_axes, [[0, 0, 1], [0, 0, 1]])
    np.testing.assert_array_equal(robot.link_coms, [[0.15, 0, 0], [0.125, 0, 0]])
    np.testing.assert_allclose(np.diagonal(robot.link_inertias[0]),
                               0.6 * 0.3 ** 2 * np.array([ROD_AXIAL_SHARE, 1 / 12, 1 / 12]))
    np.testing.assert_array_equal(robot.tool_xyz, [0.25, 0, 0])
    np.testing.assert_array_equal(robot.velocity_limits, [DEFAULT_VELOCITY_LIMIT] * 2)
    text = VALID.replace("upper = 1.0\n[[joints]]", "upper = 1.0\nvelocity = 2.5\n[[joints]]")
    faster = load_robot_params(write(tmp_path, text))
    np.testing.assert_array_equal(faster.velocity_limits, [2.5, DEFAULT_VELOCITY_LIMIT])


@pytest.mark.parametrize("old, new, message", [
    ('kind = "serial"', 'kind = "spherical"', "key 'kind' must be one of"),
    ("axis = [0.0, 0.0, 2.0]\n", "", r"joints\[0\]: missing key 'axis'"),
    ("axis = [0.0, 0.0, 2.0]", "axis = [0.0, 0.0, 0.0]",
     r"joints\[0\]: key 'axis' must be a non-zero"),
    ("xyz = [0.0, 0.0, 0.05]", "xyz = [0.0, 0.05]", r"joints\[0\]: key 'xyz' must be a list of 3"),
    ("rpy = [0.0, 0.5, 0.0]", 'rpy = [0.0, "a", 0.0]', r"joints\[1\]: key 'rpy' must be a finite"),
    ("effort = 5.0\n", "", r"joints\[1\]: missing key 'effort'"),
    ("velocity = 3.0", "velocity = -3.0", r"joints\[1\]: key 'velocity' must be positive"),
    ("lower = -2.0", "lower = 3.0", r"joints\[1\]: key 'lower' \(3.0\) is greater"),
    ("mass = 0.5", "mass = -0.5", r"links\[1\]: key 'mass' must be positive"),
    ("com = [0.1, 0.0, 0.0]\n", "", r"links\[1\]: missing key 'com'"),
    ("inertia = { ixx = 0.01, ixy = 0.0, ", "inertia = { ixx = 0.01, ",
     r"links\[0\]: inertia: missing key 'ixy'"),
    ("iyy = 0.002, iyz", "iyy = -0.002, iyz",
     r"links\[1\]: key 'inertia' is not positive definite"),
    ("ixy = 0.0001", "ixy = 0.01", r"links\[1\]: key 'inertia' is not positive definite"),
    ("izz = 0.005", "izz = 0.05", r"links\[0\]: key 'inertia' violates the triangle inequality"),
    ("[[links]]\nmass = 0.5", "[[nothing]]\nmass = 0.5", r"2 \[\[joints\]\] but 1 \[\[links\]\]"),
    ('[tool]\nxyz = [0.2, 0.0, 0.0]\n', "", r"missing '\[tool\]' table"),
    ("[base]\nxyz = [0.0, 0.0, 0.1]", "[base]\nxyz = 0.1", r"base: key 'xyz' must be a list of 3"),
])
def test_broken_serial_file_names_file_and_key(tmp_path, old, new, message):
    assert_broken(tmp_path, SERIAL, old, new, message)


def test_planar_file_may_not_place_its_base(tmp_path):
    path = write(tmp_path, VALID + "[base]\nxyz = [1.0, 0.0, 0.0]\n")
    with pytest.raises(ValueError, match=r"'\[base\]' table needs kind = \"serial\""):
        load_robot_params(path)


def test_direct_construction_checks_shapes():
    from lpa_transfer.robots.params import RobotParams

    with pytest.raises(ValueError, match=r"joint_axes must have shape \(2, 3\)"):
        RobotParams("arm", [0.3, 0.2], [(0, 1), (0, 1)], "test", joint_axes=[[0, 0, 1]])
    with pytest.raises(ValueError, match="kind must be one of"):
        RobotParams("arm", [0.3], [(0, 1)], "test", kind="spherical")


# -- joint drives: armature and damping (both kinds) ---------------------------------------
def test_armature_and_damping_are_optional_and_stored(tmp_path):
    robot = load_robot_params(write(tmp_path, SERIAL))
    np.testing.assert_array_equal(robot.joint_armature, [0, 0])   # default: no drive model
    np.testing.assert_array_equal(robot.joint_damping, [0, 0])
    driven = load_robot_params(write(tmp_path, SERIAL.replace(
        "velocity = 3.0", "velocity = 3.0\narmature = 0.05\ndamping = 1.5")))
    np.testing.assert_array_equal(driven.joint_armature, [0, 0.05])
    np.testing.assert_array_equal(driven.joint_damping, [0, 1.5])
    planar = load_robot_params(write(tmp_path, VALID.replace(
        "upper = 1.0\n[[joints]]", "upper = 1.0\narmature = 0.2\ndamping = 0\n[[joints]]")))
    np.testing.assert_array_equal(planar.joint_armature, [0.2, 0])
    np.testing.assert_array_equal(planar.joint_damping, [0, 0])
    with pytest.raises(ValueError):
        driven.joint_armature[0] = 1.0   # read-only


@pytest.mark.parametrize("text, old, new, message", [
    ("serial", "velocity = 3.0", "velocity = 3.0\narmature = -0.1",
     r"joints\[1\]: key 'armature' must be >= 0, got -0.1"),
    ("serial", "velocity = 2.0", "velocity = 2.0\ndamping = -1",
     r"joints\[0\]: key 'damping' must be >= 0, got -1.0"),
    ("serial", "velocity = 2.0", "velocity = 2.0\narmature = inf",
     r"joints\[0\]: key 'armature' must be a finite number, got inf"),
    ("serial", "velocity = 2.0", 'velocity = 2.0\ndamping = "viscous"',
     r"joints\[0\]: key 'damping' must be a finite number"),
    ("planar", "upper = 1.0\n[[joints]]", "upper = 1.0\ndamping = nan\n[[joints]]",
     r"joints\[0\]: key 'damping' must be a finite number, got nan"),
    ("planar", "lower = -1.0", "lower = -1.0\narmature = -2",
     r"joints\[1\]: key 'armature' must be >= 0"),
])
def test_bad_armature_or_damping_names_file_and_key(tmp_path, text, old, new, message):
    base = SERIAL if text == "serial" else VALID
    assert old in base
    path = write(tmp_path, base.replace(old, new, 1))
    with pytest.raises(ValueError, match=message) as info:
        load_robot_params(path)
    assert str(path) in str(info.value)


def test_direct_construction_checks_armature_and_damping():
    from lpa_transfer.robots.params import RobotParams

    args = ("arm", [0.3, 0.2], [(0, 1), (0, 1)], "test")
    assert RobotParams(*args, joint_armature=[0.1, 0.0]).joint_armature.tolist() == [0.1, 0.0]
    with pytest.raises(ValueError, match=r"joint_armature must be finite and >= 0"):
        RobotParams(*args, joint_armature=[0.1, -0.1])
    with pytest.raises(ValueError, match=r"joint_damping must be finite and >= 0"):
        RobotParams(*args, joint_damping=[np.nan, 0.0])
    with pytest.raises(ValueError, match=r"joint_damping must have shape \(2,\)"):
        RobotParams(*args, joint_damping=[1.0])


def test_chapter_5_drives_are_the_sourced_ones():
    """armature = rotor inertia x gear ratio² (the files' comments give the sources)."""
    youbot = load_robot_params(ROBOTS / "youbot_arm.toml")
    rotor = np.array([92.5, 135.0, 92.5, 92.5, 35.0]) * 1e-7          # g·cm² -> kg·m², maxon
    ratio = np.array([156, 156, 100, 71, 71])                          # youbot_driver config
    np.testing.assert_allclose(youbot.joint_armature, rotor * ratio ** 2, rtol=1e-12)
    np.testing.assert_array_equal(youbot.joint_damping, 1.0)            # youbot_description
    pincher = load_robot_params(ROBOTS / "pincher_arm.toml")
    # assumed: >= tau_m (10 ms) x stall torque / no-load speed of the AX-12A
    np.testing.assert_allclose(pincher.joint_armature, 0.010 * 1.5 / (59 * 2 * np.pi / 60),
                               rtol=0.02)
    np.testing.assert_array_equal(pincher.joint_damping, 0.0)
    for stem, n in (("two_link_arm", 2), ("three_dof_arm", 3)):
        np.testing.assert_allclose(load_robot_params(ROBOTS / f"{stem}.toml").joint_armature,
                                   [92.5e-7 * 156 ** 2] * n, rtol=1e-12)
    for stem in ("two_link_source", "two_link_target"):   # Table 3.1 robots: no drives
        table = load_robot_params(ROBOTS / f"{stem}.toml")
        assert not table.joint_armature.any() and not table.joint_damping.any()


def test_extends_places_the_same_chain_elsewhere(tmp_path):
    """poppy_right_arm_zup.toml: poppy_right_arm.toml's chain with its own [base]; the z-up
    scene's right shoulder stands 0.66 m above the floor."""
    from lpa_transfer.robots.serial_chain import chain_frames

    base = load_robot_params(ROBOTS / "poppy_right_arm.toml")
    placed = load_robot_params(ROBOTS / "poppy_right_arm_zup.toml")
    assert placed.name == base.name and placed.source != base.source
    for field in ("joint_xyz", "joint_rpy", "joint_axes", "joint_limits", "link_masses",
                  "effort_limits", "tool_xyz"):
        np.testing.assert_array_equal(getattr(placed, field), getattr(base, field))
    np.testing.assert_array_equal(placed.base_xyz, [0.0, 0.42, 0.017])
    shoulder = chain_frames(placed, np.zeros((1, 5)))[0, 1, :3, 3]     # world y is up
    assert shoulder[1] == pytest.approx(0.6625, abs=1e-3)
    (tmp_path / "a.toml").write_text('extends = "b.toml"\n')
    (tmp_path / "b.toml").write_text('extends = "a.toml"\n')
    with pytest.raises(ValueError, match="'extends' loops back"):
        load_robot_params(tmp_path / "a.toml")
    (tmp_path / "c.toml").write_text('extends = "missing.toml"\n')
    with pytest.raises(ValueError, match="missing.toml, which does not exist"):
        load_robot_params(tmp_path / "c.toml")
