"""Joint-space Dynamic Movement Primitives (thesis §4.4.4, eq. 4.1-4.5), on movement_primitives.

The thesis encodes each transferred joint trajectory q̂_{1:T} as a DMP, one transformation
system per joint with a common phase x and time constant τ:

    τ ż = α_z (β_z (q_g − q) − z) + g(x),   τ q̇ = z,   τ ẋ = −α_x x    (eq. 4.1-4.3)
    g(x) = x Σ_i w_i Ψ_i(x) / Σ_i Ψ_i(x),   Ψ_i(x) = exp(−h_i (x − c_i)²)  (eq. 4.4-4.5)

Eliminating z = τ q̇ gives the transformation system of :class:`movement_primitives.dmp.DMP`
(Fabisch, DFKI; BSD-3) with α_y = α_z, β_y = β_z and forcing term f = g: eq. 4.4 exactly,
with no (q_g − q_0) amplitude factor (Ijspeert et al. 2013 have one, the thesis does not).
``fit_many`` learns one DMP from several demonstrations, as §4.5.2 does ("We learned a DMP
model from the 5 transferred demonstrations for each letter"): their phases aligned, one
ridge regression over all their samples. What the thesis leaves open (α_x, the centres and
widths, the derivatives, the integrator) and our defaults (α_z = 25, β_z = α_z/4, N = 30
weights per joint): docs/library.md, "DMPs".
"""
import numpy as np
from movement_primitives.dmp import DMP
# Private helpers of DMP.imitate: fit_many needs its regression over several demonstrations
# at once, which the public API does not offer; the pin movement_primitives==0.9.1
# (requirements/python.txt) keeps them fixed and test/test_dmp.py checks what they compute.
from movement_primitives.dmp._dmp import determine_forces, ridge_regression

from lpa_transfer import _validation as check
from lpa_transfer._estimator import Estimator

#: ``integrator`` values: the library's pure-Python step functions (identical on every
#: install, whether or not its optional C extension was built).
INTEGRATORS = ("rk4", "euler")


