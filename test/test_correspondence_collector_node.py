"""correspondence_collector over real DDS: two robot_sim processes, lpa_mapping and a recorder.

The collector's pairs must equal the library's own collection with in-process simulators (the
lock-step graph is deterministic), reach the mapping service as a fitted model, be published
one by one, and survive a recording: the player's replay of the bag, with no simulator
running, reproduces the same correspondence set and refits the same model.
"""
import dataclasses
import signal

import numpy as np
import pytest

from conftest import ROOT
from lpa_transfer.exploration.babbling import BabblingProgram
from lpa_transfer.robots.kinematics import planar_kinematics
from lpa_transfer.robots.control import PID, start_servo
from lpa_transfer.exploration.correspondences import collect_correspondences
from lpa_transfer.transfer.model_store import ModelStore
from lpa_transfer.robots.params import load_robot_params
from lpa_transfer.robots.simulator import RobotSimulator, robot_urdf
from ros_harness import (NodeProcess, PairListener, ros_params, run_to_end, start_robot_sims,
                         unique_domain_id)

from lpa_transfer_interfaces.srv import FitModel, ListModels

ROBOTS = {side: ROOT / "scenarios" / "robots" / f"two_link_{side}.toml"
          for side in ("source", "target")}
PAIR = "two_link_source->two_link_target"
PROGRAM = dict(program="joint_lines", n_segments=6, samples_per_segment=3, seed=7)
STEPS = 200
FIT = dict(method="lpa", n_min=5, c_min=0.0, random_state=3)


def collector_params(**overrides):
    params = dict(source_robot=ROBOTS["source"], target_robot=ROBOTS["target"],
                  steps_per_sample=STEPS, wait_timeout=20.0, **PROGRAM, **FIT)
    params.update(overrides)
    return ros_params(**params)


def library_pairs():
    """The same collection with two in-process simulators (what the graph must reproduce)."""
    robots = {side: load_robot_params(path) for side, path in ROBOTS.items()}
    sims = {side: RobotSimulator(robot_urdf(robot)) for side, robot in robots.items()}
    try:
        return collect_correspondences(
            BabblingProgram(**PROGRAM), "same_command", planar_kinematics(robots["source"]),
            planar_kinematics(robots["target"]), sims["source"].step, sims["target"].step, STEPS)
    finally:
        for sim in sims.values():
            sim.close()


def start_sims(domain_id, log_dir):
    return start_robot_sims(domain_id, log_dir, ROBOTS)


@pytest.fixture(scope="module")
def graph_run(tmp_path_factory):
    """One collection over the graph, recorded; yields what the tests check."""
    work = tmp_path_factory.mktemp("collector")
    domain_id = unique_domain_id()
    nodes = start_sims(domain_id, work) + [
        NodeProcess("lpa_mapping", domain_id, work, ros_params(model_dir=work / "models")),
        NodeProcess("recorder", domain_id, work,
                    ros_params(output=work / "run.mcap", topics="[/correspondences]",
                               discovery_period=0.1))]
    listener = PairListener(domain_id)
    try:
        collector = NodeProcess("correspondence_collector", domain_id, work, collector_params(
            output=work / "pairs.npz", model_id=PAIR, wait_for_subscribers=3))
        code = run_to_end(collector)
        listener.spin_until(lambda: len(listener.samples) >= 18, timeout=10,
                            what="all 18 samples")
        client = listener.node.create_client(ListModels, "/lpa_mapping/list")
        models = listener.call(client, ListModels.Request()).model_ids
        samples = listener.matrices()
    finally:
        listener.close()
        # Stopped here, not by a test: the recorder finalises the bag the replay test reads.
        stop_codes = {node.log_path.stem: node.stop() for node in nodes}
    yield dict(work=work, code=code, log=collector.log(), samples=samples, models=list(models),
               nodes=nodes, stop_codes=stop_codes)


def test_the_graph_collects_what_the_library_collects(graph_run):
    assert graph_run["code"] == 0, graph_run["log"]
    expected = library_pairs()
    with np.load(graph_run["work"] / "pairs.npz") as saved:
        assert np.array_equal(saved["source"], expected.source)
        assert np.array_equal(saved["target"], expected.target)
        assert bool(saved["complete"]) and str(saved["pairing_rule"]) == "same_command"
        # settled by state: at least 400 steps a sample, the same clock as the library's
        assert float(saved["sim_time"]) == expected.sim_time >= 18 * STEPS * 1e-3
        assert int(saved["meta_pairs_checked"]) == 18 and int(saved["meta_pairs_dropped"]) == 0
        assert float(saved["meta_worst_residual"]) < 1e-3
    assert expected.source.shape == (18, 4)


