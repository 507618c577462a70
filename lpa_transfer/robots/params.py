"""Robot parameter files (TOML): fixed-base serial chains of revolute joints.

A file is one of two kinds; both load into one :class:`RobotParams`. ``kind = "planar"`` (the
default) is a planar chain as in the thesis' Table 3.1 (§3.6): one ``[[links]]`` (length,
optional mass) and one ``[[joints]]`` (limits, optional effort, velocity, armature, damping)
table per link; :func:`planar_chain_fields` derives the general fields (joints about z, thin
uniform rods, moving in the simulator's vertical x-y plane). ``kind = "serial"`` is a general
chain, each value as in a URDF (frames, rad, m, kg, kg·m²): an optional ``[base]``, a
``[[joints]]`` (xyz, rpy, axis, limits) and a ``[[links]]`` (mass, com, inertia) table per
joint, and a ``[tool]``. ``extends = "other.toml"`` starts from another file's table.

Drive (both kinds, per joint, default 0): ``armature`` (the motor rotor's inertia reflected
through the gearbox, J_rotor·N²) and ``damping`` (viscous friction), which dominate geared
joints; :class:`lpa_transfer.robots.simulator.RobotSimulator` applies them. Frames compose as
in URDF. Unknown keys are ignored, so files can carry notes; errors name the file and the
key. Both formats with examples, the drive model and the frame conventions: docs/library.md,
"Robot files".
"""
import dataclasses
import numbers
import tomllib
from pathlib import Path

import numpy as np

from lpa_transfer.robots.urdf import urdf_robot_table

#: Link mass (kg) when a planar ``[[links]]`` table has no ``mass``.
DEFAULT_LINK_MASS = 1.0
#: Joint effort limit (N·m) when a planar ``[[joints]]`` table has no ``effort`` (as
#: planar_chain_urdf).
DEFAULT_EFFORT_LIMIT = 100.0
#: Joint velocity limit (rad/s) when a planar ``[[joints]]`` table has no ``velocity`` (as
#: planar_chain_urdf; pybullet does not enforce it).
DEFAULT_VELOCITY_LIMIT = 100.0
#: Axial inertia of a planar link, as a share of m L² (a thin rod has none; as planar_chain_urdf).
ROD_AXIAL_SHARE = 1e-6
KINDS = ("planar", "serial")
INERTIA_KEYS = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")


@dataclasses.dataclass(frozen=True, eq=False)
class RobotParams:
    """A robot read from a parameter file; the arrays are read-only.

    ``link_lengths[i]`` is the distance from joint i to joint i + 1 (to the tool for the last
    joint): the link lengths of a planar chain. The general fields (``joint_xyz`` …
    ``base_rpy``, module docstring) default to those of the planar chain with these lengths
    and masses (:func:`planar_chain_fields`).
    """

    name: str
    link_lengths: np.ndarray   # (n,) m
    joint_limits: np.ndarray   # (n, 2) rad, columns (lower, upper)
    source: str                # where the numbers come from (e.g. a thesis table)
    link_masses: np.ndarray = None    # (n,) kg; None -> DEFAULT_LINK_MASS each
    effort_limits: np.ndarray = None  # (n,) N·m; None -> DEFAULT_EFFORT_LIMIT each
    kind: str = "planar"              # "planar": link_lengths describe the whole chain
    joint_xyz: np.ndarray = None      # (n, 3) m, joint origin in the previous joint frame
    joint_rpy: np.ndarray = None      # (n, 3) rad
    joint_axes: np.ndarray = None     # (n, 3) unit vectors in the joint frames
    velocity_limits: np.ndarray = None  # (n,) rad/s
    link_coms: np.ndarray = None      # (n, 3) m, centre of mass in the link frame
    link_inertias: np.ndarray = None  # (n, 3, 3) kg·m², about the centre of mass
    tool_xyz: np.ndarray = None       # (3,) m, end effector in the last link frame
    tool_rpy: np.ndarray = None       # (3,) rad
    base_xyz: np.ndarray = None       # (3,) m, first joint frame's parent in the world
    base_rpy: np.ndarray = None       # (3,) rad
    joint_armature: np.ndarray = None  # (n,) kg·m², reflected rotor inertia; None -> zeros
    joint_damping: np.ndarray = None   # (n,) N·m·s/rad, viscous joint friction; None -> zeros

    def __post_init__(self):
        if self.kind not in KINDS:
            raise ValueError(f"kind must be one of {KINDS}, got {self.kind!r}")
        if self.link_lengths is None or self.joint_limits is None:
            raise ValueError(f"RobotParams {self.name!r}: link_lengths and joint_limits are "
                             "required")
        n = len(self.link_lengths)
        self._set_arrays(dict(link_lengths=np.empty(n), joint_limits=np.empty((n, 2)),
                              link_masses=np.full(n, DEFAULT_LINK_MASS),
                              effort_limits=np.full(n, DEFAULT_EFFORT_LIMIT),
                              joint_armature=np.zeros(n), joint_damping=np.zeros(n)))
        self._set_arrays(planar_chain_fields(self.link_lengths, self.link_masses))
        for field in ("joint_armature", "joint_damping"):
            values = getattr(self, field)
            if not (np.isfinite(values).all() and (values >= 0).all()):
                raise ValueError(f"RobotParams {self.name!r}: {field} must be finite and >= 0, "
                                 f"got {values.tolist()}")

    def _set_arrays(self, defaults):
        """Store each field as a read-only float array shaped as its default (used if None)."""
        for field, default in defaults.items():
            value = getattr(self, field)
            array = np.array(default if value is None else value, dtype=np.float64)
            if array.shape != default.shape:
                raise ValueError(f"RobotParams {self.name!r}: {field} must have shape "
                                 f"{default.shape}, got {array.shape}")
            array.setflags(write=False)
            object.__setattr__(self, field, array)

    @property
    def n_joints(self):
        return len(self.link_lengths)


