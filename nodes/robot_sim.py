"""robot_sim: a simulated robot (pybullet, :mod:`lpa_transfer.robots.simulator`) on ROS 2.

Run: ``robot_sim --ros-args -p robot:=scenarios/robots/two_link_source.toml`` (or
``python -m lpa_transfer_nodes.robot_sim ...``).

Lock-step mode (default): the service ``~/step`` (StepRobot) applies a command, advances
``n_steps`` physics steps and answers with the new state; ``~/reset`` (ResetRobot) puts the
robot at rest at a pose (the clock runs on). Why: the experiments (babbling, demonstrations,
evaluating transferred models) should run faster than real time and give the same numbers on
every run. When the caller advances the simulation, nothing depends on timers, CPU load or DDS
latency: the same sequence of requests always yields the same trajectory, as fast as the
machine can compute it.

Free-running mode (``lockstep:=false``): a timer advances the simulation so that simulated
time tracks wall time, with the latest command received on ``joint_commands``.

Both modes publish ``joint_states``, ``end_effector`` and the link frames on ``/tf`` (frames
``<frame_prefix><link>``, the base fixed to ``world`` on ``/tf_static``) after each advance,
stamped with the simulated time; the URDF goes out once, latched, on ``robot_description``
(std_msgs/String), so Foxglove's 3-D panel or RViz draws the robot as simulated. The
simulated time goes out as a ``rosgraph_msgs/Clock`` on ``clock_topic`` (default
``clock``: ``/clock`` for a robot in the root namespace, ``/<ns>/clock`` for a robot in a
namespace — two lock-step robots advance independently, so each has its own clock). A node
that stamps this robot's data runs with ``use_sim_time:=true`` and ``-r /clock:=<that topic>``,
so its ROS clock and the stamps agree; the scenarios do that. Bad requests are
refused and bad commands ignored (logged); neither touches the simulation, and the node keeps
serving.

Parameters, topics and services: docs/nodes.md.
"""
import math

from rclpy.node import Node
from rosgraph_msgs.msg import Clock
from geometry_msgs.msg import Point, PointStamped, TransformStamped
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray, String
from tf2_msgs.msg import TFMessage

from lpa_transfer.robots.simulator import (ACTUATORS, CONTROL_MODES, RobotSimulator,
                                          simulated_description)
from lpa_transfer_interfaces.srv import ResetRobot, StepRobot
from lpa_transfer_nodes.conversions import WORLD_FRAME, sim_stamp
from lpa_transfer_nodes.entry import FastExecutor, serve
from lpa_transfer_nodes.params import DOUBLES, declare_table, describe_use_sim_time
from lpa_transfer_nodes.qos import CLOCK_QOS, LATCHED_QOS, TF_QOS
from lpa_transfer_nodes.servers import answering


def parameters(namespace):
    """robot_sim's parameters as a table (:func:`~lpa_transfer_nodes.params.declare_table`);
    the TF frame prefix defaults to the node's ``namespace``."""
    return (
        ("robot", "", "robot parameter file (scenarios/robots/*.toml) or a URDF file (*.urdf: "
         "its serial chain from the root link); set exactly one of robot and urdf"),
        ("urdf", "", "a URDF file simulated as it is (its meshes and package:// paths "
         "resolved against its own folder), instead of robot"),
        ("tip_link", "", "the chain's last link: robot:=*.urdf reads the chain down to it, "
         "urdf:= takes its frame as the end effector; empty: the only leaf (robot), the "
         "last link (urdf)"),
        ("base_link", "", "robot:=*.urdf only: the chain's first link; empty: the root link"),
        ("repair_inertia", False, "URDF only: raise the smallest principal moment of each "
         "inertia that violates a rigid body's triangle inequality (logged per link); "
         "false: such a URDF is refused, naming the links"),
        ("control_mode", "position", "position: commands are joint targets (rad); torque: "
         "commands are joint torques (N m)", dict(choices=CONTROL_MODES)),
        ("physics_step", 1e-3, "the pybullet time step (s)", dict(positive=True, finite=True)),
        ("control_rate", 100.0, "free-running mode only: the timer's rate (Hz)",
         dict(positive=True, finite=True)),
        ("initial_positions", DOUBLES, "the initial pose (rad), also the pose of a ~/reset "
         "with empty positions; unset: zero clipped into the joint limits",
         dict(additional_constraints="one value per joint")),
        ("seed", 0, "seed passed to the simulator (which is deterministic)"),
        ("position_gain", 0.05, "the position motors' gain (pybullet's positionGains: the "
         "share of the position error removed per physics step; pybullet's own 0.1 can "
         "chatter)", dict(range=(0.0, 1.0), positive=True)),
        ("actuator", "torque", "torque mode only. torque: joint torques, with the robot file's "
         "armature and damping; velocity_motor: V-REP's torque mode (each joint's velocity "
         "motor towards its velocity limit, force capped at |torque|; no armature, no "
         "damping), as in thesis ch. 5", dict(choices=ACTUATORS)),
        ("lockstep", True, "true: lock-step, the ~/step and ~/reset services advance the "
         "simulation; false: free-running, a timer advances it in wall time with the latest "
         "joint_commands"),
        ("clock_topic", "clock", "where the simulated time is published (rosgraph_msgs/Clock) "
         "after every advance; relative names resolve in the robot's namespace; empty: not "
         "published"),
        ("frame_prefix", f"{namespace}/" if namespace else "", "prefix of the TF frame names "
         "of this robot's links (as robot_state_publisher's frame_prefix), so that robots "
         "sharing /tf keep their frames apart; default: the node's namespace without its "
         "leading '/', then '/' (empty in the root namespace)"),
        ("publish_tf", True, "publish the link frames on /tf after every advance (and the "
         "world -> base link transform on /tf_static)"))


