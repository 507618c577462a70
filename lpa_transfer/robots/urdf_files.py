"""A user's URDF file as pybullet should load it: mesh paths resolved against the file's own
folder, and inertias checked (and, when asked, repaired) to be a rigid body's.

* Meshes: pybullet resolves a ``<mesh filename>`` relative to the folder of the file it loads,
  and strips ``package://`` to a path relative to that folder too (bullet3,
  examples/Importers/ImportURDFDemo/UrdfFindMeshFile.h, whose warning names the file it tried). The simulator loads URDF
  *text* through a temporary file (:func:`lpa_transfer.robots.planar_chain.load_fixed_robot`),
  so :func:`resolve_mesh_paths` makes every relative and ``package://`` mesh path absolute
  first (only the ``filename`` attributes of ``<mesh>`` change; the rest of the text stays).
* Inertias: the principal moments of a rigid body's inertia about its centre of mass are
  non-negative and each is at most the sum of the other two (the triangle inequality: with
  the second moments c_i = ∫ x_i² dm ≥ 0, I_1 = c_2 + c_3 ≤ (c_1 + c_3) + (c_1 + c_2) =
  I_2 + I_3; e.g. Traversaro, Brossette, Escande, Nori, "Identification of fully physical
  consistent inertial parameters using optimization on manifolds", IROS 2016, §III).
  pybullet silently sets a link's inertia to zero when it is not (its URDF importer's "Bad
  inertia tensor properties" warning, BulletUrdfImporter.cpp; seen for the xArm6's link2 and
  link3: test/test_urdf_robots.py), which is not the user's robot. :func:`inertia_problems`
  names such links; with ``repair=True`` it raises the smallest principal moment to
  (largest − middle) + 1e-6 · largest, about the same principal axes, so the largest moment
  is just below the sum of the other two; mass, centre of mass and the other two moments stay.
"""
import os
import re
from pathlib import Path

import numpy as np

_INERTIA_KEYS = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
_MESH = re.compile(r'(<mesh\b[^>]*?\bfilename\s*=\s*)(["\'])(.*?)\2', re.S)
REPAIR_MARGIN = 1e-6     # relative to the largest principal moment
TOLERANCE = 1e-9         # relative rounding allowed in the triangle inequality


def _mesh_candidates(filename, folder):
    if filename.startswith("file://"):
        return [Path(filename[len("file://"):])]
    if not filename.startswith("package://"):
        return [folder / filename]
    rest = filename[len("package://"):]
    package, _, inside = rest.partition("/")
    # as pybullet: relative to the file's folder; then the package's folder at or above it
    above = [ancestor / inside if ancestor.name == package else ancestor / package / inside
             for ancestor in (folder, *folder.parents)
             if ancestor.name == package or (ancestor / package).is_dir()]
    return [folder / rest, folder / inside] + above[:1]


def resolve_mesh_paths(text, folder):
    """``text`` (URDF) with every relative, ``file://`` and ``package://`` mesh filename
    replaced by the absolute path of the file it names, searched from ``folder`` (the URDF's
    own folder; a ``package://<pkg>/...`` path also in ``<pkg>`` at or above it). A mesh
    that is found nowhere is a ValueError naming it and the places tried."""
    folder = Path(folder).resolve()
    missing = []

    def absolute(match):
        filename = match.group(3)
        if os.path.isabs(filename):
            return match.group(0)
        candidates = _mesh_candidates(filename, folder)
        found = next((c for c in candidates if c.is_file()), None)
        if found is None:
            missing.append(f"{filename} (tried {', '.join(map(str, candidates))})")
            return match.group(0)
        return f"{match.group(1)}{match.group(2)}{found.resolve()}{match.group(2)}"

    text = _MESH.sub(absolute, text)
    if missing:
        raise ValueError(f"URDF meshes not found: {'; '.join(missing)}")
    return text


def _tensor(inertia):
    ixx, ixy, ixz, iyy, iyz, izz = (float(inertia.get(k, "nan")) for k in _INERTIA_KEYS)
    return np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])


def inertia_problems(root, repair=False):
    """Check every ``<link>``'s ``<inertial><inertia>`` of the parsed URDF ``root``; returns
    one line per link that is not a rigid body's (module docstring). With ``repair`` the
    triangle inequality is restored in place (the line says from what to what); a negative
    principal moment is never repaired and stays a ValueError, as are all problems without
    ``repair``."""
    lines, refused = [], []
    for link in root.findall("link"):
        inertia = link.find("inertial/inertia")
        if inertia is None:
            continue
        tensor = _tensor(inertia)
        if not np.isfinite(tensor).all():
            continue            # urdf_robot_table names it when it reads the chain
        moments, axes = np.linalg.eigh(tensor)
        scale = max(abs(moments).max(), np.finfo(float).tiny)
        name = link.get("name")
        if moments[0] < -TOLERANCE * scale:
            refused.append(f"link {name!r}: negative principal moment {moments.tolist()}")
            continue
        if 2 * moments[2] <= moments.sum() * (1 + TOLERANCE):
            continue
        line = (f"link {name!r}: principal moments {moments.tolist()} violate the triangle "
                f"inequality of a rigid body (largest {moments[2]:.6g} > "
                f"{moments[0] + moments[1]:.6g}, the sum of the other two)")
        if not repair:
            refused.append(line)
            continue
        fixed = moments.copy()
        fixed[0] = moments[2] - moments[1] + REPAIR_MARGIN * moments[2]
        new = axes @ np.diag(fixed) @ axes.T
        for key, (i, j) in zip(_INERTIA_KEYS, ((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2))):
            inertia.set(key, repr(float(new[i, j])))
        lines.append(f"link {name!r}: inertia repaired, smallest principal moment "
                     f"{moments[0]:.6g} -> {fixed[0]:.6g} kg m^2 (the others "
                     f"{moments[1]:.6g}, {moments[2]:.6g} and the axes kept)")
    if refused:
        hint = "" if repair else "; repair_inertia raises the smallest principal moments"
        raise ValueError(f"inertias that are not a rigid body's: {'; '.join(refused)}{hint}")
    return lines