def planar_chain_fields(link_lengths, link_masses):
    """The general fields of a planar chain (module docstring), as a dict of arrays.

    Joint i sits at the end of link i − 1 and turns about z; link i is a uniform rod of
    length L and mass m along x: centre of mass (L/2, 0, 0), inertia m L²/12 about y and z,
    ``ROD_AXIAL_SHARE``·m L² about x — the model of
    :func:`lpa_transfer.robots.planar_chain.planar_chain_urdf`.
    """
    lengths = np.asarray(link_lengths, dtype=np.float64).reshape(-1)
    masses = np.broadcast_to(np.asarray(link_masses, dtype=np.float64), lengths.shape)
    n, moment = len(lengths), masses * lengths ** 2
    starts, coms, inertias = np.zeros((n, 3)), np.zeros((n, 3)), np.zeros((n, 3, 3))
    starts[1:, 0], coms[:, 0] = lengths[:-1], lengths / 2
    inertias[:, [0, 1, 2], [0, 1, 2]] = np.column_stack((ROD_AXIAL_SHARE * moment,
                                                          moment / 12, moment / 12))
    return dict(joint_xyz=starts, joint_rpy=np.zeros((n, 3)),
                joint_axes=np.tile([0.0, 0.0, 1.0], (n, 1)),
                velocity_limits=np.full(n, DEFAULT_VELOCITY_LIMIT), link_coms=coms,
                link_inertias=inertias, tool_xyz=np.array([lengths[-1] if n else 0.0, 0, 0]),
                tool_rpy=np.zeros(3), base_xyz=np.zeros(3), base_rpy=np.zeros(3))


# -- reading values ---------------------------------------------------------------------------
def _number(table, key, where):
    value = table.get(key)
    if value is None:
        raise ValueError(f"{where}: missing key '{key}'")
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not np.isfinite(value):
        raise ValueError(f"{where}: key '{key}' must be a finite number, got {value!r}")
    return float(value)


def _non_negative(table, key, where):
    """An optional value >= 0 (default 0): a joint's ``armature`` or ``damping``."""
    if key not in table:
        return 0.0
    value = _number(table, key, where)
    if value < 0:
        raise ValueError(f"{where}: key '{key}' must be >= 0, got {value}")
    return value


def _positive(table, key, where, default=None):
    if default is not None and key not in table:
        return default
    value = _number(table, key, where)
    if value <= 0:
        raise ValueError(f"{where}: key '{key}' must be positive, got {value}")
    return value


