"""The 2-link graph over three network namespaces (scenarios/multi_host/run.sh), as if on three
hosts: the same results as on one host, every topic recorded, no route out, and a link that goes
down for 2 s mid-collection ridden out, a crashed mapping host restarted from its model files
(chapter 5 seed shares on two namespaces:
test_inverse_dynamics_variants.py). Skipped, with the script's one-line reason, where
network namespaces cannot be made (not root, no ip netns)."""
import json
import os
import subprocess

import numpy as np
import pytest

from conftest import ROOT
from lpa_transfer.recording.bag import summary
from ros_harness import run_scenario, unique_domain_id

SCRIPT = ROOT / "scenarios" / "multi_host" / "run.sh"
SMOKE = ROOT / "scenarios" / "two_link_graph" / "smoke.yaml"
pytestmark = [pytest.mark.timeout(600), pytest.mark.slow]


def run_multi_host(*args, timeout=400):
    """scenarios/multi_host/run.sh ARGS on a fresh ROS domain: its result once it succeeded;
    a skip with the script's one-line reason where namespaces cannot be made."""
    env = dict(os.environ, ROS_DOMAIN_ID=str(unique_domain_id()))
    result = subprocess.run(["bash", str(SCRIPT), *map(str, args)], env=env,
                            capture_output=True, text=True, timeout=timeout)
    if result.returncode == 77:
        pytest.skip(result.stderr.strip())
    assert result.returncode == 0, result.stdout + result.stderr
    return result


def multi_host(out, *extra):
    return run_multi_host(*extra, "--config", SMOKE, "--out", out)


@pytest.fixture(scope="module")
def one_host(shared_run):
    """The 2-link graph's smoke run on one host, the one test_two_link_graph_scenario.py
    reads (made once a session)."""
    from test_two_link_graph_scenario import run_smoke
    out, result = shared_run("two_link_graph_smoke", run_smoke)
    assert result.returncode == 0, result.stdout + result.stderr
    return out


def same_results(out, reference):
    evaluation = json.loads((out / "evaluation.json").read_text())
    expected = json.loads((reference / "evaluation.json").read_text())
    for key in ("mapping_rmse_m", "model_rmse_m", "n_correspondences", "n_experience"):
        assert evaluation[key] == expected[key], key
    with np.load(out / "correspondences.npz") as pairs, \
            np.load(reference / "correspondences.npz") as expected_pairs:
        for key in ("source", "target"):
            assert np.array_equal(pairs[key], expected_pairs[key])


def test_three_hosts_give_the_one_host_results_and_record_every_topic(tmp_path, one_host):
    out = tmp_path / "run"
    multi_host(out)
    same_results(out, one_host)
    assert sorted(summary(out / "run.mcap")) == sorted(summary(one_host / "run.mcap"))
    topology = (out / "topology.txt").read_text()
    host_routes = topology.split("== root namespace links")[0]
    assert "default" not in host_routes                          # no route out of any host
    assert "10.231.0.1" in host_routes and "10.231.0.3" in host_routes
    root_links = topology.split("== root namespace links")[1].split("== bridge ports")[0]
    assert "lpa" not in root_links                               # nothing of ours out here
    ports = [line for line in topology.split("== bridge ports")[1].splitlines()
             if "master br0" in line]
    assert len(ports) == 3                                       # the traffic crossed the bridge
    prefix = topology.split("== ")[1].split()[0][:-3]            # lpa<pid>
    left = subprocess.run(["ip", "netns", "list"], capture_output=True, text=True).stdout
    assert prefix not in left                                    # removed at the end


def test_a_robots_host_link_down_for_2_s_is_ridden_out(tmp_path, one_host):
    out = tmp_path / "run"
    result = multi_host(out, "--link-down", "rob", "0.2", "2")
    assert "fault: host rob link down for 2 s" in result.stderr
    assert "fault: host rob link up again" in result.stderr
    same_results(out, one_host)



def test_a_killed_mapping_host_is_a_clear_error_and_a_restart_reruns_to_the_same_result(
        tmp_path, one_host):
    """--kill-map: the mapping host crashes once the model is fitted; the evaluation stops
    with one FATAL line naming the service, nothing recorded before is lost, and the service
    restarted on that host serves the model from disk, so the evaluation re-runs to the
    one-host result."""
    out = tmp_path / "run"
    result = multi_host(out, "--kill-map")
    assert "fault: host map's processes killed" in result.stderr
    assert "error: transfer_evaluation failed" in result.stderr
    failed = (out / "logs" / "transfer_evaluation.log").read_text()
    assert "[FATAL]" in failed and "service /lpa_mapping/transfer is not available" in failed
    assert "Traceback" not in failed
    restarted = (out / "logs" / "lpa_mapping_restarted.log").read_text()
    assert "serving 1 models from" in restarted and "two_link_source->two_link_target" \
        in restarted
    evaluation = json.loads((out / "rerun" / "evaluation.json").read_text())
    expected = json.loads((one_host / "evaluation.json").read_text())
    for key in ("mapping_rmse_m", "model_rmse_m", "n_correspondences", "n_experience"):
        assert evaluation[key] == expected[key], key
    recorded, reference = summary(out / "run.mcap"), summary(one_host / "run.mcap")
    for topic in ("/correspondences", "/correspondence_batch"):   # nothing recorded is lost
        assert recorded[topic].message_count == reference[topic].message_count, topic


def test_the_mapping_round_trip_bench_runs_across_hosts(tmp_path):
    """bench/mapping_round_trip.sh under --scenario mapping_round_trip: the client on the
    learners' host discovers lpa_mapping on the mapping host, fits through it and times
    transfers (the README's figures)."""
    result = run_multi_host("--scenario", "mapping_round_trip", "--out", tmp_path / "run",
                            timeout=300)
    assert "discovery: /lpa_mapping/transfer found" in result.stdout
    for n_points in (1, 100, 10000):
        assert f"transfer of {n_points:>5} points: median" in result.stdout


def test_on_host_reads_every_line_of_lpa_hosts_and_matches_patterns():
    """graph.sh's on_host: LPA_HOSTS entries on several lines (as multi_host/run.sh writes
    them) all count, a name may be a shell pattern (the first match wins), no file name is
    expanded, and a node that no entry names stays on this host."""
    graph = (ROOT / "scenarios" / "lib" / "graph.sh").read_text()
    function = graph[graph.index("on_host() {"):]
    function = function[:function.index("\n}\n") + 3]
    script = function + """
set -euo pipefail
LPA_HOSTS="a_sim=R b_sim=R
    lpa_mapping=M
    *_sim=X *=L"
for name in a_sim b_sim lpa_mapping c_sim experiment; do echo "$name:$(on_host "$name")"; done
LPA_HOSTS=""; echo "empty:$(on_host x)"
"""
    result = subprocess.run(["bash", "-c", script], capture_output=True, text=True, timeout=30,
                            cwd=ROOT)                   # ROOT holds files that '*' would match
    assert result.returncode == 0, result.stderr
    hosts = dict(line.split(":", 1) for line in result.stdout.splitlines())
    assert {name: prefix.split(" env")[0] for name, prefix in hosts.items()} == {
        "a_sim": "ip netns exec R", "b_sim": "ip netns exec R",
        "lpa_mapping": "ip netns exec M", "c_sim": "ip netns exec X",
        "experiment": "ip netns exec L", "empty": ""}
