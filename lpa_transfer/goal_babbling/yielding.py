"""Transferred goal-babbling experience that yields to the robot's own (beyond the thesis).

The thesis adds transferred samples to the k-NN inverse model with the weight of own data
(§6.4, §6.5); its conclusion (ch. 7) asks for models that "quickly forget inaccurately
transferred knowledge". :class:`YieldingModel` keeps the transferred samples as a prior the
own samples override wherever they are trustworthy (confidence gating): a query x is
answered by the own samples alone when the nearest own sample lies within ``gate_radius``
of x (the reaching threshold: own data that close reach the accuracy the robot is judged
by), and by the thesis' mixing of own and transferred samples (K nearest, weight 1)
elsewhere. With ``explore="own"`` the robot also explores with its own samples alone
(Alg. 6 asks the inverse model for each sub-target): the transferred knowledge answers
where the robot has none, and never steers what it goes on to collect.
"""
import numpy as np

from lpa_transfer import _validation as check
from lpa_transfer.goal_babbling.negative_transfer import _ActiveIndex, _MergedKNN
from lpa_transfer.learners.sensorimotor import make_sensorimotor_model

EXPLORATIONS = ("own", "gated")


class _GatedKNN:
    """``predict`` of the own k-NN where its nearest sample is within ``radius`` of the
    query, else of the merged own and transferred k-NN."""

    def __init__(self, own, merged, radius):
        self.own, self.merged, self.radius = own, merged, radius

    def predict(self, X):
        X = check.as_matrix(X, "X")
        if not hasattr(self.own, "n_samples_"):
            return self.merged.predict(X)
        near = self.own.kneighbors(X)[0][:, 0] <= self.radius
        if near.all() or self.merged.index is None:
            return self.own.predict(X)
        answer = np.empty((len(X), self.own.n_outputs_))
        if near.any():
            answer[near] = self.own.predict(X[near])
        answer[~near] = self.merged.predict(X[~near])
        return answer


class YieldingModel:
    """A sensorimotor model whose transferred samples yield to the own ones (module
    docstring); goal babbling uses it as a SensorimotorModel (``update``,
    ``infer_command``, ``inverse``).

    Parameters (the thesis gives none; ours)
    ----------
    model : SensorimotorModel or None
        Holds the own samples (default: a fresh K = 3 inverse-only k-NN model, §6.5).
    gate_radius : float, default 0.01 m
        Own samples this close to a query answer it alone (§6.5.1's reaching threshold).
    explore : {"own", "gated"}
        What :meth:`infer_command` (exploration) asks: the own samples alone once there are
        any, or the gated model, as ``inverse``.

    Learned attributes: ``transferred_commands_`` (N, d), ``transferred_points_`` (N, m),
    ``n_active_`` (the transferred samples held: all, none is retired).
    """

    def __init__(self, model=None, gate_radius=0.01, explore="own"):
        self.model = make_sensorimotor_model(forward=False) if model is None else model
        self.gate_radius = gate_radius
        self.explore = explore
        check.check_float(gate_radius, "gate_radius", 0)
        if explore not in EXPLORATIONS:
            raise ValueError(f"explore must be one of {EXPLORATIONS}, got {explore!r}")
        self._index = None

    @property
    def inverse(self):
        """L⁻¹ gated between the own samples and own plus transferred ones."""
        merged = _MergedKNN(self.model.inverse, self._index,
                            getattr(self, "transferred_commands_", None), 1.0)
        return _GatedKNN(self.model.inverse, merged, self.gate_radius)

    @property
    def n_active_(self):
        return len(getattr(self, "transferred_points_", ()))

    def infer_command(self, x):
        if self.explore == "own" and hasattr(self.model.inverse, "n_samples_"):
            return self.model.infer_command(x)
        return self.inverse.predict(x)

    def update(self, q, x, sample_weight=None):
        """Learn own samples (commands q (N, d) executed, points x (N, m) observed)."""
        self.model.update(q, x, sample_weight)
        return self

    def transfer(self, commands, points):
        """Add transferred samples (commands (N, d), points (N, m))."""
        commands, points = check.as_correspondences(commands, points, (1, "one sample"))
        if hasattr(self, "transferred_points_"):
            commands = np.vstack((self.transferred_commands_, commands))
            points = np.vstack((self.transferred_points_, points))
        self.transferred_commands_, self.transferred_points_ = commands, points
        self._index = _ActiveIndex(points, np.ones(len(points), dtype=bool))
        return self
