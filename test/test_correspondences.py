"""lpa_transfer.exploration.correspondences: pairing two robots' babbling samples, and correspondence files.

The collections drive real pybullet simulators of the §3.6 robots
(scenarios/robots/two_link_{source,target}.toml)."""
import os
import types

import numpy as np
import pytest

from lpa_transfer.robots import inverse_kinematics
from lpa_transfer.exploration.babbling import BabblingProgram
from lpa_transfer.robots.kinematics import Kinematics, planar_kinematics
from lpa_transfer.exploration.correspondences import (DEFAULT_FEATURES, FEATURES,
                                                      CorrespondenceSet, PairCheck, PairingError,
                                                      SettlingStep,
                                                      check_guided_exploration,
                                                      collect_correspondences,
                                                      collect_guided_correspondences,
                                                      feature_names, feature_vector,
                                                      load_correspondences,
                                                      load_guided_exploration, planned_commands,
                                                      run_commands)
from lpa_transfer.robots.kinematics import domain_data, end_effector_rmse
from lpa_transfer.transfer.local_procrustes import LocalProcrustesAnalysis
from lpa_transfer.transfer.procrustes import ProcrustesAnalysis
from lpa_transfer.goal_babbling.goal_babbling import GoalBabbling
from lpa_transfer.robots.kinematics import planar_forward_kinematics
from lpa_transfer.robots.environment import stepped_environment
from lpa_transfer.robots.simulator import RobotSimulator, robot_urdf
from two_link import elbow_ik, robot

SOURCE = planar_kinematics(robot("two_link_source"))
TARGET = planar_kinematics(robot("two_link_target"))
#: slow enough that both arms settle at every command (400 physics steps of 1 ms a sample)
SLOW = BabblingProgram("joint_lines", 10, 5, seed=0)
STEPS = 400
DT = 1e-3   # the simulators' physics step
SMALL = BabblingProgram("joint_lines", 3, 2, seed=1)   # fast, for layout and control flow


class Recorder:
    """A simulator's ``step`` that records the commands it got and the states it returned."""

    def __init__(self, sim):
        self.sim, self.commands, self.states, self.n_steps = sim, [], [], []

    def __call__(self, command, n_steps):
        self.commands.append(np.array(command, dtype=float))
        self.n_steps.append(n_steps)
        self.states.append(self.sim.step(command, n_steps))
        return self.states[-1]


@pytest.fixture
def arms():
    """arms() -> (source step, target step): recorders of fresh simulators of the two robots."""
    sims = []

    def arms(target="two_link_target"):
        sims.extend([RobotSimulator(robot_urdf(robot("two_link_source"))),
                     RobotSimulator(robot_urdf(robot(target)))])
        return Recorder(sims[-2]), Recorder(sims[-1])

    yield arms
    for sim in sims:
        sim.close()


#: a sample exactly ``steps_per_sample`` steps after its command, no settling and no check:
#: the tests of layout and control flow count steps on short programs; settling and the
#: checks have their own tests below
FIXED = PairCheck(max_settle_steps=0, tolerance=np.inf, time_tolerance=np.inf)


def collect(arms, program, pairing_rule, steps=STEPS, **kwargs):
    source_step, target_step = arms()
    kwargs.setdefault("pair_check", FIXED)
    pairs = collect_correspondences(program, pairing_rule, SOURCE, TARGET, source_step,
                                    target_step, steps, **kwargs)
    return pairs, source_step, target_step


def positions(recorder):
    """Joint angles after each recorded command, without the settling sample at home."""
    return np.array([state.positions for state in recorder.states[1:]])


# -- features ---------------------------------------------------------------------------------
def test_feature_vector_and_names_follow_the_requested_order():
    previous = types.SimpleNamespace(time=1.0, velocities=np.array([1.0, -1.0]))
    state = types.SimpleNamespace(time=1.5, positions=np.array([0.1, 0.2]),
                                  velocities=np.array([2.0, 1.0]), efforts=np.array([3.0, 4.0]),
                                  end_effector=np.array([0.5, 0.6, 0.7]))
    features = ("ee_z", "acceleration", "position", "effort", "velocity", "ee_x", "ee_y")
    vector = feature_vector(state, previous, features)
    assert vector.dtype == np.float64
    np.testing.assert_allclose(vector, [0.7, 2.0, 4.0, 0.1, 0.2, 3.0, 4.0, 2.0, 1.0, 0.5, 0.6])
    assert feature_names(features, ["j1", "j2"]) == [
        "ee_z", "acceleration/j1", "acceleration/j2", "position/j1", "position/j2",
        "effort/j1", "effort/j2", "velocity/j1", "velocity/j2", "ee_x", "ee_y"]
    assert feature_names(DEFAULT_FEATURES, ["joint1", "joint2"]) == [
        "position/joint1", "position/joint2", "ee_x", "ee_y"]
    assert set(FEATURES) == set(features)


def test_acceleration_does_not_depend_on_how_long_the_clock_has_run():
    """A simulator's clock is steps x physics_step; the difference of two such readings
    carries rounding that grows with the time run (10 steps of 1 ms after 57,600 steps
    differ from 0.01 in the 15th digit), which LWPR magnified into other curves for the same
    seed (measured on the youBot). The acceleration uses the difference rounded to 1 ns."""
    accelerations = set()
    for steps in (0, 14400, 57600, 1000003):
        previous = types.SimpleNamespace(time=steps * 0.001, velocities=np.array([0.3]))
        state = types.SimpleNamespace(time=(steps + 10) * 0.001, velocities=np.array([0.7]))
        accelerations.add(float(feature_vector(state, previous, ("acceleration",))[0]))
    assert accelerations == {(0.7 - 0.3) / 0.01}
    raw = {(0.7 - 0.3) / ((s + 10) * 0.001 - s * 0.001) for s in (0, 14400, 57600, 1000003)}
    assert len(raw) > 1        # without the rounding the four would not agree


