"""Public names of a package imported on first use (PEP 562), so that importing the package
(e.g. for ``lpa_transfer.robots`` alone) does not import every subpackage and scikit-learn."""
import importlib


def lazy_names(package, names, namespace):
    """``(__getattr__, __dir__)`` for the package ``package`` (its ``__name__``) whose public
    ``names`` map to the modules that define them; ``namespace`` is its ``globals()``."""
    def __getattr__(name):
        if name in names:
            return getattr(importlib.import_module(names[name]), name)
        raise AttributeError(f"module {package!r} has no attribute {name!r}")

    def __dir__():
        return sorted(set(namespace) | set(names))

    return __getattr__, __dir__
