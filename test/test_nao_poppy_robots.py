"""The Nao and Poppy arms of thesis §6.5.2 (scenarios/robots/nao_right_arm.toml,
poppy_right_arm.toml) and their placement in scenarios/goal_babbling/nao_poppy.yaml: what
guided exploration (Alg. 7) needs of them — the 4 shared joints give both arms the same
posture, both shoulders stand at one world point, the homes lie in the task boxes — and the
simulated robots agree with the analytic kinematics."""
import numpy as np
import pytest
import yaml

from conftest import ROOT
from lpa_transfer.robots import serial_chain
from lpa_transfer.robots.kinematics import robot_kinematics
from lpa_transfer.exploration.guided import shared_limits
from lpa_transfer.goal_babbling.reaching import evaluation_points
from lpa_transfer.robots.params import load_robot_params
from lpa_transfer.robots.simulator import RobotSimulator, robot_urdf

ROBOTS = ROOT / "scenarios" / "robots"
CONFIG = yaml.safe_load((ROOT / "scenarios" / "goal_babbling" / "nao_poppy.yaml").read_text())
NAO_JOINTS, POPPY_JOINTS = [0, 1, 2, 3], [1, 2, 3, 4]
URDF_ZERO = np.array([0.0, 0.0, -np.pi / 2, np.pi / 2, 0.0])   # Poppy's q at its URDF's q = 0


@pytest.fixture(scope="module")
def robots():
    return {name: load_robot_params(ROBOTS / f"{name}_right_arm.toml") for name in ("nao", "poppy")}


def joint_origins(robot, q):
    """World positions of every joint origin and the tool of ``robot`` at one pose ``q``."""
    return serial_chain.chain_frames(robot, np.asarray(q, dtype=np.float64)[None])[0, :, :3, 3]


def unit(v):
    return v / np.linalg.norm(v)


def angle_deg(a, b):
    return np.degrees(np.arccos(np.clip(unit(a) @ unit(b), -1.0, 1.0)))


def test_the_shared_joints_give_both_arms_the_same_posture(robots):
    """Alg. 7 sends the same commands to both robots; Poppy's shared joints are zeroed so that
    the same values put its upper arm and forearm along Nao's (within the small offsets of
    the two designs), everywhere in the shared joint ranges."""
    nao, poppy = robots["nao"], robots["poppy"]
    limits = shared_limits(robot_kinematics(nao), robot_kinematics(poppy), NAO_JOINTS,
                           POPPY_JOINTS)
    rng = np.random.default_rng(0)
    upper, fore = [], []
    for q in rng.uniform(limits[:, 0], limits[:, 1], (300, 4)):
        n = joint_origins(nao, np.r_[q, 0.0])       # shoulder 0, elbow 2, wrist 4, tool 5
        p = joint_origins(poppy, np.r_[0.0, q])     # torso 0, shoulder 1, elbow 4, tool 5
        upper.append(angle_deg(n[2] - n[0], p[4] - p[1]))
        fore.append(angle_deg(n[5] - n[3], p[5] - p[4]))
    assert max(upper) < 15 and max(fore) < 10
    # without Poppy's re-zeroing (commands read in its URDF's convention) the
    # same commands would point the arms tens of degrees apart
    n = joint_origins(nao, np.r_[q, 0.0])
    p = joint_origins(poppy, np.r_[0.0, q] + URDF_ZERO)
    assert angle_deg(n[2] - n[0], p[4] - p[1]) > 30