def test_default_layout_and_same_command_pairs_equal_joint_angles(arms):
    """§3.6: both 2-link arms at the same joint angles; z = (q, x) = 4 columns."""
    pairs, source, target = collect(arms, SLOW, "same_command")
    assert pairs.source.shape == pairs.target.shape == (50, 4) and len(pairs) == 50
    assert pairs.features == DEFAULT_FEATURES and pairs.pairing_rule == "same_command"
    assert pairs.complete and pairs.source_robot == pairs.target_robot == ""
    assert pairs.sim_time == pytest.approx(50 * STEPS * DT)
    # The samples are the states after each command (the first step settles at home).
    for recorder, samples in ((source, pairs.source), (target, pairs.target)):
        assert len(recorder.commands) == 51
        np.testing.assert_array_equal(recorder.commands[0], [0.0, 0.0])
        np.testing.assert_array_equal(samples[:, :2], positions(recorder))
        np.testing.assert_array_equal(samples[:, 2:],
                                      [state.end_effector[:2] for state in recorder.states[1:]])
    # Same commands on both robots, inside both robots' limits: equal angles.
    np.testing.assert_array_equal(source.commands, target.commands)
    commands = np.array(source.commands[1:])
    np.testing.assert_array_equal(commands, SLOW.commands(SOURCE))   # limits are shared here
    assert ((commands >= 0) & (commands <= [np.pi / 2, np.pi])).all()
    np.testing.assert_allclose(pairs.source[:, :2], pairs.target[:, :2], atol=1e-3)
    np.testing.assert_allclose(pairs.source[:, :2], commands, atol=1e-3)   # settled
    # The end effectors are each robot's forward kinematics of its angles.
    np.testing.assert_allclose(pairs.source[:, 2:], SOURCE.forward(pairs.source[:, :2]),
                               atol=1e-6)
    np.testing.assert_allclose(pairs.target[:, 2:], TARGET.forward(pairs.target[:, :2]),
                               atol=1e-6)
    assert np.abs(pairs.source[:, 2:] - pairs.target[:, 2:]).max() > 0.1   # different arms


def test_all_features_match_the_simulator_states(arms):
    features = ("position", "velocity", "acceleration", "effort", "ee_x", "ee_y", "ee_z")
    steps = 60   # short samples: the arms are still moving
    pairs, source, target = collect(arms, SMALL, "same_command", steps, features=features)
    assert pairs.source.shape == pairs.target.shape == (6, 11)
    assert pairs.features == features
    for recorder, samples in ((source, pairs.source), (target, pairs.target)):
        states = recorder.states
        velocities = np.array([state.velocities for state in states])
        np.testing.assert_array_equal(samples[:, 0:2], [s.positions for s in states[1:]])
        np.testing.assert_array_equal(samples[:, 2:4], velocities[1:])
        # acceleration: backward difference of the velocities over the sample period
        np.testing.assert_allclose(samples[:, 4:6], np.diff(velocities, axis=0) / (steps * DT),
                                   rtol=1e-9, atol=1e-9)
        assert np.abs(samples[:, 4:6]).max() > 1.0
        np.testing.assert_array_equal(samples[:, 6:8], [s.efforts for s in states[1:]])
        assert np.abs(samples[:, 6:8]).max() > 0.1
        np.testing.assert_array_equal(samples[:, 8:11], [s.end_effector for s in states[1:]])
        np.testing.assert_allclose(samples[:, 10], 0.0, atol=1e-9)   # planar arms: z = 0


@pytest.mark.parametrize("kwargs, message", [
    (dict(features=("position", "torque")), "features must be distinct names"),
    (dict(features=("position", "position")), "features must be distinct names"),
    (dict(features=()), "features must be distinct names"),
    (dict(steps=0), "steps_per_sample must be an integer >= 1"),
    (dict(pairing_rule="same_angle"), "pairing_rule must be one of"),
    (dict(pairing_rule="same_task_point", task_offset=[0.1, 0.2, 0.3]),
     r"task_offset needs 2 finite values, got \[0.1, 0.2, 0.3\]"),
    (dict(pairing_rule="same_task_point", task_offset=[0.1, np.nan]),
     "task_offset needs 2 finite values"),
])
def test_bad_arguments_raise_before_any_step(kwargs, message):
    source, target = Recorder(None), Recorder(None)   # any step would fail on None
    kwargs = {"pairing_rule": "same_command", "steps": 10, **kwargs}
    with pytest.raises(ValueError, match=message):
        collect_correspondences(SMALL, kwargs.pop("pairing_rule"), SOURCE, TARGET, source,
                                target, kwargs.pop("steps"), **kwargs)
    assert source.commands == target.commands == []


# -- planned commands (pure) ------------------------------------------------------------------
ARM_2 = Kinematics(np.array([(0.0, np.pi / 2), (0.0, np.pi)]), np.zeros(2),
                   lambda q: np.asarray(q)[:, :2])
ARM_3 = Kinematics(np.array([(-0.5, 1.0), (0.5, 2.0), (-1.0, 1.0)]), np.array([0.2, 1.0, 0.3]),
                   lambda q: np.asarray(q)[:, :2])


def test_same_command_draws_joint_lines_in_the_shared_limits():
    program = BabblingProgram("joint_lines", 20, 3, seed=4)
    shared = np.array([(0.0, 1.0), (0.5, 2.0)])
    for source, target in ((ARM_2, ARM_3), (ARM_3, ARM_2)):
        source_commands, target_commands = planned_commands(program, "same_command", source,
                                                            target)
        assert source_commands.shape == (60, source.n_joints)
        assert target_commands.shape == (60, target.n_joints)
        common = source_commands[:, :2]
        assert ((common >= shared[:, 0]) & (common <= shared[:, 1])).all()
        np.testing.assert_array_equal(target_commands[:, :2], common)
        # The waypoints fill the shared box (scaled unit waypoints, joint j from (seed, j)).
        np.testing.assert_allclose(common[2::3], shared[:, 0] + program.unit_waypoints(2)
                                   * (shared[:, 1] - shared[:, 0]))
        extra = ARM_3.home[2]   # the 3-joint arm's third joint stays at home
        np.testing.assert_array_equal((source_commands if source is ARM_3 else
                                       target_commands)[:, 2], extra)
    # The first line starts at the source's home clipped into the shared limits: (0, 0.5).
    source_commands, _ = planned_commands(program, "same_command", ARM_2, ARM_3)
    waypoint = shared[:, 0] + program.unit_waypoints(2)[0] * (shared[:, 1] - shared[:, 0])
    np.testing.assert_allclose(source_commands[0], [0, 0.5] + (waypoint - [0, 0.5]) / 3)


