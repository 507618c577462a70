"""Robot parameter files (TOML) for the source and target robots.

A file describes a planar serial chain as in the thesis' Table 3.1 (§3.6)::

    name = "two_link_source"
    source = "Makondo, PhD thesis, §3.6, Table 3.1 (source robot)"
    [[links]]
    length = 0.3          # m
    [[joints]]
    lower = 0.0           # rad
    upper = 1.5707963

with one ``[[joints]]`` table per ``[[links]]`` table (joint i moves link i). Optional keys,
needed only by the dynamics simulator (:mod:`lpa_transfer.simulator`)::

    [[links]]
    mass = 0.6            # kg, default DEFAULT_LINK_MASS (1 kg)
    [[joints]]
    effort = 10.0         # N·m, default DEFAULT_EFFORT_LIMIT (100 N·m)

Other keys are ignored, so files can grow (inertias, ...) without breaking this loader.
"""
import dataclasses
import numbers
import tomllib
from pathlib import Path

import numpy as np

#: Link mass (kg) when a ``[[links]]`` table has no ``mass``.
DEFAULT_LINK_MASS = 1.0
#: Joint effort limit (N·m) when a ``[[joints]]`` table has no ``effort`` (as planar_chain_urdf).
DEFAULT_EFFORT_LIMIT = 100.0


@dataclasses.dataclass(frozen=True, eq=False)
class RobotParams:
    """A robot read from a parameter file; the arrays are read-only."""

    name: str
    link_lengths: np.ndarray   # (n,) m
    joint_limits: np.ndarray   # (n, 2) rad, columns (lower, upper)
    source: str                # where the numbers come from (e.g. a thesis table)
    link_masses: np.ndarray = None    # (n,) kg; None -> DEFAULT_LINK_MASS each
    effort_limits: np.ndarray = None  # (n,) N·m; None -> DEFAULT_EFFORT_LIMIT each

    def __post_init__(self):
        n_links = len(self.link_lengths)
        if self.link_masses is None:
            object.__setattr__(self, "link_masses", [DEFAULT_LINK_MASS] * n_links)
        if self.effort_limits is None:
            object.__setattr__(self, "effort_limits", [DEFAULT_EFFORT_LIMIT] * n_links)
        for field in ("link_lengths", "joint_limits", "link_masses", "effort_limits"):
            array = np.array(getattr(self, field), dtype=np.float64)
            array.setflags(write=False)
            object.__setattr__(self, field, array)

    @property
    def n_joints(self):
        return len(self.link_lengths)


def _number(table, key, where):
    value = table.get(key)
    if value is None:
        raise ValueError(f"{where}: missing key '{key}'")
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not np.isfinite(value):
        raise ValueError(f"{where}: key '{key}' must be a finite number, got {value!r}")
    return float(value)


def _tables(data, key, path):
    tables = data.get(key)
    if not isinstance(tables, list) or not tables or not all(isinstance(t, dict)
                                                            for t in tables):
        raise ValueError(f"{path}: missing or empty '[[{key}]]' tables")
    return tables


def _optional_positive(table, key, default, where):
    if key not in table:
        return default
    value = _number(table, key, where)
    if value <= 0:
        raise ValueError(f"{where}: key '{key}' must be positive, got {value}")
    return value


def load_robot_params(path):
    """Read and validate a robot parameter file; errors name the file and the key."""
    path = Path(path)
    try:
        with path.open("rb") as handle:
            data = tomllib.load(handle)
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"{path}: not valid TOML: {exc}") from None
    for key in ("name", "source"):
        if not isinstance(data.get(key), str) or not data[key].strip():
            raise ValueError(f"{path}: missing key '{key}' (a non-empty string)")
    links, joints = _tables(data, "links", path), _tables(data, "joints", path)
    if len(links) != len(joints):
        raise ValueError(f"{path}: {len(links)} [[links]] but {len(joints)} [[joints]]; a "
                         "serial chain needs one joint per link")
    lengths, masses, efforts = [], [], []
    for i, link in enumerate(links):
        masses.append(_optional_positive(link, "mass", DEFAULT_LINK_MASS,
                                         f"{path}: links[{i}]"))
        length = _number(link, "length", f"{path}: links[{i}]")
        if length <= 0:
            raise ValueError(f"{path}: links[{i}]: key 'length' must be positive, got {length}")
        lengths.append(length)
    limits = []
    for i, joint in enumerate(joints):
        where = f"{path}: joints[{i}]"
        lower, upper = _number(joint, "lower", where), _number(joint, "upper", where)
        if lower > upper:
            raise ValueError(f"{where}: key 'lower' ({lower}) is greater than 'upper' ({upper})")
        limits.append((lower, upper))
        efforts.append(_optional_positive(joint, "effort", DEFAULT_EFFORT_LIMIT, where))
    return RobotParams(name=data["name"], link_lengths=lengths, joint_limits=limits,
                       source=data["source"], link_masses=masses, effort_limits=efforts)