def _as_times(times, name, minimum):
    try:
        times = np.array(times, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be a numeric 1-D array: {exc}") from None
    if times.ndim != 1:
        raise ValueError(f"{name} must be a 1-D array of sample times, got shape {times.shape}")
    if len(times) < minimum:
        raise ValueError(f"{name} must have at least {minimum} samples, got {len(times)}")
    if not np.isfinite(times).all():
        raise ValueError(f"{name} contains NaN or infinite values")
    if (np.diff(times) <= 0).any():
        raise ValueError(f"{name} must be strictly increasing")
    return times


def _as_demonstration(times, Q, k=None):
    """Check one demonstration; ``k`` is its index in ``fit_many`` (named in the errors)."""
    t_name, q_name = ("times", "Q") if k is None else (f"times_list[{k}]", f"Q_list[{k}]")
    Q = check.as_matrix(Q, q_name)
    if len(Q) < 3:
        raise ValueError(f"{q_name} must have at least 3 samples (rows) for the finite "
                         f"differences, got {len(Q)}")
    times = _as_times(times, t_name, minimum=3)
    if len(Q) != len(times):
        raise ValueError(f"{q_name} has {len(Q)} rows but {t_name} has {len(times)} samples")
    return times, Q


def _as_vector(value, name, n):
    value = np.asarray(value, dtype=np.float64)
    if value.shape != (n,) or not np.isfinite(value).all():
        raise ValueError(f"{name} must be a finite vector of {n} joint values, got shape "
                         f"{value.shape}")
    return value.copy()


class JointDMP(Estimator):
    """A DMP over d joints with a common phase (thesis eq. 4.1-4.5; module docstring).

    Parameters
    ----------
    n_weights_per_dim : int
        N, the radial basis functions (and weights w_i) per joint, eq. 4.4-4.5.
    alpha_z, beta_z : float
        Gains of eq. 4.1; ``beta_z=None`` uses α_z/4 (critical damping).
    regularization : float
        Ridge coefficient of the weight regression (0: ordinary least squares).
    integrator : {"rk4", "euler"}

    Learned attributes
    ------------------
    weights_ : (d, N) the w_i of every joint
    start_, goal_ : (d,) q_0 and q_g, the first and last configurations of the (first)
        demonstration
    tau_ : τ, the demonstration's duration (s); with ``fit_many`` the mean duration
    times_ : (T,) the (first) demonstration's sample times, shifted to start at 0 (and
        rescaled to span [0, τ])
    n_features_in_ : d
    n_demonstrations_ : the number of demonstrations fitted
    """

    def __init__(self, n_weights_per_dim=30, alpha_z=25.0, beta_z=None, regularization=0.0,
                 integrator="rk4"):
        self.n_weights_per_dim = n_weights_per_dim
        self.alpha_z = alpha_z
        self.beta_z = beta_z
        self.regularization = regularization
        self.integrator = integrator

    def _library_dmp(self, n_dims, tau):
        check.check_int(self.n_weights_per_dim, "n_weights_per_dim", minimum=2)
        check.check_float(self.alpha_z, "alpha_z", minimum=0.0)
        beta_z = self.alpha_z / 4 if self.beta_z is None else self.beta_z
        check.check_float(beta_z, "beta_z", minimum=0.0)
        if self.alpha_z == 0 or beta_z == 0:
            raise ValueError("alpha_z and beta_z must be > 0")
        check.check_float(self.regularization, "regularization", minimum=0.0)
        if self.integrator not in INTEGRATORS:
            raise ValueError(f"integrator must be one of {INTEGRATORS}, got {self.integrator!r}")
        return DMP(n_dims=n_dims, execution_time=tau, n_weights_per_dim=self.n_weights_per_dim,
                   alpha_y=float(self.alpha_z), beta_y=float(beta_z))

    def fit(self, times, Q):
        """Learn the DMP from one joint trajectory ``Q`` (T, d) sampled at ``times`` (T,) s."""
        return self._fit([_as_demonstration(times, Q)])

    def fit_many(self, times_list, Q_list):
        """Learn one DMP from several demonstrations (thesis §4.5.2; module docstring).

        ``Q_list[k]`` (T_k, d) is sampled at ``times_list[k]`` (T_k,) s; T_k and the durations
        may differ. start_, goal_ and times_ are the first demonstration's.
        """
        times_list, Q_list = list(times_list), list(Q_list)
        if len(times_list) != len(Q_list):
            raise ValueError(f"times_list has {len(times_list)} demonstrations but Q_list has "
                             f"{len(Q_list)}")
        if not Q_list:
            raise ValueError("fit_many needs at least one demonstration")
        demos = [_as_demonstration(t, Q, k) for k, (t, Q) in enumerate(zip(times_list, Q_list))]
        for k, (_, Q) in enumerate(demos):
            if Q.shape[1] != demos[0][1].shape[1]:
                raise ValueError(f"Q_list[{k}] has {Q.shape[1]} joints (columns) but Q_list[0] "
                                 f"has {demos[0][1].shape[1]}")
        return self._fit(demos)

    def _fit(self, demos):
        """Ridge regression of eq. 4.4's weights on the stacked samples of checked demos."""
        tau = float(np.mean([t[-1] - t[0] for t, _ in demos]))
        dmp = self._library_dmp(demos[0][1].shape[1], tau)
        term = dmp.forcing_term
        # each demonstration on [0, τ], so the phases line up (its targets and features are
        # invariant to this up to rounding: the library computes them in units of its duration)
        rescaled = [(t - t[0]) * (tau / (t[-1] - t[0])) for t, _ in demos]
        X = [term.design_matrix(t) for t in rescaled]                         # (N, T_k)
        F = [determine_forces(t, Q, dmp.alpha_y, dmp.beta_y, term.alpha_z,
                              allow_final_velocity=False, smooth_scaling=dmp.smooth_scaling)[0]
             for t, (_, Q) in zip(rescaled, demos)]                           # (T_k, d)
        self.weights_ = ridge_regression(np.hstack(X), np.vstack(F), float(self.regularization))
        self.start_, self.goal_ = demos[0][1][0].copy(), demos[0][1][-1].copy()
        self.tau_, self.times_ = tau, rescaled[0]
        self.n_features_in_ = demos[0][1].shape[1]
        self.n_demonstrations_ = len(demos)
        return self

    def reproduce(self, times=None, start=None, goal=None):
        """Integrate the DMP from ``start`` to ``goal`` (default: the first demonstration's).

        ``times`` (T,) are the sample times in s, the movement starting at ``times[0]``; they
        may run past τ. Default: the first demonstration's. Returns Q (T, d), Q[0] = start.
        """
        check.check_fitted(self, "weights_")
        d = self.n_features_in_
        times = self.times_ if times is None else _as_times(times, "times", minimum=1)
        start = self.start_.copy() if start is None else _as_vector(start, "start", d)
        goal = self.goal_.copy() if goal is None else _as_vector(goal, "goal", d)
        dmp = self._library_dmp(d, self.tau_)
        dmp.set_weights(np.asarray(self.weights_, dtype=np.float64))
        dmp.configure(start_y=start, goal_y=goal)
        dmp.reset()
        Q = np.empty((len(times), d))
        Q[0] = y = start.copy()
        yd = np.zeros(d)
        for k, dt in enumerate(np.diff(times), start=1):
            dmp.dt_ = dt                       # the library advances its clock by dt_
            y, yd = dmp.step(y, yd, step_function=self.integrator)
            Q[k] = y
        return Q