def _vector(table, key, where, default=None):
    if default is not None and key not in table:
        return np.asarray(default, dtype=np.float64)
    value = table.get(key)
    if value is None:
        raise ValueError(f"{where}: missing key '{key}'")
    if not isinstance(value, list) or len(value) != 3:
        raise ValueError(f"{where}: key '{key}' must be a list of 3 numbers, got {value!r}")
    return np.array([_number({key: v}, key, where) for v in value])


def _tables(data, key, path):
    tables = data.get(key)
    if not isinstance(tables, list) or not tables or not all(isinstance(t, dict)
                                                            for t in tables):
        raise ValueError(f"{path}: missing or empty '[[{key}]]' tables")
    return tables


def _table(data, key, path, required):
    table = data.get(key)
    if table is None and not required:
        return {}
    if not isinstance(table, dict):
        raise ValueError(f"{path}: missing '[{key}]' table")
    return table


def _joint_limits(joint, where):
    lower, upper = _number(joint, "lower", where), _number(joint, "upper", where)
    if lower > upper:
        raise ValueError(f"{where}: key 'lower' ({lower}) is greater than 'upper' ({upper})")
    return lower, upper


def _axis(joint, where):
    axis = _vector(joint, "axis", where)
    norm = np.linalg.norm(axis)
    if norm < 1e-9:
        raise ValueError(f"{where}: key 'axis' must be a non-zero vector, got {axis.tolist()}")
    return axis / norm


def _inertia(link, where):
    """The 3×3 inertia tensor of ``link['inertia']``: positive definite, a rigid body's."""
    table = link.get("inertia")
    if not isinstance(table, dict):
        raise ValueError(f"{where}: missing key 'inertia' (a table with keys "
                         f"{', '.join(INERTIA_KEYS)})")
    ixx, ixy, ixz, iyy, iyz, izz = (_number(table, k, f"{where}: inertia") for k in INERTIA_KEYS)
    tensor = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
    principal = np.linalg.eigvalsh(tensor)
    if principal[0] <= 0:
        raise ValueError(f"{where}: key 'inertia' is not positive definite (principal moments "
                         f"{principal.tolist()})")
    if 2 * principal.max() > principal.sum() * (1 + 1e-9):
        raise ValueError(f"{where}: key 'inertia' violates the triangle inequality of a rigid "
                         f"body (principal moments {principal.tolist()})")
    return tensor


# -- the two kinds ----------------------------------------------------------------------------
def _planar_fields(data, path):
    links, joints = _tables(data, "links", path), _tables(data, "joints", path)
    if len(links) != len(joints):
        raise ValueError(f"{path}: {len(links)} [[links]] but {len(joints)} [[joints]]; a "
                         "serial chain needs one joint per link")
    for key in ("base", "tool"):
        if key in data:
            raise ValueError(f"{path}: a '[{key}]' table needs kind = \"serial\"; a planar "
                             "chain has its base at the origin and its tool at the last link's end")
    lengths, masses = [], []
    for i, link in enumerate(links):
        where = f"{path}: links[{i}]"
        masses.append(_positive(link, "mass", where, DEFAULT_LINK_MASS))
        lengths.append(_positive(link, "length", where))
    wheres = [f"{path}: joints[{i}]" for i in range(len(joints))]
    return dict(link_lengths=lengths, link_masses=masses,
                joint_limits=[_joint_limits(j, w) for j, w in zip(joints, wheres)],
                effort_limits=[_positive(j, "effort", w, DEFAULT_EFFORT_LIMIT)
                               for j, w in zip(joints, wheres)],
                velocity_limits=[_positive(j, "velocity", w, DEFAULT_VELOCITY_LIMIT)
                                 for j, w in zip(joints, wheres)],
                **_drive_fields(joints, wheres))


def _drive_fields(joints, wheres):
    """The optional ``armature`` and ``damping`` of each joint (docs/library.md, "Robot files")."""
    return dict(joint_armature=[_non_negative(j, "armature", w) for j, w in zip(joints, wheres)],
                joint_damping=[_non_negative(j, "damping", w) for j, w in zip(joints, wheres)])


