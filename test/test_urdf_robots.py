"""Robots from a user's URDF (lpa_transfer.robots.urdf): forward kinematics against pybullet
loading the same file, and the simulator running the chain."""
import numpy as np
import pybullet as p
import pytest

from lpa_transfer.robots.kinematics import robot_kinematics
from lpa_transfer.robots.params import load_robot_params
from lpa_transfer.robots.simulator import RobotSimulator, robot_urdf

# 3 revolute joints about different axes, a fixed joint between the second and third (a
# bracket with its own mass), a tilted first joint, a fixed tool frame at the tip, and a
# base link offset from the world by a fixed joint.
URDF = """<?xml version="1.0"?>
<robot name="hand_written_arm">
  <link name="world_base"/>
  <link name="base"><inertial><mass value="2.0"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
  <joint name="mount" type="fixed"><parent link="world_base"/><child link="base"/><origin xyz="0.1 0 0.2" rpy="0 0 0.3"/></joint>
  <link name="upper"><inertial><origin xyz="0 0 0.15" rpy="0.2 0 0"/><mass value="1.2"/><inertia ixx="0.012" ixy="0" ixz="0" iyy="0.011" iyz="0" izz="0.002"/></inertial></link>
  <joint name="shoulder_yaw" type="revolute"><parent link="base"/><child link="upper"/><origin xyz="0 0 0.1" rpy="0.1 0 0"/><axis xyz="0 0 1"/><limit lower="-2.0" upper="2.0" effort="30" velocity="3"/><dynamics damping="0.5"/></joint>
  <link name="fore"><inertial><origin xyz="0.12 0 0"/><mass value="0.8"/><inertia ixx="0.001" ixy="0" ixz="0" iyy="0.006" iyz="0" izz="0.006"/></inertial></link>
  <joint name="elbow" type="revolute"><parent link="upper"/><child link="fore"/><origin xyz="0 0 0.3"/><axis xyz="0 1 0"/><limit lower="-1.5" upper="1.5" effort="20" velocity="3"/></joint>
  <link name="bracket"><inertial><origin xyz="0.02 0 0"/><mass value="0.1"/><inertia ixx="0.0001" ixy="0" ixz="0" iyy="0.0001" iyz="0" izz="0.0001"/></inertial></link>
  <joint name="bracket_fix" type="fixed"><parent link="fore"/><child link="bracket"/><origin xyz="0.25 0 0" rpy="0 0 0.5"/></joint>
  <link name="wrist"><inertial><origin xyz="0.05 0 0"/><mass value="0.3"/><inertia ixx="0.0002" ixy="0" ixz="0" iyy="0.0005" iyz="0" izz="0.0005"/></inertial></link>
  <joint name="wrist_roll" type="continuous"><parent link="bracket"/><child link="wrist"/><origin xyz="0.03 0.01 0"/><axis xyz="1 0 0"/><limit effort="5" velocity="6"/></joint>
  <link name="tip"/>
  <joint name="tool" type="fixed"><parent link="wrist"/><child link="tip"/><origin xyz="0.1 0.02 -0.01"/></joint>
</robot>
"""


@pytest.fixture
def urdf_file(tmp_path):
    path = tmp_path / "arm.urdf"
    path.write_text(URDF)
    return path


def test_forward_kinematics_equal_pybullet_on_the_same_file(urdf_file):
    robot = load_robot_params(urdf_file)
    assert (robot.name, robot.n_joints, robot.kind) == ("hand_written_arm", 3, "serial")
    np.testing.assert_array_equal(robot.joint_limits, [[-2, 2], [-1.5, 1.5], [-np.pi, np.pi]])
    np.testing.assert_array_equal(robot.effort_limits, [30, 20, 5])
    np.testing.assert_array_equal(robot.joint_damping, [0.5, 0, 0])
    # the fore link carries the bracket fixed to it: 0.8 + 0.1 kg
    assert robot.link_masses[1] == pytest.approx(0.9)
    q = np.random.default_rng(0).uniform(robot.joint_limits[:, 0], robot.joint_limits[:, 1],
                                         size=(20, 3))
    ours = robot_kinematics(robot).forward(q)
    client = p.connect(p.DIRECT)
    try:
        body = p.loadURDF(str(urdf_file), useFixedBase=True, physicsClientId=client)
        names = {p.getJointInfo(body, j, physicsClientId=client)[1].decode(): j
                 for j in range(p.getNumJoints(body, physicsClientId=client))}
        moving = [names[n] for n in ("shoulder_yaw", "elbow", "wrist_roll")]
        for row, expected in zip(q, ours):
            for index, angle in zip(moving, row):
                p.resetJointState(body, index, angle, physicsClientId=client)
            tip = p.getLinkState(body, names["tool"], computeForwardKinematics=True,
                                 physicsClientId=client)[4]
            # pybullet reports link frames in single precision (LINK_STATE_ATOL elsewhere)
            np.testing.assert_allclose(expected, tip, atol=1e-6)
    finally:
        p.disconnect(client)


