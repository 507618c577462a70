"""The fit of a transfer model as one record: the method and its hyperparameters.

The mapping service's FitModel request, the correspondence collector's parameters and the
mapping client's keyword arguments carry the same fields; :class:`FitSpec` writes them once,
with one default rule (0 or empty: the default), and turns them into the hyperparameters of
PA (thesis Alg. 1-2) or LPA (Alg. 3-5).
"""
from dataclasses import dataclass, field, fields

from lpa_transfer.transfer.cross_validation import held_out_nmse
from lpa_transfer.transfer.local_procrustes import LocalProcrustesAnalysis
from lpa_transfer.transfer.model_store import METHODS
from lpa_transfer.transfer.procrustes import ProcrustesAnalysis

LPA_DEFAULTS = LocalProcrustesAnalysis().get_params()


def _field(default, description, **constraints):
    """A FitSpec field: its default, what it is and the values it takes (``range``, both ends
    inclusive, None for an open side; ``choices``)."""
    return field(default=default,
                 metadata=dict(description=description, constraints=constraints))


@dataclass(frozen=True)
class FitSpec:
    """What to fit: ``method`` ('pa' or 'lpa') and its hyperparameters, in FitModel.srv's
    order; 0 or empty means the default (:meth:`hyperparameters`)."""

    method: str = _field("lpa", "as in FitModel.srv: pa or lpa", choices=tuple(METHODS))
    latent_dim: int = _field(0, "as in FitModel.srv; 0: the service's default (no limit)",
                             range=(0, None))
    n_min: int = _field(0, "as in FitModel.srv: LPA's N_min; 0: the service's default",
                        range=(0, None))
    c_min: float = _field(0.0, "as in FitModel.srv: LPA's c_min (0: always split)",
                          range=(0.0, None))
    k_max: int = _field(0, "as in FitModel.srv: LPA's most clusters; 0: no limit",
                        range=(0, None))
    cluster_dims: tuple = _field((), "as in FitModel.srv: the source columns LPA clusters "
                                 "in; unset: all source dimensions")
    n_init: int = _field(0, "as in FitModel.srv: LPA's k-means restarts; 0: the service's "
                         "default", range=(0, None))
    random_state: int = _field(0, "the fit's seed (also the folds')", range=(0, None))

    @classmethod
    def from_request(cls, request):
        """The spec of a FitModel request (or any object with its fields)."""
        values = {f.name: getattr(request, f.name) for f in fields(cls)}
        values["cluster_dims"] = tuple(values["cluster_dims"])
        return cls(**values)

    def request_fields(self):
        """The fields of a FitModel request, by name (``cluster_dims`` a list)."""
        values = {f.name: getattr(self, f.name) for f in fields(self)}
        values["cluster_dims"] = list(self.cluster_dims)
        return values

    def hyperparameters(self):
        """The estimator's hyperparameters. 0 / empty mean None for latent_dim, k_max and
        cluster_dims, and the library default for n_min and n_init (a request that leaves
        them unset gets a working model); c_min is taken as given: 0 is meaningful ("always
        split", the thesis' advice to control K with n_min, §3.5)."""
        latent_dim = self.latent_dim or None
        if self.method != "lpa":
            return dict(latent_dim=latent_dim)
        return dict(latent_dim=latent_dim, n_min=self.n_min or LPA_DEFAULTS["n_min"],
                    c_min=self.c_min, k_max=self.k_max or None,
                    cluster_dims=list(self.cluster_dims) or None,
                    n_init=self.n_init or LPA_DEFAULTS["n_init"],
                    random_state=self.random_state)

    def held_out_errors(self, source, target, n_folds):
        """The k-fold held-out nMSE of the target columns of the model this spec fits and of
        PA beside it, by method ('pa', then 'lpa' for an LPA spec), folds seeded by
        ``random_state``."""
        hyperparameters = self.hyperparameters()
        estimators = {"pa": ProcrustesAnalysis(latent_dim=hyperparameters["latent_dim"])}
        if self.method == "lpa":
            estimators["lpa"] = LocalProcrustesAnalysis(**hyperparameters)
        return {name: held_out_nmse(estimator, source, target, n_folds, self.random_state)
                for name, estimator in estimators.items()}


def limited(hyperparameters, n_points, limits):
    """The hyperparameters of a fit within a service's ``limits`` (limit name -> value):
    ``k_max = None`` (0 in the request) becomes ``max_k_max``; more correspondences than
    ``max_fit_points``, an n_init above ``max_n_init`` or a k_max above ``max_k_max`` is a
    ValueError naming the limit parameter and its value."""
    def refuse(what, name):
        raise ValueError(f"{what} exceeds the limit {name} = {limits[name]} (a parameter of "
                         f"lpa_mapping)")
    if n_points > limits["max_fit_points"]:
        refuse(f"the fit's {n_points} correspondences", "max_fit_points")
    hyperparameters = dict(hyperparameters)
    if "n_init" in hyperparameters:
        if hyperparameters["n_init"] > limits["max_n_init"]:
            refuse(f"n_init = {hyperparameters['n_init']}", "max_n_init")
        if hyperparameters["k_max"] is None:
            hyperparameters["k_max"] = limits["max_k_max"]
        elif hyperparameters["k_max"] > limits["max_k_max"]:
            refuse(f"k_max = {hyperparameters['k_max']}", "max_k_max")
    return hyperparameters
