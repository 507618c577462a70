"""The chapter 5 graph scenario (scenarios/inverse_dynamics/run.sh) with the smoke.yaml
override: 1 seed, Star 1 only, 2 trials a condition; every node a real process over DDS (the
experiment step took 290 s beside two other experiments on the 2 cores, hence the timeout).
youBot <-> Pincher (config.yaml), and youBot <-> 2-link arm (5 and 2 joints)."""
import csv
import json
import re

import numpy as np
import pytest

from conftest import ROOT
from rosbags.rosbag2 import Reader
from rosbags.typesys import Stores, get_typestore
from tf_tree import world_poses
from lpa_transfer.recording.bag import decoded_messages, summary
from lpa_transfer.recording.scene import render
from lpa_transfer.robots.params import load_robot_params
from lpa_transfer.robots.serial_chain import forward_kinematics
from ros_harness import run_scenario

SCENARIO = ROOT / "scenarios" / "inverse_dynamics"
# over setup.cfg's 300 s: each run takes minutes
pytestmark = [pytest.mark.timeout(600), pytest.mark.slow]
ROBOTS = ("youbot", "pincher")
CONDITIONS = ("uninitialised", "random", "transfer-PA", "transfer-LPA", "own+transfer-PA",
              "own+transfer-LPA", "transfer-PA-yielding", "transfer-LPA-yielding")


@pytest.fixture(scope="module")
def smoke_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("inverse_dynamics") / "run"
    result = run_scenario(SCENARIO, out, "config.yaml", timeout=480, overrides=["smoke.yaml"])
    assert result.returncode == 0, result.stdout + result.stderr
    return out


#: What `make demo` runs (demo.yaml), at the smoke size and as a share of the conditions.
DEMO_SHAPE = ("experiment:\n  ros__parameters:\n    targets: [youbot]\n"
              "    conditions: [transfer-PA, own+transfer-LPA]\n")


@pytest.fixture(scope="module")
def demo_share(tmp_path_factory):
    """The demo's shape on one host: (run directory, its override file, the run's result)."""
    base = tmp_path_factory.mktemp("demo_share")
    override = base / "demo_like.yaml"
    override.write_text(DEMO_SHAPE)
    out = base / "run"
    result = run_scenario(SCENARIO, out, "config.yaml", timeout=480,
                          overrides=["smoke.yaml", str(override)], extra_args=["--progress"])
    assert result.returncode == 0, result.stdout + result.stderr
    return out, override, result


def test_every_condition_learns_on_both_robots(smoke_run):
    results = json.loads((smoke_run / "results.json").read_text())
    curves = results["curves_m"]
    for robot in ("youbot", "pincher"):
        for condition in CONDITIONS:
            runs = np.asarray(curves[f"{robot}/star1/{condition}"])
            assert runs.shape == (1, 2) and np.isfinite(runs).all() and (runs > 0).all()
        scratch = curves[f"{robot}/star1/uninitialised"][0]
        assert scratch[1] < scratch[0]          # learning online lowers the error
        # LWPR answers 0 where no receptive field is active (config.yaml, as the LWPR package),
        # so data that activate no field on the task leave the PID alone. At this size (3
        # babbling lines, 2 source trials) the PA-mapped experience reaches the task: trial 1
        # measured over the graph, youBot scratch 18.63, transfer-PA 15.90, own+transfer-PA
        # 15.55 mm; Pincher 20.48, 13.68, 12.68 mm (ratios 0.62-0.85)
        for condition in ("transfer-PA", "own+transfer-PA"):
            assert curves[f"{robot}/star1/{condition}"][0][0] < 0.9 * scratch[0], condition
        # the own babbling and LPA's data (n_min 20 on 180 pairs) activate fewer fields there:
        # random 18.57 / 19.52, transfer-LPA 13.79 / 19.91, own+transfer-LPA 13.68 / 18.80 mm
        # (ratios 0.73-1.00); none may start far worse than nothing
        for condition in ("random", "transfer-LPA", "own+transfer-LPA"):
            assert curves[f"{robot}/star1/{condition}"][0][0] < 1.15 * scratch[0], condition
        # a yielding learner starts from the same initial model as the plain transfer: its
        # first trial differs only by the fields its own samples make during it
        for method in ("PA", "LPA"):
            first = curves[f"{robot}/star1/transfer-{method}-yielding"][0][0]
            assert first == pytest.approx(curves[f"{robot}/star1/transfer-{method}"][0][0],
                                          rel=0.1), method
    with open(smoke_run / "learning_curves.csv") as handle:
        assert len(list(csv.DictReader(handle))) == 2 * len(CONDITIONS) * 2
    traces = results["traces"]["youbot/star1"]
    assert [t["trial"] for t in traces] == [1, 2]
    assert np.asarray(traces[0]["actual"]).shape == (840, 3)


