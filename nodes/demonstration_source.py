"""demonstration_source: the demonstrator's letters as joint trajectories (thesis §4.5, Fig. 4-9).

Run: ``demonstration_source --ros-args --params-file scenarios/lfd/config.yaml`` (or
``python -m lpa_transfer_nodes.demonstration_source ...``).

The node makes the demonstrations once at start (:func:`lpa_transfer.lfd.experiment.
demonstrations`: LASA shapes placed in a box of the demonstrator's task space and traced with
its IK) and publishes each on ``demonstrations`` (lpa_transfer_interfaces/msg/Demonstration),
reliable and transient local with a queue of all of them, so a subscriber that joins later
(the experiment, the recorder) still receives every one. It then keeps serving them until
SIGINT/SIGTERM. A shape the demonstrator cannot trace, or a bad parameter, stops the node at
start with the reason.

Parameters (frames, shapes, n_demos, n_samples, task box, ...): docs/nodes.md.
"""
import os
import time

from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

from lpa_transfer.lfd.demonstrations import LASA_DEMOS_PER_SHAPE, lasa_shape_names
from lpa_transfer.lfd.experiment import demonstrations, load_setup
from lpa_transfer_interfaces.msg import Demonstration
from lpa_transfer_nodes.conversions import to_matrix
from lpa_transfer_nodes.entry import serve
from lpa_transfer_nodes.params import declare, describe_use_sim_time


def demonstration_qos(count):
    """Reliable, transient local, deep enough for ``count`` demonstrations."""
    return QoSProfile(depth=max(1, count), reliability=ReliabilityPolicy.RELIABLE,
                      durability=DurabilityPolicy.TRANSIENT_LOCAL)


def demonstration_msg(body, demo, index, n_demos, stamp):
    """A :class:`lpa_transfer.lfd.experiment.Demonstration` as a message."""
    msg = Demonstration(body=body, shape=demo.shape, index=index, n_demos=n_demos,
                        times=[float(t) for t in demo.times], joints=to_matrix(demo.q),
                        points=to_matrix(demo.x))
    msg.header.stamp, msg.header.frame_id = stamp, "world"
    return msg


class DemonstrationSource(Node):
    def __init__(self):
        super().__init__("demonstration_source")
        frames = os.path.expanduser(declare(
            self, "frames", "", "the scenario's frames file (e.g. scenarios/lfd/frames.yaml): "
            "its demonstrator is the body that demonstrates; required"))
        if not frames:
            raise ValueError("parameter 'frames' (the scenario's frames file) is required")
        demonstrator = load_setup(frames, os.getcwd()).demonstrator
        shapes = list(declare(self, "shapes", ["LShape"], "LASA shape names",
                         additional_constraints="LASA names: " + ", ".join(lasa_shape_names())))
        n_demos = declare(self, "n_demos", 5, "demonstrations per shape",
                          range=(1, LASA_DEMOS_PER_SHAPE))
        box = tuple(list(declare(self, f"task_box_{end}", [0.0], f"the {end} corner of the "
                                 f"box the shapes are placed in (m, the demonstrator's world "
                                 f"frame); the default [0.0] is a placeholder: set both"))
                    for end in ("low", "high"))
        seed = declare(self, "layout_seed", 0, "seed of the shapes' placement in the box",
                       range=(0, None))
        n_samples = declare(self, "n_samples", 100, "samples per demonstration",
                            range=(3, None))
        n_joints = declare(self, "n_joints", 4, "the demonstrator's joints that move (its "
                           "first n)", range=(1, None))
        describe_use_sim_time(self)
        started = time.perf_counter()
        demos = demonstrations(demonstrator, shapes, box, seed=seed, n_demos=n_demos,
                               n_samples=n_samples, n_joints=n_joints)
        publisher = self.create_publisher(Demonstration, "demonstrations",
                                          demonstration_qos(len(demos)))
        stamp = self.get_clock().now().to_msg()
        for k, demo in enumerate(demos):
            publisher.publish(demonstration_msg(demonstrator.name, demo, k % n_demos, n_demos,
                                                stamp))
        self.get_logger().info(
            f"published {len(demos)} demonstrations by {demonstrator.name} ({len(shapes)} "
            f"shapes x {n_demos}, traced in {time.perf_counter() - started:.1f} s)")


def main(args=None):
    serve("demonstration_source", lambda stop: DemonstrationSource(), args)


if __name__ == "__main__":
    main()
