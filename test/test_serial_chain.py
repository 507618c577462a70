"""General serial chains: the robot files of chapter 5, their URDF and forward kinematics."""
from pathlib import Path

import numpy as np
import pytest

import pybullet as p

from lpa_transfer.robots.kinematics import planar_forward_kinematics
from lpa_transfer.robots.planar_chain import inverse_dynamics, load_fixed_robot
from lpa_transfer.robots.params import load_robot_params
from lpa_transfer.robots.serial_chain import (chain_frames, forward_kinematics, matrix_rpy,
                                              reach_sphere, rpy_matrix, serial_chain_urdf,
                                              tool_transforms, urdf_joint_armatures)
from lpa_transfer.robots.simulator import RobotSimulator, robot_urdf

ROBOTS = Path(__file__).resolve().parents[1] / "scenarios" / "robots"
#: pybullet reports link positions in single precision (getLinkState of a link at x = 0.3 m
#: gives 0x1.333332p-2, float32's 0.3): 1e-7 m is that rounding at ~1 m, not a model error.
LINK_STATE_ATOL = 1e-7
# stem: (kind, joints, effort limit N·m of the thesis/ICRA 2018)
CHAPTER_5 = {"youbot_arm": ("serial", 5, 100.0), "pincher_arm": ("serial", 4, 2.5),
             "three_dof_arm": ("planar", 3, 40.0), "two_link_arm": ("planar", 2, 40.0)}
# A chain with everything a file can say: base placement, tilted frames, skew axes.
GENERAL = """name = "skew"
source = "test"
kind = "serial"
[base]
xyz = [0.3, -0.2, 0.5]
rpy = [0.4, -1.1, 2.0]
[[joints]]
xyz = [0.1, 0.0, 0.2]
rpy = [0.3, 0.2, -0.5]
axis = [0.0, 0.0, 1.0]
lower = -3.0
upper = 3.0
effort = 10.0
velocity = 2.0
[[joints]]
xyz = [0.0, 0.05, 0.3]
rpy = [1.5707963267948966, 0.0, 0.7]
axis = [1.0, 2.0, -0.5]
lower = -2.0
upper = 2.5
effort = 5.0
velocity = 2.0
[[joints]]
xyz = [0.25, -0.1, 0.0]
axis = [0.0, 1.0, 0.0]
lower = -1.0
upper = 1.0
effort = 5.0
velocity = 2.0
[[links]]
mass = 1.0
com = [0.05, 0.0, 0.1]
inertia = { ixx = 0.01, ixy = 0.001, ixz = -0.002, iyy = 0.02, iyz = 0.0005, izz = 0.015 }
[[links]]
mass = 0.5
com = [0.0, 0.02, 0.15]
inertia = { ixx = 0.004, ixy = 0.0, ixz = 0.0, iyy = 0.004, iyz = 0.0, izz = 0.001 }
[[links]]
mass = 0.2
com = [0.1, 0.0, 0.0]
inertia = { ixx = 0.0002, ixy = 0.0, ixz = 0.0, iyy = 0.001, iyz = 0.0, izz = 0.001 }
[tool]
xyz = [0.12, 0.0, 0.03]
rpy = [0.0, 0.5, 0.0]
"""


def robot(stem):
    return load_robot_params(ROBOTS / f"{stem}.toml")


def random_poses(robot, n, seed=0):
    limits = robot.joint_limits
    return np.random.default_rng(seed).uniform(limits[:, 0], limits[:, 1], (n, robot.n_joints))


class Bullet:
    """A robot's URDF in its own DIRECT client: tool positions and inverse dynamics."""

    def __init__(self, urdf):
        self.client = p.connect(p.DIRECT)
        self.body = load_fixed_robot(p, urdf, self.client)
        self.n_joints = p.getNumJoints(self.body, physicsClientId=self.client) - 1   # - tool

    def tool(self, q):
        for j, value in enumerate(q):
            p.resetJointState(self.body, j, value, physicsClientId=self.client)
        return p.getLinkState(self.body, self.n_joints, computeForwardKinematics=True,
                              physicsClientId=self.client)[4]

    def torques(self, q, qd=None, qdd=None):
        zero = [0.0] * self.n_joints
        return np.array(p.calculateInverseDynamics(
            self.body, list(q), zero if qd is None else list(qd), zero if qdd is None
            else list(qdd), physicsClientId=self.client))

    def close(self):
        p.disconnect(physicsClientId=self.client)


@pytest.fixture
def bullet():
    opened = []

    def make(robot):
        opened.append(Bullet(serial_chain_urdf(robot)))
        return opened[-1]

    yield make
    for sim in opened:
        sim.close()


