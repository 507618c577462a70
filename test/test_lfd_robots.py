"""The arms of thesis chapter 4 (human demonstrations -> PR2 / Meka M1): scenarios/robots/
pr2_right_arm.toml, meka_right_arm.toml, human_arm.toml. Their upper arms and forearms have
Table 4.1's lengths, shoulders and tools sit where the files' headers say, Table 4.2's joint
mapping gives the robots the human model's posture (with the PR2's elbow sign flipped, see
pr2_right_arm.toml), and the simulated arms agree with the analytic kinematics."""
import numpy as np
import pytest

from conftest import ROOT
from lpa_transfer.robots import serial_chain
from lpa_transfer.robots.params import load_robot_params
from lpa_transfer.robots.simulator import RobotSimulator, robot_urdf

ROBOTS = ROOT / "scenarios" / "robots"
NAMES = ("pr2_right_arm", "meka_right_arm", "human_arm")
HALF_PI = np.pi / 2

# Table 4.1 (mm) and where each file's upper arm and forearm start and end: indices into
# joint_frames (0..6 the joint frames, 7 the tool). Meka: the URDF's shoulder -> elbow is
# 280.42 mm (278.57 mm along the arm plus its 31.75 mm and 5.02 mm offsets), its elbow ->
# palm (the tool) 321.61 mm at q = 0 (the file header says so).
LENGTHS = {
    "pr2_right_arm": dict(upper=(1, 3, 400.0), forearm=(3, 5, 321.0), forearm_q0_only=False),
    "meka_right_arm": dict(upper=(0, 3, 279.0), forearm=(3, 7, 322.0), forearm_q0_only=True),
    "human_arm": dict(upper=(0, 3, 250.0), forearm=(3, 5, 250.0), forearm_q0_only=False),
}
URDF_LENGTHS_MM = {"meka_right_arm": (280.42, 321.61)}
# World points from the headers: shoulder (first joint origin) and tool at q = 0.
SHOULDER_AND_TOOL = {
    "pr2_right_arm": ((0.0, 0.0, 0.188), (1.001, 0.0, 0.188)),
    "meka_right_arm": ((0.0, 0.2337, 0.18465), (0.00502, -0.36648, 0.2164)),
    "human_arm": ((0.0, 0.0, 0.0), (0.5862, 0.0, 0.0)),
}
T_POSE = np.array([0.0, -HALF_PI, -HALF_PI, 0.0])   # human J1..J4 (human_arm.toml)
U_POSE = np.array([0.0, -HALF_PI, -HALF_PI, HALF_PI])


@pytest.fixture(scope="module")
def robots():
    return {name: load_robot_params(ROBOTS / f"{name}.toml") for name in NAMES}


def joint_frames(robot, q):
    """World frames (4×4) of every joint (after its rotation) and of the tool, at pose q."""
    return list(serial_chain.chain_frames(robot, np.asarray(q, dtype=np.float64)[None])[0])


def points(robot, q):
    return np.array([f[:3, 3] for f in joint_frames(robot, q)])


def random_poses(robot, n, seed):
    limits = robot.joint_limits
    return np.random.default_rng(seed).uniform(limits[:, 0], limits[:, 1], (n, robot.n_joints))


def within_limits(robot, q):
    return bool(np.all(robot.joint_limits[:, 0] <= q) and np.all(q <= robot.joint_limits[:, 1]))


def human_to_pr2(h):
    """Table 4.2 for the PR2, with J4 <- -J4 (the PR2's elbow flexes with negative angles)."""
    return np.r_[h[1], h[0], h[2] + HALF_PI, -h[3], 0.0, 0.0, 0.0]


def human_to_meka(h):
    """Table 4.2 for the Meka, as printed."""
    return np.r_[HALF_PI - h[0], -h[1], h[2] + HALF_PI, h[3], 0.0, 0.0, 0.0]


def segment_directions(robot, q, upper_axis, fore_axis):
    """World directions of the upper arm (link 3's ``upper_axis``) and the forearm (link 4's
    ``fore_axis``): the link-frame axes that point along the segments."""
    frames = joint_frames(robot, q)
    return frames[2][:3, :3] @ upper_axis, frames[3][:3, :3] @ fore_axis


@pytest.mark.parametrize("name", NAMES)
def test_files_are_seven_joint_serial_chains(robots, name):
    robot = robots[name]
    assert robot.kind == "serial" and robot.n_joints == 7
    assert np.all(robot.joint_limits[:, 0] < robot.joint_limits[:, 1])
    assert np.all(robot.link_masses > 0) and np.all(robot.effort_limits > 0)