def test_every_pair_is_published_and_the_model_is_fitted(graph_run):
    source, target = graph_run["samples"]
    with np.load(graph_run["work"] / "pairs.npz") as saved:
        assert np.array_equal(source, saved["source"]) and np.array_equal(target,
                                                                           saved["target"])
    assert PAIR in graph_run["models"]
    model = ModelStore(graph_run["work"] / "models").get(PAIR)
    assert model.n_correspondences_ == 18


def test_every_node_of_the_graph_stops_cleanly(graph_run):
    for node in graph_run["nodes"]:
        assert graph_run["stop_codes"][node.log_path.stem] == 0, node.log()


def test_replayed_bag_reproduces_the_set_and_refits_without_simulators(graph_run, tmp_path):
    domain_id = unique_domain_id()           # a fresh graph: no simulator, no collector
    mapping = NodeProcess("lpa_mapping", domain_id, tmp_path,
                          ros_params(model_dir=tmp_path / "models"))
    listener = PairListener(domain_id)
    try:
        listener.spin_for(1.0)
        player = NodeProcess("player", domain_id, tmp_path, ros_params(
            input=graph_run["work"] / "run.mcap", rate=0.0, wait_for_subscribers=2,
            wait_timeout=20.0))
        assert run_to_end(player) == 0, player.log()
        listener.spin_until(lambda: len(listener.samples) >= 18, timeout=10,
                            what="the replayed samples")
        replayed = listener.matrices()
        with np.load(graph_run["work"] / "pairs.npz") as saved:
            assert np.array_equal(replayed[0], saved["source"])
            assert np.array_equal(replayed[1], saved["target"])
        fit = listener.node.create_client(FitModel, "/lpa_mapping/fit")
        answer = listener.call(fit, FitModel.Request(model_id="refit", received_pair=PAIR,
                                                     **FIT))
        assert answer.success, answer.message + mapping.log()
        assert answer.n_points == 18
    finally:
        listener.close()
        mapping.stop()
    refit = ModelStore(tmp_path / "models").get("refit")
    original = ModelStore(graph_run["work"] / "models").get(PAIR)
    probe = replayed[0]
    assert np.array_equal(refit.transfer(probe), original.transfer(probe))


def test_sigint_saves_the_pairs_made_so_far(tmp_path):
    domain_id = unique_domain_id()
    sims = start_sims(domain_id, tmp_path)
    listener = PairListener(domain_id)
    try:
        collector = NodeProcess("correspondence_collector", domain_id, tmp_path,
                                collector_params(n_segments=2000, output=tmp_path / "p.npz"))
        # interrupted once pairs were made, however fast the host
        listener.spin_until(lambda: len(listener.samples) >= 2, timeout=60,
                            what="the first pairs")
        assert collector.stop(signal.SIGINT) == 0, collector.log()
    finally:
        listener.close()
        for sim in sims:
            sim.stop()
    with np.load(tmp_path / "p.npz") as saved:
        assert not bool(saved["complete"])
        assert 0 < len(saved["source"]) < 2000 * 3
        assert len(saved["source"]) == len(saved["target"])
    assert "stopped early" in collector.log()


def test_missing_robot_service_is_a_clear_error(tmp_path):
    collector = NodeProcess("correspondence_collector", unique_domain_id(), tmp_path,
                            collector_params(wait_timeout=1.0))
    assert run_to_end(collector, timeout=30) == 1
    assert "/source/robot_sim/step is not available after 1 s" in collector.log()


@pytest.mark.parametrize("params, message", [
    (dict(pairing_rule="same_colour"), "pairing_rule must be one of"),
    (dict(source_task_halfwidth="[0.1, 0.1]", source_task_low="[0.0, 0.0]",
          source_task_high="[0.1, 0.1]"), "give source_task_halfwidth or source_task_low/high"),
    (dict(target_task_halfwidth="[0.1, -0.1]"), "half-width needs 2 finite values >= 0"),
])
def test_bad_parameters_are_a_clear_error(tmp_path, params, message):
    collector = NodeProcess("correspondence_collector", unique_domain_id(), tmp_path,
                            collector_params(wait_timeout=1.0, **params))
    assert run_to_end(collector, timeout=30) == 1
    assert message in collector.log()