def test_planned_commands_of_the_other_rules():
    program = BabblingProgram("joint_lines", 5, 2, seed=0)
    # same_time_index: each robot draws the seeded lines in its own limits, from its own home
    # (linear law, 2 samples a line: the midpoint, then the waypoint).
    source_commands, target_commands = planned_commands(program, "same_time_index", ARM_2, ARM_3)
    for arm, commands in ((ARM_2, source_commands), (ARM_3, target_commands)):
        low, high = arm.joint_limits.T
        waypoints = low + program.unit_waypoints(arm.n_joints) * (high - low)
        np.testing.assert_allclose(commands[1::2], waypoints)
        np.testing.assert_allclose(commands[0], (arm.home + waypoints[0]) / 2)
        np.testing.assert_allclose(commands[2::2], (waypoints[:-1] + waypoints[1:]) / 2)
    # same_task_point: the source's side is the same; the target's is decided on the robots.
    same_point_source, target_commands = planned_commands(program, "same_task_point", ARM_2,
                                                          ARM_3)
    np.testing.assert_array_equal(same_point_source, source_commands)
    assert target_commands is None
    # Task lines with same_command: the source's IK commands put its hand on every task point
    # it can reach; on the others (beyond its 0.55 m reach) a joint stops at its limit. The
    # target executes the same commands.
    lines = BabblingProgram("task_lines", 4, 3, seed=0, task_low=(0.3, 0.3), task_high=(0.5, 0.5))
    source_commands, target_commands = planned_commands(lines, "same_command", SOURCE, TARGET)
    points = lines.task_points(SOURCE.forward(SOURCE.home[None])[0])
    miss = np.linalg.norm(SOURCE.forward(source_commands) - points, axis=1)
    at_limit = np.isclose(source_commands, SOURCE.joint_limits[:, 0], atol=1e-5).any(axis=1)
    assert (miss < 1e-6).sum() == 4 and ((miss < 1e-6) | at_limit).all()
    assert miss.max() < 0.04
    np.testing.assert_array_equal(target_commands, source_commands)
    with pytest.raises(ValueError, match="pairing_rule must be one of"):
        planned_commands(program, "nearest", ARM_2, ARM_3)
    apart = Kinematics(np.array([(2.0, 3.0), (0.0, 1.0)]), np.array([2.0, 0.0]), ARM_2.forward)
    with pytest.raises(ValueError, match="ranges do not overlap"):
        planned_commands(program, "same_command", ARM_2, apart)


# -- the pairing rules on the simulators ------------------------------------------------------
def test_same_time_index_runs_each_robots_own_program(arms):
    """Task lines through each robot's own IK: sample i pairs with sample i, and at the ends
    of the lines (the shared waypoints) both hands are at the same point where reachable."""
    program = BabblingProgram("task_lines", 6, 4, seed=3, task_low=(0.3, 0.3),
                              task_high=(0.38, 0.38))
    pairs, source, target = collect(arms, program, "same_time_index")
    np.testing.assert_array_equal(source.commands[1:], program.commands(SOURCE))
    np.testing.assert_array_equal(target.commands[1:], program.commands(TARGET))
    assert not np.allclose(program.commands(SOURCE), program.commands(TARGET), atol=0.1)
    waypoints = program.task_waypoints()
    _, source_ok = elbow_ik(waypoints, robot("two_link_source").link_lengths)
    _, target_ok = elbow_ik(waypoints, robot("two_link_target").link_lengths)
    both = source_ok & target_ok
    assert both.sum() >= 4
    np.testing.assert_allclose(pairs.source[3::4, 2:][both], waypoints[both], atol=1e-4)
    np.testing.assert_allclose(pairs.target[3::4, 2:][both], waypoints[both], atol=1e-4)


def test_same_time_index_with_joint_lines_scales_to_each_robots_limits(arms):
    pairs, source, target = collect(arms, SMALL, "same_time_index", 10)
    np.testing.assert_array_equal(source.commands[1:], SMALL.commands(SOURCE))
    np.testing.assert_array_equal(target.commands[1:], SMALL.commands(TARGET))
    assert pairs.source.shape == pairs.target.shape == (6, 4)


def test_same_task_point_sends_the_target_to_the_sources_point(arms):
    """The target reaches the source's hand + task_offset where it can; elsewhere the gap is
    the IK residual (the nearest point its inverse kinematics finds)."""
    offset = np.array([0.3, 0.0])
    pairs, source, target = collect(arms, SLOW, "same_task_point", task_offset=offset)
    np.testing.assert_array_equal(source.commands[1:], SLOW.commands(SOURCE))
    points = pairs.source[:, 2:] + offset
    gap = np.linalg.norm(pairs.target[:, 2:] - points, axis=1)
    _, reachable = elbow_ik(points, robot("two_link_target").link_lengths)
    assert 10 <= reachable.sum() <= 40   # both cases occur
    assert (gap[reachable] < 1e-4).all()
    commands = np.array(target.commands[1:])
    residual = np.linalg.norm(TARGET.forward(commands) - points, axis=1)
    assert (gap[~reachable] > 1e-3).all()
    np.testing.assert_allclose(gap[~reachable], residual[~reachable], atol=1e-4)
    # Each command is the IK solution warm-started at the previous one (first: home).
    previous = TARGET.home
    for point, command in zip(points, commands):
        np.testing.assert_array_equal(command, inverse_kinematics.solve(
            TARGET.forward, point, previous, TARGET.joint_limits)[0])
        previous = command


def test_same_task_point_without_offset_on_task_lines(arms):
    program = BabblingProgram("task_lines", 4, 3, seed=0, task_low=(0.3, 0.3),
                              task_high=(0.38, 0.38))
    pairs, _, _ = collect(arms, program, "same_task_point")
    _, reachable = elbow_ik(pairs.source[:, 2:], robot("two_link_target").link_lengths)
    assert reachable.sum() >= 6
    np.testing.assert_allclose(pairs.target[reachable, 2:], pairs.source[reachable, 2:],
                               atol=1e-4)


