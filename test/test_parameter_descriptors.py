"""Parameter descriptors (so ros2 param describe explains each one): every parameter of the
converted nodes, asked over the standard ``~/list_parameters`` and ``~/describe_parameters``
services of the running node, has a description, and those read only at start are flagged
read-only (so a change at run time is refused, not silently ignored); bounded ones carry their
range. A value outside the range at start is one FATAL line naming the parameter and what it
accepts, exit 1.

Nodes with one job (the collector, the scenario experiments) are asked while they wait for
services or messages that never come; they spin meanwhile (``wait_for_services`` with their
executor), so they answer.
"""
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import ROOT
from ros_harness import (ClientNode, NodeProcess, _terminate_with_parent, ros_env, ros_params,
                         run_to_end, unique_domain_id)

from rcl_interfaces.msg import Parameter, ParameterType, ParameterValue
from rcl_interfaces.srv import DescribeParameters, GetParameters, ListParameters, SetParameters

ROBOTS = ROOT / "scenarios" / "robots"
TWO_LINK = dict(source_robot=ROBOTS / "two_link_source.toml",
                target_robot=ROBOTS / "two_link_target.toml")
GOAL_BABBLING = dict(source_robot=ROBOTS / "goal_babbling_source.toml",
                     target_robot=ROBOTS / "goal_babbling_target.toml")
FRAMES = ROOT / "scenarios" / "lfd" / "frames.yaml"
#: rclpy's own parameters: use_sim_time stays writable (its time source follows it).
WRITABLE = {"use_sim_time"}


class ScriptProcess(NodeProcess):
    """A scenario script (``python <script>``) run from the repository root, as run.sh does."""

    def __init__(self, script, domain_id, log_dir, args=(), name=None):
        self.module, self.log_dir = Path(script).stem, Path(log_dir)
        self.log_dir.mkdir(parents=True, exist_ok=True)
        self.log_path = self.log_dir / f"{name or self.module}.log"
        self._log = open(self.log_path, "ab")
        self.process = subprocess.Popen(
            [sys.executable, str(script), *args], cwd=ROOT,
            env=ros_env(domain_id, self.log_dir), stdout=self._log, stderr=subprocess.STDOUT,
            start_new_session=True, preexec_fn=_terminate_with_parent)


def node(module, **params):
    return lambda domain_id, work: NodeProcess(module, domain_id, work, ros_params(**params))


def script(path, *extra, **params):
    return lambda domain_id, work: ScriptProcess(ROOT / path, domain_id, work,
                                                 [*extra, *ros_params(**params)])


def player(domain_id, work):
    """A player of a one-message bag that waits (60 s) for a subscriber nobody starts."""
    from lpa_transfer.recording.bag import BagWriter
    from rclpy.serialization import serialize_message
    from std_msgs.msg import String

    path = work / "one.mcap"
    writer = BagWriter(path)
    writer.add_topic("/chatter", "std_msgs/msg/String")
    writer.write("/chatter", serialize_message(String(data="hello")), 1)
    writer.close()
    return NodeProcess("player", domain_id, work, ros_params(input=path, wait_timeout=60.0))


