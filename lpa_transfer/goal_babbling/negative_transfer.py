"""A guard against negative transfer for goal-babbling sensorimotor models (thesis §6.6, ch. 7).

The thesis adds transferred samples to its k-NN model with the weight of own data and observes
negative transfer (§6.5.1: with PA, and with LPA fitted on little data); §6.6 traces it to
"equal weights [...] assigned to all data" and proposes "weighting transferred data less,
especially when the robot is generating new data", and the conclusion (ch. 7) to "quickly
forget inaccurately transferred knowledge". RobMech 2019 filtered the transferred points by
their (known, simulated) error: 0.001 m kept 32.1 %, 0.005 m kept 82.6 %. :class:`GuardedModel`
is an online version needing no ground truth: transferred samples count less, and are retired
once the target's own data cover their region or once what the robot observes contradicts
them.
"""
import numpy as np
from scipy.spatial import cKDTree

from lpa_transfer import _validation as check
from lpa_transfer.learners.sensorimotor import make_sensorimotor_model

#: Retire a stale KD-tree (one that still holds retired samples) once this many are retired.
_MIN_STALE = 16
ACTIVE, COVERED, DISAGREED = 0, 1, 2   # GuardedModel.status_ values


class _ActiveIndex:
    """Nearest-neighbour search among fixed points of which some are retired.

    A KD-tree over the points active when it was built; retired points are skipped at query
    time (by asking for as many extra neighbours as points were retired since), and the tree
    is rebuilt once more than ``_MIN_STALE`` of them, and 1 % of the tree, are stale.
    """

    def __init__(self, points, active):
        self.points, self.active = points, active
        self.rebuild()

    def rebuild(self):
        self._rows = np.flatnonzero(self.active)
        self._tree = cKDTree(self.points[self._rows]) if len(self._rows) else None
        self.stale = 0

    def query(self, X, k):
        """(distances (M, k), rows (M, k)) of the k nearest active points, sorted; missing
        neighbours (fewer than k active) have distance inf."""
        if self.stale > max(_MIN_STALE, 0.01 * len(self._rows)):
            self.rebuild()
        distances, rows = np.full((len(X), k), np.inf), np.zeros((len(X), k), dtype=np.intp)
        n = min(k + self.stale, len(self._rows))
        if n:
            found, index = self._tree.query(X, n)
            found, index = found.reshape(len(X), n), self._rows[index.reshape(len(X), n)]
            found[~self.active[index]] = np.inf
            order = np.argsort(found, axis=1, kind="stable")[:, :k]
            picked = np.take_along_axis(found, order, 1), np.take_along_axis(index, order, 1)
            distances[:, :picked[0].shape[1]], rows[:, :picked[0].shape[1]] = picked
        return distances, rows

    def within(self, X, radius):
        """Rows of the active points within ``radius`` of any query row of X (with
        repetitions: one per query)."""
        if self._tree is None:
            return np.zeros(0, dtype=np.intp)
        hits = [self._rows[np.asarray(found, dtype=np.intp)]
                for found in self._tree.query_ball_point(X, radius)]
        rows = np.concatenate(hits) if hits else np.zeros(0, dtype=np.intp)
        return rows[self.active[rows]]


class _MergedKNN:
    """``predict`` of a KNNRegressor of own samples merged with transferred ones.

    The K nearest among the own regressor's K candidates and the active transferred samples'
    K candidates; weights w_j = s_j·κ(d_j) as in :class:`lpa_transfer.learners.sensorimotor.KNNRegressor`,
    s_j = the own sample weight or ``weight`` for a transferred sample."""

    def __init__(self, own, index, outputs, weight):
        self.own, self.index, self.outputs, self.weight = own, index, outputs, weight

    def predict(self, X):
        X = check.as_matrix(X, "X")
        k, parts = self.own.n_neighbors, []
        if hasattr(self.own, "n_samples_"):
            found, rows = self.own.kneighbors(X)
            parts.append((found, self.own.sample_weight_[rows], self.own.Y_[rows]))
        if self.index is not None and self.index.active.any():
            if X.shape[1] != self.index.points.shape[1]:
                raise ValueError(f"X has {X.shape[1]} columns but the transferred samples "
                                 f"have {self.index.points.shape[1]}")
            found, rows = self.index.query(X, k)
            parts.append((found, np.where(np.isfinite(found), self.weight, 0.0),
                          self.outputs[rows]))
        if not parts:
            raise check.not_fitted("the guarded model holds no samples yet")
        found, scale, outputs = (np.concatenate(part, axis=1) for part in zip(*parts))
        order = np.argsort(found, axis=1, kind="stable")[:, :k]
        found, scale = np.take_along_axis(found, order, 1), np.take_along_axis(scale, order, 1)
        outputs = np.take_along_axis(outputs, order[:, :, None], 1)
        nearest = found[:, :1]
        if self.own.weights == "uniform":
            kernel = np.isfinite(found).astype(float)
        else:   # κ = 1/d scaled by the nearest distance; only exact matches if that is 0
            with np.errstate(divide="ignore", invalid="ignore"):
                kernel = np.where(nearest > 0, nearest / found, found == 0)
        mixing = scale * kernel
        return np.einsum("mk,mko->mo", mixing / mixing.sum(axis=1, keepdims=True), outputs)


