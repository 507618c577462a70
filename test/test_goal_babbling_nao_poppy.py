"""The chapter 6 graph scenario's experiment 2 (§6.5.2, Nao -> Poppy; scenarios/goal_babbling/run.sh
with nao_poppy.yaml and the smoke.yaml override), every node a real process over DDS; apart
from experiment 1's module (test_goal_babbling_scenario.py) so that the two run side by side."""
import json

import numpy as np
import pytest

from conftest import ROOT
from lpa_transfer.recording.bag import read_messages, summary
from lpa_transfer.robots.kinematics import robot_kinematics
from lpa_transfer.robots.params import load_robot_params
from ros_harness import run_scenario

SCENARIO = ROOT / "scenarios" / "goal_babbling"

pytestmark = pytest.mark.slow     # scenario runs over the node graph


# -- experiment 2 (§6.5.2): Nao -> Poppy, nao_poppy.yaml with the same smoke override ----------
NAO_POPPY = ("scratch", "LPA/T20", "LPA-guarded/T20", "LPA-yielding/T20")


@pytest.fixture(scope="module")
def nao_poppy_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("nao_poppy") / "run"
    result = run_scenario(SCENARIO, out, "nao_poppy.yaml", timeout=280,
                          overrides=["smoke.yaml"])
    assert result.returncode == 0, result.stdout + result.stderr
    return out


def test_nao_poppy_transfers_nao_experience_after_guided_exploration(nao_poppy_run):
    """LPA only, as the thesis; Nao's experience after T_guided is transferred (§6.5.2): of
    its 240 samples (60 s at 4 movements a second) the last 160."""
    results = json.loads((nao_poppy_run / "results.json").read_text())
    curves, settings = results["curves"], results["settings"]
    assert sorted(curves) == sorted(NAO_POPPY)
    assert settings["transfer_from_guided"] and settings["reaching_threshold"] == 0.015
    assert settings["robot_files"]["target"].endswith("poppy_right_arm.toml")
    for name in NAO_POPPY:
        assert curves[name][0]["times"] == [20.0, 40.0, 60.0]
    assert curves["LPA/T20"][0]["n_transferred"] == [160] * 3
    guarded = curves["LPA-guarded/T20"][0]["n_transferred"]
    assert guarded[-1] <= guarded[0] <= 160
    # Nao's experience lowers Poppy's mean error at every evaluation (measured: 129/109/102 mm
    # against scratch's 154/148/144 mm)
    for name in NAO_POPPY[1:]:
        assert all(np.less(curves[name][0]["mean_error"], curves["scratch"][0]["mean_error"]))
    assert "nao_right_arm -> poppy_right_arm" in (nao_poppy_run / "report.txt").read_text()


def test_nao_poppy_pairs_share_commands_on_four_joints(nao_poppy_run):
    """Guided exploration pairs (q̄, x) with q̄ Poppy's joints 1-4 and Nao's 0-3 (7-D rows);
    each side's task point is its own arm's, the other joints at home. Poppy explores its own
    ranges (target_range own): the file holds its rows of all 80 commands (20 s, 4 a second),
    the pairs are those of the commands Nao could follow."""
    with np.load(nao_poppy_run / "guided_0.npz") as pairs:
        source, target = pairs["source"], pairs["target"]
        followed, experience = pairs["meta_followed"], pairs["meta_target_experience"]
        assert str(pairs["meta_target_range"]) == "own"
    assert experience.shape == (80, 7) and followed.shape == (80,)
    assert source.shape == target.shape == (followed.sum(), 7) and followed.sum() >= 40
    np.testing.assert_array_equal(target, experience[followed])
    for rows, name, home, joints in ((source, "nao", [0.2, -0.7, 0.4, 1.3, 0.0], [0, 1, 2, 3]),
                                     (experience, "poppy", [0.0, 0.2, -0.7, 0.4, 1.3],
                                      [1, 2, 3, 4])):
        robot = load_robot_params(ROOT / "scenarios" / "robots" / f"{name}_right_arm.toml")
        q = np.tile(home, (len(rows), 1))
        q[:, joints] = rows[:, :4]
        # 1e-4 m: the held joint sways by a few 1e-5 rad under the moving arm's load
        np.testing.assert_allclose(rows[:, 4:], robot_kinematics(robot).forward(q), atol=1e-4)
    assert np.abs(source[:, :4] - target[:, :4]).max() <= 1e-3   # true same_command pairs
    topics = summary(nao_poppy_run / "run.mcap")
    assert topics["/correspondences"].message_count == followed.sum()
    # Nao babbles with its 4 shared joints (active_joints): its wrist never leaves home
    from rclpy.serialization import deserialize_message
    from sensor_msgs.msg import JointState
    wrist = [deserialize_message(m.data, JointState).position[4] for m in read_messages(
        nao_poppy_run / "run.mcap", topics=["/source/joint_states"])]
    assert len(wrist) > 240 and np.abs(wrist).max() < 1e-3
    # the empty model's evaluation, then 3 of each of the 4 target runs
    assert topics["/target/reaching_evaluation"].message_count == 3 * len(NAO_POPPY) + 1


def test_nao_poppy_in_the_thesis_z_up_scene(tmp_path):
    """The chapter 6 set-up (nao_poppy_zup.yaml) in small: both robots standing in the
    z-up scene, X_bounds read there, conditions scratch, LPA (guarded too) and PA; Nao's
    experience lowers Poppy's mean error (measured at 60 s: scratch 126 mm, LPA 93, PA 93)."""
    out = tmp_path / "run"
    result = run_scenario(SCENARIO, out, "nao_poppy.yaml", timeout=280,
                          overrides=["nao_poppy_zup.yaml", "smoke.yaml"])
    assert result.returncode == 0, result.stdout + result.stderr
    results = json.loads((out / "results.json").read_text())
    curves, settings = results["curves"], results["settings"]
    assert settings["robot_files"]["target"].endswith("poppy_right_arm_zup.toml")
    assert settings["x_bounds"] == [[0.1, 0.4, -0.3], [0.4, 0.8, -0.05]]
    assert sorted(curves) == sorted(("scratch", "LPA/T20", "LPA-guarded/T20", "PA/T20",
                                     "PA-guarded/T20", "LPA-yielding/T20", "PA-yielding/T20"))
    for name in ("LPA/T20", "PA/T20"):
        assert curves[name][0]["mean_error"][-1] < 0.9 * curves["scratch"][0]["mean_error"][-1]
    report = (out / "report.txt").read_text()
    assert "points of the 0.1 m grid over X_bounds (the test points are the" in report