# -- control flow -----------------------------------------------------------------------------
def test_should_stop_ends_collection_early(arms):
    calls = []

    def should_stop():
        calls.append(1)
        return len(calls) > 4

    pairs, source, target = collect(arms, SMALL, "same_command", 10, should_stop=should_stop)
    assert not pairs.complete and len(pairs) == 4 and pairs.target.shape == (4, 4)
    assert pairs.sim_time == pytest.approx(4 * 10 * DT)
    assert len(source.commands) == len(target.commands) == 5   # home + 4 samples
    pairs, _, _ = collect(arms, SMALL, "same_command", 10, should_stop=lambda: True)
    assert not pairs.complete and len(pairs) == 0 and pairs.sim_time == 0
    pairs, _, _ = collect(arms, SMALL, "same_command", 10, should_stop=lambda: False)
    assert pairs.complete and len(pairs) == SMALL.n_samples


def test_on_pair_sees_every_pair_in_order(arms):
    seen = []
    pairs, _, _ = collect(arms, SMALL, "same_task_point", 10,
                          on_pair=lambda i, s, t: seen.append((i, s.copy(), t.copy())))
    assert [i for i, _, _ in seen] == list(range(SMALL.n_samples))
    np.testing.assert_array_equal([s for _, s, _ in seen], pairs.source)
    np.testing.assert_array_equal([t for _, _, t in seen], pairs.target)


def test_collections_are_deterministic(arms):
    features = ("position", "velocity", "acceleration", "effort", "ee_x", "ee_y")
    first, _, _ = collect(arms, SMALL, "same_task_point", 50, features=features,
                          task_offset=[0.3, 0.0])
    second, _, _ = collect(arms, SMALL, "same_task_point", 50, features=features,
                           task_offset=[0.3, 0.0])
    np.testing.assert_array_equal(first.source, second.source)
    np.testing.assert_array_equal(first.target, second.target)
    assert first.sim_time == second.sim_time
    other, _, _ = collect(arms, BabblingProgram("joint_lines", 3, 2, seed=2), "same_task_point",
                          50, features=features, task_offset=[0.3, 0.0])
    assert not np.allclose(first.source, other.source)


def test_run_commands_is_one_robots_side_of_a_collection(arms):
    pairs, _, _ = collect(arms, SLOW, "same_time_index", 100)
    source_step, _ = arms()
    samples, sim_time = run_commands(SLOW.commands(SOURCE), source_step, 100, DEFAULT_FEATURES,
                                     SOURCE.home)
    np.testing.assert_array_equal(samples, pairs.source)
    assert sim_time == pytest.approx(pairs.sim_time) and sim_time == pytest.approx(5.0)
    np.testing.assert_array_equal(source_step.commands[0], SOURCE.home)   # settles first
    source_step, _ = arms()
    calls = iter(range(100))
    samples, sim_time = run_commands(SLOW.commands(SOURCE), source_step, 100, ("position",),
                                     SOURCE.home, should_stop=lambda: next(calls) >= 3)
    assert samples.shape == (3, 2) and sim_time == pytest.approx(0.3)
    np.testing.assert_array_equal(samples, pairs.source[:3, :2])
    with pytest.raises(ValueError, match="features must be distinct names"):
        run_commands(SLOW.commands(SOURCE), source_step, 100, ("speed",), SOURCE.home)
    with pytest.raises(ValueError, match="steps_per_sample must be an integer >= 1"):
        run_commands(SLOW.commands(SOURCE), source_step, 0, DEFAULT_FEATURES, SOURCE.home)


# -- the §3.6 example end to end --------------------------------------------------------------
def test_collected_2_link_correspondences_fit_lpa_better_than_pa(arms):
    """§3.6 with correspondences babbled on the simulators (same_command): local Procrustes
    maps uniform source points much better than one global Procrustes map (measured 4.2 mm vs
    28.6 mm on these test points)."""
    pairs, _, _ = collect(arms, BabblingProgram("joint_lines", 80, 5, seed=0), "same_command")
    assert pairs.source.shape == (400, 4)
    rng = np.random.default_rng(0)
    q = rng.uniform(SOURCE.joint_limits[:, 0], SOURCE.joint_limits[:, 1], (1000, 2))
    source_test = domain_data(q, robot("two_link_source").link_lengths)
    target_test = domain_data(q, robot("two_link_target").link_lengths)
    lpa = LocalProcrustesAnalysis(n_min=7, c_min=1e-7, cluster_dims=[0, 1],
                                  random_state=0).fit(pairs.source, pairs.target)
    pa = ProcrustesAnalysis().fit(pairs.source, pairs.target)
    errors = {name: end_effector_rmse(model.transfer(source_test)[:, 2:], target_test[:, 2:])
              for name, model in (("lpa", lpa), ("pa", pa))}
    assert errors["lpa"] < 0.5 * errors["pa"] and errors["lpa"] < 0.010, errors


# -- files ------------------------------------------------------------------------------------
def test_save_and_load_round_trip_atomically(tmp_path):
    rng = np.random.default_rng(0)
    pairs = CorrespondenceSet(rng.normal(size=(5, 4)), rng.normal(size=(5, 6)), "two_link_source",
                              "two_link_target", "same_task_point", ("position", "ee_x", "ee_y"),
                              sim_time=2.0, complete=False,
                              metadata={"seed": 3, "program": "joint_lines",
                                        "task_offset": [0.3, 0.0]})
    path = tmp_path / "pairs.npz"
    pairs.save(path)
    assert os.listdir(tmp_path) == ["pairs.npz"]   # no temporary file left
    source, target = load_correspondences(path)
    np.testing.assert_array_equal(source, pairs.source)
    np.testing.assert_array_equal(target, pairs.target)
    with np.load(path, allow_pickle=False) as archive:   # plain arrays: no pickles needed
        assert str(archive["source_robot"]) == "two_link_source"
        assert str(archive["target_robot"]) == "two_link_target"
        assert str(archive["pairing_rule"]) == "same_task_point"
        assert archive["features"].tolist() == ["position", "ee_x", "ee_y"]
        assert float(archive["sim_time"]) == 2.0 and not bool(archive["complete"])
        assert int(archive["meta_seed"]) == 3 and str(archive["meta_program"]) == "joint_lines"
        np.testing.assert_array_equal(archive["meta_task_offset"], [0.3, 0.0])
    # Saving again replaces the file; a name without .npz is kept as given.
    CorrespondenceSet(np.ones((2, 2)), np.zeros((2, 2))).save(path)
    assert load_correspondences(path)[0].shape == (2, 2)
    pairs.save(str(tmp_path / "pairs"))
    assert sorted(os.listdir(tmp_path)) == ["pairs", "pairs.npz"]
    np.testing.assert_array_equal(load_correspondences(tmp_path / "pairs")[1], pairs.target)


