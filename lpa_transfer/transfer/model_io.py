"""The model file format: a versioned ``.npz`` archive, read without pickle.

A model file is a NumPy ``.npz`` (zip of ``.npy`` arrays) with these entries:

=====================  =====================================================================
``format``             the string ``"lpa_transfer-model"``
``format_version``     integer, currently ``1``; readers refuse versions they do not know
``model_class``        ``"ProcrustesAnalysis"`` or ``"LocalProcrustesAnalysis"``
``hyperparameters``    JSON text of the constructor arguments (``get_params()``)
``<attribute>_``       one entry per learned attribute (float64/int arrays; scalars as 0-d
                       arrays), named exactly as the attribute, e.g. ``coef_``, ``means_``
``metadata``           optional: JSON text of an object describing the model (the model
                       store's robot names, column names, training error); files without it
                       (written before it existed) load with empty metadata
=====================  =====================================================================

Arrays are stored bit for bit, so a loaded model transfers bit-identically. Files are written
to a temporary name and renamed, so a crash never leaves a half-written model behind.
"""
import json
import os
import tempfile

import numpy as np

from lpa_transfer._validation import open_regular_file

FORMAT = "lpa_transfer-model"
FORMAT_VERSION = 1
_REGISTRY = {}
#: ``save`` writes to ``<prefix>*.npz`` beside the model and renames it into place.
TEMPORARY_PREFIX = ".tmp-"


class SavableModel:
    """Mixin: ``save(path)`` and ``load(path)`` for estimators that list ``_learned``."""

    _learned = ()

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        _REGISTRY[cls.__name__] = cls

    def save(self, path, metadata=None):
        """Write the fitted model to ``path`` (see the module docstring for the format), with
        ``metadata`` (a JSON-serialisable dict) if given."""
        from lpa_transfer._validation import check_fitted
        check_fitted(self)
        entries = {
            "format": np.array(FORMAT),
            "format_version": np.array(FORMAT_VERSION),
            "model_class": np.array(type(self).__name__),
            "hyperparameters": np.array(json.dumps(self.get_params())),
        }
        if metadata is not None:
            if not isinstance(metadata, dict):
                raise ValueError(f"metadata must be a dict, got {type(metadata).__name__}")
            try:
                entries["metadata"] = np.array(json.dumps(metadata, allow_nan=True))
            except (TypeError, ValueError) as exc:
                raise ValueError(f"metadata must be JSON-serialisable: {exc}") from None
        entries.update({name: np.asarray(getattr(self, name)) for name in self._learned})
        path = os.fspath(path)
        directory = os.path.dirname(os.path.abspath(path))
        fd, tmp = tempfile.mkstemp(dir=directory, prefix=TEMPORARY_PREFIX, suffix=".npz")
        try:
            with os.fdopen(fd, "wb") as stream:
                np.savez(stream, **entries)
                stream.flush()
                os.fsync(stream.fileno())      # the data on disk before the name points at it
            os.replace(tmp, path)
            _fsync_directory(directory)        # and the rename itself survives a power loss
        except BaseException:
            if os.path.exists(tmp):
                os.unlink(tmp)
            raise
        return path

    @classmethod
    def load(cls, path):
        """Read a model written by :meth:`save`; raises ValueError if it is not one of ours."""
        model = load_model(path)
        if not isinstance(model, cls):
            raise ValueError(f"{path} holds a {type(model).__name__}, not a {cls.__name__}")
        return model


def _fsync_directory(directory):
    fd = os.open(directory, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def load_model(path):
    """Load any lpa_transfer model file, dispatching on its ``model_class`` entry.

    Any file that is not a complete model of ours — truncated, empty, failing its zip CRCs,
    of another format, or with learned arrays that do not fit together — raises ValueError
    naming the file and the reason (the model is tried on one point before it is returned).
    """
    return load_model_and_metadata(path)[0]


def load_model_and_metadata(path):
    """``(model, metadata)`` of a model file: as :func:`load_model`, and the dict saved with
    it (``{}`` for a file without); metadata that is not a JSON object is a ValueError."""
    try:
        model, metadata = _read_model(path)
        model.transfer(np.zeros((1, int(model.n_features_in_))))
    except ValueError as exc:
        if str(path) in str(exc):
            raise
        raise ValueError(f"model file {path} does not hold a working model: {exc}") from None
    except Exception as exc:  # BadZipFile, zlib.error, EOFError, KeyError, shape errors...
        raise ValueError(f"cannot read model file {path}: {type(exc).__name__}: {exc}") from None
    return model, metadata


def _read_model(path):
    try:
        file = open_regular_file(path, "model file")
    except OSError as exc:
        raise ValueError(f"cannot read model file {path}: {exc}") from None
    with file:
        return _read_archive(path, file)


#: The first bytes of a zip archive (an .npz): a local file header, or an empty archive's end.
_ZIP_MAGIC = (b"PK\x03\x04", b"PK\x05\x06")


def _read_archive(path, file):
    if file.read(4) not in _ZIP_MAGIC:   # numpy would take it for a pickle and say so
        raise ValueError(f"{path} is not an lpa_transfer model file (not a zip archive)")
    file.seek(0)
    try:
        archive = np.load(file, allow_pickle=False)
    except (OSError, ValueError) as exc:
        raise ValueError(f"cannot read model file {path}: {exc}") from None
    with archive:
        header = {key: archive[key].item() for key in
                  ("format", "format_version", "model_class", "hyperparameters")
                  if key in archive.files}
        if header.get("format") != FORMAT:
            raise ValueError(f"{path} is not an lpa_transfer model file")
        if header.get("format_version") != FORMAT_VERSION:
            raise ValueError(f"{path} has model format version {header.get('format_version')}, "
                             f"this library reads version {FORMAT_VERSION}")
        cls = _REGISTRY.get(header.get("model_class"))
        if cls is None:
            raise ValueError(f"{path} holds an unknown model class {header.get('model_class')!r}")
        model = cls(**json.loads(header["hyperparameters"]))
        missing = [name for name in cls._learned if name not in archive.files]
        if missing:
            raise ValueError(f"{path} lacks the learned attributes {missing}")
        for name in cls._learned:
            value = archive[name]
            setattr(model, name, value.item() if value.ndim == 0 else value)
        metadata = {}
        if "metadata" in archive.files:
            metadata = json.loads(archive["metadata"].item())
            if not isinstance(metadata, dict):
                raise ValueError(f"{path} has metadata that is not a JSON object")
    return model, metadata