@pytest.mark.parametrize("stem", CHAPTER_5)
def test_chapter_5_robot_files_load_into_the_simulator(stem):
    arm = robot(stem)
    kind, n_joints, effort = CHAPTER_5[stem]
    assert (arm.name, arm.kind, arm.n_joints) == (stem, kind, n_joints)
    np.testing.assert_array_equal(arm.effort_limits, effort)
    assert (arm.link_masses > 0).all() and arm.source
    with RobotSimulator(robot_urdf(arm)) as sim:
        assert sim.joint_names == [f"joint{i + 1}" for i in range(n_joints)]
        np.testing.assert_allclose(sim.joint_limits, arm.joint_limits, rtol=1e-12)
        np.testing.assert_array_equal(sim.effort_limits, arm.effort_limits)
        np.testing.assert_allclose(sim.state().end_effector,
                                   forward_kinematics(arm, np.zeros((1, n_joints)))[0],
                                   atol=LINK_STATE_ATOL)
        np.testing.assert_array_equal(sim.armature, arm.joint_armature)      # via the URDF
        np.testing.assert_array_equal(sim.joint_damping, arm.joint_damping)
        assert sim.armature.all()   # every chapter 5 joint is a geared drive


@pytest.mark.parametrize("stem", [*CHAPTER_5, "general"])
def test_forward_kinematics_matches_pybullet(stem, bullet, tmp_path):
    if stem == "general":
        (tmp_path / "skew.toml").write_text(GENERAL)
        arm = load_robot_params(tmp_path / "skew.toml")
    else:
        arm = robot(stem)
    q = random_poses(arm, 25)
    sim = bullet(arm)
    expected = np.array([sim.tool(row) for row in q])
    np.testing.assert_allclose(forward_kinematics(arm, q), expected, rtol=0,
                               atol=LINK_STATE_ATOL)


@pytest.mark.parametrize("stem", ["two_link_source", "two_link_target", "three_dof_arm"])
def test_planar_files_agree_with_the_planar_chain(stem, bullet):
    """A planar file is the special case: same tool positions, same dynamics (eq. 5.1)."""
    arm = robot(stem)
    q = random_poses(arm, 20, seed=1)
    tool = forward_kinematics(arm, q)
    np.testing.assert_allclose(tool[:, :2], planar_forward_kinematics(q, arm.link_lengths),
                               atol=1e-12)
    np.testing.assert_array_equal(tool[:, 2], 0.0)
    rng = np.random.default_rng(2)
    qd, qdd = rng.normal(size=q.shape), rng.normal(size=q.shape)
    sim = bullet(arm)
    np.testing.assert_allclose(
        [sim.torques(*rows) for rows in zip(q, qd, qdd)],
        inverse_dynamics(arm.link_lengths, arm.link_masses, q, qd, qdd, arm.joint_limits),
        rtol=1e-9, atol=1e-9)


def test_youbot_gravity_torques_are_plausible(bullet):
    """Upright (q = 0) the arm is nearly balanced; stretched out horizontally the shoulder
    holds about 9.81·Σ m_i x_i = 8.2 N·m of the published link masses, under the real motor's
    9.5 N·m and far under the thesis' 100 N·m limit."""
    sim = bullet(robot("youbot_arm"))
    upright = sim.torques(np.zeros(5))
    assert np.abs(upright).max() < 0.5
    horizontal = sim.torques([0.0, np.pi / 2, 0.0, 0.0, 0.0])
    assert 5.0 < abs(horizontal[1]) < 9.5 and np.abs(horizontal).max() < 100.0
    assert abs(horizontal[2]) < abs(horizontal[1])


def test_pincher_holds_itself_within_its_torque_limits(bullet):
    """Upright and horizontal, the AX-12A joints need less than their 1.5 N·m stall torque."""
    sim = bullet(robot("pincher_arm"))
    for q in ([0.0] * 4, [0.0, np.pi / 2, 0.0, 0.0], [1.0, -np.pi / 2, 0.0, 0.0]):
        torques = sim.torques(q)
        assert np.abs(torques).max() < 1.5, (q, torques)
    assert abs(sim.torques([0.0, np.pi / 2, 0.0, 0.0])[1]) > 0.3


def test_rpy_round_trip_including_gimbal_lock():
    rng = np.random.default_rng(4)
    angles = np.vstack((rng.uniform(-3, 3, (50, 3)), [[0.3, np.pi / 2, -1.0],
                                                        [1.0, -np.pi / 2, 0.2]]))
    for rpy in angles:
        rotation = rpy_matrix(rpy)
        np.testing.assert_allclose(rotation @ rotation.T, np.eye(3), atol=1e-12)
        np.testing.assert_allclose(rpy_matrix(matrix_rpy(rotation)), rotation, atol=1e-12)


