"""Task paths as visualization_msgs/MarkerArray, so Foxglove's 3-D panel and RViz draw them.

The learners publish what their robot is asked to do and what it did on ``~/task_markers``
(``/<robot>/<learner>/task_markers``; latched, so a late viewer or the recorder gets the
latest arrays): the chapter 5 star (desired path and the last trial's path), the chapter 6
test points of the last evaluation (green: reached within the threshold, red: not), the
chapter 4 letters as executed. All in frame ``world``, the frame of robot_sim's ``end_effector`` and ``/tf``.
Each array is complete: a viewer shows the latest array and needs nothing before it.
"""
import numpy as np
from geometry_msgs.msg import Point
from std_msgs.msg import ColorRGBA
from visualization_msgs.msg import Marker, MarkerArray

from lpa_transfer_nodes.conversions import WORLD_FRAME
from lpa_transfer_nodes.qos import MARKERS_QOS

TOPIC = "~/task_markers"   # one topic per learner: its DELETEALL clears only its own
DESIRED, ACTUAL = (0.12, 0.47, 0.71, 1.0), (0.84, 0.15, 0.16, 1.0)
REACHED, MISSED = (0.17, 0.63, 0.17, 0.9), (0.84, 0.15, 0.16, 0.9)


def _marker(kind, namespace, marker_id, stamp, scale):
    marker = Marker(type=kind, action=Marker.ADD, ns=namespace, id=marker_id)
    marker.header.stamp, marker.header.frame_id = stamp, WORLD_FRAME
    marker.pose.orientation.w = 1.0
    marker.scale.x = marker.scale.y = marker.scale.z = float(scale)
    return marker


def _points(points):
    points = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    return [Point(x=float(x), y=float(y), z=float(z)) for x, y, z in points]


def line_strip(namespace, marker_id, points, rgba, stamp, width=0.002):
    """A LINE_STRIP through ``points`` (N, 3) in the world frame; ``width`` in m."""
    marker = _marker(Marker.LINE_STRIP, namespace, marker_id, stamp, width)
    marker.points = _points(points)
    marker.color = ColorRGBA(r=rgba[0], g=rgba[1], b=rgba[2], a=rgba[3])
    return marker


def sphere_list(namespace, marker_id, points, colours, stamp, diameter=0.01):
    """A SPHERE_LIST at ``points`` (N, 3), one RGBA of ``colours`` (N, 4) each."""
    marker = _marker(Marker.SPHERE_LIST, namespace, marker_id, stamp, diameter)
    marker.points = _points(points)
    marker.colors = [ColorRGBA(r=float(c[0]), g=float(c[1]), b=float(c[2]), a=float(c[3]))
                     for c in np.asarray(colours, dtype=np.float64).reshape(-1, 4)]
    marker.color = marker.colors[0] if marker.colors else ColorRGBA(a=1.0)
    return marker


def marker_array(*markers):
    """A MarkerArray that first clears what the topic showed before (DELETEALL), then adds
    ``markers``: each array stands alone."""
    clear = Marker(action=Marker.DELETEALL)
    clear.header.frame_id = WORLD_FRAME
    return MarkerArray(markers=[clear, *markers])


def task_marker_publisher(node):
    """The node's latched ``~/task_markers`` publisher: the latest arrays reach subscribers
    that join later (the recorder, a viewer); see MARKERS_QOS."""
    return node.create_publisher(MarkerArray, TOPIC, MARKERS_QOS)
