"""A directory of fitted transfer models keyed by caller-chosen model ids.

One mapping service serves many robot pairs, so each model is stored under an id such as
``pincher->youbot``. A model lives in ``<directory>/<encoded id>.npz`` (the library's model
file, see :mod:`lpa_transfer.transfer.model_io`). The file name is the id percent-encoded
(``urllib.parse.quote`` with no safe characters, and ``.`` encoded too), so any id maps to a
plain file name, the mapping is reversible (the id survives a restart with no index file to
keep in step) and no model file starts with ``.`` like the library's temporary files.

Each model carries metadata (:data:`METADATA`), saved in its file (the ``metadata`` entry of
the model file): the robots' names and the columns' names a caller gave, where the
correspondences came from and the training error. A file without it loads with the defaults.
"""
import os
import threading
import urllib.parse
from pathlib import Path

import numpy as np

from lpa_transfer.transfer import gmm
from lpa_transfer.transfer.local_procrustes import LocalProcrustesAnalysis
from lpa_transfer.transfer.model_io import TEMPORARY_PREFIX, load_model_and_metadata
from lpa_transfer.transfer.procrustes import ProcrustesAnalysis

#: Transfer methods by the name a caller uses: one global map (PA) or local maps (LPA).
METHODS = {"pa": ProcrustesAnalysis, "lpa": LocalProcrustesAnalysis}
SUFFIX = ".npz"
_MAX_FILE_NAME = 255
#: A model's metadata and its defaults (a model file written without it): the robots' names,
#: the names of the source and target columns (one per dimension, or none), the training
#: RMSE (:func:`training_rmse`; NaN: unknown) and where the correspondences came from.
METADATA = dict(source_robot="", target_robot="", source_features=[], target_features=[],
                training_rmse=float("nan"), correspondences="")


def training_rmse(model, source, target):
    """Root-mean-square Euclidean error of the model on its correspondences."""
    error = model.transfer(source) - np.asarray(target, dtype=np.float64)
    return float(np.sqrt((error ** 2).sum(axis=1).mean()))