def test_outputs_and_bag(smoke_run):
    for name in ("report.txt", "fig5_7_5_8_learning_curves.png", "fig5_6_traces.png",
                 "pairs_0_star1.npz"):
        assert (smoke_run / name).stat().st_size > 0, name
    report = (smoke_run / "report.txt").read_text()
    assert "training time saved" in report and "thesis: 58.7%" in report
    topics = summary(smoke_run / "run.mcap")
    # 8 conditions x 2 trials per robot, each published as a TrialResult
    assert topics["/youbot/trial_result"].message_count == 2 * len(CONDITIONS)
    assert topics["/pincher/trial_result"].message_count == 2 * len(CONDITIONS)
    assert topics["/correspondences"].message_count == 3 * 60
    with np.load(smoke_run / "pairs_0_star1.npz") as pairs:
        assert pairs["source"].shape == (180, 20) and pairs["target"].shape == (180, 16)
        # paired by time index: sample i of both robots at the same simulated time
        assert str(pairs["meta_residual_unit"]) == "s" and float(pairs["meta_worst_residual"]) == 0
        assert int(pairs["meta_pairs_dropped"]) == 0
        source_q = pairs["source"][:, :5]
    # babbled in the vicinity of Star 1: the youBot's box is ±0.15 m around the star's centre;
    # the PID alone tracks the lines, and on config.yaml's minimum-jerk lines (peak speed 1.875
    # times the constant speed's) it overshoots their ends: measured up to 8.4 cm past the box
    # here (constant-speed lines: under 3 cm), so allow 10 cm
    youbot = load_robot_params(ROOT / "scenarios" / "robots" / "youbot_arm.toml")
    centre = forward_kinematics(youbot, np.array([[0.0, 0.0, 1.2, 0.8, 0.0]]))[0]
    offsets = np.abs(forward_kinematics(youbot, source_q) - centre)
    assert offsets[:, :2].max() < 0.25 and offsets[:, :2].max() > 0.05
    models = sorted(p.name for p in (smoke_run / "models").iterdir())
    assert len(models) == 4


def test_the_bag_shows_each_robot_to_an_independent_reader(smoke_run):
    """What a viewer needs: the scenario's bag (the demo's graph) read with rosbags' own Jazzy
    types has each robot's simulated clock, its URDF and, at its last state, a complete
    transform tree from the world to every link of that URDF, whose last link is where
    end_effector says."""
    store = get_typestore(Stores.ROS2_JAZZY)
    wanted = {f"/{robot}/{topic}" for robot in ROBOTS
              for topic in ("clock", "robot_description", "end_effector")} | {"/tf", "/tf_static"}
    messages = {topic: [] for topic in wanted}
    with Reader(smoke_run / "run.mcap") as reader:
        connections = [c for c in reader.connections if c.topic in wanted]
        for connection, _, raw in reader.messages(connections=connections):
            messages[connection.topic].append(store.deserialize_cdr(raw, connection.msgtype))
    static = [t for m in messages["/tf_static"] for t in m.transforms]
    for robot in ROBOTS:
        clock = [m.clock.sec + 1e-9 * m.clock.nanosec for m in messages[f"/{robot}/clock"]]
        assert len(clock) > 1000 and clock == sorted(clock), robot
        description = messages[f"/{robot}/robot_description"][-1].data
        frames = {"world"} | {f"{robot}/{link}"
                              for link in re.findall(r'<link name="([^"]+)"', description)}
        last = [m for m in messages["/tf"] if m.transforms[0].child_frame_id.startswith(robot)][-1]
        world = world_poses([t for t in static if t.child_frame_id.startswith(robot)]
                            + list(last.transforms))
        assert set(world) == frames, robot
        stamp = last.transforms[0].header.stamp
        point = next(m.point for m in reversed(messages[f"/{robot}/end_effector"])
                     if m.header.stamp == stamp)
        tip = world[last.transforms[-1].child_frame_id][:3, 3]
        assert np.allclose(tip, (point.x, point.y, point.z), atol=1e-6), robot
    # the project's own picture of it (lpa_transfer.recording.scene) chains the same poses
    scene = render(smoke_run / "run.mcap", smoke_run / "robots.png")
    assert sorted(scene) == sorted(ROBOTS) and (smoke_run / "robots.png").stat().st_size > 10_000
    for robot in ROBOTS:
        frames = scene[robot]["frames"]
        ours = {f: pose[:3, 3] for f, (_, pose) in frames.items()}
        last = [m for m in messages["/tf"] if m.transforms[0].child_frame_id.startswith(robot)][-1]
        theirs = world_poses([t for t in static if t.child_frame_id.startswith(robot)]
                             + list(last.transforms))
        assert set(ours) == set(theirs)
        assert all(np.allclose(ours[f], theirs[f][:3, 3], atol=1e-12) for f in ours), robot
        assert len(scene[robot]["trail"]) > 100
        assert [m.ns for m in scene[robot]["markers"]] == ["star1/desired", "star1/actual"]