@pytest.mark.parametrize("name", NAMES)
def test_upper_arm_and_forearm_have_table_4_1_lengths(robots, name):
    robot, spec = robots[name], LENGTHS[name]
    poses = np.vstack([np.zeros(7), random_poses(robot, 20, seed=0)])
    for q in poses:
        p = points(robot, q) * 1000.0
        (a, b, upper), (c, d, fore) = spec["upper"], spec["forearm"]
        assert np.linalg.norm(p[b] - p[a]) == pytest.approx(upper, abs=2.0)
        if not spec["forearm_q0_only"] or not q.any():
            assert np.linalg.norm(p[d] - p[c]) == pytest.approx(fore, abs=2.0)
    if name in URDF_LENGTHS_MM:    # the URDF values documented in the file
        p = points(robot, np.zeros(7)) * 1000.0
        upper, fore = URDF_LENGTHS_MM[name]
        assert np.linalg.norm(p[3] - p[0]) == pytest.approx(upper, abs=0.01)
        assert np.linalg.norm(p[7] - p[3]) == pytest.approx(fore, abs=0.01)


@pytest.mark.parametrize("name", NAMES)
def test_shoulder_and_tool_are_where_the_header_says(robots, name):
    p = points(robots[name], np.zeros(7))
    shoulder, tool = SHOULDER_AND_TOOL[name]
    np.testing.assert_allclose(p[0], shoulder, atol=1e-9)
    np.testing.assert_allclose(p[-1], tool, atol=1e-9)


def test_table_4_2_gives_the_meka_the_human_posture(robots):
    """Meka <- (pi/2 - J1, -J2, J3 + pi/2, J4): upper arm and forearm turn exactly as the
    human model's, anywhere in the human's ranges (the Meka's segments run along -z of its
    link frames, the human's along +x)."""
    human, meka = robots["human_arm"], robots["meka_right_arm"]
    x, minus_z = np.array([1.0, 0, 0]), np.array([0, 0, -1.0])
    for q in random_poses(human, 200, seed=1):
        h = np.r_[q[:4], 0.0, 0.0, 0.0]
        for a, b in zip(segment_directions(human, h, x, x),
                        segment_directions(meka, human_to_meka(h), minus_z, minus_z)):
            np.testing.assert_allclose(a, b, atol=1e-12)


def test_table_4_2_gives_the_pr2_the_human_posture_with_its_elbow_flipped(robots):
    """PR2 <- (J2, J1, J3 + pi/2, -J4): the same posture whenever human J1 = 0 or J2 = 0
    (the PR2 pans before it lifts, the human model the other way round). Table 4.2's
    literal J4 <- J4 would put a flexed human elbow outside the PR2's elbow range."""
    human, pr2 = robots["human_arm"], robots["pr2_right_arm"]
    x = np.array([1.0, 0, 0])
    for q in random_poses(human, 100, seed=2):
        for h in (np.r_[0.0, q[1:4], 0, 0, 0], np.r_[q[0], 0.0, q[2:4], 0, 0, 0]):
            for a, b in zip(segment_directions(human, h, x, x),
                            segment_directions(pr2, human_to_pr2(h), x, x)):
                np.testing.assert_allclose(a, b, atol=1e-12)
    assert pr2.joint_limits[3, 1] == 0.0 and human.joint_limits[3, 0] == 0.0
    flexed = np.r_[U_POSE[1], U_POSE[0], U_POSE[2] + HALF_PI, U_POSE[3], 0, 0, 0]
    assert not within_limits(pr2, flexed)


@pytest.mark.parametrize("pose", ["T", "U"])
def test_t_and_u_poses_map_onto_the_robots(robots, pose):
    """The T-pose (arm out to the right, horizontal) and U-pose (forearm up) of the human
    model map, by Table 4.2, to poses within the robots' limits in which the upper arm points
    to the right (world +z) and the forearm right (T) or up (world +y, U)."""
    h = np.r_[T_POSE if pose == "T" else U_POSE, 0.0, 0.0, 0.0]
    up, right = np.array([0, 1.0, 0]), np.array([0, 0, 1.0])
    fore_expected = right if pose == "T" else up
    cases = [("human_arm", h, [1.0, 0, 0]), ("pr2_right_arm", human_to_pr2(h), [1.0, 0, 0]),
             ("meka_right_arm", human_to_meka(h), [0, 0, -1.0])]
    for name, q, along in cases:
        robot = robots[name]
        assert within_limits(robot, q), name
        upper, fore = segment_directions(robot, q, np.array(along), np.array(along))
        np.testing.assert_allclose(upper, right, atol=1e-12)
        np.testing.assert_allclose(fore, fore_expected, atol=1e-12)


@pytest.mark.parametrize("name", NAMES)
def test_simulated_arm_end_effector_is_the_analytic_one(robots, name):
    """pybullet loads the generated URDF; at random poses within the limits (as initial
    positions, then after 50 position-mode steps of 1 ms) its end effector is
    serial_chain.forward_kinematics of its joint positions."""
    robot = robots[name]
    for q in random_poses(robot, 3, seed=3):
        with RobotSimulator(robot_urdf(robot), "position", 0.001, initial_positions=q) as sim:
            state = sim.state()
            np.testing.assert_allclose(state.positions, q, atol=1e-9)
            np.testing.assert_allclose(state.end_effector,
                                       serial_chain.forward_kinematics(robot, q[None])[0],
                                       atol=1e-6)
            state = sim.step(q, 50)
            np.testing.assert_allclose(state.end_effector, serial_chain.forward_kinematics(
                robot, np.asarray(state.positions)[None])[0], atol=1e-6)
