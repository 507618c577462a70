"""Input checks shared by the transfer models.

Every check raises ``ValueError`` with a message that names the offending argument, so a
caller (for example the mapping service) can hand the message straight back to its user.
"""
import numbers
import os
import stat

import numpy as np


def as_matrix(X, name):
    """Return ``X`` as a C-contiguous float64 (rows, cols) array, or raise ValueError."""
    try:
        X = np.asarray(X, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be a numeric 2-D array: {exc}") from None
    if X.ndim != 2:
        raise ValueError(f"{name} must be a 2-D array (rows = samples), got {X.ndim}-D "
                         f"with shape {X.shape}")
    if X.shape[1] == 0:
        raise ValueError(f"{name} has no columns")
    finite = np.isfinite(X)
    if not finite.all():
        row = int(np.argwhere(~finite)[0, 0])
        raise ValueError(f"{name} contains NaN or infinite values (first in row {row})")
    return np.ascontiguousarray(X)


def as_correspondences(source, target, min_rows):
    """Check a correspondence set: ``source[i]`` and ``target[i]`` are in correspondence."""
    source = as_matrix(source, "source")
    target = as_matrix(target, "target")
    if source.shape[0] != target.shape[0]:
        raise ValueError("source and target must have the same number of rows (one row per "
                         f"correspondence): got {source.shape[0]} and {target.shape[0]}")
    if source.shape[0] < min_rows[0]:
        raise ValueError(f"too few correspondences: got {source.shape[0]}, need at least "
                         f"{min_rows[0]} ({min_rows[1]})")
    return source, target


def resolve_latent_dim(latent_dim, n_source_dims, n_target_dims):
    """The latent dimensionality d of PA (thesis §3.2); ``None`` means min(D_s, D_t)."""
    if latent_dim is None:
        return min(n_source_dims, n_target_dims)
    check_int(latent_dim, "latent_dim", minimum=1)
    for side, dims in (("source", n_source_dims), ("target", n_target_dims)):
        if latent_dim > dims:
            raise ValueError(f"latent_dim={latent_dim} is larger than the {side} "
                             f"dimensionality {dims}")
    return int(latent_dim)


def check_int(value, name, minimum):
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < minimum:
        raise ValueError(f"{name} must be an integer >= {minimum}, got {value!r}")


def check_float(value, name, minimum):
    if (isinstance(value, bool) or not isinstance(value, numbers.Real)
            or not np.isfinite(value) or value < minimum):
        raise ValueError(f"{name} must be a finite number >= {minimum}, got {value!r}")


def check_unit(value, name):
    """``value`` must be a real number in (0, 1] (a share, an activation threshold)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not 0 < value <= 1:
        raise ValueError(f"{name} must be a number in (0, 1], got {value!r}")


def check_seed(value):
    if value is not None:
        check_int(value, "random_state", minimum=0)


def not_fitted(message):
    """scikit-learn's NotFittedError (a ValueError and an AttributeError) with ``message``,
    to raise. scikit-learn is imported here, not with the module, so that the nodes start
    without loading it (lpa_transfer._estimator)."""
    from sklearn.exceptions import NotFittedError
    return NotFittedError(message)


def check_fitted(model, attribute="coef_"):
    """scikit-learn's NotFittedError (:func:`not_fitted`) unless ``model`` has ``attribute``."""
    if not hasattr(model, attribute):
        raise not_fitted(f"this {type(model).__name__} is not fitted yet: call "
                         "fit(source, target) first")


def as_transfer_input(model, source):
    """Check the source points handed to ``transfer`` against the fitted width."""
    check_fitted(model)
    source = as_matrix(source, "source")
    if source.shape[1] != model.n_features_in_:
        raise ValueError(f"source has {source.shape[1]} columns but the model was fitted "
                         f"on {model.n_features_in_} source dimensions")
    return source


def check_box(low, high, problem):
    """(low, high) of an axis-aligned box as float arrays; ValueError starting with
    ``problem`` unless they are finite 1-D vectors of one length with low <= high."""
    low, high = (np.asarray(bound, dtype=np.float64) for bound in (low, high))
    if low.ndim != 1 or low.size == 0 or low.shape != high.shape \
            or not (np.isfinite(low).all() and np.isfinite(high).all()) or (low > high).any():
        raise ValueError(f"{problem}, got {low.tolist()} and {high.tolist()}")
    return low, high


def check_x_bounds(x_bounds, n_task=None):
    """``x_bounds`` = (low, high) as two float arrays; ValueError unless finite, of one length
    (``n_task`` if given) and low <= high."""
    try:
        low, high = (np.asarray(bound, dtype=np.float64) for bound in x_bounds)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"x_bounds must be a pair (low, high) of coordinate lists: {exc}") \
            from None
    check_box(low, high, "x_bounds must be finite (low, high) of one length with "
                               "low <= high")
    if n_task is not None and low.size != n_task:
        raise ValueError(f"x_bounds have {low.size} coordinates but the robot's task space has "
                         f"{n_task}")
    return low, high


def finite_transfer(mapped, source):
    """``mapped`` if every value is finite; otherwise ValueError (a transfer never answers
    with inf or NaN for finite inputs silently: e.g. inputs near the float limit)."""
    if not np.isfinite(mapped).all():
        rows = np.flatnonzero(~np.isfinite(mapped).all(axis=1))
        raise ValueError(f"the transferred points of {len(rows)} input rows (first: row "
                         f"{rows[0]}, largest |value| {np.abs(source[rows[0]]).max():.3g}) are "
                         "not finite: the inputs are too large for float64 arithmetic")
    return mapped


_KINDS = ((stat.S_ISDIR, "a directory"), (stat.S_ISFIFO, "a FIFO"), (stat.S_ISSOCK, "a socket"),
          (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"))


def open_regular_file(path, what):
    """``path`` opened for reading in binary mode, never blocking on a FIFO or a device;
    ValueError "<what> <path> is not a regular file (a FIFO)" for anything but a regular file
    (a symbolic link to one is one). Checked with stat before it is opened (a device or a
    socket is never opened), then opened with O_NONBLOCK and checked again on the open
    descriptor, so the file checked is the file read."""
    _check_regular(os.stat(os.fspath(path)).st_mode, path, what)
    fd = os.open(os.fspath(path), os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
    try:
        _check_regular(os.fstat(fd).st_mode, path, what)
    except ValueError:
        os.close(fd)
        raise
    return os.fdopen(fd, "rb")


def _check_regular(mode, path, what):
    if not stat.S_ISREG(mode):
        kind = next((name for test, name in _KINDS if test(mode)), "an unknown kind of file")
        raise ValueError(f"{what} {path} is not a regular file ({kind})")