def test_the_simulator_runs_the_chain(urdf_file):
    robot = load_robot_params(urdf_file)
    sim = RobotSimulator(robot_urdf(robot), "position")
    try:
        state = sim.step([0.5, -0.4, 1.0], 2000)
    finally:
        sim.close()
    np.testing.assert_allclose(state.positions, [0.5, -0.4, 1.0], atol=2e-2)
    np.testing.assert_allclose(state.end_effector,
                               robot_kinematics(robot).forward(state.positions[None])[0],
                               atol=1e-6)


@pytest.mark.parametrize("text, message", [
    (URDF.replace('type="revolute"><parent link="upper"', 'type="prismatic"><parent link="upper"'),
     r"only revolute, continuous and fixed joints .*'elbow \(prismatic\)'"),
    (URDF.replace('<joint name="tool" type="fixed">', '<joint name="tool2" type="fixed">'
                  '<parent link="wrist"/><child link="side"/></joint><link name="side"/>'
                  '<joint name="tool" type="fixed">'), r"link 'wrist' branches into joints"),
    (URDF.replace('<limit lower="-1.5" upper="1.5" effort="20" velocity="3"/>', ''),
     "needs <limit>"),
    ("<robot><link", "not a readable URDF"),
])
def test_urdfs_outside_the_subset_are_refused_with_the_reason(tmp_path, text, message):
    path = tmp_path / "bad.urdf"
    path.write_text(text)
    with pytest.raises(ValueError, match=message):
        load_robot_params(path)


def test_robot_sim_node_serves_a_urdf_robot(urdf_file, tmp_path):
    """The node takes the URDF as its ``robot`` file, like a TOML robot file."""
    from lpa_transfer_interfaces.srv import StepRobot
    from ros_harness import ClientNode, NodeProcess, ros_params, unique_domain_id

    domain_id = unique_domain_id()
    node = NodeProcess("robot_sim", domain_id, tmp_path / "log",
                       ros_params(robot=urdf_file, control_mode="position", lockstep=True))
    client = ClientNode(domain_id, "urdf_test_client")
    try:
        step = client.node.create_client(StepRobot, "/robot_sim/step")
        answer = client.call(step, StepRobot.Request(command=[0.5, -0.4, 1.0], n_steps=2000))
        assert answer.success, answer.message + node.log()
        assert len(answer.joint_state.name) == 3    # (the chain's own names, not the URDF's)
        np.testing.assert_allclose(answer.joint_state.position, [0.5, -0.4, 1.0], atol=2e-2)
    finally:
        client.close()
        assert node.stop() == 0, node.log()


# -- the arms that ship with pybullet ------------------------------------------------------
import xml.etree.ElementTree as ElementTree  # noqa: E402
from pathlib import Path  # noqa: E402

import pybullet_data  # noqa: E402

from conftest import ROOT  # noqa: E402
from lpa_transfer.robots.simulator import simulated_description  # noqa: E402
from lpa_transfer.robots.urdf import read_urdf, simulated_urdf  # noqa: E402

DATA = Path(pybullet_data.getDataPath())
IIWA, PANDA, XARM = (DATA / "kuka_iiwa/model.urdf", DATA / "franka_panda/panda.urdf",
                     DATA / "xarm/xarm6_robot.urdf")


def _link_pose(urdf_path, names, q, link):
    """pybullet's world position of ``link`` with the named joints at ``q`` (same file)."""
    client = p.connect(p.DIRECT)
    try:
        body = p.loadURDF(str(urdf_path), useFixedBase=True, physicsClientId=client)
        infos = [p.getJointInfo(body, j, physicsClientId=client)
                 for j in range(p.getNumJoints(body, physicsClientId=client))]
        index = {info[1].decode(): info[0] for info in infos}
        for name, angle in zip(names, q):
            p.resetJointState(body, index[name], angle, physicsClientId=client)
        link_index = next(info[0] for info in infos if info[12].decode() == link)
        return np.array(p.getLinkState(body, link_index, computeForwardKinematics=True,
                                       physicsClientId=client)[4])
    finally:
        p.disconnect(client)


def test_panda_chain_down_to_a_named_tip_link():
    with pytest.raises(ValueError, match=r"branches into joints .*-p tip_link:=<link>\), one "
                                         r"of the links \['panda_link0'.*'panda_hand'"):
        load_robot_params(PANDA)
    robot = load_robot_params(PANDA, tip_link="panda_hand")
    assert robot.n_joints == 7          # the fingers' prismatic joints are off the chain
    q = np.random.default_rng(1).uniform(robot.joint_limits[:, 0], robot.joint_limits[:, 1])
    names = [f"panda_joint{i}" for i in range(1, 8)]
    np.testing.assert_allclose(robot_kinematics(robot).forward(q[None])[0],
                               _link_pose(PANDA, names, q, "panda_hand"), atol=1e-9)
    # from a base link: the joints above it are left out
    assert load_robot_params(PANDA, base_link="panda_link2", tip_link="panda_hand").n_joints == 5


