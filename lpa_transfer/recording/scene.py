"""A picture of the robots in a recorded bag, drawn from what Foxglove's 3-D panel reads.

Each ``robot_sim`` publishes its URDF on ``/<robot>/robot_description``, the base fixed to
``world`` on ``/tf_static`` and every link relative to its parent on ``/tf`` (frames
``<robot>/<link>``). :func:`robot_poses` chains those transforms of one moment into world
poses, as a TF listener would; :func:`render` draws each robot as a stick figure (a line from
every link frame's parent to it) with its end effector's recent path and the latest task
markers of its learners (``/<robot>/.../task_markers``: lines and point lists), one panel per
robot, so that a run can be looked at without Foxglove and the picture checks what Foxglove
would show.

The simulator's world has gravity along -y (``lpa_transfer.robots.planar_chain``): the
figure draws y upwards.

Usage: ``python -m lpa_transfer.recording.scene BAG.mcap OUT.png [--at SECONDS] [--trail S]``.
"""
import argparse
import re
import sys
from pathlib import Path

import numpy as np

from lpa_transfer.recording.bag import BagError, decoded_messages, summary

DESCRIPTION = re.compile(r"^/(?P<robot>.+)/robot_description$")
MARKERS = re.compile(r"^/(?P<robot>[^/]+)/(.+/)?task_markers$")
LINE_STRIP, SPHERE_LIST = 4, 7         # visualization_msgs/Marker types drawn


def _seconds(stamp):
    return stamp.sec + 1e-9 * stamp.nanosec


