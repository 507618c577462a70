"""scikit-learn's estimator protocol (``get_params``, ``set_params``, ``clone``) without
importing scikit-learn.

Why: importing ``sklearn.base`` loads scipy.stats and most of scikit-learn, which a node pays
at every start (the mapping service, the goal-babbling learner, the collector, the skill
learner). PA, LPA, the k-NN sensorimotor model and the DMP only need the protocol: their
hyperparameters are their ``__init__`` arguments, stored unchanged, and their learned state
ends in ``_``. So ``sklearn.base.clone`` and parameter handling by name (nested ones as
``name__parameter``) work with them as with a BaseEstimator; scikit-learn's other machinery
(metadata routing, HTML repr) is not offered. LWPR stays a BaseEstimator: it is a full
scikit-learn regressor (``check_estimator``).
"""
import copy
import inspect


class Estimator:
    """Base of the sklearn-style estimators that must not load scikit-learn."""

    @classmethod
    def _param_names(cls):
        parameters = inspect.signature(cls.__init__).parameters.values()
        return sorted(p.name for p in parameters
                      if p.name != "self" and p.kind not in (p.VAR_POSITIONAL, p.VAR_KEYWORD))

    def get_params(self, deep=True):
        """The hyperparameters by name; with ``deep``, those of nested estimators as
        ``name__parameter`` too (scikit-learn's convention)."""
        params = {}
        for name in self._param_names():
            value = getattr(self, name)
            if deep and _is_estimator(value):
                params.update((f"{name}__{key}", nested)
                              for key, nested in value.get_params().items())
            params[name] = value
        return params

    def set_params(self, **params):
        """Set hyperparameters (``name__parameter`` reaches a nested estimator); returns
        self. An unknown name is a ValueError that lists the valid ones."""
        valid = self._param_names()
        nested = {}
        for key, value in params.items():
            name, _, rest = key.partition("__")
            if name not in valid:
                raise ValueError(f"invalid parameter {name!r} for {type(self).__name__}; "
                                 f"valid parameters: {valid}")
            if rest:
                nested.setdefault(name, {})[rest] = value
            else:
                setattr(self, name, value)
        for name, values in nested.items():
            getattr(self, name).set_params(**values)
        return self

    def __repr__(self):
        defaults = inspect.signature(type(self).__init__).parameters
        changed = [f"{name}={value!r}" for name, value in self.get_params(deep=False).items()
                   if not _is_default(value, defaults[name].default)]
        return f"{type(self).__name__}({', '.join(changed)})"


def _is_estimator(value):
    """An estimator instance (not a class): its parameters nest, it is cloned, not copied."""
    return hasattr(value, "get_params") and not isinstance(value, type)


def _is_default(value, default):
    try:
        return bool(value is default or value == default)
    except (TypeError, ValueError):       # arrays: an elementwise comparison
        return False


def clone(estimator):
    """An unfitted copy with the same hyperparameters (scikit-learn's ``clone``): nested
    estimators are cloned, other values deep-copied."""
    params = {name: clone(value) if _is_estimator(value) else copy.deepcopy(value)
              for name, value in estimator.get_params(deep=False).items()}
    return type(estimator)(**params)