def test_shoulders_coincide_and_nao_box_is_the_thesis_box_scaled(robots):
    nao, poppy = robots["nao"], robots["poppy"]
    shoulder_nao = joint_origins(nao, np.zeros(5))[0]
    shoulder_poppy = joint_origins(poppy, np.zeros(5))[1]
    np.testing.assert_allclose(shoulder_nao, shoulder_poppy, atol=1e-3)
    # arm lengths, shoulder to tool, both arms stretched (Poppy's URDF zero, see the file)
    ratio = (np.linalg.norm(joint_origins(nao, np.zeros(5))[-1] - shoulder_nao)
             / np.linalg.norm(joint_origins(poppy, URDF_ZERO)[-1] - shoulder_poppy))
    assert ratio == pytest.approx(0.6157, abs=1e-3)
    learners = {side: CONFIG[f"/{side}/learner"]["ros__parameters"]
                for side in ("source", "target")}
    thesis = np.array([[0.1, 0.05, 0.4], [0.4, 0.3, 0.8]])
    np.testing.assert_allclose([learners["target"]["x_low"], learners["target"]["x_high"]], thesis)
    scaled = shoulder_poppy + ratio * (thesis - shoulder_poppy)
    np.testing.assert_allclose([learners["source"]["x_low"], learners["source"]["x_high"]], scaled,
                               atol=0.006)   # rounded to 1 cm


@pytest.mark.parametrize("side, name", [("source", "nao"), ("target", "poppy")])
def test_homes_are_in_range_and_in_the_task_boxes(robots, side, name):
    learner = CONFIG[f"/{side}/learner"]["ros__parameters"]
    robot, home = robots[name], np.array(learner["home"])
    assert np.all(robot.joint_limits[:, 0] <= home) and np.all(home <= robot.joint_limits[:, 1])
    assert CONFIG[f"/{side}/robot_sim"]["ros__parameters"]["initial_positions"] == learner["home"]
    hand = serial_chain.forward_kinematics(robot, home[None])[0]
    assert np.all(np.array(learner["x_low"]) < hand) and np.all(hand < np.array(learner["x_high"]))
    guided = CONFIG["guided_exploration"]["ros__parameters"]
    assert guided[f"{side}_home"] == learner["home"]
    # the shared joints' home values are the same on both robots
    shared = NAO_JOINTS if name == "nao" else POPPY_JOINTS
    assert list(home[shared]) == [0.2, -0.7, 0.4, 1.3]


def test_the_3d_grid_needs_many_joint_samples(robots):
    """20 000 joint samples miss thin parts of Poppy's reachable X_bounds; the scenario finds
    its test points with 200 000 (the learners' eval_joint_samples)."""
    poppy = robot_kinematics(robots["poppy"], CONFIG["/target/learner"]["ros__parameters"]["home"])
    box = ([0.1, 0.05, 0.4], [0.4, 0.3, 0.8])
    few = evaluation_points(poppy, box, spacing=0.05, n_joint_samples=20000)
    many = evaluation_points(poppy, box, spacing=0.05, n_joint_samples=200000)
    assert len(many) > 1.2 * len(few) and len(many) <= 7 * 6 * 9
    assert CONFIG["/target/learner"]["ros__parameters"]["eval_joint_samples"] == 200000


@pytest.mark.parametrize("name", ["nao", "poppy"])
def test_simulated_arm_follows_position_commands_like_its_kinematics(robots, name):
    """pybullet in position mode, 100 steps of 1 ms a command (the scenario's movement step):
    the arm reaches small random steps and its end effector is the analytic one."""
    robot = robots[name]
    home = np.array(CONFIG[f"/{'source' if name == 'nao' else 'target'}/learner"]
                    ["ros__parameters"]["home"])
    rng = np.random.default_rng(1)
    with RobotSimulator(robot_urdf(robot), "position", 0.001, initial_positions=home) as sim:
        q = home
        for _ in range(30):
            q = np.clip(q + rng.normal(0, 0.05, len(q)), robot.joint_limits[:, 0],
                        robot.joint_limits[:, 1])
            state = sim.step(q, 100)
            assert np.abs(state.positions - q).max() < 0.01
            np.testing.assert_allclose(state.end_effector[:3], serial_chain.forward_kinematics(
                robot, np.asarray(state.positions)[None])[0], atol=1e-6)