@pytest.mark.parametrize("options, message", [
    (dict(tip_link="hand"), r"no link 'hand' \(tip_link\); its links: \['panda_link0'.*"
                            r"'panda_grasptarget'\]"),
    (dict(base_link="link0"), r"no link 'link0' \(base_link\); its links: \['panda_link0'"),
    (dict(base_link="panda_link5", tip_link="panda_link2"), "is not below 'panda_link5'")])
def test_unknown_or_misplaced_links_are_refused_naming_the_links(options, message):
    with pytest.raises(ValueError, match=message):
        load_robot_params(PANDA, **options)


def test_link_options_need_a_urdf():
    with pytest.raises(ValueError, match="apply to a URDF file"):
        load_robot_params(ROOT / "scenarios/robots/two_link_source.toml", tip_link="link2")


@pytest.mark.parametrize("urdf, n_joints", [(IIWA, 7), (PANDA, 9)])
def test_the_arms_load_as_they_are_with_their_meshes(urdf, n_joints):
    text, repairs = simulated_urdf(urdf)
    assert repairs == []
    meshes = [m.get("filename") for m in ElementTree.fromstring(text).iter("mesh")]
    assert meshes and all(Path(m).is_absolute() and Path(m).is_file() for m in meshes)
    with RobotSimulator(text) as sim:      # through a temporary file, as robot_sim does
        assert sim.n_joints == n_joints
        assert sim.joint_names[0] in ("lbr_iiwa_joint_1", "panda_joint1")


def test_package_paths_resolve_against_the_file_and_a_missing_mesh_is_named(tmp_path):
    (tmp_path / "my_arm" / "meshes").mkdir(parents=True)
    (tmp_path / "my_arm" / "meshes" / "a.stl").write_text("solid a\nendsolid a\n")
    urdf = tmp_path / "my_arm" / "urdf" / "arm.urdf"
    urdf.parent.mkdir()
    body = URDF.replace('<link name="tip"/>', '<link name="tip"><visual><geometry><mesh '
                        'filename="package://my_arm/meshes/a.stl"/></geometry></visual></link>')
    urdf.write_text(body)
    text, _ = simulated_urdf(urdf)
    assert f'filename="{tmp_path / "my_arm/meshes/a.stl"}"' in text
    assert text.replace(str(tmp_path / "my_arm/meshes/a.stl"),
                        "package://my_arm/meshes/a.stl") == body   # nothing else changed
    urdf.write_text(body.replace("a.stl", "b.stl"))
    with pytest.raises(ValueError, match=r"meshes not found: package://my_arm/meshes/b.stl"):
        simulated_urdf(urdf)


def _principal(inertia):
    keys = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
    ixx, ixy, ixz, iyy, iyz, izz = (float(inertia.get(k)) for k in keys)
    return np.linalg.eigvalsh([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])


def test_xarm_inertias_are_refused_naming_the_links_and_repaired_on_request():
    for load in (lambda: load_robot_params(XARM), lambda: simulated_urdf(XARM)):
        with pytest.raises(ValueError, match=r"link 'link2'.*triangle inequality.*link 'link3'"
                                             r".*repair_inertia"):
            load()
    original = {link.get("name"): link for link in ElementTree.parse(XARM).getroot()
                .findall("link")}
    root, lines = read_urdf(XARM, repair_inertia=True)
    assert [line.split(":")[0] for line in lines] == ["link 'link2'", "link 'link3'"]
    for link in root.findall("link"):
        before = original[link.get("name")]
        if before.find("inertial/inertia") is None:
            continue
        old, new = _principal(before.find("inertial/inertia")), _principal(
            link.find("inertial/inertia"))
        assert before.find("inertial/mass").get("value") == link.find(
            "inertial/mass").get("value")
        if link.get("name") in ("link2", "link3"):
            np.testing.assert_allclose(new[1:], old[1:], rtol=1e-9)   # the others kept
            assert new[0] > old[0] and new[2] < new[0] + new[1]
        else:
            assert all(a.attrib == b.attrib for a, b in zip(before.iter(), link.iter()))
    assert load_robot_params(XARM, repair_inertia=True).n_joints == 6
    # pybullet keeps the repaired inertias (it zeroes the file's own link2 and link3)
    text, _ = simulated_urdf(XARM, repair_inertia=True)
    with RobotSimulator(text) as sim:
        body, client = sim._body, sim._client
        for name in ("link2", "link3"):
            index = sim.link_names.index(name)
            diagonal = p.getDynamicsInfo(body, index, physicsClientId=client)[2]
            assert min(diagonal) > 0, (name, diagonal)


def test_the_robot_files_are_simulated_bit_for_bit_as_before():
    for path in sorted((ROOT / "scenarios/robots").glob("*.toml")):
        assert simulated_description(robot=str(path)) == (
            robot_urdf(load_robot_params(path)), None, []), path
