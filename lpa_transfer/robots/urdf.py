"""Robots from URDF files: the serial chain from the root link to a tip link, read into the
table of a ``kind = "serial"`` robot file (:mod:`lpa_transfer.robots.params`).

A ROS user's robot comes as a URDF; this reads the subset our chains model with the standard
library's XML parser (no new dependency; pybullet still loads the URDF that
:func:`lpa_transfer.robots.serial_chain.serial_chain_urdf` writes back, so the simulation and
the kinematics share one description):

* the chain: from ``base_link`` (default: the root link, the one no joint moves; the links
  above a given one are left out) down to ``tip_link``, or, without it, down the only child
  joint of every link to a leaf (a branching link is an error that names the branches);
* revolute joints move (continuous joints too, limited to [-π, π]); fixed joints are folded
  into the next joint's origin, into the base (before the first moving joint) or into the tool
  (after the last); prismatic, floating and planar joints are refused;
* each moving joint's link carries the mass, centre of mass and inertia of its link and of
  every link fixed to it (combined about the link frame, parallel-axis theorem); joints off the
  chain and their links are left out;
* limits (lower, upper, effort, velocity) from ``<limit>``; damping from ``<dynamics>``;
  armature 0 (URDF has no rotor inertia).
"""
import xml.etree.ElementTree as ElementTree
from collections import defaultdict
from pathlib import Path

import numpy as np

from lpa_transfer.robots.serial_chain import matrix_rpy, rpy_matrix
from lpa_transfer.robots.urdf_files import inertia_problems, resolve_mesh_paths

MOVING = ("revolute", "continuous")
_INERTIA_KEYS = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")


def _floats(text, where, n=3):
    try:
        values = [float(v) for v in (text or "").split()]
    except ValueError:
        values = []
    if len(values) != n or not np.isfinite(values).all():
        raise ValueError(f"{where}: expected {n} numbers, got {text!r}")
    return np.array(values)


def _pose(element, where):
    """4x4 transform of an element's ``<origin>`` (identity when absent)."""
    origin = element.find("origin")
    transform = np.eye(4)
    if origin is not None:
        transform[:3, :3] = rpy_matrix(_floats(origin.get("rpy", "0 0 0"), f"{where} rpy"))
        transform[:3, 3] = _floats(origin.get("xyz", "0 0 0"), f"{where} xyz")
    return transform


def _xyz_rpy(transform):
    return {"xyz": transform[:3, 3].tolist(), "rpy": matrix_rpy(transform[:3, :3]).tolist()}


def _inertial(link, where):
    """(mass, centre of mass (3,), inertia about it (3, 3)) in the link frame, or None."""
    inertial = link.find("inertial")
    if inertial is None:
        return None
    pose = _pose(inertial, f"{where} <inertial>")
    mass_element, inertia_element = inertial.find("mass"), inertial.find("inertia")
    if mass_element is None or inertia_element is None:
        raise ValueError(f"{where}: <inertial> needs <mass> and <inertia>")
    mass = float(mass_element.get("value", "nan"))
    ixx, ixy, ixz, iyy, iyz, izz = (float(inertia_element.get(k, "nan")) for k in _INERTIA_KEYS)
    tensor = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
    if not (np.isfinite(mass) and np.isfinite(tensor).all()):
        raise ValueError(f"{where}: <inertial> holds a missing or non-finite value")
    rotation = pose[:3, :3]
    return mass, pose[:3, 3], rotation @ tensor @ rotation.T


def _combined(bodies):
    """One rigid body of ``bodies`` [(mass, com, inertia about com, 4x4 pose in the frame)]."""
    mass = sum(b[0] for b in bodies)
    if mass <= 0:
        return 0.0, np.zeros(3), np.zeros((3, 3))
    coms = [pose[:3, :3] @ com + pose[:3, 3] for _, com, _, pose in bodies]
    com = sum(m * c for (m, _, _, _), c in zip(bodies, coms)) / mass
    inertia = np.zeros((3, 3))
    for (m, _, tensor, pose), c in zip(bodies, coms):
        d = c - com
        inertia += pose[:3, :3] @ tensor @ pose[:3, :3].T + m * (d @ d * np.eye(3) - np.outer(d, d))
    return mass, com, inertia


def read_urdf(path, repair_inertia=False):
    """The parsed ``<robot>`` element of the URDF file ``path`` with its inertias checked
    (:func:`lpa_transfer.robots.urdf_files.inertia_problems`), and the lines saying what a
    ``repair_inertia`` changed; ValueError naming the file otherwise."""
    try:
        root = ElementTree.parse(path).getroot()
    except (ElementTree.ParseError, OSError) as exc:
        raise ValueError(f"{path}: not a readable URDF: {exc}") from None
    if root.tag != "robot":
        raise ValueError(f"{path}: the root element is <{root.tag}>, not <robot>")
    try:
        return root, inertia_problems(root, repair=repair_inertia)
    except ValueError as exc:
        raise ValueError(f"{path}: {exc}") from None