def block_rows(model, block_elements):
    """Rows per block of a blocked transfer through ``model``: about ``block_elements``
    (points x clusters) for an LPA model, None (one block) for PA or ``block_elements=None``.

    A multiple of the rows of the responsibility blocks that LPA's transfer computes anyway
    (:func:`lpa_transfer.transfer.gmm.row_blocks`), so that both see the same blocks of rows.
    """
    n_clusters = getattr(model, "n_clusters_", None)
    if block_elements is None or n_clusters is None:
        return None
    dim = len(model.cluster_dims_)
    width = max(int(n_clusters), dim * (dim + 1) // 2 + dim)   # as Responsibilities.blocks
    step = max(1, gmm._BLOCK_ELEMENTS // width)
    return max(step, int(block_elements) // int(n_clusters) // step * step)


def transfer_in_blocks(model, source, block_elements=None, out=None):
    """``model.transfer(source)`` (LPA Alg. 4) computed block of rows by block of rows, so
    that the work arrays of an LPA transfer stay near ``block_elements`` (points x clusters)
    however many points there are; the result (M, D_t) is written into one array, ``out`` if
    given (e.g. a view of the buffer a reply is sent from). The same values as one call, to
    the last bit or within 1e-12 (the sparse path of
    :func:`~lpa_transfer.transfer.local_procrustes.mix_local_maps` may group its matrix
    products differently). Bad input raises ValueError naming the row in ``source``.
    """
    rows = block_rows(model, block_elements)
    source = np.asarray(source, dtype=np.float64) if rows is not None else source
    if (rows is None or source.ndim != 2 or len(source) <= rows
            or source.shape[1] != model.n_features_in_):
        result = model.transfer(source)      # one block; the library checks the input
        if out is None:
            return result
        out[...] = result
        return out
    if out is None:
        out = np.empty((len(source), int(model.n_features_out_)))
    for start in range(0, len(source), rows):
        block = source[start:start + rows]
        finite = np.isfinite(block)
        if not finite.all():
            row = start + int(np.argwhere(~finite)[0, 0])
            raise ValueError(f"source contains NaN or infinite values (first in row {row})")
        try:
            out[start:start + rows] = model.transfer(block)
        except ValueError as exc:
            raise ValueError(f"{exc} (in the block of source rows {start}-"
                             f"{start + len(block) - 1})") from None
    return out


def check_metadata(metadata, source_dim, target_dim):
    """The full metadata (:data:`METADATA`'s defaults for what ``metadata`` leaves out) of a
    model of these dimensions; ValueError for unknown keys, values of the wrong type or
    column names that are not one per dimension."""
    unknown = sorted(set(metadata) - set(METADATA))
    if unknown:
        raise ValueError(f"unknown metadata {unknown}; known: {sorted(METADATA)}")
    full = {**METADATA, **metadata}
    for key in ("source_robot", "target_robot", "correspondences"):
        if not isinstance(full[key], str):
            raise ValueError(f"{key} must be a string, got {full[key]!r}")
    for key, dim in (("source_features", source_dim), ("target_features", target_dim)):
        names = full[key] = list(full[key])
        if not all(isinstance(name, str) for name in names):
            raise ValueError(f"{key} must be strings, got {names!r}")
        if names and len(names) != dim:
            raise ValueError(f"{key} names {len(names)} columns but the {key.split('_')[0]} "
                             f"has {dim}: give one name per column, or none")
    full["training_rmse"] = float(full["training_rmse"])
    return full


def _copied(metadata):
    return {key: list(value) if isinstance(value, list) else value
            for key, value in metadata.items()}


def method_of(model):
    return next(name for name, cls in METHODS.items() if type(model) is cls)


def method_class(method):
    """The model class of ``method`` ("pa" or "lpa"); ValueError names the known methods."""
    try:
        return METHODS[method]
    except (KeyError, TypeError):
        raise ValueError(f"unknown method {method!r}; known: {sorted(METHODS)}") from None


def file_name(model_id):
    """The model file name of ``model_id``; ValueError for ids that cannot name a model."""
    if not isinstance(model_id, str) or not model_id:
        raise ValueError("model id must be a non-empty string")
    if any(ord(char) < 32 or ord(char) == 127 for char in model_id):
        raise ValueError(f"model id {model_id!r} contains control characters")
    name = urllib.parse.quote(model_id, safe="").replace(".", "%2E") + SUFFIX
    if len(name.encode()) > _MAX_FILE_NAME:
        raise ValueError(f"model id {model_id[:40]!r}... is too long for a file name")
    return name


def model_id_of(path):
    return urllib.parse.unquote(Path(path).name[:-len(SUFFIX)])


class ModelStore:
    """Fitted PA/LPA models persisted in ``directory``, all reloaded on construction.

    One bad file never keeps the others from being served: at construction a file that cannot
    be loaded as a working model is moved to ``<directory>/quarantine/`` (its id in
    ``quarantined``, the reason in ``load_errors``); temporary files left by a save that was
    killed are removed; a model file under a name that is not its id's (placed by hand, e.g.
    ``pa.v2.npz`` for id ``pa.v2``) is renamed to it, or quarantined if the id's own file is
    there too, so that one id is one file and ``delete`` removes it. Entries that are not
    regular files (a FIFO, a device, a socket, a directory) are never opened for reading, so
    none blocks the start: they are quarantined like bad files. If ``quarantine`` is taken by
    something other than a directory, ``quarantine.1/`` (or the next free number) is used, and
    a file that cannot be moved aside at all is left in place, not served, with the reason.

    Thread-safe: fits, transfers, descriptions and deletions may run in several threads. A
    fit computes its model without a lock, then saves it and swaps it in under the store's
    write lock, so a model being refitted answers with its previous version until the new one
    is saved and stored, and the file and the served model change together.
    """

    QUARANTINE = "quarantine"

    def __init__(self, directory):
        self.directory = Path(directory).expanduser()
        self.directory.mkdir(parents=True, exist_ok=True)
        self._models, self.load_errors, self.quarantined = {}, [], []
        self._lock = threading.Lock()           # the dict of models: lookups and the swap
        self._write_lock = threading.Lock()     # one save or delete at a time
        for stale in self.directory.glob(TEMPORARY_PREFIX + "*" + SUFFIX):
            try:
                stale.unlink(missing_ok=True)     # a save killed before its rename
            except OSError as exc:                # e.g. a directory of that name
                self.load_errors.append(f"{stale.name} left in place: {exc}")
        for path in sorted(self.directory.glob("*" + SUFFIX)):
            model_id = model_id_of(path)
            try:
                canonical = self.path(model_id)
            except ValueError as exc:
                self._quarantine(path, model_id, str(exc))
                continue
            if path != canonical:
                if canonical.exists():
                    self._quarantine(path, model_id, f"a second file for id {model_id!r} "
                                     f"beside {canonical.name}")
                    continue
                path = path.rename(canonical)
            try:
                model, metadata = load_model_and_metadata(path)
                self._models[model_id] = (model, check_metadata(
                    metadata, model.n_features_in_, model.n_features_out_))
            except ValueError as exc:
                self._quarantine(path, model_id, str(exc))

    def _quarantine(self, path, model_id, reason):
        self.quarantined.append(model_id)
        try:
            folder = self._quarantine_folder()
            path.replace(folder / path.name)
            where = f"moved to {folder.name}/"
            if folder.name != self.QUARANTINE:
                where += f" ({self.QUARANTINE} in {self.directory} is not a directory)"
        except OSError as exc:
            where = f"left in place, not served (it cannot be moved aside: {exc})"
        self.load_errors.append(f"{path.name} {where}: {reason}")

    def _quarantine_folder(self):
        """``quarantine/`` in the directory, created if need be; if an entry that is not a
        directory holds that name, the first of ``quarantine.1/``, ``quarantine.2/``, ...
        that is a directory or free (OSError if none of the first 100 is)."""
        for number in range(100):
            folder = self.directory / (self.QUARANTINE + (f".{number}" if number else ""))
            if folder.is_dir() or not os.path.lexists(folder):
                folder.mkdir(exist_ok=True)
                return folder
        raise OSError(f"no quarantine folder: {self.QUARANTINE} to {self.QUARANTINE}.99 in "
                      f"{self.directory} are taken by files that are not directories")

    def path(self, model_id):
        return self.directory / file_name(model_id)

    def ids(self):
        """The stored model ids, sorted."""
        with self._lock:
            return sorted(self._models)

    def _entry(self, model_id):
        with self._lock:
            entry = self._models.get(model_id)
        if entry is None:
            raise ValueError(f"unknown model id {model_id!r}; known: {self.ids()}")
        return entry

    def get(self, model_id):
        """The model stored under ``model_id``; ValueError names the known ids."""
        return self._entry(model_id)[0]

    def metadata(self, model_id):
        """The metadata of the model ``model_id`` (:data:`METADATA`), a copy."""
        return _copied(self._entry(model_id)[1])

    def fit(self, model_id, method, source, target, metadata=None, **hyperparameters):
        """Fit a ``method`` model on the correspondences, save it under ``model_id`` with
        ``metadata`` (:data:`METADATA`; the training RMSE is computed here) replacing any model
        of that id, and return it; ``metadata(model_id)`` then gives its metadata."""
        path = self.path(model_id)
        cls = method_class(method)
        unknown = sorted(set(hyperparameters) - set(cls().get_params()))
        if unknown:
            raise ValueError(f"method {method!r} has no hyperparameters {unknown}")
        metadata = dict(metadata or {})
        metadata.pop("training_rmse", None)
        model = cls(**hyperparameters)
        if np.ndim(source) == 2 and np.ndim(target) == 2:     # a bad request before the fit
            check_metadata(metadata, np.shape(source)[1], np.shape(target)[1])
        model.fit(source, target)
        metadata = check_metadata(dict(metadata, training_rmse=training_rmse(
            model, source, target)), model.n_features_in_, model.n_features_out_)
        with self._write_lock:
            model.save(path, metadata)
            with self._lock:
                self._models[model_id] = (model, metadata)
        return model

    def transfer(self, model_id, source, block_elements=None, out=None):
        """Map source points through the model ``model_id``; an LPA model in blocks of about
        ``block_elements`` points x clusters, into ``out`` if given
        (:func:`transfer_in_blocks`)."""
        return transfer_in_blocks(self.get(model_id), source, block_elements, out)

    def describe(self, model_id):
        """Method, dimensions, number of local maps and correspondences, hyperparameters and
        the model's metadata (:data:`METADATA`)."""
        model, metadata = self._entry(model_id)       # one entry: model and metadata agree
        return dict(method=method_of(model), source_dim=int(model.n_features_in_),
                    target_dim=int(model.n_features_out_),
                    n_clusters=int(getattr(model, "n_clusters_", 1)),
                    n_points=int(model.n_correspondences_), hyperparameters=model.get_params(),
                    **_copied(metadata))

    def delete(self, model_id):
        """Forget the model ``model_id`` and remove its file."""
        with self._write_lock:
            self.get(model_id)
            self.path(model_id).unlink(missing_ok=True)
            with self._lock:
                del self._models[model_id]
