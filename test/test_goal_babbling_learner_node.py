"""goal_babbling_learner over real DDS, babbling on a position-mode robot_sim (thesis ch. 6)."""
import math
import os
import signal

import numpy as np
import pytest

from conftest import ROOT
from ros_harness import ClientNode, NodeProcess, ros_params, unique_domain_id

from lpa_transfer.robots.kinematics import planar_forward_kinematics
from lpa_transfer_interfaces.msg import Matrix, ReachingEvaluation
from lpa_transfer_interfaces.action import GoalBabble
from lpa_transfer_interfaces.srv import InitialiseSensorimotor
from lpa_transfer_nodes.conversions import from_matrix, to_matrix
from sensor_msgs.msg import JointState
from visualization_msgs.msg import Marker, MarkerArray

TARGET = ROOT / "scenarios" / "robots" / "goal_babbling_target.toml"
LINKS = (0.7, 0.4)
LIMITS = np.array([[-np.pi / 2, 0.0], [0.4, 2.9]])
HOME = "[-0.785398, 1.65]"
LEARNER = dict(robot=TARGET, home=HOME, x_low="[0.1, -1.1]", x_high="[1.1, 0.4]",
               eval_spacing=0.1)


def grid_samples(n_per_joint):
    """Rows (q, x) of the target's analytic kinematics on a joint-space grid."""
    axes = [np.linspace(low, high, n_per_joint) for low, high in LIMITS]
    q = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 2)
    return np.hstack((q, planar_forward_kinematics(q, LINKS)))


@pytest.fixture(scope="module")
def learners(tmp_path_factory):
    """One robot_sim under /target; an unguarded learner beside it and a guarded one under
    /guarded (same robot, its own topic), used one at a time."""
    work = tmp_path_factory.mktemp("goal_babbling")
    domain_id = unique_domain_id()
    nodes = [NodeProcess("robot_sim", domain_id, work, ros_params(
                 robot=TARGET, control_mode="position", initial_positions=HOME)
                 + ["-r", "__ns:=/target"]),
             NodeProcess("goal_babbling_learner", domain_id, work, ros_params(**LEARNER)
                         + ["-r", "__ns:=/target"]),
             NodeProcess("goal_babbling_learner", domain_id, work, ros_params(
                 **LEARNER, guard=True, step_service="/target/robot_sim/step",
                 reset_service="/target/robot_sim/reset") + ["-r", "__ns:=/guarded"],
                 name="guarded_learner")]
    client = ClientNode(domain_id, "goal_babbling_test_client")
    received = []
    client.node.create_subscription(ReachingEvaluation, "/target/reaching_evaluation",
                                    received.append, 100)
    client.markers = []      # the learner's task_markers arrays
    client.node.create_subscription(MarkerArray, "/target/goal_babbling_learner/task_markers",
                                    client.markers.append, 100)

    def clients(namespace):
        prefix = f"/{namespace}/goal_babbling_learner"
        return (client.node.create_client(InitialiseSensorimotor, f"{prefix}/initialise"),
                client.action_client(GoalBabble, f"{prefix}/babble"))

    try:
        yield client, clients("target"), clients("guarded"), received, nodes, (domain_id, work)
    finally:
        client.close()
        for node in nodes:
            node.stop()


def reset(client, init, own=None, transferred=None, elapsed=0.0, seed=-1):
    request = InitialiseSensorimotor.Request(reset=True, elapsed=elapsed, seed=seed)
    if own is not None:
        request.own = to_matrix(own)
    if transferred is not None:
        request.transferred = to_matrix(transferred)
    return client.call(init, request, timeout=60)


def babble(client, action, seconds, interval=0.0, on_feedback=None):
    return client.run(action, GoalBabble.Goal(seconds=seconds, evaluation_interval=interval),
                      timeout=60, on_feedback=on_feedback)


