"""Online inverse-dynamics learning for tracking control (thesis ch. 5, §5.3).

:class:`FeedForwardLearner` is the loop of Fig. 5-1 and Fig. 5-2: at every control period it
predicts the feed-forward torque τ_ff = f(q_d, q̇_d, q̈_d) with its online regressor, adds the
PID feedback, applies τ (clipped by the robot) for one control period, and learns from what it
observed: input (q, q̇, q̈), output the applied τ — the sample layout of
:mod:`lpa_transfer.exploration.correspondences` with features (position, velocity, acceleration, effort):
q, q̇ at the end of the period, q̈ the backward difference of velocities over it, τ the torque
applied during it. Transferred or babbled data in that layout initialise the learner offline.

The regressor is a hyperparameter (anything with ``predict``/``partial_fit``, e.g.
:class:`lpa_transfer.learners.lwpr.LWPR`); until it has seen data τ_ff is 0. Samples with NaN or
infinite values are rejected and counted, never learned.

A yielding learner (``yielding``, beyond the thesis, whose future work asks for models that
forget inaccurate transferred knowledge) keeps the transferred data's head start without
letting them hold the tail: LWPR places a new receptive field only where no field answers a
sample above ``w_gen``, so fields made by transferred data, centred on another robot's mapped
states, go on holding the target's own samples with the centres and shapes those data gave
them, while learning from scratch places its fields on the task. After the initial data the
yielding learner raises that threshold to ``own_w_gen`` for the robot's own samples. Of the
designs measured (reference_results/yielding/README.md: the transferred data discounted, a
frozen prior beside an own model as residual or evidence gate), this one alone saved more
than the thesis' initialisation.
"""
from dataclasses import dataclass

import numpy as np
from sklearn.exceptions import NotFittedError

from lpa_transfer._validation import check_unit
from lpa_transfer.exploration.correspondences import feature_vector
from lpa_transfer.inverse_dynamics.tasks import tracking_error

ID_FEATURES = ("position", "velocity", "acceleration", "effort")


@dataclass
class Trial:
    """One trial's record: what was asked, what happened, what was learned."""

    tracking_error: float          # mean task-space distance, m (§5.5.2)
    desired: np.ndarray            # (T, m) desired end-effector positions
    actual: np.ndarray             # (T, m) measured end-effector positions
    samples: np.ndarray            # (T, 4n) observed (q, q̇, q̈, τ): the trial's experience
    feedforward: np.ndarray        # (T, n) τ_ff predicted
    end_state: object              # the robot's state after the trial


class FeedForwardLearner:
    """τ = τ_ff(q_d, q̇_d, q̈_d) + PID, τ_ff learned online (module docstring).

    ``regressor``: the online model of τ given (q, q̇, q̈); ``pid``: a
    :class:`lpa_transfer.robots.control.PID`; ``learn``: update online (False to evaluate a frozen
    model). ``yielding``: False learns initial (e.g. transferred) data as the thesis does;
    True lets them yield to the robot's own experience: after them, the regressor (an LWPR)
    makes a receptive field of the robot's own for every sample that no field answers above
    ``own_w_gen`` (instead of its ``w_gen``), so the transferred data's fields, placed by
    another robot's states, stop holding the task's samples wherever they answer them only
    weakly (module docstring). ``n_rejected_`` counts refused samples.
    """

    def __init__(self, regressor, pid, learn=True, yielding=False, own_w_gen=0.3):
        if yielding and not hasattr(regressor, "set_w_gen"):
            raise ValueError(f"yielding needs a regressor with set_w_gen (LWPR), got "
                             f"{type(regressor).__name__}")
        check_unit(own_w_gen, "own_w_gen")      # LWPR.set_w_gen's check, before any data
        self.regressor, self.pid, self.learn = regressor, pid, learn
        self.yielding, self.own_w_gen = bool(yielding), own_w_gen
        self.n_rejected_ = 0
        self.n_learned_ = 0

    def initialise(self, samples):
        """Learn offline from samples (N, 4n) in the (q, q̇, q̈, τ) layout; returns how many
        were learned (rows with NaN/inf or the wrong width are rejected and counted). A
        yielding learner then makes fields of its own above ``own_w_gen``."""
        return self._learn(samples, offline=True)

    def _learn(self, samples, offline):
        samples = np.asarray(samples, dtype=np.float64)
        if samples.ndim != 2 or samples.shape[1] % 4:
            raise ValueError(f"samples must be (N, 4n) rows of (q, q̇, q̈, τ), got shape "
                             f"{samples.shape}")
        finite = np.isfinite(samples).all(axis=1)
        self.n_rejected_ += int((~finite).sum())
        good = samples[finite]
        if len(good):
            n = samples.shape[1] // 4
            self.regressor.partial_fit(good[:, :3 * n], good[:, 3 * n:])
            if offline and self.yielding:
                self.regressor.set_w_gen(self.own_w_gen)
            self.n_learned_ += len(good)
        return len(good)

    def feedforward(self, desired_state):
        try:
            return np.asarray(self.regressor.predict(desired_state[None]), dtype=np.float64)[0]
        except NotFittedError:
            return np.zeros(len(desired_state) // 3)

    def observe(self, sample):
        """Learn one (q, q̇, q̈, τ) sample unless it holds NaN/inf (then count it)."""
        return self._learn(np.asarray(sample, dtype=np.float64)[None], offline=False) == 1

    def run_trial(self, step, state, q_d, qd_d, qdd_d, x_d, n_steps, dt):
        """Track one trial's desired joint trajectory (T, n) from ``state``.

        ``step(τ, n_steps)`` is a torque-mode robot; ``x_d`` (T, m) the desired task points
        the tracking error is measured against (the first m end-effector coordinates).
        """
        self.pid.reset()
        rows, actual, feedforward = [], [], []
        for k in range(len(q_d)):
            tau_ff = self.feedforward(np.concatenate((q_d[k], qd_d[k], qdd_d[k])))
            tau = tau_ff + self.pid.torque(q_d[k], qd_d[k], state.positions, state.velocities,
                                           dt)
            new_state = step(tau, n_steps)
            sample = feature_vector(new_state, state, ID_FEATURES)
            if self.learn:
                self.observe(sample)
            rows.append(sample)
            feedforward.append(tau_ff)
            actual.append(new_state.end_effector[:x_d.shape[1]])
            state = new_state
        actual = np.array(actual)
        return Trial(tracking_error(x_d, actual), np.asarray(x_d), actual, np.array(rows),
                     np.array(feedforward), state)


def regressors():
    """Online regressors by the name a configuration uses (the learner is a parameter)."""
    from lpa_transfer.learners.lwpr import LWPR
    return {"lwpr": LWPR}


def make_regressor(name, **hyperparameters):
    """A fresh online regressor ``name`` with its hyperparameters; ValueError if unknown."""
    available = regressors()
    if name not in available:
        raise ValueError(f"unknown regressor {name!r}; available: {sorted(available)}")
    return available[name](**hyperparameters)


def input_scale(q_d, qd_d, qdd_d, floor=1e-6):
    """Per-column spread of the desired states (q, q̇, q̈) of a task: a regressor's input
    normalisation (LWPR's ``norm_in``). Columns that barely move (a joint the task does not
    use: spread below ``floor``) get 1, so their tiny observed motion is not blown up."""
    spread = np.hstack((q_d, qd_d, qdd_d)).std(axis=0)
    return np.where(spread > floor, spread, 1.0)
