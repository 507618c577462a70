"""The 2-link graph scenario (scenarios/two_link_graph/run.sh) end to end, small config."""
import json
import os
import signal
import subprocess
from pathlib import Path

import numpy as np
import pytest

from conftest import ROOT
from lpa_transfer.recording.bag import read_messages, summary
from lpa_transfer.transfer.model_store import ModelStore
from ros_harness import PairListener, run_scenario, unique_domain_id

SCENARIO = ROOT / "scenarios" / "two_link_graph"
MODEL_ID = "two_link_source->two_link_target"
NODE_LOGS = ("recorder", "lpa_mapping", "source_sim", "target_sim", "correspondence_collector",
             "transfer_evaluation")

pytestmark = pytest.mark.slow     # scenario runs over the node graph


def run_smoke(out):
    """The 2-link graph's smoke run: made once a session (test_multi_host.py reads it too)."""
    return run_scenario(SCENARIO, out, timeout=240)


@pytest.fixture(scope="module")
def smoke_run(shared_run):
    return shared_run("two_link_graph_smoke", run_smoke)


def test_scenario_runs_and_stops_every_node_cleanly(smoke_run):
    out, result = smoke_run
    assert result.returncode == 0, result.stdout + result.stderr
    for name in NODE_LOGS:
        assert (out / "logs" / f"{name}.log").stat().st_size > 0, name
    report = (out / "report.txt").read_text()
    assert "faster than real time" in report and "mapping RMSE" in report


def test_bag_holds_the_run(smoke_run):
    out, _ = smoke_run
    topics = summary(out / "run.mcap")
    assert topics["/correspondences"].message_count == 80
    assert topics["/correspondence_batch"].message_count == 1
    # every lock-step advance publishes a state: at least settle + 80 pairs, settle + 100
    # experience; settling by state adds an advance per check (50 steps) on each pair
    states = topics["/source/joint_states"].message_count
    assert 81 + 101 + 80 <= states <= 81 + 101 + 80 * 60, states
    assert sum(1 for _ in read_messages(out / "run.mcap")) == sum(
        info.message_count for info in topics.values())


def test_model_and_transfer_scores(smoke_run):
    out, _ = smoke_run
    with np.load(out / "correspondences.npz") as pairs:
        assert pairs["source"].shape == pairs["target"].shape == (80, 4)
        # same_command at settled poses: both arms at the same joint angles
        assert np.abs(pairs["source"][:, :2] - pairs["target"][:, :2]).max() < 1e-3
    model = ModelStore(out / "models").get(MODEL_ID)
    assert model.n_correspondences_ == 80 and model.n_clusters_ > 1
    evaluation = json.loads((out / "evaluation.json").read_text())
    # PA's mapping error on this pair stays near 27 mm at any N (§3.6); LPA on 80 settled pairs
    # measured 17.5 mm
    assert evaluation["mapping_rmse_m"] < 0.022
    assert evaluation["n_experience"] == 100
    assert all(0 < value < 0.05 for value in evaluation["model_rmse_m"].values())


def test_refuses_to_clear_a_foreign_directory(tmp_path):
    (tmp_path / "precious.txt").write_text("keep me")
    result = subprocess.run(["bash", str(SCENARIO / "run.sh"), "--out", str(tmp_path)],
                            capture_output=True, text=True, timeout=30)
    assert result.returncode == 2 and "not a run directory" in result.stderr
    assert (tmp_path / "precious.txt").read_text() == "keep me"


def _default_sigint():
    """A shell started with SIGINT ignored (e.g. pytest as a background job of a
    non-interactive shell) cannot trap it; give the script the default disposition, as a
    terminal would."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def test_ctrl_c_leaves_a_finalised_bag_and_the_pairs_so_far(tmp_path):
    """SIGINT to the script's process group (what Ctrl-C in a terminal sends) mid-collection."""
    out = tmp_path / "run"
    # this test's listener is a third subscriber of /correspondences: without counting it the
    # collector's wait for 2 (the recorder and lpa_mapping) can end before a slow recorder has
    # subscribed, and the bag misses the first pairs (seen once in CI: 0 recorded of 5 saved)
    listened = tmp_path / "listened.yaml"
    listened.write_text("correspondence_collector:\n  ros__parameters:\n"
                        "    wait_for_subscribers: 3\n")
    env = dict(os.environ, ROS_DOMAIN_ID=str(unique_domain_id()))
    script = subprocess.Popen(["bash", str(SCENARIO / "run.sh"), "--out", str(out),
                               "--override", str(listened)], env=env,
                              stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                              start_new_session=True, preexec_fn=_default_sigint)
    listener = PairListener(int(env["ROS_DOMAIN_ID"]))
    try:   # interrupted once pairs were made, however fast the host
        listener.spin_until(lambda: len(listener.samples) >= 3, timeout=60,
                            what="the first correspondences")
    finally:
        listener.close()
    os.killpg(script.pid, signal.SIGINT)
    _, stderr = script.communicate(timeout=60)
    assert script.returncode == 130, stderr
    topics = summary(out / "run.mcap")            # a finalised file: its summary is readable
    with np.load(out / "correspondences.npz") as pairs:
        assert not bool(pairs["complete"])
        assert 0 < len(pairs["source"]) < 400
        assert topics["/correspondences"].message_count == len(pairs["source"])