def urdf_robot_table(path, tip_link=None, base_link=None, repair_inertia=False):
    """The robot-file table (name, source, kind, joints, links, base, tool) of a URDF's
    chain from ``base_link`` (default: the root link) to ``tip_link`` (module docstring);
    ValueError naming the file and the element when it cannot be read as one. With
    ``repair_inertia`` inertias that are not a rigid body's are repaired first
    (:func:`read_urdf`)."""
    path = Path(path)
    root, _ = read_urdf(path, repair_inertia)
    links = {link.get("name"): link for link in root.findall("link")}
    joints, by_parent, by_child = {}, defaultdict(list), {}
    for joint in root.findall("joint"):
        name, parent, child = joint.get("name"), joint.find("parent"), joint.find("child")
        if parent is None or child is None:
            raise ValueError(f"{path}: joint {name!r} needs <parent> and <child>")
        joints[name] = joint
        by_parent[parent.get("link")].append(joint)
        by_child[child.get("link")] = joint
    roots = [name for name in links if name not in by_child]
    if len(roots) != 1:
        raise ValueError(f"{path}: expected one root link, found {roots}")
    for role, name in (("base_link", base_link), ("tip_link", tip_link)):
        if name is not None and name not in links:
            raise ValueError(f"{path}: no link {name!r} ({role}); its links: {list(links)}")
    if base_link is not None:
        roots = [base_link]
    chain = _chain(path, roots[0], tip_link, links, by_parent, by_child)
    moving = [joint for joint in chain if joint.get("type") in MOVING]
    refused = [f"{joint.get('name')} ({joint.get('type')})" for joint in chain
               if joint.get("type") not in MOVING + ("fixed",)]
    if refused:
        raise ValueError(f"{path}: only revolute, continuous and fixed joints are supported "
                         f"on the chain, not {refused}")
    if not moving:
        raise ValueError(f"{path}: the chain from {roots[0]!r} has no moving joint")
    table = {"name": root.get("name") or path.stem, "source": f"URDF {path}", "kind": "serial",
             "joints": [], "links": []}
    pending = np.eye(4)       # fixed joints since the last moving one
    for joint in chain:
        where = f"{path}: joint {joint.get('name')!r}"
        if joint.get("type") == "fixed":
            pending = pending @ _pose(joint, where)
            continue
        if not table["joints"]:
            table["base"], pending = _xyz_rpy(pending), np.eye(4)
        table["joints"].append({**_xyz_rpy(pending @ _pose(joint, where)),
                                **_joint_entry(joint, where)})
        table["links"].append(_link_entry(path, joint.find("child").get("link"), links,
                                          by_parent))
        pending = np.eye(4)
    table["tool"] = _xyz_rpy(pending)
    return table


def _chain(path, root, tip_link, links, by_parent, by_child):
    if tip_link is not None:
        chain, link = [], tip_link
        while link != root:
            if link not in by_child:
                raise ValueError(f"{path}: link {tip_link!r} (tip_link) is not below "
                                 f"{root!r} (base_link)")
            chain.append(by_child[link])
            link = by_child[link].find("parent").get("link")
        return chain[::-1]
    chain, link = [], root
    while by_parent.get(link):
        if len(by_parent[link]) > 1:
            branches = [joint.get("name") for joint in by_parent[link]]
            raise ValueError(f"{path}: link {link!r} branches into joints {branches}; name the "
                             f"tip link of the chain to use (tip_link; robot_sim: -p "
                             f"tip_link:=<link>), one of the links {list(links)}")
        chain.append(by_parent[link][0])
        link = chain[-1].find("child").get("link")
    return chain


def _joint_entry(joint, where):
    axis = joint.find("axis")
    entry = {"axis": (_floats(axis.get("xyz"), f"{where} axis") if axis is not None
                      else np.array([1.0, 0.0, 0.0])).tolist()}
    limit = joint.find("limit")
    if limit is None or limit.get("effort") is None or limit.get("velocity") is None:
        raise ValueError(f"{where}: needs <limit> with effort and velocity")
    if joint.get("type") == "continuous":
        entry["lower"], entry["upper"] = -np.pi, np.pi
    else:
        if limit.get("lower") is None or limit.get("upper") is None:
            raise ValueError(f"{where}: a revolute joint needs <limit lower=... upper=...>")
        entry["lower"], entry["upper"] = float(limit.get("lower")), float(limit.get("upper"))
    entry["effort"], entry["velocity"] = float(limit.get("effort")), float(limit.get("velocity"))
    dynamics = joint.find("dynamics")
    if dynamics is not None and dynamics.get("damping") is not None:
        entry["damping"] = float(dynamics.get("damping"))
    return entry


def _link_entry(path, name, links, by_parent):
    """The ``[[links]]`` entry of a moving joint's link: it and every link fixed to it."""
    bodies, stack = [], [(name, np.eye(4))]
    while stack:
        link_name, pose = stack.pop()
        inertial = _inertial(links[link_name], f"{path}: link {link_name!r}")
        if inertial is not None:
            bodies.append((*inertial, pose))
        stack += [(joint.find("child").get("link"), pose @ _pose(joint, f"{path}: joint"))
                  for joint in by_parent.get(link_name, []) if joint.get("type") == "fixed"]
    mass, com, inertia = _combined(bodies)
    if mass <= 0:
        raise ValueError(f"{path}: link {name!r} (with the links fixed to it) has no mass: "
                         "the simulator needs an <inertial> with a positive <mass>")
    return {"mass": mass, "com": com.tolist(),
            "inertia": dict(zip(_INERTIA_KEYS, (inertia[0, 0], inertia[0, 1], inertia[0, 2],
                                                inertia[1, 1], inertia[1, 2], inertia[2, 2])))}


def simulated_urdf(path, repair_inertia=False):
    """(URDF text, repair lines) of the file ``path`` for the simulator to load as it is:
    its mesh paths made absolute against its own folder
    (:func:`~lpa_transfer.robots.urdf_files.resolve_mesh_paths`), its inertias checked and,
    with ``repair_inertia``, repaired (:func:`read_urdf`; only then is the text rewritten from
    the parsed tree, otherwise it is the file's own)."""
    path = Path(path)
    root, lines = read_urdf(path, repair_inertia)
    text = ElementTree.tostring(root, encoding="unicode") if lines else path.read_text()
    try:
        return resolve_mesh_paths(text, path.parent), lines
    except ValueError as exc:
        raise ValueError(f"{path}: {exc}") from None