def test_the_task_markers_show_the_star_and_the_last_trial(smoke_run):
    """What a viewer draws: each learner's latched ~/task_markers (visualization_msgs/MarkerArray,
    read with rosbags' Jazzy types) clears its earlier markers and draws the star's desired path
    and the last trial's path, point for point those of its TrialResult (read with the
    project's own decoder)."""
    store = get_typestore(Stores.ROS2_JAZZY)
    trials = {robot: [m for _, _, m in decoded_messages(smoke_run / "run.mcap",
                                                          [f"/{robot}/trial_result"])]
              for robot in ROBOTS}
    with Reader(smoke_run / "run.mcap") as reader:
        for robot in ROBOTS:
            topic = f"/{robot}/star1/task_markers"
            connections = [c for c in reader.connections if c.topic == topic]
            arrays = [store.deserialize_cdr(raw, c.msgtype)
                      for c, _, raw in reader.messages(connections=connections)]
            # one at start (the star alone), one after every trial
            assert len(arrays) == 1 + len(trials[robot]), robot
            assert [(m.action, m.type) for m in arrays[0].markers] == [(3, 0), (0, 4)]  # clear, star
            last = arrays[-1].markers
            assert [(m.action, m.type, m.ns) for m in last[1:]] == [
                (0, 4, "star1/desired"), (0, 4, "star1/actual")]
            assert last[0].action == 3 and all(m.header.frame_id == "world" for m in last)
            trial = trials[robot][-1]
            for marker, matrix in zip(last[1:], (trial.desired, trial.actual)):
                expected = np.reshape(matrix.data, (matrix.rows, matrix.cols))
                drawn = np.array([(p.x, p.y, p.z) for p in marker.points])
                assert np.array_equal(drawn, expected), (robot, marker.ns)


def test_a_share_in_the_demos_shape_repeats_the_full_runs_curves(smoke_run, demo_share):
    """What `make demo` runs (demo.yaml), at the smoke size and as a share of the conditions
    (reference results are joined from shares): only the youBot is a target (the Pincher
    learns from scratch to have experience to give), progress and the summary table reach the
    terminal. own+transfer-LPA runs right after transfer-PA instead of after three other
    conditions on the same learner and simulator nodes, and every curve repeats the full smoke
    run's to a relative 1e-6, merge_results' check (measured: the 16th digit differed)."""
    out, _, result = demo_share
    shown = result.stdout + result.stderr
    assert "seed 0 youbot star1 transfer-PA: trial 2/2 tracking error" in shown
    assert "seed 0 pincher star1 from scratch: trial 1/2" in shown
    assert "converged at trial" in shown and f"figure  {out}/fig5_7_5_8" in shown
    curves = json.loads((out / "results.json").read_text())["curves_m"]
    assert sorted(curves) == ["youbot/star1/own+transfer-LPA", "youbot/star1/transfer-PA",
                              "youbot/star1/uninitialised"]
    full = json.loads((smoke_run / "results.json").read_text())["curves_m"]
    for key, runs in curves.items():    # merge_results' check (it joins shares of one target set)
        assert np.allclose(runs, full[key], rtol=1e-6, atol=0), key
    assert sorted(p.name for p in (out / "models").iterdir()) == \
        sorted(p.name for p in (smoke_run / "models").iterdir() if "pincher-" in p.name)
    report = (out / "report.txt").read_text()
    assert "pincher as target" not in report and "youbot as target" in report


def test_the_graph_over_three_network_hosts_gives_the_same_curves(demo_share, tmp_path):
    """Across hosts: scenarios/multi_host/run.sh --scenario inverse_dynamics puts the robot_sims,
    lpa_mapping and the rest on three network namespaces (DDS over UDP on their bridge); the
    lock-step curves of the demo's shape equal the one-host run's bit for bit and the bag
    holds the same topics. Skipped, with the script's one-line reason, where namespaces
    cannot be made."""
    from test_multi_host import run_multi_host
    one_host, override, _ = demo_share
    out = tmp_path / "run"
    run_multi_host("--scenario", "inverse_dynamics", "--override", SCENARIO / "smoke.yaml",
                   "--override", override, "--out", out, timeout=480)
    assert (out / "learning_curves.csv").read_bytes() \
        == (one_host / "learning_curves.csv").read_bytes()
    assert sorted(summary(out / "run.mcap")) == sorted(summary(one_host / "run.mcap"))