def test_babbling_learns_from_what_the_robot_did(learners):
    client, (init, service), _, received, nodes, _ = learners
    assert reset(client, init).success, nodes[1].log()
    client.spin_until(lambda: received and math.isnan(received[-1].mean_error), timeout=10,
                      what="the reset's evaluation (an empty model)")
    before = len(received)
    feedback = []
    answer = babble(client, service, 30.0, 10.0, feedback.append)
    assert answer.success, answer.message + nodes[1].log()
    # the action's feedback: each evaluation as it is made, with the steps done
    assert [(f.evaluation.learning_time, f.steps_done, f.n_steps) for f in feedback] == \
        [(10.0, 100, 300), (20.0, 200, 300), (30.0, 300, 300)]
    times = [e.learning_time for e in answer.evaluations]
    assert times == pytest.approx([10.0, 20.0, 30.0])
    errors = [e.mean_error for e in answer.evaluations]
    # measured: 305, 285, 244 mm (reaching rate 4, 6, 11 %)
    assert errors[-1] < errors[0]
    last = answer.evaluations[-1]
    assert last.n_own_samples == 301 and last.n_transferred_samples == 0   # home + 300
    assert last.n_test_points > 50 and last.reaching_threshold == 0.01
    assert 0.0 <= last.reaching_rate <= 1.0
    experience = from_matrix(answer.experience, "experience")
    assert experience.shape == (300, 4)
    np.testing.assert_allclose(experience[:, 2:], planar_forward_kinematics(experience[:, :2],
                                                                            LINKS), atol=1e-6)
    assert (experience[:, :2] >= LIMITS[:, 0] - 1e-3).all()
    assert (experience[:, :2] <= LIMITS[:, 1] + 1e-3).all()
    client.spin_until(lambda: len(received) >= before + 3, timeout=10, what="3 evaluations")
    received = received[before:]
    assert [(e.learning_time, e.mean_error, e.robot) for e in received] == \
        [(e.learning_time, e.mean_error, "goal_babbling_target") for e in answer.evaluations]
    stamps = [e.header.stamp.sec + 1e-9 * e.header.stamp.nanosec for e in received]
    assert stamps[-1] == pytest.approx(answer.sim_time, abs=1e-6)
    assert np.diff(stamps) == pytest.approx([10.0, 10.0], abs=1e-6)   # 100 steps of 1 ms
    assert received[0].header.frame_id == "world"
    # each evaluation's test points on task_markers: reached (green) as many as the rate says
    client.spin_until(lambda: client.markers and client.markers[-1].markers[-1].header.stamp
                      == received[-1].header.stamp, timeout=10, what="the last markers")
    clear, points = client.markers[-1].markers
    assert clear.action == Marker.DELETEALL and points.type == Marker.SPHERE_LIST
    assert len(points.points) == len(points.colors) == last.n_test_points
    green = sum(c.g > c.r for c in points.colors)
    assert green == round(last.reaching_rate * last.n_test_points)
    assert all(p.z == 0.0 for p in points.points) and points.header.frame_id == "world"


def test_initialising_with_own_samples_beats_a_fresh_model(learners):
    client, (init, service), _, _, nodes, _ = learners
    empty = reset(client, init)
    assert empty.success and math.isnan(empty.evaluation.mean_error)
    assert empty.evaluation.n_own_samples == 0 and empty.evaluation.reaching_rate == 0.0
    fresh = babble(client, service, 0.0, 10.0)   # starts babbling: the home sample only
    assert fresh.success and len(fresh.evaluations) == 1, fresh.message
    assert fresh.evaluations[0].n_own_samples == 1
    assert from_matrix(fresh.experience, "experience").shape == (0, 4)
    own = grid_samples(15)
    own[3, 0], own[7, 3] = np.nan, np.inf
    answer = reset(client, init, own=own, elapsed=60.0)
    assert answer.success, answer.message + nodes[1].log()
    assert (answer.n_own, answer.n_transferred, answer.n_rejected) == (223, 0, 2)
    evaluation = answer.evaluation
    assert evaluation.learning_time == 60.0 and evaluation.n_own_samples == 223
    # measured: the home sample alone 386 mm, the grid 8.9 mm (rate 70 %)
    assert evaluation.mean_error < 0.5 * fresh.evaluations[0].mean_error
    # the clock goes on from 60 s: multiples of 25 s are 75 s, then the end at 80 s
    later = babble(client, service, 20.0, 25.0)
    assert later.success, later.message
    assert [e.learning_time for e in later.evaluations] == pytest.approx([75.0, 80.0])
    assert later.evaluations[-1].n_own_samples == 223 + 1 + 200


