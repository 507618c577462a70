"""inverse_dynamics_learner over real DDS, driving a torque-mode robot_sim (thesis ch. 5)."""
import json

import numpy as np
import pytest

from conftest import ROOT
from ros_harness import ClientNode, NodeProcess, ros_params, unique_domain_id

from lpa_transfer_interfaces.msg import TrialResult
from lpa_transfer_interfaces.action import RunTrials
from lpa_transfer_interfaces.srv import InitialiseLearner
from lpa_transfer_nodes.conversions import from_matrix, to_matrix

PINCHER = ROOT / "scenarios" / "robots" / "pincher_arm.toml"
CENTRE_POSE = "[0.0, 0.6, 0.9, 0.6]"


@pytest.fixture
def learner(tmp_path_factory):
    """A fresh graph per test: a learner's clock, trial count and model are what the tests
    before it left, so a shared one would make the tests depend on their order."""
    work = tmp_path_factory.mktemp("learner")
    domain_id = unique_domain_id()
    namespace = ["-r", "__ns:=/pincher"]
    nodes = [NodeProcess("robot_sim", domain_id, work, ros_params(
                 robot=PINCHER, control_mode="torque", initial_positions=CENTRE_POSE) + namespace),
             NodeProcess("inverse_dynamics_learner", domain_id, work, ros_params(
                 robot=PINCHER, pid="[5.0, 0.01, 0.1]", centre_pose=CENTRE_POSE,
                 star_radius=0.05, regressor_params="'%s'" % json.dumps(   # a YAML string
                     {"init_D": 3.0, "init_alpha": 1.1})) + namespace)]
    client = ClientNode(domain_id, "learner_test_client")
    results = []
    client.node.create_subscription(TrialResult, "/pincher/trial_result", results.append, 10)
    run = client.action_client(RunTrials, "/pincher/inverse_dynamics_learner/run_trials")
    init = client.node.create_client(InitialiseLearner,
                                     "/pincher/inverse_dynamics_learner/initialise")
    try:
        yield client, run, init, results, nodes
    finally:
        client.close()
        for node in nodes:
            node.stop()


def test_learning_online_beats_pid_alone(learner):
    client, run, _, results, nodes = learner
    pid_only = client.run(run, RunTrials.Goal(n_trials=1, frozen=True), timeout=120)
    assert pid_only.success, pid_only.message + nodes[1].log()
    feedback = []
    learned = client.run(run, RunTrials.Goal(n_trials=2), timeout=120,
                         on_feedback=feedback.append)
    assert learned.success, learned.message
    # the action's feedback after each trial: its count and error, the robot's time
    assert [(f.trial, f.n_trials) for f in feedback] == [(1, 2), (2, 2)]
    assert [f.tracking_error for f in feedback] == list(learned.tracking_errors)
    assert feedback[-1].sim_time == pytest.approx(learned.sim_time)
    assert len(learned.tracking_errors) == 2
    # measured: PID alone 32 mm; learning online 10 mm in its first trial, 4 mm in its second
    assert learned.tracking_errors[1] < 0.5 * pid_only.tracking_errors[0]
    experience = from_matrix(learned.experience, "experience")
    assert experience.shape == (2 * 840, 16) and np.isfinite(experience).all()
    assert learned.sim_time == pytest.approx(3 * 8.4, abs=1e-6)   # resets keep the clock
    client.spin_until(lambda: len(results) >= 3, timeout=10, what="three TrialResults")
    last = results[-1]
    assert (last.trial, last.robot, last.task) == (3, "pincher_arm", "inverse_dynamics_learner")
    assert last.n_learned == 840
    assert last.tracking_error == pytest.approx(learned.tracking_errors[1])
    desired, actual = from_matrix(last.desired, "desired"), from_matrix(last.actual, "actual")
    assert desired.shape == actual.shape == (840, 3)
    assert np.linalg.norm(desired - actual, axis=1).mean() == pytest.approx(last.tracking_error)


def test_initialise_rejects_bad_samples_and_keeps_serving(learner):
    client, run, init, _, _ = learner
    wrong = client.call(init, InitialiseLearner.Request(samples=to_matrix(np.zeros((5, 12)))))
    assert not wrong.success and "4 x 4 columns" in wrong.message
    samples = np.tile(np.linspace(0.0, 0.1, 16), (6, 1))
    samples[2, 5] = np.nan
    samples[4, 0] = np.inf
    answer = client.call(init, InitialiseLearner.Request(samples=to_matrix(samples), reset=True))
    assert answer.success, answer.message
    assert (answer.n_learned, answer.n_rejected) == (4, 2)
    # a yielding prior (transfer-PA-yielding) needs a fresh learner: refused on a plain one
    mixed = client.call(init, InitialiseLearner.Request(samples=to_matrix(samples),
                                                        yielding=True))
    assert not mixed.success and "reset" in mixed.message
    prior = client.call(init, InitialiseLearner.Request(samples=to_matrix(samples), reset=True,
                                                        yielding=True))
    assert prior.success and (prior.n_learned, prior.n_rejected) == (4, 2), prior.message
    again = client.run(run, RunTrials.Goal(n_trials=1, frozen=True), timeout=120)
    assert again.success and len(again.tracking_errors) == 1


