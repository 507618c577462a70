"""Checks of a mapping service's requests before any work is done or memory allocated.

A request's sizes come from a peer on the network: a Matrix with ``rows = 50,000,000`` and
``cols = 0`` holds no values at all, yet the answer it asks for would take gigabytes. So a
transfer is checked against the model and the service's memory budget from its shape alone
(:func:`check_transfer`), with the messages the library's own checks give, and a correspondence
batch from its shape (:func:`check_batch`), before anything is allocated.
"""
import numpy as np

from lpa_transfer.transfer.model_store import block_rows

MIB = 2 ** 20
_FLOAT = np.dtype(np.float64).itemsize


def transfer_bytes(model, rows, block_elements=None):
    """Bytes a transfer of ``rows`` points through ``model`` allocates, estimated from its
    shape: the answer (rows x target dimensions x 8) and its work arrays — as much again for
    one block (a PA model, or an LPA model of fewer rows than a block), else one block's
    share of the answer and of its points x clusters (``block_elements``)."""
    answer = int(rows) * int(model.n_features_out_) * _FLOAT
    step = block_rows(model, block_elements)
    if step is None or rows <= step:
        return 2 * answer
    return answer + step * int(model.n_features_out_) * _FLOAT + int(block_elements) * _FLOAT


def check_transfer(model, shape, block_elements, max_mib):
    """The (rows, target dimensions) of the answer to a transfer of source points of ``shape``
    (rows, cols) through ``model``; ValueError, before anything is allocated, for a source
    without columns or of another width than the model's (the library's messages) and for a
    transfer whose :func:`transfer_bytes` exceed ``max_mib`` MiB (naming the parameter
    ``max_transfer_mib``)."""
    rows, cols = (int(size) for size in shape)
    if cols == 0:
        raise ValueError("source has no columns")
    if cols != model.n_features_in_:
        raise ValueError(f"source has {cols} columns but the model was fitted on "
                         f"{model.n_features_in_} source dimensions")
    needed = transfer_bytes(model, rows, block_elements)
    if needed > max_mib * MIB:
        raise ValueError(f"a transfer of {rows} points into {int(model.n_features_out_)} "
                         f"target dimensions takes about {needed / MIB:.1f} MiB, beyond the "
                         f"limit max_transfer_mib = {max_mib} (a parameter of lpa_mapping): "
                         f"send the points in smaller requests")
    return rows, int(model.n_features_out_)


def check_batch(source_shape, target_shape, max_points):
    """ValueError unless a correspondence batch of these (rows, cols) shapes has columns on
    both sides, as many rows on each and at most ``max_points`` (the fit limit
    ``max_fit_points``) rows: checked before its rows are taken apart."""
    for name, (rows, cols) in (("source", source_shape), ("target", target_shape)):
        if cols == 0 and rows:
            raise ValueError(f"{name} has no columns")
    if source_shape[0] != target_shape[0]:
        raise ValueError(f"source and target have {source_shape[0]} and {target_shape[0]} "
                         f"rows: one row per correspondence")
    if source_shape[0] > max_points:
        raise ValueError(f"the batch's {source_shape[0]} correspondences exceed the limit "
                         f"max_fit_points = {max_points} (a parameter of lpa_mapping)")


def file_inside(directory, name):
    """The file ``name`` names inside ``directory`` (a relative name is taken in it); one
    that resolves outside it (an absolute path, ``..``, a symbolic link) is a ValueError."""
    path = (directory / name).resolve()
    if not path.is_relative_to(directory):
        raise ValueError(f"correspondence_file {name!r} is outside the data directory "
                         f"{directory} (the parameter data_dir): only files in it are "
                         f"read; give a path relative to it")
    return path
