"""Conversions between numpy arrays or simulator states and ROS messages.

Matrix messages carry every point set of the graph (correspondences, experience, trials);
the conversions copy as little as rclpy allows.
"""
import array
import importlib

import numpy as np

from builtin_interfaces.msg import Time

from lpa_transfer.recording.bag import split_type_name
from lpa_transfer.robots.simulator import SimState
from lpa_transfer_interfaces.msg import Matrix

#: The frame of every pose and point the nodes publish (robot_sim's bases stand at its origin).
WORLD_FRAME = "world"


def to_matrix(values):
    """A Matrix message of a 2-D float64 array: one buffer copy into the ``array.array`` that
    rclpy takes without converting element by element (see the ROS notes)."""
    values = np.ascontiguousarray(values, dtype=np.float64)   # no copy when it already is
    data = array.array("d")
    data.frombytes(memoryview(values.reshape(-1)).cast("B"))
    return Matrix(rows=values.shape[0], cols=values.shape[1], data=data)


def from_matrix(msg, name):
    """The (rows, cols) array of a Matrix message; ValueError if rows*cols != len(data)."""
    return matrix_from_rows(msg.rows, msg.cols, msg.data, name)


def sim_stamp(seconds):
    """A builtin_interfaces/Time of a simulated time in seconds."""
    nanoseconds = int(round(seconds * 1e9))
    return Time(sec=nanoseconds // 1_000_000_000, nanosec=nanoseconds % 1_000_000_000)


def message_class(type_name):
    """The Python class of ``pkg/msg/Type`` (rosidl_runtime_py is not available as a wheel)."""
    package, name = split_type_name(type_name)
    return getattr(importlib.import_module(f"{package}.msg"), name)


def matrix_from_rows(rows, cols, data, name):
    """A (rows, cols) float64 view of row-major ``data``; ValueError if the sizes disagree."""
    if rows * cols != len(data):
        raise ValueError(f"{name}: rows*cols = {rows}*{cols} = {rows * cols} does not match "
                         f"the {len(data)} values in data")
    if isinstance(data, array.array) and data.typecode == "d":
        return np.frombuffer(data, dtype=np.float64).reshape(rows, cols)   # no copy
    return np.asarray(data, dtype=np.float64).reshape(rows, cols)


def sim_state(response):
    """The SimState of a StepRobot or ResetRobot answer."""
    state, point = response.joint_state, response.end_effector
    return SimState(response.sim_time, np.array(state.position), np.array(state.velocity),
                    np.array(state.effort), np.array([point.x, point.y, point.z]))