def test_bad_requests_are_refused_and_the_node_keeps_serving(learners):
    client, (init, service), _, _, _, _ = learners
    wrong = client.call(init, InitialiseSensorimotor.Request(own=to_matrix(np.zeros((4, 3)))))
    assert not wrong.success and "4 columns" in wrong.message
    bad_size = client.call(init, InitialiseSensorimotor.Request(
        transferred=Matrix(rows=2, cols=4, data=[0.0] * 7)))
    assert not bad_size.success and "transferred" in bad_size.message
    for elapsed in (-1.0, math.inf):
        refused = client.call(init, InitialiseSensorimotor.Request(elapsed=elapsed))
        assert not refused.success and "elapsed" in refused.message
    for seconds, interval in ((-1.0, 0.0), (math.nan, 0.0), (1.0, -2.0), (1.0, math.inf)):
        refused = babble(client, service, seconds, interval)
        assert not refused.success, (seconds, interval)
    good = babble(client, service, 1.0)
    assert good.success and from_matrix(good.experience, "experience").shape == (10, 4)


def test_a_guarded_learner_keeps_transferred_samples_apart(learners):
    client, _, (init, service), _, nodes, _ = learners
    own, transferred = grid_samples(6), grid_samples(9)[1::2]
    transferred[0] = own[5]
    transferred[0, 2:] += 0.1   # where own[5]'s command leads 14 cm off: contradicted, retired
    transferred[1, 0] = np.nan
    answer = reset(client, init, own=own, transferred=transferred)
    assert answer.success, answer.message + nodes[2].log()
    assert (answer.n_own, answer.n_transferred, answer.n_rejected) == (36, 39, 1)
    active = answer.evaluation.n_transferred_samples
    assert active == 38 and answer.evaluation.n_own_samples == 36
    later = babble(client, service, 10.0)
    assert later.success, later.message
    assert later.evaluations[-1].n_transferred_samples <= active
    assert later.evaluations[-1].n_own_samples == 36 + 1 + 100


def test_the_same_calls_give_the_same_experience(learners):
    client, (init, service), _, _, _, _ = learners
    runs = []
    for _ in range(2):
        assert reset(client, init).success
        answers = [babble(client, service, 5.0, 2.0), babble(client, service, 3.0)]
        assert all(a.success for a in answers)
        runs.append(([from_matrix(a.experience, "experience").copy() for a in answers],
                     [(e.learning_time, e.mean_error) for a in answers for e in a.evaluations]))
    for first, second in zip(runs[0][0], runs[1][0]):
        np.testing.assert_array_equal(first, second)
    assert runs[0][1] == runs[1][1]
    assert [t for t, _ in runs[0][1]] == pytest.approx([2.0, 4.0, 5.0, 8.0])


def test_a_reset_can_seed_the_next_run(learners):
    client, (init, service), _, _, _, _ = learners
    experience = {}
    for seed in (5, 6, 5, -1):
        assert reset(client, init, seed=seed).success
        answer = babble(client, service, 3.0)
        assert answer.success, answer.message
        experience.setdefault(seed, []).append(from_matrix(answer.experience, "e").copy())
    np.testing.assert_array_equal(*experience[5])
    assert not np.array_equal(experience[5][0], experience[6][0])
    assert not np.array_equal(experience[5][0], experience[-1][0])   # the parameter: 0
    refused = reset(client, init, seed=-2)
    assert not refused.success and "seed" in refused.message