def test_chain_frames_are_the_partial_products_of_the_chain():
    """Joint i's frame sits at its origin (its own rotation does not move it), the last frame
    is the tool's, and link lengths do not depend on the pose."""
    arm = robot("youbot_arm")
    q = random_poses(arm, 5, seed=3)
    frames = chain_frames(arm, q)
    assert frames.shape == (5, arm.n_joints + 1, 4, 4)
    np.testing.assert_allclose(frames[:, -1], tool_transforms(arm, q))
    np.testing.assert_allclose(frames[:, -1, :3, 3], forward_kinematics(arm, q))
    moved = q.copy()
    moved[:, 2] += 0.7          # turning joint 2 leaves the origins up to joint 2 in place
    np.testing.assert_allclose(chain_frames(arm, moved)[:, :3, :3, 3], frames[:, :3, :3, 3],
                               atol=1e-12)
    lengths = np.linalg.norm(np.diff(frames[:, :, :3, 3], axis=1), axis=2)
    np.testing.assert_allclose(lengths, np.broadcast_to(lengths[0], lengths.shape), atol=1e-12)


@pytest.mark.parametrize("rows", [255, 256, 257])   # both sides of the one-pass threshold
def test_each_rows_frames_do_not_depend_on_its_batch(rows):
    """Bit for bit: inverse_kinematics.solve_many evaluates a row's step halvings together
    with other rows' and must see what a call on that row alone gives."""
    arm = robot("youbot_arm")
    q = random_poses(arm, rows, seed=5)
    batch = chain_frames(arm, q)
    for i in (0, rows // 2, rows - 1):
        assert np.array_equal(batch[i], chain_frames(arm, q[i:i + 1])[0])
    assert np.array_equal(forward_kinematics(arm, q[::-1])[::-1], batch[:, -1, :3, 3])


@pytest.mark.parametrize("stem", ["human_arm", "pr2_right_arm", "meka_right_arm",
                                  "nao_right_arm_zup", "poppy_right_arm", "youbot_arm"])
def test_the_reach_sphere_holds_every_pose(stem):
    """reach_sphere bounds the tool for random poses (and for the human, whose stretched arm
    is within its limits, it is tight: 20 000 random poses reach 0.58619 m of 0.5862)."""
    arm = robot(stem)
    centre, radius = reach_sphere(arm)
    distances = np.linalg.norm(forward_kinematics(arm, random_poses(arm, 20000, seed=3))
                               - centre, axis=1)
    assert distances.max() <= radius + 1e-12
    if stem == "human_arm":
        assert distances.max() > radius - 1e-3


def test_forward_kinematics_rejects_bad_joint_arrays():
    arm = robot("pincher_arm")
    with pytest.raises(ValueError, match=r"shape \(N, 4\)"):
        forward_kinematics(arm, np.zeros((3, 5)))
    with pytest.raises(ValueError, match="NaN"):
        forward_kinematics(arm, [[0.0, np.nan, 0.0, 0.0]])


def test_urdf_carries_the_joint_drives(tmp_path):
    """damping -> <dynamics damping> (pybullet reads it), armature -> <lpa:armature>."""
    import dataclasses

    arm = robot("youbot_arm")
    urdf = serial_chain_urdf(arm)
    assert urdf_joint_armatures(urdf) == {f"joint{i + 1}": a
                                          for i, a in enumerate(arm.joint_armature)}
    client = p.connect(p.DIRECT)
    try:
        body = load_fixed_robot(p, urdf, client)   # the extension does not disturb pybullet
        assert [p.getJointInfo(body, j, physicsClientId=client)[6]
                for j in range(arm.n_joints)] == arm.joint_damping.tolist()
    finally:
        p.disconnect(client)
    plain = dataclasses.replace(arm, joint_armature=np.zeros(5), joint_damping=np.zeros(5))
    assert "lpa:" not in serial_chain_urdf(plain)    # as before drives existed
    assert urdf_joint_armatures(serial_chain_urdf(plain)) == {}
    partial = dataclasses.replace(arm, joint_armature=[0, 0.5, 0, 0, 0])
    assert urdf_joint_armatures(serial_chain_urdf(partial)) == {"joint2": 0.5}


@pytest.mark.parametrize("value, message", [('"-1"', "must be a finite number >= 0"),
                                            ('"nan"', "must be a finite number >= 0"),
                                            ('"heavy"', "must be a finite number >= 0")])
def test_urdf_armature_values_are_checked(value, message):
    import re

    urdf = re.sub(r'armature value="[^"]*"', f"armature value={value}",
                  serial_chain_urdf(robot("pincher_arm")), count=1)
    with pytest.raises(ValueError, match=f"joint1.*{message}"):
        urdf_joint_armatures(urdf)
    with pytest.raises(ValueError, match="not valid XML"):
        urdf_joint_armatures(serial_chain_urdf(robot("pincher_arm")).replace("</robot>", ""))
    undeclared = re.sub(r' xmlns:lpa="[^"]*"', "", serial_chain_urdf(robot("pincher_arm")))
    with pytest.raises(ValueError, match="does not declare their namespace"):
        urdf_joint_armatures(undeclared)