def _serial_fields(data, path):
    joints, links = _tables(data, "joints", path), _tables(data, "links", path)
    if len(links) != len(joints):
        raise ValueError(f"{path}: {len(joints)} [[joints]] but {len(links)} [[links]]; a "
                         "serial chain needs one link per joint")
    fields = {k: [] for k in ("joint_xyz", "joint_rpy", "joint_axes", "joint_limits",
                              "effort_limits", "velocity_limits", "link_masses", "link_coms",
                              "link_inertias")}
    for i, (joint, link) in enumerate(zip(joints, links)):
        where = f"{path}: joints[{i}]"
        fields["joint_xyz"].append(_vector(joint, "xyz", where))
        fields["joint_rpy"].append(_vector(joint, "rpy", where, default=np.zeros(3)))
        fields["joint_axes"].append(_axis(joint, where))
        fields["joint_limits"].append(_joint_limits(joint, where))
        fields["effort_limits"].append(_positive(joint, "effort", where))
        fields["velocity_limits"].append(_positive(joint, "velocity", where))
        where = f"{path}: links[{i}]"
        fields["link_masses"].append(_positive(link, "mass", where))
        fields["link_coms"].append(_vector(link, "com", where))
        fields["link_inertias"].append(_inertia(link, where))
    tool, base = _table(data, "tool", path, required=True), _table(data, "base", path, False)
    fields["tool_xyz"] = _vector(tool, "xyz", f"{path}: tool")
    fields["tool_rpy"] = _vector(tool, "rpy", f"{path}: tool", default=np.zeros(3))
    fields["base_xyz"] = _vector(base, "xyz", f"{path}: base", default=np.zeros(3))
    fields["base_rpy"] = _vector(base, "rpy", f"{path}: base", default=np.zeros(3))
    fields.update(_drive_fields(joints, [f"{path}: joints[{i}]" for i in range(len(joints))]))
    offsets = np.vstack((fields["joint_xyz"][1:], [fields["tool_xyz"]]))
    fields["link_lengths"] = np.linalg.norm(offsets, axis=1)
    return fields


def _read_toml(path, seen=()):
    """The file's table; with ``extends = "<file>"`` (relative to this file) the parent's
    table with this file's top-level keys in place of its own: the same robot placed or
    named otherwise without a copy of its chain."""
    if path.resolve() in seen:
        raise ValueError(f"{path}: 'extends' loops back to {path.name}")
    try:
        with path.open("rb") as handle:
            data = tomllib.load(handle)
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"{path}: not valid TOML: {exc}") from None
    parent = data.pop("extends", None)
    if parent is None:
        return data
    if not isinstance(parent, str) or not parent.strip():
        raise ValueError(f"{path}: key 'extends' must name a robot file")
    parent_path = path.parent / parent
    if not parent_path.is_file():
        raise ValueError(f"{path}: 'extends' names {parent_path}, which does not exist")
    return {**_read_toml(parent_path, (*seen, path.resolve())), **data}


def load_robot_params(path, **urdf_options):
    """Read and validate a robot parameter file, or the chain of a URDF (``*.urdf``,
    :mod:`lpa_transfer.robots.urdf`; ``urdf_options``: ``tip_link``, ``base_link``,
    ``repair_inertia`` of :func:`~lpa_transfer.robots.urdf.urdf_robot_table`, for a URDF
    only); errors name the file and the key."""
    path = Path(path)
    is_urdf = path.suffix.lower() == ".urdf"
    if urdf_options and not is_urdf:
        raise ValueError(f"{path}: {sorted(urdf_options)} apply to a URDF file (*.urdf) only")
    data = urdf_robot_table(path, **urdf_options) if is_urdf else _read_toml(path)
    for key in ("name", "source"):
        if not isinstance(data.get(key), str) or not data[key].strip():
            raise ValueError(f"{path}: missing key '{key}' (a non-empty string)")
    kind = data.get("kind", "planar")
    if kind not in KINDS:
        raise ValueError(f"{path}: key 'kind' must be one of {KINDS}, got {kind!r}")
    fields = (_planar_fields if kind == "planar" else _serial_fields)(data, path)
    return RobotParams(name=data["name"], source=data["source"], kind=kind, **fields)
