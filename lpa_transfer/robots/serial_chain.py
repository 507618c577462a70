"""URDF and forward kinematics of a :class:`~lpa_transfer.robots.params.RobotParams` chain.

Frames follow URDF (module docstring of :mod:`lpa_transfer.robots.params`); the world frame
is the simulator's, gravity −9.81 m/s² along −y
(:func:`lpa_transfer.robots.planar_chain.load_fixed_robot`), and

    T_tool(q) = B · Π_i [T(xyz_i) R(rpy_i) Rot(axis_i, q_i)] · T(tool_xyz) R(tool_rpy),

B the base placement, R(r, p, y) = Rz(y) Ry(p) Rx(r), Rot by Rodrigues' formula. This
T_tool is the forward kinematics the chapter 5 tasks are tracked in (§5.5.1: the robots
track 'star' figures with their end effectors). Pure numpy; pybullet only reads the URDF.

Joint drives (:mod:`lpa_transfer.robots.params`, "Drive"): the viscous ``damping`` goes into the
standard ``<dynamics damping=...>``, which pybullet reads. URDF has no reflected rotor inertia,
so a joint's ``armature`` is written as an extension element ``<lpa:armature value="..."/>``
(namespace :data:`LPA_URDF_NAMESPACE`) inside ``<joint>``, which URDF parsers, pybullet's
included, ignore; :class:`lpa_transfer.robots.simulator.RobotSimulator` reads it back with
:func:`urdf_joint_armatures` and applies both (its module docstring says how).
"""
import weakref
import xml.etree.ElementTree as ElementTree

import numpy as np

from lpa_transfer._validation import as_matrix


def rpy_matrix(rpy):
    """R(roll, pitch, yaw) = Rz(yaw) Ry(pitch) Rx(roll) (URDF's fixed-axis convention)."""
    (cr, cp, cy), (sr, sp, sy) = np.cos(rpy), np.sin(rpy)
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


def matrix_rpy(rotation):
    """(roll, pitch, yaw) of a rotation matrix, the inverse of :func:`rpy_matrix`."""
    r = np.asarray(rotation, dtype=np.float64)
    pitch = np.arctan2(-r[2, 0], np.hypot(r[0, 0], r[1, 0]))
    if np.hypot(r[0, 0], r[1, 0]) < 1e-12:            # gimbal lock: put it all in yaw
        return np.array([0.0, pitch, np.arctan2(-r[0, 1], r[1, 1])])
    return np.array([np.arctan2(r[2, 1], r[2, 2]), pitch, np.arctan2(r[1, 0], r[0, 0])])


def _transform(xyz, rpy):
    transform = np.eye(4)
    transform[:3, :3], transform[:3, 3] = rpy_matrix(rpy), xyz
    return transform


_EYE4 = np.eye(4)
#: Per robot (RobotParams is immutable), the chain's constant parts: computed once, because
#: inverse kinematics calls the forward kinematics thousands of times on a few rows each.
_CHAINS = weakref.WeakKeyDictionary()


def _chain(robot):
    """(base, joint origins, Rodrigues' K and K² of every joint axis stacked (n, 3, 3), tool)
    of ``robot``."""
    chain = _CHAINS.get(robot)
    if chain is None:
        ks = np.array([[[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]]
                       for x, y, z in robot.joint_axes]).reshape(-1, 3, 3)
        chain = (_transform(robot.base_xyz, robot.base_rpy),
                 [_transform(xyz, rpy) for xyz, rpy in zip(robot.joint_xyz, robot.joint_rpy)],
                 ks, ks @ ks, _transform(robot.tool_xyz, robot.tool_rpy))
        _CHAINS[robot] = chain
    return chain


#: Up to this many rows the joints' rotations are built in one pass (the per-call overhead
#: dominates), beyond it joint by joint (memory traffic dominates); docs/history.md.
_ALL_JOINTS_AT_ONCE = 256