#: (node name, how to start it, parameters it must have among others). The job nodes wait
#: (for robots, learners or demonstrations that are not there) long enough to be asked.
NODES = {
    "robot_sim": ("/robot_sim", node("robot_sim", robot=ROBOTS / "two_link_source.toml"),
                  {"robot", "urdf", "control_mode", "physics_step", "control_rate",
                   "initial_positions", "seed", "position_gain", "lockstep"}),
    "lpa_mapping": ("/lpa_mapping", lambda domain_id, work: NodeProcess(
        "lpa_mapping", domain_id, work, ros_params(model_dir=work / "models")), {"model_dir"}),
    "correspondence_collector": (
        "/correspondence_collector",
        node("correspondence_collector", **TWO_LINK, wait_timeout=120.0),
        {"source_robot", "target_robot", "pairing_rule", "program", "n_segments", "time_law",
         "max_bad_share", "features", "cluster_dims", "wait_timeout", "source_pid"}),
    "guided_collector": (
        "/correspondence_collector",
        node("correspondence_collector", **GOAL_BABBLING, program="goal_babbling",
             x_low="[0.0, -1.1]", x_high="[1.1, 0.4]", wait_timeout=120.0),
        {"guided_seconds", "x_low", "x_high", "source_joints", "target_range", "sigma",
         "p_home", "source_reset"}),
    "demonstration_source": (
        "/demonstration_source",
        node("demonstration_source", frames=FRAMES, shapes="[LShape]", n_demos=1, n_samples=10,
             task_box_low="[0.25, -0.15, -0.05]", task_box_high="[0.40, 0.10, 0.20]"),
        {"frames", "shapes", "n_demos", "n_samples", "task_box_low", "task_box_high",
         "layout_seed", "n_joints"}),
    "goal_babbling_learner": (
        "/goal_babbling_learner",
        node("goal_babbling_learner", robot=ROBOTS / "goal_babbling_target.toml",
             x_low="[0.1, -1.1]", x_high="[1.1, 0.4]", eval_spacing=0.1),
        {"robot", "home", "active_joints", "x_low", "n_subtargets", "p_home", "guard_params",
         "eval_low", "reaching_threshold", "step_service"}),
    "skill_learner": (
        "/skill_learner", node("skill_learner", robot=ROBOTS / "meka_right_arm.toml"),
        {"robot", "n_joints", "dmp_weights_per_joint", "dmp_alpha_z", "physics_step",
         "settle_steps", "call_timeout", "reset_service"}),
    "inverse_dynamics_learner": (
        "/inverse_dynamics_learner",
        node("inverse_dynamics_learner", robot=ROBOTS / "pincher_arm.toml", pid="[5.0, 0.01, 0.1]",
             centre_pose="[0.0, 0.6, 0.9, 0.6]"),
        {"robot", "pid", "centre_pose", "control_rate", "star_radius", "star_time_law",
         "regressor", "regressor_params", "call_timeout", "step_service", "reset_service"}),
    "inverse_dynamics_experiment": (
        "/experiment",
        script("scenarios/inverse_dynamics/run_experiment.py", "pairs_0.npz",
               robot_files="[scenarios/robots/youbot_arm.toml, scenarios/robots/pincher_arm.toml]"),
        {"robots", "robot_files", "targets", "seeds", "conditions", "n_trials", "latent_dim",
         "start_noise", "interpolation", "babbling_line_samples", "call_timeout"}),
    "recorder": ("/recorder", lambda domain_id, work: NodeProcess(
        "recorder", domain_id, work, ros_params(output=work / "run.mcap")),
        {"output", "topics", "topic_regex", "exclude", "include_hidden_topics", "qos_depth"}),
    "player": ("/player", player, {"input", "rate", "loop", "wait_for_subscribers",
                                   "wait_timeout", "clock"}),
    "goal_babbling_experiment": (
        "/experiment",
        script("scenarios/goal_babbling/run_experiment.py", "guided_0.npz", **GOAL_BABBLING),
        {"seeds", "guided_seconds", "methods", "guarded", "thesis", "n_min", "call_timeout"}),
    "lfd_experiment": (
        "/experiment", script("scenarios/lfd/run_experiment.py", frames=FRAMES,
                              wait_timeout=120.0),
        {"frames", "shapes", "n_demos", "graph_pairs", "graph_n_min", "teacher", "learner"}),
    "transfer_evaluation": (
        "/transfer_evaluation",
        script("scenarios/two_link_graph/evaluate_transfer.py", **TWO_LINK, wait_timeout=120.0),
        {"model_id", "correspondence_file", "n_segments", "n_test", "transfer_service"}),
}


def describe(client, name, timeout=60.0):
    """{parameter name: ParameterDescriptor} of every parameter of the running node ``name``."""
    lister = client.node.create_client(ListParameters, f"{name}/list_parameters")
    names = list(client.call(lister, ListParameters.Request(), timeout).result.names)
    describer = client.node.create_client(DescribeParameters, f"{name}/describe_parameters")
    descriptors = client.call(describer, DescribeParameters.Request(names=names)).descriptors
    return dict(zip(names, descriptors))


