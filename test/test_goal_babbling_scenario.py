"""The chapter 6 graph scenario (scenarios/goal_babbling/run.sh) with the smoke.yaml override:
one seed, 60 s of goal babbling, 20 s of guided exploration; every node a real process over
DDS (two robot_sim nodes in position mode, three goal_babbling_learner nodes, the collector
in guided-exploration mode, lpa_mapping, the recorder)."""
import csv
import json

import numpy as np
import pytest

from conftest import ROOT
from lpa_transfer.recording.bag import summary
from lpa_transfer.robots.kinematics import robot_kinematics
from lpa_transfer.robots.params import load_robot_params
from ros_harness import run_scenario

SCENARIO = ROOT / "scenarios" / "goal_babbling"
CONDITIONS = ("scratch", "PA/T20", "PA-guarded/T20", "PA-yielding/T20", "LPA/T20",
              "LPA-guarded/T20", "LPA-yielding/T20")

pytestmark = pytest.mark.slow     # scenario runs over the node graph


@pytest.fixture(scope="module")
def smoke_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("goal_babbling") / "run"
    result = run_scenario(SCENARIO, out, "config.yaml", timeout=280, overrides=["smoke.yaml"])
    assert result.returncode == 0, result.stdout + result.stderr
    return out


def test_every_condition_is_evaluated_on_the_learning_clock(smoke_run):
    curves = json.loads((smoke_run / "results.json").read_text())["curves"]
    assert sorted(curves) == sorted(CONDITIONS)
    assert curves["scratch"][0]["times"] == [20.0, 40.0, 60.0]
    for name in CONDITIONS[1:]:
        run = curves[name][0]
        assert run["times"] == [20.0, 40.0, 60.0]     # right after the transfer, then babbling
        assert all(0 <= r <= 1 for r in run["rate"]) and all(e > 0 for e in run["mean_error"])
    # the unguarded learner keeps every transferred sample (the source's 600); the guarded
    # one retires some as the target's own data arrive
    assert curves["LPA/T20"][0]["n_transferred"] == [600] * 3
    guarded = curves["LPA-guarded/T20"][0]["n_transferred"]
    assert guarded[-1] < guarded[0] <= 600
    # the yielding learner keeps them all, as a prior its own samples override
    assert curves["LPA-yielding/T20"][0]["n_transferred"] == [600] * 3
    scratch = curves["scratch"][0]
    assert scratch["mean_error"][-1] < scratch["mean_error"][0]   # babbling learns
    # Transfer helps early (measured at 20 s: mean error scratch 117 mm, PA 55, LPA 93; reaching
    # rate scratch 2.4 %, PA 11.0 %, LPA 4.9 %).
    for name in CONDITIONS[1:]:
        assert curves[name][0]["mean_error"][0] < scratch["mean_error"][0], name
        assert curves[name][0]["rate"][0] > scratch["rate"][0], name
    with open(smoke_run / "learning_curves.csv") as handle:
        assert len(list(csv.DictReader(handle))) == len(CONDITIONS) * 3


def test_guided_exploration_pairs_and_the_bag(smoke_run):
    with np.load(smoke_run / "guided_0.npz") as pairs:
        source, target = pairs["source"], pairs["target"]
    assert source.shape == target.shape == (200, 4)     # 20 s at 10 movements a second
    for rows, side in ((source, "source"), (target, "target")):
        robot = load_robot_params(ROOT / "scenarios" / "robots" / f"goal_babbling_{side}.toml")
        np.testing.assert_allclose(rows[:, 2:], robot_kinematics(robot).forward(rows[:, :2]),
                                   atol=1e-6)
    assert np.abs(source[:, :2] - target[:, :2]).max() <= 1e-3   # true same_command pairs
    topics = summary(smoke_run / "run.mcap")
    assert topics["/correspondences"].message_count == 200
    # 3 evaluations of each of the 7 target runs, and the empty model's before scratch starts
    assert topics["/target/reaching_evaluation"].message_count == 3 * len(CONDITIONS) + 1
    assert topics["/source/reaching_evaluation"].message_count >= 1
    for name in ("report.txt", "fig6_6_7_learning_curves.png", "fig6_5_task_spaces.png"):
        assert (smoke_run / name).stat().st_size > 0, name
    report = (smoke_run / "report.txt").read_text()
    assert "time saved" in report and "against scratch over the seeds" in report
    assert len(list((smoke_run / "models").iterdir())) == 2    # PA and LPA of seed 0


def test_merge_results_joins_shares_and_refuses_a_repeated_seed(smoke_run, tmp_path):
    """merge_results.py rebuilds one run's outputs from its CSV and settings; the same seed
    given twice is refused."""
    import subprocess
    import sys
    script = SCENARIO / "merge_results.py"
    merged = tmp_path / "merged"
    done = subprocess.run([sys.executable, str(script), str(merged), str(smoke_run)],
                          capture_output=True, text=True, cwd=ROOT)
    assert done.returncode == 0, done.stderr
    original = json.loads((smoke_run / "results.json").read_text())
    again = json.loads((merged / "results.json").read_text())
    assert again["settings"] == original["settings"]
    assert again["curves"] == original["curves"]
    assert (merged / "report.txt").read_text().splitlines()[:4] == \
        (smoke_run / "report.txt").read_text().splitlines()[:4]
    twice = subprocess.run([sys.executable, str(script), str(tmp_path / "twice"), str(smoke_run),
                            str(smoke_run)], capture_output=True, text=True, cwd=ROOT)
    assert twice.returncode != 0 and "more than one run" in twice.stderr
