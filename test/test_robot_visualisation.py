"""What Foxglove and RViz need to draw a simulated robot, over real DDS and
read back from the recorder's bag by an independent reader (rosbags, with its own Jazzy type
store): the latched URDF on robot_description, the base fixed to the world on /tf_static, and
at every published robot state a transform for every link on /tf, which chained from the world
put the last link where end_effector says it is."""
import re
import signal

import numpy as np
import pytest

from conftest import ROOT
from tf_tree import world_poses
from lpa_transfer.robots.params import load_robot_params
from lpa_transfer.robots.simulator import robot_urdf
from ros_harness import ClientNode, NodeProcess, ros_params, unique_domain_id, wait_until

from lpa_transfer_interfaces.srv import StepRobot

from rosbags.rosbag2 import Reader
from rosbags.typesys import Stores, get_typestore

ROBOT = ROOT / "scenarios" / "robots" / "youbot_arm.toml"
STEPS = 15


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("visualisation")
    domain_id, output = unique_domain_id(), tmp / "robot.mcap"
    sim = NodeProcess("robot_sim", domain_id, tmp,
                      ros_params(robot=ROBOT, control_mode="position") + ["-r", "__ns:=/youbot"])
    recorder = NodeProcess("recorder", domain_id, tmp, ros_params(output=output,
                                                                  discovery_period=0.1))
    client = ClientNode(domain_id, "visualisation_test")
    try:
        step = client.node.create_client(StepRobot, "/youbot/robot_sim/step")
        for topic in ("/tf", "/tf_static", "/youbot/robot_description", "/youbot/joint_states",
                      "/youbot/end_effector"):
            wait_until(lambda: client.node.count_subscribers(topic) >= 1,
                       what=f"the recorder's subscription to {topic}")
        n_joints = load_robot_params(ROBOT).n_joints
        for k in range(STEPS):
            command = [0.3 * np.sin(0.4 * k + j) for j in range(n_joints)]
            assert client.call(step, StepRobot.Request(command=command, n_steps=20)).success
        client.spin_for(0.5)
    finally:
        client.close()
        assert recorder.stop(signal.SIGINT) == 0, recorder.log()
        sim.stop()
    store = get_typestore(Stores.ROS2_JAZZY)
    messages = {}
    with Reader(output) as reader:
        for connection, _, raw in reader.messages():
            messages.setdefault(connection.topic, []).append(
                store.deserialize_cdr(raw, connection.msgtype))
    return messages


def stamp_ns(stamp):
    return stamp.sec * 10**9 + stamp.nanosec


def test_the_description_is_the_simulated_urdf(recorded):
    assert [m.data for m in recorded["/youbot/robot_description"]] == [
        robot_urdf(load_robot_params(ROBOT))]


def test_every_state_has_a_complete_tree_that_ends_at_the_end_effector(recorded):
    static = [t for m in recorded["/tf_static"] for t in m.transforms]
    assert [(t.header.frame_id, t.child_frame_id) for t in static] == [("world", "youbot/base")]
    links = {stamp_ns(m.transforms[0].header.stamp): m.transforms for m in recorded["/tf"]}
    states = recorded["/youbot/joint_states"]
    assert len(states) >= STEPS                     # (the one at start may precede the recorder)
    end_effectors = {stamp_ns(m.header.stamp): m.point for m in recorded["/youbot/end_effector"]}
    description = recorded["/youbot/robot_description"][0].data
    frames = {"world"} | {f"youbot/{link}" for link in re.findall(r'<link name="([^"]+)"',
                                                                   description)}
    moved = set()
    for state in states:
        stamp = stamp_ns(state.header.stamp)
        transforms = links[stamp]                      # a tree at every robot state
        assert all(stamp_ns(t.header.stamp) == stamp for t in transforms)
        world = world_poses(list(transforms) + static)
        assert set(world) == frames                    # every link of the URDF, no other
        last = transforms[-1].child_frame_id
        point = end_effectors[stamp]
        assert np.allclose(world[last][:3, 3], (point.x, point.y, point.z), atol=1e-6)
        moved.add(tuple(np.round(world[last][:3, 3], 4)))
    assert len(moved) > STEPS // 2                     # the arm moved: the tree followed it
