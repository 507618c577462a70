"""correspondence_collector in goal_babbling mode (guided exploration, thesis §6.4.2, Alg. 7)
over real DDS: two robot_sim processes (position mode) with the Table 6.1 arms, lpa_mapping.

The target goal-babbles on its StepRobot service, then the source takes the posture the
target reached in each movement and settles there; the saved pairs must equal the library's
collection with in-process simulators (the lock-step graph is deterministic), each side's x
must be its own forward kinematics of its q̄, both sides' q̄ must agree within the pairing
check's tolerance, the pairs must be published one by one as the source makes them, and bad
parameters must stop the collector with a clear message.
"""
import signal

import numpy as np
import pytest

from conftest import ROOT
from lpa_transfer.robots.kinematics import planar_kinematics
from lpa_transfer.exploration.correspondences import (PairCheck, SettlingStep,
                                                      collect_guided_correspondences)
from lpa_transfer.goal_babbling.goal_babbling import GoalBabbling
from lpa_transfer.transfer.model_store import ModelStore
from lpa_transfer.robots.environment import stepped_environment
from lpa_transfer.robots.params import load_robot_params
from lpa_transfer.robots.simulator import RobotSimulator, robot_urdf
from ros_harness import (NodeProcess, PairListener, ros_params, run_to_end, start_robot_sims,
                         unique_domain_id, wait_until)


ROBOTS = {side: ROOT / "scenarios" / "robots" / f"goal_babbling_{side}.toml"
          for side in ("source", "target")}
HOME = [-0.785398, 1.65]
BOUNDS = ((0.1, -1.1), (1.1, 0.4))
SECONDS, STEPS, SEED = 10.0, 100, 5          # 100 movement steps of 100 physics steps (0.1 s)
N_MOVEMENTS = 100
PAIR = "goal_babbling_source->goal_babbling_target"
FIT = dict(method="lpa", n_min=5, c_min=0.0, random_state=3)


def collector_params(**overrides):
    params = dict(source_robot=ROBOTS["source"], target_robot=ROBOTS["target"],
                  program="goal_babbling", guided_seconds=SECONDS, steps_per_sample=STEPS,
                  seed=SEED, x_low=str(list(BOUNDS[0])), x_high=str(list(BOUNDS[1])),
                  source_home=str(HOME), target_home=str(HOME), wait_timeout=20.0)
    params.update(overrides)
    return ros_params(**params)


def library_pairs():
    """Alg. 7 with two in-process simulators (what the graph must reproduce)."""
    robots = {side: load_robot_params(path) for side, path in ROBOTS.items()}
    sims = {side: RobotSimulator(robot_urdf(robot), initial_positions=HOME)
            for side, robot in robots.items()}
    settling = SettlingStep(sims["source"].step, PairCheck())
    try:
        environments = {side: stepped_environment(planar_kinematics(robots[side], HOME),
                                                  settling if side == "source"
                                                  else sims[side].step, STEPS)
                        for side in sims}
        return collect_guided_correspondences(
            GoalBabbling(BOUNDS, seed=SEED), environments["source"], environments["target"],
            [0, 1], [0, 1], SECONDS, source_settling=settling)
    finally:
        for sim in sims.values():
            sim.close()


def start_sims(domain_id, log_dir):
    return start_robot_sims(domain_id, log_dir, ROBOTS, initial_positions=str(HOME))


@pytest.fixture(scope="module")
def expected():
    return library_pairs()


@pytest.fixture(scope="module")
def guided_run(tmp_path_factory, expected):
    """One guided collection over the graph, fitted by lpa_mapping; what the tests check."""
    n_pairs = len(expected)
    work = tmp_path_factory.mktemp("guided")
    domain_id = unique_domain_id()
    nodes = start_sims(domain_id, work) + [
        NodeProcess("lpa_mapping", domain_id, work, ros_params(model_dir=work / "models"))]
    listener = PairListener(domain_id)
    try:
        collector = NodeProcess("correspondence_collector", domain_id, work, collector_params(
            output=work / "pairs.npz", model_id=PAIR, wait_for_subscribers=2, **FIT))
        code = run_to_end(collector)
        listener.spin_until(lambda: len(listener.samples) >= n_pairs, timeout=10,
                            what=f"all {n_pairs} samples")
        yield dict(work=work, code=code, log=collector.log(), samples=list(listener.samples))
    finally:
        listener.close()
        for node in nodes:
            node.stop()