@pytest.mark.parametrize("case", sorted(NODES))
def test_every_parameter_is_described(tmp_path, case):
    name, start, expected = NODES[case]
    domain_id = unique_domain_id()
    process = start(domain_id, tmp_path)
    client = ClientNode(domain_id, "descriptor_client")
    try:
        descriptors = describe(client, name)
        assert process.alive(), process.log()
    finally:
        client.close()
        process.stop()
    assert expected <= set(descriptors), sorted(expected - set(descriptors))
    undescribed = sorted(n for n, d in descriptors.items() if not d.description.strip())
    assert not undescribed, f"{case}: parameters without a description: {undescribed}"
    writable = sorted(n for n, d in descriptors.items() if not d.read_only)
    assert set(writable) <= WRITABLE, f"{case}: parameters not flagged read-only: {writable}"


def test_ranges_and_choices_are_in_the_descriptors(tmp_path):
    domain_id = unique_domain_id()
    name, start, _ = NODES["correspondence_collector"]
    process = start(domain_id, tmp_path)
    client = ClientNode(domain_id, "descriptor_client")
    try:
        descriptors = describe(client, name)
    finally:
        client.close()
        process.stop()
    n_segments = descriptors["n_segments"]
    assert n_segments.type == ParameterType.PARAMETER_INTEGER
    assert n_segments.integer_range[0].from_value == 1
    assert n_segments.additional_constraints == "an integer >= 1"
    share = descriptors["max_bad_share"].floating_point_range[0]
    assert (share.from_value, share.to_value) == (0.0, 1.0)
    rule = descriptors["pairing_rule"].additional_constraints
    assert all(choice in rule for choice in ("same_command", "same_time_index",
                                             "same_task_point")), rule
    assert descriptors["source_home"].type == ParameterType.PARAMETER_DOUBLE_ARRAY


@pytest.mark.parametrize("module, params, message", [
    ("robot_sim", dict(robot=ROBOTS / "two_link_source.toml", physics_step=-0.001),
     "the parameter physics_step must be a finite number > 0, got -0.001"),
    ("robot_sim", dict(robot=ROBOTS / "two_link_source.toml", control_mode="velocity"),
     "the parameter control_mode must be one of 'position', 'torque', got 'velocity'"),
    ("robot_sim", dict(robot=ROBOTS / "two_link_source.toml", seed=1.5),
     "the parameter seed must be an integer, got 1.5"),
    ("correspondence_collector", dict(**TWO_LINK, n_segments=0),
     "the parameter n_segments must be an integer >= 1, got 0"),
    ("goal_babbling_learner", dict(robot=ROBOTS / "goal_babbling_target.toml",
                                   x_low="[0.1, -1.1]", x_high="[1.1, 0.4]", p_home=1.5),
     "the parameter p_home must be a number in [0, 1], got 1.5"),
])
def test_a_value_out_of_range_at_start_is_one_fatal_line(tmp_path, module, params, message):
    process = NodeProcess(module, unique_domain_id(), tmp_path, ros_params(**params))
    assert run_to_end(process, timeout=60) == 1, process.log()
    log = process.log()
    fatal = [line for line in log.splitlines() if "FATAL" in line]
    assert len(fatal) == 1 and message in fatal[0], log
    assert "Traceback" not in log


def test_a_read_only_parameter_is_refused_at_run_time(tmp_path):
    """The issue's case: setting lpa_mapping's model_dir at run time answered success and
    changed nothing; now it is refused and the value stays."""
    domain_id = unique_domain_id()
    mapping = NodeProcess("lpa_mapping", domain_id, tmp_path,
                          ros_params(model_dir=tmp_path / "models"))
    client = ClientNode(domain_id, "descriptor_client")
    try:
        setter = client.node.create_client(SetParameters, "/lpa_mapping/set_parameters")
        value = ParameterValue(type=ParameterType.PARAMETER_STRING,
                               string_value=str(tmp_path / "elsewhere"))
        answer = client.call(setter, SetParameters.Request(
            parameters=[Parameter(name="model_dir", value=value)]), timeout=60.0)
        getter = client.node.create_client(GetParameters, "/lpa_mapping/get_parameters")
        kept = client.call(getter, GetParameters.Request(names=["model_dir"])).values[0]
    finally:
        client.close()
        assert mapping.stop() == 0, mapping.log()
    result = answer.results[0]
    assert not result.successful and "read-only" in result.reason, result
    assert kept.string_value == str(tmp_path / "models")
