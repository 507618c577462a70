"""A user's URDF file as pybullet should load it: mesh paths resolved against the file's own
folder.

* Meshes: pybullet resolves a ``<mesh filename>`` relative to the folder of the file it loads,
  and strips ``package://`` to a path relative to that folder too. The simulator loads URDF
  *text* through a temporary file (:func:`lpa_transfer.robots.planar_chain.load_fixed_robot`),
  so :func:`resolve_mesh_paths` makes every relative and ``package://`` mesh path absolute
  first (only the ``filename`` attributes of ``<mesh>`` change; the rest of the text stays).
"""
import os
import re
from pathlib import Path

_MESH = re.compile(r'(<mesh\b[^>]*?\bfilename\s*=\s*)(["\'])(.*?)\2', re.S)


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