def test_run_trials_starts_from_the_offset_pose_and_refuses_bad_offsets(learner):
    """A seeded run's start (RunTrials.start_offset): the centre pose moved joint by joint;
    a wrong length, NaN or a pose outside the joint limits is refused, and the node serves on."""
    client, run, init, _, _ = learner
    frozen = lambda offset: client.run(run, RunTrials.Goal(   # noqa: E731
        n_trials=1, frozen=True, start_offset=offset), timeout=120)
    for offset, message in (([0.01, 0.0], "needs 4 finite joint values"),
                            ([0.0, float("nan"), 0.0, 0.0], "needs 4 finite joint values"),
                            ([0.0, 0.0, 0.0, 3.0], "outside the joint limits")):
        answer = frozen(offset)
        assert not answer.success and message in answer.message, answer.message
    assert client.call(init, InitialiseLearner.Request(samples=to_matrix(np.zeros((0, 16))),
                                                       reset=True)).success
    centre, again, moved = frozen([]), frozen([]), frozen([0.0, 0.05, -0.05, 0.0])
    assert centre.success and again.success and moved.success, moved.message
    assert again.tracking_errors == centre.tracking_errors        # deterministic
    assert moved.tracking_errors[0] > centre.tracking_errors[0]   # starts off the path
    q0 = from_matrix(moved.experience, "experience")[0, :4]
    assert q0 == pytest.approx([0.0, 0.65, 0.85, 0.6], abs=0.03)


def test_a_cancelled_goal_stops_between_trials_and_the_next_is_served(learner):
    """RunTrials is an action: a cancel sent after the first trial's feedback ends the goal
    canceled after that trial (not after all 5); a second goal while one runs is rejected;
    initialise is refused meanwhile; the learner then serves the next goal."""
    from action_msgs.msg import GoalStatus

    client, run, init, _, nodes = learner
    client.run(run, RunTrials.Goal(n_trials=0), timeout=60)     # server up, discovery done
    feedback = []
    sent = run.send_goal_async(RunTrials.Goal(n_trials=5), feedback_callback=feedback.append)
    handle = client.spin_until(lambda: sent.done() and sent.result(), timeout=30,
                               what="the goal accepted")
    assert handle.accepted
    second = run.send_goal_async(RunTrials.Goal(n_trials=1))
    assert not client.spin_until(lambda: second.done() and second.result(), timeout=30,
                                 what="the second goal answered").accepted
    busy = client.call(init, InitialiseLearner.Request(samples=to_matrix(np.zeros((0, 16)))))
    assert not busy.success and "run_trials goal is running" in busy.message
    client.spin_until(lambda: feedback, timeout=60, what="the first trial's feedback")
    handle.cancel_goal_async()
    done = handle.get_result_async()
    outcome = client.spin_until(lambda: done.done() and done.result(), timeout=60,
                                what="the cancelled goal's result")
    assert outcome.status == GoalStatus.STATUS_CANCELED
    assert not outcome.result.success and outcome.result.message.startswith("cancelled")
    assert 1 <= len(outcome.result.tracking_errors) < 5, outcome.result.message
    after = client.run(run, RunTrials.Goal(n_trials=1, frozen=True), timeout=120)
    assert after.success, after.message + nodes[1].log()


def test_run_actions_cancels_the_accepted_goals_when_one_is_refused(learner):
    """run_actions (the chapter 5 experiment's robots side by side) sends all goals before it
    waits: two goals to one learner, which runs one at a time, get one accepted and one
    refused; it raises on the refusal and cancels the accepted goal, which stops between
    trials (not after its 5), so the learner serves the next goal."""
    import time

    from lpa_transfer_nodes.calls import run_actions

    client, run, _, results, nodes = learner
    client.run(run, RunTrials.Goal(n_trials=0), timeout=60)     # server up, discovery done
    with pytest.raises(RuntimeError, match="rejected the goal"):
        run_actions(client.executor, [(run, RunTrials.Goal(n_trials=5), None),
                                      (run, RunTrials.Goal(n_trials=5), None)], 120)
    deadline = time.monotonic() + 60
    while True:                 # the cancelled goal ends after the trial it is in
        try:
            after = client.run(run, RunTrials.Goal(n_trials=1, frozen=True), timeout=120)
            break
        except RuntimeError as error:
            if "rejected" not in str(error) or time.monotonic() > deadline:
                raise
            time.sleep(0.2)
    assert after.success, after.message + nodes[1].log()
    client.spin_until(lambda: len(results) >= 2, timeout=10, what="the trial results")
    assert len(results) < 5 + 1, [r.trial for r in results]   # the first goal was cut short