class RobotSim(Node):
    def __init__(self):
        super().__init__("robot_sim")
        p = declare_table(self, parameters(self.get_namespace().strip("/")))
        self.lockstep, self.frame_prefix = p["lockstep"], p["frame_prefix"]
        describe_use_sim_time(self)
        robot, urdf = p["robot"], p["urdf"]
        description, tip_link, repairs = simulated_description(
            robot, urdf, p["tip_link"], p["base_link"], p["repair_inertia"])
        for line in repairs:
            self.get_logger().warning(f"{robot or urdf}: {line}")
        self.initial = p["initial_positions"] or None
        self.sim = RobotSimulator(description, control_mode=p["control_mode"],
                                  physics_step=p["physics_step"],
                                  initial_positions=self.initial, seed=p["seed"],
                                  position_gain=p["position_gain"], actuator=p["actuator"],
                                  tip_link=tip_link)
        self.joint_state_pub = self.create_publisher(JointState, "joint_states", 10)
        self.end_effector_pub = self.create_publisher(PointStamped, "end_effector", 10)
        self.clock_pub = (self.create_publisher(Clock, p["clock_topic"], CLOCK_QOS)
                          if p["clock_topic"] else None)
        # The URDF, latched, as robot_state_publisher offers it; Foxglove's 3-D panel draws it
        # with the TF frames below (docs/nodes.md).
        self.create_publisher(String, "robot_description", LATCHED_QOS).publish(
            String(data=description))
        # /tf only while someone listens (a lock-step period costs less without it)
        self.tf_pub = self.create_publisher(TFMessage, "/tf", TF_QOS) if p["publish_tf"] else None
        if p["publish_tf"]:
            self.tf_static_pub = self.create_publisher(TFMessage, "/tf_static", LATCHED_QOS)
            self.start_tf()
        mode = self.start_mode(p["control_mode"], p["control_rate"], p["physics_step"])
        self.get_logger().info(
            f"simulating {robot or urdf} ({p['control_mode']} control, joints "
            f"{self.sim.joint_names}, physics step {p['physics_step']} s), {mode}")
        self.publish(self.sim.state())

    def start_mode(self, control_mode, control_rate, physics_step):
        """Lock-step: the ~/step and ~/reset services; free-running: a timer and the
        joint_commands subscription. Returns the mode, as the start-up line says it."""
        if self.lockstep:
            self.create_service(StepRobot, "~/step", answering(self, "step", self.step_service))
            self.create_service(ResetRobot, "~/reset", answering(self, "reset",
                                                                 self.reset_service))
            return "lock-step"
        if not (math.isfinite(control_rate) and control_rate > 0):
            raise ValueError(f"control_rate must be a positive number of Hz, "
                             f"got {control_rate}")
        self.substeps = max(1, round(1.0 / (control_rate * physics_step)))
        state = self.sim.state()
        self.command = (list(state.positions) if control_mode == "position"
                        else [0.0] * self.sim.n_joints)
        self.create_subscription(Float64MultiArray, "joint_commands", self.on_command, 10)
        self.create_timer(1.0 / control_rate, self.on_timer)
        return f"free-running at {control_rate} Hz"

    def joint_state(self, state):
        msg = JointState()
        msg.header.stamp = sim_stamp(state.time)
        msg.name = list(self.sim.joint_names)
        msg.position, msg.velocity, msg.effort = (
            [float(v) for v in values]
            for values in (state.positions, state.velocities, state.efforts))
        return msg

    def transform(self, parent, child):
        """An empty TransformStamped from ``parent`` (None: the world) to ``child``."""
        msg = TransformStamped(child_frame_id=self.frame_prefix + child)
        msg.header.frame_id = WORLD_FRAME if parent is None else self.frame_prefix + parent
        return msg

    @staticmethod
    def set_transform(msg, stamp, translation, rotation):
        msg.header.stamp = stamp
        vector, quaternion = msg.transform.translation, msg.transform.rotation
        vector.x, vector.y, vector.z = (float(v) for v in translation)
        quaternion.x, quaternion.y, quaternion.z, quaternion.w = (float(v) for v in rotation)

    def start_tf(self):
        """Latch the world -> base link transform on /tf_static (the base is fixed) and make
        the TFMessage of the links that :meth:`tf_links` updates."""
        (_, base, translation, rotation), *links = self.sim.link_frames()
        static = self.transform(None, base)
        self.set_transform(static, sim_stamp(self.sim.time), translation, rotation)
        self.tf_static_pub.publish(TFMessage(transforms=[static]))
        self._tf = TFMessage(transforms=[self.transform(parent, child)
                                         for parent, child, _, _ in links])

    def tf_links(self, stamp):
        """Every link relative to its parent (:meth:`RobotSimulator.link_frames`) at
        ``stamp``: one TFMessage, made once and updated in place, which costs less than new
        messages at every lock-step period (bench/bench_control_period.py --no-tf)."""
        for msg, (_, _, translation, rotation) in zip(self._tf.transforms,
                                                      self.sim.link_frames()[1:]):
            self.set_transform(msg, stamp, translation, rotation)
        return self._tf

    def publish(self, state):
        joint_state = self.joint_state(state)
        if self.clock_pub is not None:
            self.clock_pub.publish(Clock(clock=joint_state.header.stamp))
        if self.tf_pub is not None and self.tf_pub.get_subscription_count():
            self.tf_pub.publish(self.tf_links(joint_state.header.stamp))
        self.joint_state_pub.publish(joint_state)
        point = PointStamped()
        point.header.stamp, point.header.frame_id = joint_state.header.stamp, WORLD_FRAME
        point.point = Point(x=float(state.end_effector[0]), y=float(state.end_effector[1]),
                            z=float(state.end_effector[2]))
        self.end_effector_pub.publish(point)
        return joint_state, point.point

    def step_service(self, request, response):
        response.sim_time = self.sim.time      # what a failed request reports
        state = self.sim.step(list(request.command), request.n_steps)
        response.joint_state, response.end_effector = self.publish(state)
        response.sim_time = state.time
        return f"advanced {max(1, request.n_steps)} step(s) to t={state.time:.6f} s"

    def reset_service(self, request, response):
        response.sim_time = self.sim.time
        state = self.sim.reset(list(request.positions) or self.initial, keep_time=True)
        response.joint_state, response.end_effector = self.publish(state)
        return f"reset to {[round(float(q), 6) for q in state.positions]} at t={state.time:.6f} s"

    def on_command(self, msg):
        command = list(msg.data)
        if len(command) != self.sim.n_joints or not all(map(math.isfinite, command)):
            self.get_logger().warning(
                f"ignoring joint command {command}: needs {self.sim.n_joints} finite values "
                f"(joints {self.sim.joint_names})", throttle_duration_sec=1.0)
            return
        self.command = command

    def on_timer(self):
        self.publish(self.sim.step(self.command, self.substeps))

    def destroy_node(self):
        self.sim.close()
        super().destroy_node()


def main(args=None):
    # The step service is the lock-step control loop's critical path: the fast executor.
    serve("robot_sim", lambda stop: RobotSim(), args, executor_class=FastExecutor)


if __name__ == "__main__":
    main()