def _matrix(transform):
    """The 4x4 pose of a geometry_msgs/Transform (unit quaternion x, y, z, w)."""
    t, q = transform.translation, transform.rotation
    x, y, z, w = q.x, q.y, q.z, q.w
    matrix = np.eye(4)
    matrix[:3, :3] = [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                      [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                      [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]
    matrix[:3, 3] = (t.x, t.y, t.z)
    return matrix


def chain(transforms, root="world"):
    """``{frame: (parent, 4x4 pose in root)}`` of ``transforms`` (TransformStamped-like);
    ValueError when a frame has two parents or does not reach ``root``."""
    parents = {}
    for transform in transforms:
        child = transform.child_frame_id
        if child in parents:
            raise ValueError(f"frame {child!r} has two parents")
        parents[child] = (transform.header.frame_id, _matrix(transform.transform))
    poses = {root: (None, np.eye(4))}
    while len(poses) < len(parents) + 1:
        ready = [c for c, (p, _) in parents.items() if c not in poses and p in poses]
        if not ready:
            lost = sorted(set(parents) - set(poses))
            raise ValueError(f"frames not connected to {root!r}: {lost}")
        for child in ready:
            parent, relative = parents[child]
            poses[child] = (parent, poses[parent][1] @ relative)
    return poses


def robot_poses(path, at=None, trail=10.0):
    """Each robot of the bag at simulated time ``at`` (s; default: its last state):
    ``{robot: dict(time, urdf, frames={frame: (parent, pose)}, trail=(N, 3), markers)}``,
    ``trail`` the end effector's positions over the ``trail`` seconds before, ``markers`` the
    LINE_STRIP and SPHERE_LIST markers of the robot's latest task_markers arrays. BagError
    when the bag has no robot_description, or a robot no transforms up to ``at``."""
    recorded = summary(path)
    robots = sorted(m.group("robot") for topic in recorded if (m := DESCRIPTION.match(topic)))
    if not robots:
        raise BagError(f"{path}: no /<robot>/robot_description topic: nothing to draw (was "
                       "robot_sim's publish_tf on and the topic recorded?)")
    marker_topics = [topic for topic in recorded if (m := MARKERS.match(topic))
                     and m.group("robot") in robots]
    topics = ["/tf", "/tf_static", *(f"/{r}/robot_description" for r in robots),
              *(f"/{r}/end_effector" for r in robots), *marker_topics]
    static, latest, urdf, points = [], {}, {}, {r: [] for r in robots}
    markers = {}
    for topic, _, message in decoded_messages(path, topics):
        if topic in marker_topics:
            added = [m for m in message.markers if m.type in (LINE_STRIP, SPHERE_LIST)]
            if added and (at is None or _seconds(added[0].header.stamp) <= at):
                markers[topic] = added
        elif topic == "/tf_static":
            static.extend(message.transforms)
        elif topic == "/tf":
            if not message.transforms:
                continue
            stamp = _seconds(message.transforms[0].header.stamp)
            robot = message.transforms[0].child_frame_id.split("/", 1)[0]
            if robot in points and (at is None or stamp <= at):
                latest[robot] = (stamp, message.transforms)
        elif topic.endswith("/robot_description"):
            urdf[topic.split("/")[1]] = message.data
        else:
            stamp, p = _seconds(message.header.stamp), message.point
            if at is None or stamp <= at:
                points[topic.split("/")[1]].append((stamp, p.x, p.y, p.z))
    scene = {}
    for robot in robots:
        if robot not in latest:
            raise BagError(f"{path}: no /tf transforms of {robot!r}"
                           + (f" up to t = {at} s" if at is not None else ""))
        stamp, transforms = latest[robot]
        own_static = [t for t in static if t.child_frame_id.startswith(f"{robot}/")]
        track = np.array([p[1:] for p in points[robot] if stamp - trail <= p[0] <= stamp])
        scene[robot] = dict(time=stamp, urdf=urdf[robot],
                            frames=chain(own_static + list(transforms)),
                            trail=track.reshape(-1, 3),
                            markers=[marker for topic, added in sorted(markers.items())
                                     if MARKERS.match(topic).group("robot") == robot
                                     for marker in added])
    return scene


def render(path, output, at=None, trail=10.0):
    """Draw :func:`robot_poses` into the PNG ``output``, one 3-D panel per robot; returns the
    scene it drew."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    scene = robot_poses(path, at, trail)
    figure = plt.figure(figsize=(5.5 * len(scene), 5.5))
    for index, (robot, view) in enumerate(scene.items(), start=1):
        axes = figure.add_subplot(1, len(scene), index, projection="3d")
        points = []
        for frame, (parent, pose) in view["frames"].items():
            if parent in (None, "world"):
                continue
            a, b = view["frames"][parent][1][:3, 3], pose[:3, 3]
            axes.plot([a[0], b[0]], [a[2], b[2]], [a[1], b[1]], color="tab:blue", lw=3)
            points.append(b)
        points = np.array(points)
        axes.scatter(points[:, 0], points[:, 2], points[:, 1], color="k", s=12,
                     label="link frames (TF)")
        if len(view["trail"]):
            path_ = view["trail"]
            axes.plot(path_[:, 0], path_[:, 2], path_[:, 1], color="0.55", lw=0.8,
                      label=f"end effector, last {trail:g} s")
        drawn = []
        for marker in view["markers"]:
            xyz = np.array([(p.x, p.y, p.z) for p in marker.points]).reshape(-1, 3)
            drawn.append(xyz)
            if marker.type == LINE_STRIP:
                c = marker.color
                axes.plot(xyz[:, 0], xyz[:, 2], xyz[:, 1], color=(c.r, c.g, c.b), lw=1.2,
                          label=f"task: {marker.ns}")
            else:
                colours = [(c.r, c.g, c.b) for c in marker.colors] or "k"
                axes.scatter(xyz[:, 0], xyz[:, 2], xyz[:, 1], c=colours, s=6,
                             label=f"task: {marker.ns}")
        everything = np.vstack([points, view["trail"], np.zeros((1, 3)), *drawn])
        centre = (everything.max(0) + everything.min(0)) / 2
        half = max(float((everything.max(0) - everything.min(0)).max()) / 2, 0.05)
        axes.set_xlim(centre[0] - half, centre[0] + half)
        axes.set_ylim(centre[2] - half, centre[2] + half)
        axes.set_zlim(centre[1] - half, centre[1] + half)
        axes.set_xlabel("x (m)")
        axes.set_ylabel("z (m)")
        axes.set_zlabel("y (m, up)")
        axes.view_init(elev=15, azim=-75)      # nearly facing the x-y plane the arms move in
        axes.set_title(f"{robot} at t = {view['time']:.2f} s (simulated)")
        axes.legend(loc="upper left", fontsize=8)
    figure.suptitle(f"{Path(path).name}: robot_description, /tf and task_markers, as "
                    "Foxglove's 3-D panel reads them", fontsize=10)
    figure.tight_layout()
    figure.savefig(output, dpi=100)
    plt.close(figure)
    return scene


def _main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("bag")
    parser.add_argument("output", help="the PNG to write")
    parser.add_argument("--at", type=float, default=None,
                        help="simulated time (s) to draw; default: each robot's last state")
    parser.add_argument("--trail", type=float, default=10.0,
                        help="seconds of end-effector path drawn before that time")
    args = parser.parse_args(argv)
    try:
        scene = render(args.bag, args.output, args.at, args.trail)
    except (BagError, OSError, ValueError) as error:
        print(f"error: {error}", file=sys.stderr)
        return 1
    for robot, view in scene.items():
        print(f"{robot}: {len(view['frames']) - 1} frames at t = {view['time']:.3f} s")
    print(f"wrote {args.output}")
    return 0


if __name__ == "__main__":
    sys.exit(_main())