def _axis_rotations(ks, kks, q):
    """Rot(axis_i, q_i) of the joints i given by ``ks`` (n, 3, 3), the axes' cross-product
    matrices, and ``kks`` = K², for every row of ``q`` (N, n), as (n, N, 4, 4):
    R = I + sin q K + (1 − cos q) K² (Rodrigues). All joints in one pass: inverse kinematics
    calls the forward kinematics thousands of times on a few rows, where the per-call
    overhead is what costs."""
    angles = q.T[:, :, None, None]                                   # (n, N, 1, 1)
    s, c = np.sin(angles), np.cos(angles)
    rotations = np.empty((q.shape[1], len(q), 4, 4))
    rotations[:] = _EYE4
    rotations[:, :, :3, :3] += s * ks[:, None] + (1 - c) * kks[:, None]
    return rotations


def _frames(robot, q, every):
    """The world frames of the chain for ``q`` (N, n): every joint's and the tool's (a list),
    or, unless ``every``, only the tool's."""
    q = as_matrix(q, "q")
    if q.shape[1] != robot.n_joints:
        raise ValueError(f"q must have shape (N, {robot.n_joints}) (one row of joint angles per "
                         f"sample), got shape {q.shape}")
    base, origins, ks, kks, tool = _chain(robot)
    if len(q) <= _ALL_JOINTS_AT_ONCE:
        rotations = _axis_rotations(ks, kks, q)
    else:       # joint by joint: the temporaries stay in cache (same values, bit for bit)
        rotations = (_axis_rotations(ks[i:i + 1], kks[i:i + 1], q[:, i:i + 1])[0]
                     for i in range(len(origins)))
    frame = np.broadcast_to(base, (len(q), 4, 4))
    frames = []
    for origin, rotation in zip(origins, rotations):
        frame = frame @ origin @ rotation
        if every:
            frames.append(frame)
    frames.append(frame @ tool)
    return frames


def chain_frames(robot, q):
    """World frames (N, n + 1, 4, 4) of every joint (its origin, after its rotation q_i) and,
    last, of the tool, for joint angles ``q`` (N, n): the partial products of the chain in
    the module docstring (e.g. to measure link lengths or compare two arms' postures)."""
    return np.stack(_frames(robot, q, every=True), axis=1)


def reach_sphere(robot):
    """(centre (3,), radius): a ball in the world frame that holds the tool for every ``q``.
    The centre is joint 0's origin, which no joint moves; the radius is the sum of
    ``link_lengths``, by the triangle inequality over the joint origins and the tool (each
    step between them is a fixed offset rotated). Used to skip the inverse kinematics of
    points no pose can reach."""
    centre = _frames(robot, np.zeros((1, robot.n_joints)), every=True)[0][0, :3, 3]
    return centre.copy(), float(np.sum(robot.link_lengths))


def tool_transforms(robot, q):
    """Homogeneous end-effector transforms T_tool(q) (N, 4, 4) in the world frame."""
    return _frames(robot, q, every=False)[-1]


def forward_kinematics(robot, q):
    """End-effector positions (N, 3) in the world frame for joint angles ``q`` (N, n)."""
    return tool_transforms(robot, q)[:, :3, 3]


#: XML namespace of this project's URDF extension elements (``<lpa:armature>``).
LPA_URDF_NAMESPACE = "urn:lpa-transfer:urdf"


def urdf_joint_armatures(urdf_text):
    """{joint name: armature} of the joints that carry an ``<lpa:armature value="..."/>``.

    ``urdf_text`` is URDF text (not a path). Text without the extension is not parsed (any
    URDF a user brings works as before); text with it must be valid XML and every value a
    finite number >= 0, else ValueError.
    """
    if LPA_URDF_NAMESPACE not in urdf_text:
        if "lpa:armature" in urdf_text:
            raise ValueError(f"URDF has lpa:armature elements but does not declare their "
                             f'namespace: add xmlns:lpa="{LPA_URDF_NAMESPACE}" to <robot>')
        return {}
    try:
        root = ElementTree.fromstring(urdf_text)
    except ElementTree.ParseError as exc:
        raise ValueError(f"URDF with lpa:armature elements is not valid XML: {exc}") from None
    armatures = {}
    for joint in root.iter("joint"):
        element = joint.find(f"{{{LPA_URDF_NAMESPACE}}}armature")
        if element is None:
            continue
        name = joint.get("name")
        try:
            value = float(element.get("value"))
        except (TypeError, ValueError):
            value = float("nan")
        if not (np.isfinite(value) and value >= 0):
            raise ValueError(f"URDF joint {name!r}: lpa:armature value must be a finite number "
                             f">= 0, got {element.get('value')!r}")
        armatures[name] = value
    return armatures