def test_torque_mode_pid_tracking_of_task_lines_equals_the_library(tmp_path):
    """§5.4.1's collection: both robots track the same task-space lines (each in its own box)
    with PID torque control; samples (q, q̇, q̈, τ) paired by time index."""
    boxes = {"source": ((0.2, 0.2), (0.4, 0.4)), "target": ((0.4, 0.3), (0.7, 0.5))}
    gains = [40.0, 10.0, 2.0]
    program = BabblingProgram("task_lines", 3, 20, seed=5)
    features = ["position", "velocity", "acceleration", "effort"]
    domain_id = unique_domain_id()
    sims = start_robot_sims(domain_id, tmp_path, ROBOTS, control_mode="torque")
    try:
        params = dict(source_robot=ROBOTS["source"], target_robot=ROBOTS["target"],
                      pairing_rule="same_time_index", program="task_lines", n_segments=3,
                      samples_per_segment=20, seed=5, steps_per_sample=1, wait_timeout=20.0,
                      features="[" + ",".join(features) + "]", output=tmp_path / "id.npz",
                      source_pid=str(gains), target_pid=str(gains))
        for side, (low, high) in boxes.items():
            params[f"{side}_task_low"], params[f"{side}_task_high"] = str(list(low)), str(list(high))
        collector = NodeProcess("correspondence_collector", domain_id, tmp_path,
                                ros_params(**params))
        assert run_to_end(collector) == 0, collector.log()
    finally:
        for sim in sims:
            sim.stop()
    robots = {side: load_robot_params(path) for side, path in ROBOTS.items()}
    kinematics, steps = {}, {}
    for side, robot in robots.items():
        kinematics[side] = dataclasses.replace(planar_kinematics(robot), task_box=boxes[side])
        simulator = RobotSimulator(robot_urdf(robot), control_mode="torque")
        steps[side] = start_servo(simulator.step, robot.n_joints, PID(*gains)).step
    expected = collect_correspondences(program, "same_time_index", kinematics["source"],
                                       kinematics["target"], steps["source"], steps["target"],
                                       1, features)
    with np.load(tmp_path / "id.npz") as saved:
        assert saved["source"].shape == (60, 8)
        assert np.array_equal(saved["source"], expected.source)
        assert np.array_equal(saved["target"], expected.target)
        efforts = saved["target"][:, 6:]
    assert np.abs(efforts).max() > 0.1            # the PID torques are what was recorded


def robot_file(name):
    return ROOT / "scenarios" / "robots" / f"{name}.toml"


def collect_over_graph(tmp_path, robots, **params):
    """A collector run (no mapping service) on its own graph of ``robots``; (exit code, log,
    saved file path)."""
    domain_id = unique_domain_id()
    sims = start_robot_sims(domain_id, tmp_path, robots)
    try:
        collector = NodeProcess("correspondence_collector", domain_id, tmp_path, ros_params(
            source_robot=robots["source"], target_robot=robots["target"], steps_per_sample=400,
            output=tmp_path / "pairs.npz", wait_timeout=20.0, program="joint_lines",
            n_segments=10, samples_per_segment=2, seed=0, **params))
        code = run_to_end(collector, timeout=120)
    finally:
        for sim in sims:
            sim.stop()
    return code, collector.log(), tmp_path / "pairs.npz"


def test_commands_that_cannot_settle_in_time_end_in_one_fatal_line(tmp_path):
    """The user's longer arms given at most 400 ms a command: not true pairs, so no file and
    no model, and an error naming the robots, the rule and the residual."""
    robots = {side: robot_file(f"user_two_link_{side}") for side in ("source", "target")}
    code, log, saved = collect_over_graph(tmp_path, robots, max_settle_steps=400)
    assert code != 0 and not saved.exists()
    fatal = [line for line in log.splitlines() if "FATAL" in line]
    assert len(fatal) == 1 and "Traceback" not in log, log
    assert "user_two_link_source -> user_two_link_target" in fatal[0]
    assert "same_command pairs are not true correspondences" in fatal[0]
    assert "worst residual" in fatal[0] and "did not settle" in fatal[0]


def test_different_joint_counts_pair_on_the_shared_joints_over_the_graph(tmp_path):
    """2-link source -> 3-joint target: the common joints agree in every pair."""
    robots = {"source": robot_file("two_link_source"), "target": robot_file("three_dof_arm")}
    code, log, saved = collect_over_graph(tmp_path, robots)
    assert code == 0, log
    with np.load(saved) as pairs:
        assert pairs["source"].shape == (20, 4) and pairs["target"].shape == (20, 5)
        assert np.abs(pairs["source"][:, :2] - pairs["target"][:, :2]).max() < 1e-3
        assert int(pairs["meta_pairs_dropped"]) == 0
    assert "pairing check: 20 pairs checked, 0 dropped" in log