def test_a_collected_set_saves_and_loads(arms, tmp_path):
    pairs, _, _ = collect(arms, SMALL, "same_command", 10)
    pairs.save(tmp_path / "collected.npz")
    source, target = load_correspondences(tmp_path / "collected.npz")
    np.testing.assert_array_equal(source, pairs.source)
    np.testing.assert_array_equal(target, pairs.target)
    assert os.listdir(tmp_path) == ["collected.npz"]


def test_load_correspondences(tmp_path):
    np.savez(tmp_path / "pairs.npz", source=np.ones((3, 2)), target=np.zeros((3, 4)))
    source, target = load_correspondences(tmp_path / "pairs.npz")
    assert source.shape == (3, 2) and target.shape == (3, 4)
    np.savez(tmp_path / "half.npz", source=np.ones((3, 2)))
    with pytest.raises(ValueError, match=r"lacks the arrays \['target'\]"):
        load_correspondences(tmp_path / "half.npz")
    with pytest.raises(ValueError, match="cannot read correspondence file"):
        load_correspondences(tmp_path / "missing.npz")


def test_load_correspondences_rejects_damaged_and_foreign_files(tmp_path):
    np.savez(tmp_path / "pairs.npz", source=np.ones((300, 2)), target=np.zeros((300, 4)))
    data = (tmp_path / "pairs.npz").read_bytes()
    (tmp_path / "truncated.npz").write_bytes(data[:len(data) // 2])
    (tmp_path / "text.npz").write_text("source, target\n1, 2\n")
    (tmp_path / "empty.npz").write_bytes(b"")
    for name in ("truncated.npz", "text.npz", "empty.npz"):
        with pytest.raises(ValueError, match="cannot read correspondence file .*" + name):
            load_correspondences(tmp_path / name)
    np.save(tmp_path / "array.npy", np.ones((3, 2)))
    with pytest.raises(ValueError, match="is not an .npz archive"):
        load_correspondences(tmp_path / "array.npy")
    np.savez(tmp_path / "objects.npz", source=np.array([{"a": 1}], dtype=object),
             target=np.zeros(3))
    with pytest.raises(ValueError, match="cannot read correspondence file"):
        load_correspondences(tmp_path / "objects.npz")
    np.savez(tmp_path / "none.npz", x=np.ones(2))
    with pytest.raises(ValueError, match=r"lacks the arrays \['source', 'target'\]"):
        load_correspondences(tmp_path / "none.npz")


# -- guided exploration (§6.4.2, Alg. 7) ------------------------------------------------------
GB_HOME = [-0.785398, 1.65]                 # the Table 6.1 arms' home (the sims start there)
GB_BOUNDS = ((0.1, -1.1), (1.1, 0.4))       # the target's X_bounds
GB_STEPS = 100                              # physics steps a movement step (0.1 s)
UNCHECKED = PairCheck(tolerance=np.inf)     # the plumbing tests: pairs kept whatever apart


@pytest.fixture
def gb_arms():
    """gb_arms(side, settle=False) -> (kinematics, stepped environment, recorder of its
    steps): an in-process Table 6.1 arm (scenarios/robots/goal_babbling_<side>.toml) at home;
    ``settle``: each command stepped on until the arm settles (SettlingStep, PairCheck's
    defaults; the environment's ``settling``)."""
    sims = []

    def make(side, settle=False):
        params = robot(f"goal_babbling_{side}")
        kinematics = planar_kinematics(params, GB_HOME)
        sims.append(RobotSimulator(robot_urdf(params), initial_positions=GB_HOME))
        recorder = Recorder(sims[-1])
        step = SettlingStep(recorder, PairCheck()) if settle else recorder
        environment = stepped_environment(kinematics, step, GB_STEPS)
        return kinematics, environment, recorder, step

    yield make
    for sim in sims:
        sim.close()


def guided(gb_arms, seconds=10.0, seed=2, settle=None, **kwargs):
    """A guided collection; the source settles (by default unless it follows the commands)."""
    if settle is None:
        settle = kwargs.get("source_follows", "reached") == "reached"
    (source_kinematics, source, source_steps, settling), \
        (target_kinematics, target, target_steps, _) = gb_arms("source", settle), \
        gb_arms("target")
    pairs = collect_guided_correspondences(
        GoalBabbling(GB_BOUNDS, seed=seed), source, target, [0, 1], [0, 1], seconds,
        source_settling=settling if settle else None, **kwargs)
    return pairs, (source_kinematics, source_steps), (target_kinematics, target_steps)


def first_steps(recorder):
    """The commands a settling robot was sent, one per movement (the step calls of a whole
    movement step; the settling ones are shorter)."""
    return [command for command, n in zip(recorder.commands, recorder.n_steps) if n == GB_STEPS]


def test_guided_collection_pairs_the_targets_reached_postures_with_the_settled_source(gb_arms):
    pairs, (source_kinematics, source), (target_kinematics, target) = guided(gb_arms)
    assert pairs.complete and pairs.pairing_rule == "same_command"
    assert pairs.features == DEFAULT_FEATURES and pairs.sim_time == pytest.approx(10.0)
    assert pairs.metadata["seed"] == 2 and pairs.metadata["guided_seconds"] == 10.0
    assert pairs.metadata["source_follows"] == "reached"
    np.testing.assert_array_equal(pairs.metadata["x_high"], GB_BOUNDS[1])
    # Alg. 7: the target babbles first (from its home); the source then takes each posture
    # the target reached, settling there (more step calls than movements).
    assert len(target.commands) == 101 and len(source.commands) > 100
    np.testing.assert_array_equal(target.commands[0], GB_HOME)
    reached = np.array([state.positions for state in target.states[1:]])
    np.testing.assert_array_equal(first_steps(source), np.clip(
        reached, *np.array(source_kinematics.joint_limits).T))
    # Each side's rows are what that robot reached, x its own kinematics of q̄; the pairs'
    # shared joints agree within the check's tolerance, and every pair is kept here.
    experience = pairs.metadata["target_experience"]
    np.testing.assert_array_equal(experience[:, :2], reached)
    assert len(pairs) == pairs.metadata["followed"].sum() == pairs.metadata["pairs_checked"]
    for kinematics, samples in ((source_kinematics, pairs.source),
                                (target_kinematics, pairs.target)):
        np.testing.assert_allclose(samples[:, 2:], kinematics.forward(samples[:, :2]),
                                   atol=1e-6)
    residual = np.abs(pairs.source[:, :2] - pairs.target[:, :2]).max(axis=1)
    assert residual.max() <= PairCheck().tolerance
    assert pairs.metadata["worst_residual"] == residual.max()
    assert pairs.metadata["median_residual"] == np.median(residual)
    assert pairs.metadata["unsettled_source"] == 0
    assert pairs.metadata["pairs_dropped"] == 0 and len(pairs) >= 95
    assert np.abs(pairs.source[:, 2:] - pairs.target[:, 2:]).max() > 0.1   # other arms
    # Seeded: fresh simulators and the same seed repeat the collection bit for bit.
    again, _, _ = guided(gb_arms)
    np.testing.assert_array_equal(again.source, pairs.source)
    np.testing.assert_array_equal(again.target, pairs.target)


def test_guided_source_following_the_commands_lags_and_fails_the_pairing_check(gb_arms):
    """source_follows 'command' (the collector before the check): both arms lag the same
    command their own way; with the check off it reports how far apart (up to 0.3 rad here),
    with the default check it refuses the set, naming the robots, the rule and the residual."""
    pairs, (_, source), (_, target) = guided(gb_arms, source_follows="command",
                                             pair_check=PairCheck(tolerance=np.inf))
    assert pairs.source.shape == pairs.target.shape == (100, 4)
    np.testing.assert_array_equal(source.commands, target.commands[1:])   # one step each
    lag = np.abs(pairs.source[:, :2] - pairs.target[:, :2])
    assert 0.01 < lag.max() < 0.3 and np.median(lag) < 0.02
    assert pairs.metadata["worst_residual"] == lag.max()
    assert (pairs.metadata["pairs_checked"], pairs.metadata["pairs_dropped"]) == (100, 0)
    with pytest.raises(PairingError, match=r"arm_s -> arm_t: \d+ of \d+ same_command pairs "
                       r"are not true correspondences \(worst residual 0\.\d+ rad > "
                       r"tolerance 0\.001 rad"):
        guided(gb_arms, source_follows="command", names=("arm_s", "arm_t"))
    # dropping up to half of them is allowed if asked for: the rest are true pairs
    kept, _, _ = guided(gb_arms, source_follows="command",
                        pair_check=PairCheck(max_bad_share=0.5))
    assert 0 < kept.metadata["pairs_dropped"] <= 50
    assert len(kept) == 100 - kept.metadata["pairs_dropped"]
    assert np.abs(kept.source[:, :2] - kept.target[:, :2]).max() <= 1e-3
    assert kept.metadata["followed"].sum() == len(kept)
    assert kept.metadata["target_experience"].shape == (100, 4)   # the target keeps them all


def test_guided_on_pair_sees_each_pair_as_the_source_executes_its_command(gb_arms):
    seen = []
    steps = {}

    def on_pair(index, source_row, target_row):
        seen.append((index, len(steps["source"].commands), len(steps["target"].commands),
                     source_row.copy(), target_row.copy()))

    (_, source, steps["source"], _), (_, target, steps["target"], _) = \
        gb_arms("source"), gb_arms("target")
    pairs = collect_guided_correspondences(GoalBabbling(GB_BOUNDS, seed=4), source, target,
                                           [0, 1], [0, 1], 3.0, on_pair=on_pair,
                                           pair_check=UNCHECKED)
    assert [index for index, *_ in seen] == list(range(30))
    assert [n for _, n, *_ in seen] == list(range(1, 31))      # right after command i
    assert {n for _, _, n, *_ in seen} == {31}                 # the target had babbled
    np.testing.assert_array_equal([row for *_, row, _ in seen], pairs.source)
    np.testing.assert_array_equal([row for *_, row in seen], pairs.target)


def test_guided_should_stop_pairs_only_the_commands_both_robots_executed(gb_arms):
    steps = {}

    def collect_until(side, n_commands):
        (_, source, steps["source"], _), (_, target, steps["target"], _) = \
            gb_arms("source"), gb_arms("target")
        return collect_guided_correspondences(
            GoalBabbling(GB_BOUNDS, seed=2), source, target, [0, 1], [0, 1], 10.0,
            should_stop=lambda: len(steps[side].commands) >= n_commands, pair_check=UNCHECKED)

    pairs = collect_until("source", 30)          # stopped while the source replays
    assert not pairs.complete and pairs.source.shape == pairs.target.shape == (30, 4)
    assert pairs.sim_time == pytest.approx(3.0)
    assert len(steps["source"].commands) == 30 and len(steps["target"].commands) == 101
    np.testing.assert_array_equal(pairs.target[:, :2], positions(steps["target"])[:30])
    full, _, _ = guided(gb_arms, settle=False, pair_check=UNCHECKED)
    np.testing.assert_array_equal(pairs.source, full.source[:30])
    np.testing.assert_array_equal(pairs.target, full.target[:30])
    pairs = collect_until("target", 50)          # stopped while the target babbles
    assert not pairs.complete and len(pairs) == 0 and pairs.sim_time == 0
    assert len(steps["target"].commands) == 50 and steps["source"].commands == []


def test_guided_kinematic_environments_share_q_and_hold_other_joints_at_home():
    """A 3-joint target whose first joint the 2-joint source lacks (as Poppy's torso)."""
    links, home = (0.2, 0.7, 0.4), np.array([0.3, -0.6, 1.5])
    sent = []

    def torso_forward(q):
        sent.extend(np.atleast_2d(q))
        return planar_forward_kinematics(q, links)

    torso = Kinematics(np.array([(-0.5, 0.5), (-1.2, 0.3), (0.4, 2.9)]), home, torso_forward)
    arm = Kinematics(np.array([(-np.pi / 2, 0.0), (0.4, 2.9)]), np.array([-0.7, 1.6]),
                     lambda q: planar_forward_kinematics(q, (0.5, 0.5)))
    pairs = collect_guided_correspondences(GoalBabbling(GB_BOUNDS, seed=1), arm, torso,
                                           [0, 1], [1, 2], 5.0)
    assert pairs.source.shape == pairs.target.shape == (50, 4)
    np.testing.assert_array_equal(pairs.source[:, :2], pairs.target[:, :2])
    assert (pairs.source[:, :2] >= [-1.2, 0.4]).all()        # the shared ranges
    assert (pairs.source[:, :2] <= [0.0, 2.9]).all()
    np.testing.assert_array_equal(np.array(sent)[:, 0], 0.3)  # the torso stays at home
    assert list(pairs.metadata["target_joints"]) == [1, 2]


@pytest.mark.parametrize("kwargs, message", [
    (dict(seconds=-1.0), "seconds must be a finite number >= 0"),
    (dict(target_joints=[0]), "pair the shared joints one to one"),
    (dict(target_joints=[0, 2]), "distinct joint indices in \\[0, 2\\)"),
    (dict(x_bounds=((1.1, -1.1), (0.1, 0.4))), "x_bounds must be finite"),
])
def test_guided_bad_arguments_raise_before_any_step(kwargs, message):
    def never(q):
        raise AssertionError("a robot moved")

    arm = Kinematics(np.array([(-np.pi / 2, 0.0), (0.4, 2.9)]), np.array([-0.7, 1.6]), never)
    args = {**dict(seconds=1.0, target_joints=[0, 1], x_bounds=GB_BOUNDS), **kwargs}
    with pytest.raises(ValueError, match=message):
        collect_guided_correspondences(GoalBabbling(args["x_bounds"]), arm, arm, [0, 1],
                                       args["target_joints"], args["seconds"])


@pytest.mark.parametrize("babbling, message", [
    (GoalBabbling(((0.1, -1.1, 0.0), (1.1, 0.4, 1.0))), "x_bounds have 3 coordinates"),
    (GoalBabbling(GB_BOUNDS, home=[0.5, 1.0]), "home .* lies outside the joint limits"),
    (GoalBabbling(GB_BOUNDS, sigma=-0.1), "sigma must be a finite number >= 0"),
    (GoalBabbling(GB_BOUNDS, p_home=2.0), "need p_home <= 1"),
])
def test_check_guided_exploration_finds_what_would_fail_on_the_robots(babbling, message):
    source = planar_kinematics(robot("goal_babbling_source"), GB_HOME)
    target = planar_kinematics(robot("goal_babbling_target"), GB_HOME)
    limits = check_guided_exploration(GoalBabbling(GB_BOUNDS), source, target, [0, 1],
                                      [0, 1], 10.0)
    np.testing.assert_allclose(limits, [(-np.pi / 2, 0.0), (0.4, 2.9)])
    with pytest.raises(ValueError, match=message):
        check_guided_exploration(babbling, source, target, [0, 1], [0, 1], 10.0)
    assert not hasattr(babbling, "model_")                  # the given one is not started


def wide_shouldered_target():
    """The Table 6.1 target with a shoulder that also turns up to +0.6 rad, where the source's
    stops at 0 (a target with a wider range of a shared joint, as Poppy's elbow)."""
    params = robot("goal_babbling_target")
    limits = np.array(params.joint_limits, dtype=np.float64)
    limits[0, 1] = 0.6
    return Kinematics(limits, np.array(GB_HOME),
                      lambda q: planar_forward_kinematics(q, params.link_lengths))


def test_guided_collection_in_the_targets_own_ranges_keeps_its_whole_experience(tmp_path):
    """target_range 'own': pairs (and on_pair) only for the commands the source followed;
    the file also holds the target's rows of every command, which load_guided_exploration
    gives back with the followed mask."""
    source = planar_kinematics(robot("goal_babbling_source"), GB_HOME)
    seen = []
    upper_box = ((0.3, 0.0), (1.1, 0.9))      # goals above the source's reach: shoulder > 0
    pairs = collect_guided_correspondences(
        GoalBabbling(upper_box, seed=2), source, wide_shouldered_target(), [0, 1], [0, 1],
        120.0, on_pair=lambda index, *rows: seen.append(index), target_range="own")
    followed, experience = pairs.metadata["followed"], pairs.metadata["target_experience"]
    assert experience.shape == (1200, 4) and pairs.sim_time == pytest.approx(120.0)
    assert pairs.metadata["target_range"] == "own"
    assert 0.05 < 1 - followed.mean() < 0.9           # it went where the source cannot
    np.testing.assert_array_equal(followed, experience[:, 0] <= 0.0)
    assert seen == np.flatnonzero(followed).tolist()
    np.testing.assert_array_equal(pairs.target, experience[followed])
    np.testing.assert_array_equal(pairs.source[:, :2], pairs.target[:, :2])
    pairs.save(tmp_path / "guided.npz")
    source_pairs, target_pairs, loaded_experience, loaded_followed = \
        load_guided_exploration(tmp_path / "guided.npz")
    np.testing.assert_array_equal(source_pairs, pairs.source)
    np.testing.assert_array_equal(target_pairs, pairs.target)
    np.testing.assert_array_equal(loaded_experience, experience)
    np.testing.assert_array_equal(loaded_followed, followed)
    assert load_correspondences(tmp_path / "guided.npz")[0].shape == pairs.source.shape
    # a file of pairs only (shared ranges, older files): every row followed
    np.savez(tmp_path / "plain.npz", source=pairs.source, target=pairs.target)
    *_, plain_experience, plain_followed = load_guided_exploration(tmp_path / "plain.npz")
    np.testing.assert_array_equal(plain_experience, pairs.target)
    assert plain_followed.all() and len(plain_followed) == len(pairs.target)
    np.savez(tmp_path / "bad.npz", source=pairs.source, target=pairs.target,
             meta_followed=np.ones(1200, dtype=bool), meta_target_experience=experience)
    with pytest.raises(ValueError, match="do not agree"):
        load_guided_exploration(tmp_path / "bad.npz")
    np.savez(tmp_path / "half.npz", source=pairs.source, target=pairs.target,
             meta_followed=followed)
    with pytest.raises(ValueError, match="no meta_target_experience"):
        load_guided_exploration(tmp_path / "half.npz")
    with pytest.raises(ValueError, match="target_range must be one of"):
        check_guided_exploration(GoalBabbling(GB_BOUNDS), source, wide_shouldered_target(),
                                 [0, 1], [0, 1], 10.0, target_range="all")


# -- true pairs for any robot pair: settling by state and the pairing checks ----------------
FAST_LINES = BabblingProgram("joint_lines", 20, 2, seed=0)   # 40 commands, long jumps


def user_pair():
    """The user's pair of longer 2-link arms (scenarios/robots/user_two_link_*.toml)."""
    params = [robot(f"user_two_link_{side}") for side in ("source", "target")]
    sims = [RobotSimulator(robot_urdf(p)) for p in params]
    return [planar_kinematics(p) for p in params], sims


def test_a_pair_that_needs_longer_than_400_ms_settles_into_true_pairs():
    """Measured on these 40 commands before settling (400 steps a sample, no check): joint
    angles up to 1.3 rad apart, 20 pairs over 1e-3 rad; settled by state: at most 8e-6 rad,
    for 24.1 instead of 16 s of simulated time."""
    (source, target), sims = user_pair()
    program = FAST_LINES
    try:
        pairs = collect_correspondences(program, "same_command", source, target, sims[0].step,
                                        sims[1].step, STEPS)
    finally:
        for sim in sims:
            sim.close()
    assert len(pairs) == 40 and pairs.complete
    residual = np.abs(pairs.source[:, :2] - pairs.target[:, :2]).max()
    assert residual < 1e-4
    meta = pairs.metadata
    assert (meta["pairs_checked"], meta["pairs_dropped"]) == (40, 0)
    assert meta["worst_residual"] == pytest.approx(residual)
    assert meta["residual_unit"] == "rad" and meta["unsettled_target"] == 0
    assert pairs.sim_time > 40 * STEPS * DT      # settling took longer than the minimum


def test_pairs_that_cannot_be_made_true_end_in_an_error_naming_robot_rule_and_residual():
    (source, target), sims = user_pair()
    program = FAST_LINES
    made = []
    try:
        with pytest.raises(PairingError, match=r"src -> tgt: \d+ of \d+ same_command pairs .*"
                           r"worst residual 0\.\d+ rad > tolerance 0\.001 rad.*"
                           r"did not settle"):
            collect_correspondences(program, "same_command", source, target, sims[0].step,
                                    sims[1].step, STEPS, names=("src", "tgt"),
                                    on_pair=lambda *pair: made.append(pair),
                                    pair_check=PairCheck(max_settle_steps=STEPS))
    finally:
        for sim in sims:
            sim.close()
    assert len(made) < 40


def test_dropped_pairs_are_counted_and_retry_settles_them():
    """A tolerance the fixed 400 ms cannot meet on some commands: drop keeps the good pairs
    only; retry settles the bad ones for another budget and keeps them."""
    program = FAST_LINES
    results = {}
    for action in ("drop", "retry"):
        (source, target), sims = user_pair()
        check = PairCheck(max_settle_steps=STEPS, on_bad_pair=action, max_bad_share=1.0,
                          tolerance=1e-2)
        try:
            results[action] = collect_correspondences(program, "same_command", source, target,
                                                      sims[0].step, sims[1].step, STEPS,
                                                      pair_check=check)
        finally:
            for sim in sims:
                sim.close()
    dropped = results["drop"]
    assert 0 < dropped.metadata["pairs_dropped"] < 40
    assert len(dropped) == 40 - dropped.metadata["pairs_dropped"]
    assert dropped.metadata["worst_dropped_residual"] > 1e-2 >= dropped.metadata["worst_residual"]
    assert np.abs(dropped.source[:, :2] - dropped.target[:, :2]).max() <= 1e-2
    retried = results["retry"]
    assert retried.metadata["pairs_dropped"] < dropped.metadata["pairs_dropped"]
    assert np.abs(retried.source[:, :2] - retried.target[:, :2]).max() <= 1e-2


def test_a_pair_with_different_joint_counts_agrees_on_the_shared_joints():
    """2 joints -> 3 joints (the target's third stays at home): same_command on joints 0-1."""
    params = [robot("two_link_source"), robot("three_dof_arm")]
    sims = [RobotSimulator(robot_urdf(p)) for p in params]
    kinematics = [planar_kinematics(p) for p in params]
    try:
        pairs = collect_correspondences(BabblingProgram("joint_lines", 4, 5, seed=3),
                                        "same_command", *kinematics, sims[0].step,
                                        sims[1].step, STEPS)
    finally:
        for sim in sims:
            sim.close()
    assert pairs.source.shape == (20, 4) and pairs.target.shape == (20, 5)
    assert np.abs(pairs.source[:, :2] - pairs.target[:, :2]).max() <= 1e-3
    assert pairs.metadata["pairs_dropped"] == 0


def test_same_time_index_pairs_share_the_clock_and_are_not_settled(arms):
    pairs, source, target = collect(arms, SMALL, "same_time_index", steps=10,
                                    pair_check=PairCheck())
    assert pairs.metadata["residual_unit"] == "s" and pairs.metadata["worst_residual"] == 0.0
    assert pairs.sim_time == pytest.approx(len(pairs) * 10 * DT)   # no settling on the move


@pytest.mark.parametrize("kwargs, message", [
    (dict(max_settle_steps=-1), "max_settle_steps"), (dict(check_steps=0), "check_steps"),
    (dict(tolerance=float("nan")), "tolerance must be a number >= 0"),
    (dict(on_bad_pair="ignore"), "on_bad_pair must be one of"),
    (dict(max_bad_share=1.5), r"max_bad_share must be a number in \[0, 1\]")])
def test_bad_pair_checks_are_refused(kwargs, message):
    with pytest.raises(ValueError, match=message):
        PairCheck(**kwargs)