class GuardedModel:
    """A sensorimotor model that guards against negative transfer (§6.6, ch. 7 future work).

    It wraps a :class:`lpa_transfer.learners.sensorimotor.SensorimotorModel` of
    :class:`~lpa_transfer.learners.sensorimotor.KNNRegressor` s holding the robot's own samples
    (:meth:`update`, as goal babbling calls it) and keeps the transferred samples
    (:meth:`transfer`) beside it. Predictions (:meth:`infer_command`, :meth:`predict_point`,
    ``inverse.predict``) take the K nearest of both kinds, a transferred sample with weight
    ``transferred_weight``. A transferred sample (q_j, x_j) is retired for good when

    (a) covered: ``coverage_count`` own samples lie within ``coverage_radius`` of x_j — the
        robot's own experience now answers queries there;
    (b) contradicted: an own sample (q, x) — executed and observed — satisfies
        ‖x − x_j‖ − L‖q − q_j‖ > ``disagreement_threshold``, L = ``lipschitz``. If the claim
        "q_j reaches x_j" were right, the forward kinematics' Lipschitz bound would give
        ‖x − x_j‖ ≤ L‖q − q_j‖; so a correct sample is never retired this way, and a sample
        wrong by e is retired once the robot executes a command within
        (e − threshold)/L of q_j. The ``n_checked`` transferred samples nearest (in joint
        space) to each executed command are tested, and at :meth:`transfer` each transferred
        sample is tested against its ``n_checked`` nearest own samples.

    Parameters (the thesis gives no values; these are ours)
    ----------
    model : SensorimotorModel or None
        Holds the own samples (default: a fresh K = 3 inverse-only k-NN model, §6.5).
    transferred_weight : float in (0, 1], default 0.3
        s_j of a transferred sample: with κ = 1/d it counts like an own sample 1/0.3 ≈ 3.3
        times as far away, so own data win wherever they are comparably close, while in
        regions without own data the transferred samples still decide alone (the weights
        are normalised).
    coverage_radius : float, default 0.01 m
        The reaching threshold of §6.5.1: own samples this close reach the accuracy the
        robot is judged by.
    coverage_count : int, default 3
        K: then own samples alone can fill a query's neighbourhood there.
    disagreement_threshold : float, default 0.01 m
        The transfer error tolerated (the reaching threshold; RobMech 2019 filtered at
        0.001-0.005 m, but with the true error, which a robot does not know).
    lipschitz : float, default 1.5 m/rad
        L, an upper bound of ‖∂x/∂q‖₂ of the target (too small a value retires correct
        samples). A chain's is at most :func:`chain_lipschitz` (1.17 for the
        Table 6.1 target); 1.5 covers planar arms up to ~1.3 m long.
    n_checked : int, default 3
        Transferred samples tested against each executed command.

    Learned attributes: ``transferred_commands_`` (N, d), ``transferred_points_`` (N, m),
    ``status_`` (N,) int (ACTIVE, COVERED or DISAGREED), ``coverage_`` (N,) own samples seen
    within the radius, ``n_active_``.
    """

    def __init__(self, model=None, transferred_weight=0.3, coverage_radius=0.01,
                 coverage_count=3, disagreement_threshold=0.01, lipschitz=1.5, n_checked=3):
        self.model = make_sensorimotor_model(forward=False) if model is None else model
        self.transferred_weight = transferred_weight
        self.coverage_radius = coverage_radius
        self.coverage_count = coverage_count
        self.disagreement_threshold = disagreement_threshold
        self.lipschitz = lipschitz
        self.n_checked = n_checked
        self._check_hyperparameters()
        self._x_index = self._q_index = None

    def _check_hyperparameters(self):
        check.check_float(self.transferred_weight, "transferred_weight", 0)
        if not 0 < self.transferred_weight <= 1:
            raise ValueError(f"transferred_weight must lie in (0, 1], got "
                             f"{self.transferred_weight!r}")
        for name in ("coverage_radius", "disagreement_threshold", "lipschitz"):
            check.check_float(getattr(self, name), name, 0)
        check.check_int(self.coverage_count, "coverage_count", 1)
        check.check_int(self.n_checked, "n_checked", 1)

    # -- the SensorimotorModel interface -------------------------------------------------------
    @property
    def inverse(self):
        """L⁻¹ merged over own and active transferred samples (``predict(x) -> q``)."""
        return _MergedKNN(self.model.inverse, self._x_index,
                          getattr(self, "transferred_commands_", None), self.transferred_weight)

    @property
    def forward(self):
        if self.model.forward is None:
            return None
        return _MergedKNN(self.model.forward, self._q_index,
                          getattr(self, "transferred_points_", None), self.transferred_weight)

    def infer_command(self, x):
        return self.inverse.predict(x)

    def predict_point(self, q):
        if self.model.forward is None:
            raise ValueError("this sensorimotor model learns no forward model (forward=None)")
        return self.forward.predict(q)

    def update(self, q, x, sample_weight=None):
        """Learn own samples (commands q (N, d) executed, points x (N, m) observed) and
        retire the transferred samples they cover or contradict."""
        self.model.update(q, x, sample_weight)
        if self._x_index is not None and self.n_active_:
            q, x = check.as_matrix(q, "q"), check.as_matrix(x, "x")
            np.add.at(self.coverage_, self._x_index.within(x, self.coverage_radius), 1)
            self._retire(np.flatnonzero(self.coverage_ >= self.coverage_count), COVERED)
            found, rows = self._q_index.query(q, self.n_checked)
            bad = self._contradicted(x[:, None], self.transferred_points_[rows], found)
            self._retire(rows[bad], DISAGREED)
        return self

    # -- transferred samples -------------------------------------------------------------------
    @property
    def n_active_(self):
        return int(np.count_nonzero(self.status_ == ACTIVE)) if hasattr(self, "status_") else 0

    def transfer(self, commands, points):
        """Add transferred samples (commands (N, d), points (N, m)); those already covered or
        contradicted by the own samples are retired at once."""
        commands, points = check.as_correspondences(commands, points, (1, "one sample"))
        if hasattr(self, "status_"):
            commands = np.vstack((self.transferred_commands_, commands))
            points = np.vstack((self.transferred_points_, points))
        n_old = len(getattr(self, "status_", ()))
        self.transferred_commands_, self.transferred_points_ = commands, points
        self.status_ = np.concatenate((getattr(self, "status_", []),
                                       np.zeros(len(points) - n_old))).astype(np.int8)
        self.coverage_ = np.concatenate((getattr(self, "coverage_", []),
                                         np.zeros(len(points) - n_old))).astype(np.intp)
        active = self.status_ == ACTIVE   # one mask, shared by both indices (view below)
        self._active = active
        self._x_index, self._q_index = _ActiveIndex(points, active), _ActiveIndex(commands, active)
        own = self.model.inverse
        if hasattr(own, "n_samples_"):
            new = np.arange(n_old, len(points))
            own_x, own_q = np.asarray(own.X_), np.asarray(own.Y_)
            self.coverage_[new] += cKDTree(own_x).query_ball_point(
                points[new], self.coverage_radius, return_length=True)
            self._retire(new[self.coverage_[new] >= self.coverage_count], COVERED)
            k = min(self.n_checked, len(own_q))
            found, rows = cKDTree(own_q).query(commands[new], k)
            found, rows = found.reshape(len(new), k), rows.reshape(len(new), k)
            bad = self._contradicted(points[new, None], own_x[rows], found)
            self._retire(new[bad.any(axis=1)], DISAGREED)
        return self

    def _contradicted(self, x_a, x_b, q_distance):
        """‖x_a − x_b‖ − L·q_distance > threshold, elementwise (criterion (b))."""
        gap = np.linalg.norm(x_a - x_b, axis=-1)
        with np.errstate(invalid="ignore"):
            return np.isfinite(q_distance) \
                & (gap - self.lipschitz * q_distance > self.disagreement_threshold)

    def _retire(self, rows, reason):
        rows = np.unique(rows)
        rows = rows[self.status_[rows] == ACTIVE]
        self.status_[rows], self._active[rows] = reason, False
        for index in (self._x_index, self._q_index):
            index.stale += len(rows)


def chain_lipschitz(link_lengths):
    """An upper bound of ‖∂x/∂q‖₂ of a chain of revolute joints: sqrt(Σ_i (Σ_{j≥i} l_j)²)
    (the Frobenius norm bound). Column i of the position Jacobian is a_i × (x − p_i), at most
    the distance from joint i to the end effector, at most the reach beyond joint i; l_j are
    the distances between successive joint origins and the tool — a planar chain's link
    lengths, a serial chain's ``RobotParams.link_lengths``."""
    reach = np.cumsum(np.asarray(link_lengths, dtype=np.float64)[::-1])
    return float(np.sqrt((reach ** 2).sum()))