def test_a_run_past_its_time_limit_stops_every_node_and_finalises_the_bag(tmp_path):
    """run_scenario's time limit (which the scenario tests rely on) ends the script the way
    its trap handles: no node of the run is left behind, and the bag is readable."""
    out = tmp_path / "run"
    # 20,000 lines x 5 samples x 0.4 s: 40,000 simulated seconds, which no host collects
    # within the limit, so the limit always strikes mid-collection.
    endless = tmp_path / "endless.yaml"
    endless.write_text("correspondence_collector:\n  ros__parameters:\n    n_segments: 20000\n")
    try:
        result = run_scenario(SCENARIO, out, config="config.yaml", timeout=20,
                              overrides=[endless])
    except subprocess.TimeoutExpired as timeout:
        stderr = timeout.stderr
    else:
        pytest.fail(f"the run ended within its 20 s limit (exit {result.returncode}); "
                    f"stderr:\n{result.stderr[-3000:]}")
    assert "interrupted: stopping the nodes" in stderr
    left = [pid for pid in os.listdir("/proc") if pid.isdigit() and _cmdline_holds(pid, out)]
    assert left == []
    summary(out / "run.mcap")          # raises unless the recorder finalised the file


def _cmdline_holds(pid, text):
    try:
        return str(text).encode() in Path(f"/proc/{pid}/cmdline").read_bytes()
    except OSError:          # the process ended meanwhile
        return False


def test_a_users_pair_beyond_the_thesis_gets_true_pairs_and_a_mapping_as_good_as_exact_pairs(
        tmp_path):
    """Settling by state: the user's longer arms (user_pair.yaml) need more than the 400 ms a
    sample that suffice for the thesis' arms. The collector settles by state: the pairs' joint
    angles agree within the check's 1e-3 rad, and the service's LPA maps within 25 % of an LPA
    fitted, with the same hyperparameters, on exact pairs (both arms' kinematics) of the same
    joints."""
    from lpa_transfer.robots.kinematics import (domain_data, end_effector_rmse,
                                                planar_forward_kinematics,
                                                sample_joint_uniform)
    from lpa_transfer.robots.params import load_robot_params
    from lpa_transfer.transfer.local_procrustes import LocalProcrustesAnalysis

    out = tmp_path / "run"
    result = run_scenario(SCENARIO, out, timeout=240, overrides=["user_pair.yaml"])
    assert result.returncode == 0, result.stdout + result.stderr
    with np.load(out / "correspondences.npz") as pairs:
        source_q = pairs["source"][:, :2]
        assert np.abs(source_q - pairs["target"][:, :2]).max() < 1e-3
        assert int(pairs["meta_pairs_checked"]) == 80 and int(pairs["meta_pairs_dropped"]) == 0
        # reported at collection time: LPA's held-out error below PA's
        assert float(pairs["meta_held_out_nmse_lpa"]) < float(pairs["meta_held_out_nmse_pa"])
    assert "pairing check: 80 pairs checked, 0 dropped" in (
        out / "logs" / "correspondence_collector.log").read_text()
    source, target = (load_robot_params(ROOT / "scenarios" / "robots" /
                                        f"user_two_link_{side}.toml")
                      for side in ("source", "target"))
    exact = LocalProcrustesAnalysis(n_min=7, c_min=1e-7, cluster_dims=[0, 1], n_init=1,
                                    random_state=0).fit(
        domain_data(source_q, source.link_lengths), domain_data(source_q, target.link_lengths))
    evaluation = json.loads((out / "evaluation.json").read_text())
    rng = np.random.default_rng(2)           # the evaluation's test points (smoke.yaml)
    sample_joint_uniform(evaluation["n_test"], target.joint_limits, rng)
    source_test_q = sample_joint_uniform(evaluation["n_test"], source.joint_limits, rng)
    exact_rmse = end_effector_rmse(
        exact.transfer(domain_data(source_test_q, source.link_lengths))[:, 2:],
        planar_forward_kinematics(source_test_q, target.link_lengths))
    assert evaluation["mapping_rmse_m"] <= 1.25 * exact_rmse, (evaluation["mapping_rmse_m"],
                                                              exact_rmse)