def test_sigint_stops_babbling_at_once(learners):
    client, *_, (domain_id, work) = learners
    learner = NodeProcess("goal_babbling_learner", domain_id, work, ros_params(
        **LEARNER, step_service="/target/robot_sim/step",
        reset_service="/target/robot_sim/reset") + ["-r", "__ns:=/stopping"],
        name="stopped_learner")
    try:
        action = client.action_client(GoalBabble, "/stopping/goal_babbling_learner/babble")
        client.spin_until(action.server_is_ready, timeout=20, what="the learner")
        client.spin_for(0.5)                                  # discovery settles
        steps = []
        client.node.create_subscription(JointState, "/target/joint_states",
                                        steps.append, 100)
        sent = action.send_goal_async(GoalBabble.Goal(seconds=1000.0))   # 10 000 steps
        handle = client.spin_until(lambda: sent.done() and sent.result(), timeout=20,
                                   what="the goal accepted")
        future = handle.get_result_async()
        client.spin_until(lambda: len(steps) >= 50, timeout=20, what="babbling under way")
        assert not future.done()
        os.killpg(learner.process.pid, signal.SIGINT)
        client.spin_until(future.done, timeout=5, what="the stopped babble's answer")
        answer = future.result().result
        assert not answer.success and "stopped (SIGINT/SIGTERM) after" in answer.message
        # the one SIGINT also ends the node, cleanly (a second one, as stop() would send,
        # could land in its shutdown after rclpy restored the default handler: exit -2)
        learner.process.wait(timeout=10)
        assert learner.stop() == 0, learner.log()
    finally:
        learner.stop()


def test_a_learner_without_test_points_does_not_start(tmp_path):
    learner = NodeProcess("goal_babbling_learner", unique_domain_id(), tmp_path, ros_params(
        **dict(LEARNER, eval_low="[5.0, 5.0]", eval_high="[6.0, 6.0]")))
    learner.process.wait(timeout=30)
    assert learner.stop() == 1
    assert "cannot start: no test points" in learner.log()


def test_a_learner_with_unknown_active_joints_does_not_start(tmp_path):
    learner = NodeProcess("goal_babbling_learner", unique_domain_id(), tmp_path, ros_params(
        **dict(LEARNER, active_joints="[0, 2]")))
    learner.process.wait(timeout=30)
    assert learner.stop() == 1
    assert "joints must hold distinct joint indices in [0, 2)" in learner.log()


def test_a_cancelled_babble_ends_at_the_next_step_and_keeps_what_it_learned(learners):
    """GoalBabble is an action: cancelled after its first evaluation, the goal ends
    canceled long before its 100 s, with the evaluations so far; the learner's clock shows
    the steps done stay learned, and the next goal babbles on from there."""
    from action_msgs.msg import GoalStatus

    client, (init, action), _, _, nodes, _ = learners
    assert reset(client, init).success, nodes[1].log()
    feedback = []
    sent = action.send_goal_async(GoalBabble.Goal(seconds=100.0, evaluation_interval=1.0),
                                  feedback_callback=lambda m: feedback.append(m.feedback))
    handle = client.spin_until(lambda: sent.done() and sent.result(), timeout=30,
                               what="the goal accepted")
    client.spin_until(lambda: feedback, timeout=30, what="the first evaluation")
    handle.cancel_goal_async()
    done = handle.get_result_async()
    outcome = client.spin_until(lambda: done.done() and done.result(), timeout=30,
                                what="the cancelled goal's result")
    assert outcome.status == GoalStatus.STATUS_CANCELED, outcome.result.message
    result = outcome.result
    assert not result.success and result.message.startswith("cancelled: after ")
    assert 1 <= len(result.evaluations) < 100
    clock = result.evaluations[-1].learning_time
    after = babble(client, action, 1.0)
    assert after.success, after.message
    assert after.evaluations[-1].learning_time > clock            # it babbled on from there
    assert after.evaluations[-1].learning_time < 50.0


def test_a_learner_both_guarded_and_yielding_does_not_start(tmp_path):
    learner = NodeProcess("goal_babbling_learner", unique_domain_id(), tmp_path, ros_params(
        **dict(LEARNER, guard=True, yielding=True)))
    learner.process.wait(timeout=30)
    assert learner.stop() == 1
    assert "guard and yielding exclude each other" in learner.log()