def _numbers(values):
    return " ".join(f"{v:.17g}" for v in values)


def _inertial(mass, com, inertia):
    ixx, ixy, ixz, iyy, iyz, izz = np.asarray(inertia)[np.triu_indices(3)]
    return (f'<inertial><origin xyz="{_numbers(com)}"/><mass value="{mass:.17g}"/>'
            f'<inertia ixx="{ixx:.17g}" ixy="{ixy:.17g}" ixz="{ixz:.17g}" iyy="{iyy:.17g}" '
            f'iyz="{iyz:.17g}" izz="{izz:.17g}"/></inertial>')


def serial_chain_urdf(robot):
    """URDF text of a robot chain, masses, centres of mass and inertias from its file.

    Links ``base`` (massless; the world frame), ``link1..linkn`` on revolute joints
    ``joint1..jointn``, a massless ``tool`` on the fixed ``tool_joint`` — the names of
    :func:`lpa_transfer.robots.planar_chain.planar_chain_urdf`. The base placement is folded into
    joint1's origin, so the simulator's last link is the tool. Joint damping is the file's
    (default 0), friction zero; a non-zero armature becomes an ``<lpa:armature>`` element
    (module docstring). pybullet enforces neither effort nor velocity limits.
    """
    massless = _inertial(0.0, np.zeros(3), np.zeros((3, 3)))
    namespace = (f' xmlns:lpa="{LPA_URDF_NAMESPACE}"' if (robot.joint_armature > 0).any()
                 else "")
    parts = [f'<?xml version="1.0"?>\n<robot name="{robot.name}"{namespace}>\n'
             f'  <link name="base">{massless}</link>']
    first = _transform(robot.base_xyz, robot.base_rpy) @ _transform(robot.joint_xyz[0],
                                                                     robot.joint_rpy[0])
    parent = "base"
    for i in range(robot.n_joints):
        xyz, rpy = ((first[:3, 3], matrix_rpy(first[:3, :3])) if i == 0
                    else (robot.joint_xyz[i], robot.joint_rpy[i]))
        (lower, upper), child = robot.joint_limits[i], f"link{i + 1}"
        armature = (f'    <lpa:armature value="{robot.joint_armature[i]:.17g}"/>\n'
                    if robot.joint_armature[i] > 0 else "")
        parts.append(
            f'  <link name="{child}">'
            f'{_inertial(robot.link_masses[i], robot.link_coms[i], robot.link_inertias[i])}'
            f'</link>\n'
            f'  <joint name="joint{i + 1}" type="revolute">\n'
            f'    <parent link="{parent}"/><child link="{child}"/>\n'
            f'    <origin xyz="{_numbers(xyz)}" rpy="{_numbers(rpy)}"/>'
            f'<axis xyz="{_numbers(robot.joint_axes[i])}"/>\n'
            f'    <limit lower="{lower:.17g}" upper="{upper:.17g}" '
            f'effort="{robot.effort_limits[i]:.17g}" velocity="{robot.velocity_limits[i]:.17g}"/>\n'
            f'    <dynamics damping="{robot.joint_damping[i]:.17g}" friction="0"/>\n'
            f'{armature}'
            f'  </joint>')
        parent = child
    parts.append(f'  <link name="tool">{massless}</link>\n'
                 f'  <joint name="tool_joint" type="fixed">\n'
                 f'    <parent link="{parent}"/><child link="tool"/>\n'
                 f'    <origin xyz="{_numbers(robot.tool_xyz)}" '
                 f'rpy="{_numbers(robot.tool_rpy)}"/>\n'
                 f'  </joint>\n</robot>\n')
    return "\n".join(parts)
