"""Transform trees read back from a bag (rosbags' deserialised geometry_msgs/TransformStamped):
the tests' own chaining, independent of the node's (which uses pybullet's transforms)."""
import numpy as np


def rotation_matrix(q):
    """The rotation matrix of a unit quaternion (x, y, z, w)."""
    x, y, z, w = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def pose(transform):
    """The 4x4 homogeneous matrix of a geometry_msgs/Transform."""
    t, r = transform.translation, transform.rotation
    matrix = np.eye(4)
    matrix[:3, :3] = rotation_matrix((r.x, r.y, r.z, r.w))
    matrix[:3, 3] = (t.x, t.y, t.z)
    return matrix


def world_poses(transforms, root="world"):
    """Every child frame's pose in ``root``, chaining ``transforms`` (TransformStamped); an
    AssertionError names the frames that have two parents or do not reach ``root``."""
    children = [t.child_frame_id for t in transforms]
    assert len(set(children)) == len(children), f"frames with two parents: {children}"
    poses, remaining = {root: np.eye(4)}, list(transforms)
    while remaining:
        ready = [t for t in remaining if t.header.frame_id in poses]
        assert ready, f"frames not connected to {root}: {[t.child_frame_id for t in remaining]}"
        for t in ready:
            poses[t.child_frame_id] = poses[t.header.frame_id] @ pose(t.transform)
            remaining.remove(t)
    return poses