def test_the_graph_collects_what_the_library_collects(guided_run, expected):
    assert guided_run["code"] == 0, guided_run["log"]
    assert expected.source.shape[1] == 4 and len(expected) >= 0.95 * N_MOVEMENTS
    with np.load(guided_run["work"] / "pairs.npz") as saved:
        assert np.array_equal(saved["source"], expected.source)
        assert np.array_equal(saved["target"], expected.target)
        assert bool(saved["complete"]) and str(saved["pairing_rule"]) == "same_command"
        assert float(saved["sim_time"]) == pytest.approx(SECONDS)
        assert str(saved["meta_program"]) == "goal_babbling" and int(saved["meta_seed"]) == SEED
        assert list(saved["features"]) == ["position", "ee_x", "ee_y"]
        assert float(saved["meta_worst_residual"]) == expected.metadata["worst_residual"]
        assert str(saved["meta_source_follows"]) == "reached"
        np.testing.assert_array_equal(saved["meta_followed"], expected.metadata["followed"])
    checked, dropped = (expected.metadata[key] for key in ("pairs_checked", "pairs_dropped"))
    assert f"pairing check: {checked} pairs checked, {dropped} dropped (residual > 0.001 rad)" \
        in guided_run["log"]


def test_each_side_is_its_own_kinematics_at_the_same_shared_joints(guided_run):
    robots = {side: planar_kinematics(load_robot_params(path)) for side, path in ROBOTS.items()}
    with np.load(guided_run["work"] / "pairs.npz") as saved:
        pairs = {side: saved[side] for side in robots}
    for side, kinematics in robots.items():
        np.testing.assert_allclose(pairs[side][:, 2:], kinematics.forward(pairs[side][:, :2]),
                                   atol=1e-6)
    residual = np.abs(pairs["source"][:, :2] - pairs["target"][:, :2])
    assert residual.max() <= 1e-3                      # true same_command pairs
    assert np.ptp(pairs["target"][:, :2], axis=0).min() > 0.1   # the target explored


def test_pairs_are_published_one_by_one_and_the_model_is_fitted(guided_run, expected):
    samples = guided_run["samples"]
    followed = np.flatnonzero(expected.metadata["followed"])
    assert [msg.index for msg in samples] == followed.tolist()   # the movements' indices
    assert {(msg.source_robot, msg.target_robot) for msg in samples} == {
        ("goal_babbling_source", "goal_babbling_target")}
    stamps = [msg.header.stamp.sec + 1e-9 * msg.header.stamp.nanosec for msg in samples]
    # the source's clock: at least a movement step a pair, more while it settles
    assert np.all(np.diff(stamps) >= 0.1 - 1e-6) and stamps[0] >= 0.1 - 1e-6
    with np.load(guided_run["work"] / "pairs.npz") as saved:
        assert np.array_equal([msg.source for msg in samples], saved["source"])
        assert np.array_equal([msg.target for msg in samples], saved["target"])
    assert ModelStore(guided_run["work"] / "models").get(PAIR).n_correspondences_ \
        == len(expected)


def test_sigint_while_the_target_babbles_saves_an_incomplete_empty_set(tmp_path):
    domain_id = unique_domain_id()
    sims = start_sims(domain_id, tmp_path)
    try:
        collector = NodeProcess("correspondence_collector", domain_id, tmp_path,
                                collector_params(guided_seconds=1e5, output=tmp_path / "p.npz"))
        wait_until(lambda: "goal babbling" in collector.log(), timeout=30,
                   what="collection start")
        assert collector.stop(signal.SIGINT) == 0, collector.log()
    finally:
        for sim in sims:
            sim.stop()
    with np.load(tmp_path / "p.npz") as saved:
        assert not bool(saved["complete"]) and len(saved["source"]) == 0
    assert "collected 0 pairs" in collector.log() and "stopped early" in collector.log()


def test_a_source_lagging_the_commands_ends_the_run_with_one_fatal_line(tmp_path):
    """source_follows:=command: both arms lag the same command their own way, more than 5 %
    of the pairs fail the check, and the collector refuses the set by name instead of fitting
    a mapping on it."""
    domain_id = unique_domain_id()
    sims = start_sims(domain_id, tmp_path)
    try:
        collector = NodeProcess("correspondence_collector", domain_id, tmp_path,
                                collector_params(source_follows="command",
                                                 output=tmp_path / "p.npz"))
        assert run_to_end(collector) == 1
    finally:
        for sim in sims:
            sim.stop()
    log = collector.log()
    assert "goal_babbling_source -> goal_babbling_target: " in log
    assert "same_command pairs are not true correspondences (worst residual 0." in log
    assert "Traceback" not in log and not (tmp_path / "p.npz").exists()


@pytest.mark.parametrize("params, message", [
    (dict(source_follows="commands"), "source_follows"),
    (dict(x_low="[1.1, -1.1]", x_high="[0.1, 0.4]"), "x_low/x_high: x_bounds must be finite"),
    (dict(guided_seconds=-1.0), "guided_seconds must be a finite number >= 0"),
    (dict(pairing_rule="same_time_index"), "pairs the robots by same_command"),
    (dict(x_low="[]"), "needs x_low and x_high"),
    (dict(target_joints="[0, 2]"), "target_joints must hold distinct joint indices"),
])
def test_bad_parameters_are_a_clear_error(tmp_path, params, message):
    collector = NodeProcess("correspondence_collector", unique_domain_id(), tmp_path,
                            collector_params(wait_timeout=1.0, **params))
    assert run_to_end(collector, timeout=30) == 1
    assert message in collector.log()
