"""Numerical inverse kinematics by damped least squares.

Task-space babbling (thesis §5.4.1: both robots track the same straight task-space lines) and
task-point pairing (§4.4.2: the demonstrator reaches the point the robot reached) need each
robot's joint angles for a task-space point. The robot is given only by its forward
kinematics ``forward(Q) -> X`` ((N, n) joint vectors to (N, m) task points), so any chain
works; the Jacobian is taken by forward differences.

One iteration (Wampler 1986; Buss 2004, "Introduction to inverse kinematics with Jacobian
transpose, pseudoinverse and damped least squares methods", eq. 10):
``Δq = Jᵀ (J Jᵀ + λ² I)⁻¹ e``, then q is clipped into the joint limits. Unreachable points
end at the nearest reachable point the iteration finds (the damping keeps the step bounded
near singularities); the returned residual says how far that is.
"""
import numpy as np

FD_STEP = 1e-7
MAX_HALVINGS = 30   # step halvings before an iteration counts as not shrinking the error
MAX_NUDGES = 3      # restarts off a stalled pose (see _nudge)
NUDGE = 0.05
#: solve_many tries a row's halvings k = 0, 1-2, 3-6, 7-14, 15-30 in five forward calls
#: instead of one call per halving (few rows stall, and a call costs more than a row): the
#: step scales 2^-k of each call, shaped (k, 1, 1) to broadcast over (rows, n).
_HALVING_SCALES = [0.5 ** np.arange(first, min(2 * first + 1, MAX_HALVINGS + 1),
                                    dtype=np.float64)[:, None, None]
                   for first in (0, 1, 3, 7, 15)]


def jacobian(forward, q):
    """(m, n) forward-difference Jacobian of ``forward`` at the joint vector ``q``."""
    n = len(q)
    points = forward(np.vstack((q, q + FD_STEP * np.eye(n))))
    return (points[1:] - points[0]).T / FD_STEP


def solve(forward, x_target, q_start, joint_limits, damping=0.01, tolerance=1e-7,
          max_iterations=200):
    """Joint angles reaching ``x_target`` from ``q_start``: ``(q, residual)``.

    Damped least squares (module docstring) with joint limits enforced by clipping; joints at
    a limit that the step would push beyond are left out of the step, and a step that does not
    shrink the error is halved (up to ``MAX_HALVINGS`` times). When no step helps, q is nudged
    towards the middle of its ranges and the iteration goes on (up to ``MAX_NUDGES`` times):
    this leaves singular poses such as a stretched arm asked to pull straight in. Stops when
    the task-space error is below ``tolerance`` (m); returns the best pose found and its
    ``residual``, the distance ||forward(q) − x_target||.
    """
    limits = np.asarray(joint_limits, dtype=np.float64)
    x_target = np.asarray(x_target, dtype=np.float64)
    q = np.clip(np.asarray(q_start, dtype=np.float64), limits[:, 0], limits[:, 1])
    error = x_target - forward(q[None])[0]
    best, nudges = (q, error), MAX_NUDGES
    for _ in range(max_iterations):
        if np.linalg.norm(error) < tolerance:
            break
        J = jacobian(forward, q)
        step = _dls_step(J, error, damping)
        pinned = ((q <= limits[:, 0]) & (step < 0)) | ((q >= limits[:, 1]) & (step > 0))
        if pinned.any():   # joints held at a limit: the step of the others without them
            step = _dls_step(J * ~pinned, error, damping)
        for _ in range(MAX_HALVINGS + 1):   # a full step can overshoot far from the target
            q_next = np.clip(q + step, limits[:, 0], limits[:, 1])
            error_next = x_target - forward(q_next[None])[0]
            if np.linalg.norm(error_next) < np.linalg.norm(error) * (1 - 1e-9):
                break
            step = step / 2
        else:   # stalled: a local minimum, or a singular pose such as a stretched arm
            if nudges == 0:
                break
            nudges -= 1
            q_next = _nudge(q, limits)
            error_next = x_target - forward(q_next[None])[0]
        q, error = q_next, error_next
        if np.linalg.norm(error) < np.linalg.norm(best[1]):
            best = (q, error)
    return best[0], float(np.linalg.norm(best[1]))


def _nudge(q, limits):
    """q moved NUDGE of the way towards the middle of its (finite) joint ranges: off a
    singular pose, where the gradient vanishes (e.g. a stretched arm pulled straight in)."""
    middle = np.where(np.isfinite(limits).all(axis=1), limits.mean(axis=1), q)
    return q + NUDGE * (middle - q)


def _dls_step(J, error, damping):
    return J.T @ np.linalg.solve(J @ J.T + damping ** 2 * np.eye(len(error)), error)


def solve_many(forward, x_targets, q_starts, joint_limits, damping=0.01, tolerance=1e-7,
                max_iterations=200):
    """:func:`solve` for many independent targets at once: ``(Q, residuals)``, row i solving
    ``x_targets[i]`` from ``q_starts[i]``.

    Every row runs :func:`solve`'s iteration (the same steps, halvings, nudges and stopping
    rules), but each iteration calls
    ``forward`` once on all rows still iterating (and their Jacobian offsets) instead of once
    per row: collecting thousands of correspondences (§4.4.2) is one batched forward
    kinematics per step. ``x_targets`` (N, m), ``q_starts`` (N, n). A row that converges
    ends where :func:`solve` does, up to rounding (batched linear algebra rounds
    differently); a row that cannot converge (an unreachable target) runs to
    ``max_iterations`` through halvings and nudges that rounding can send to another nearby
    stalled pose (on the PR2's unreachable babbled points the residuals of the two can differ
    by millimetres, docs/history.md).
    """
    limits = np.asarray(joint_limits, dtype=np.float64)
    targets = np.atleast_2d(np.asarray(x_targets, dtype=np.float64))
    q = np.clip(np.atleast_2d(np.asarray(q_starts, dtype=np.float64)), limits[:, 0],
                limits[:, 1])
    if len(q) != len(targets):
        raise ValueError(f"x_targets has {len(targets)} rows but q_starts has {len(q)}")
    n_rows, n = q.shape
    if n_rows == 0:
        return q.copy(), np.empty(0)
    error = targets - forward(q)
    best_q, best_norm = q.copy(), np.linalg.norm(error, axis=1)
    nudges = np.full(n_rows, MAX_NUDGES)
    active = np.arange(n_rows)
    for _ in range(max_iterations):
        active = active[np.linalg.norm(error[active], axis=1) >= tolerance]
        if len(active) == 0:
            break
        qa, ea, xa = q[active], error[active], targets[active]
        points = forward(np.concatenate([qa] + [qa + FD_STEP * np.eye(n)[j] for j in range(n)]))
        base = points[:len(qa)]
        J = np.stack([(points[(j + 1) * len(qa):(j + 2) * len(qa)] - base) / FD_STEP
                      for j in range(n)], axis=2)                      # (rows, m, n)
        step = _dls_steps(J, ea, damping)
        pinned = ((qa <= limits[:, 0]) & (step < 0)) | ((qa >= limits[:, 1]) & (step > 0))
        redo = pinned.any(axis=1)
        if redo.any():   # joints held at a limit: the step of the others without them
            step[redo] = _dls_steps(J[redo] * ~pinned[redo][:, None, :], ea[redo], damping)
        norm = np.linalg.norm(ea, axis=1)
        q_next, e_next = qa.copy(), ea.copy()
        pending = np.arange(len(qa))
        for scales in _HALVING_SCALES:   # a full step can overshoot far from the target
            # the next few halvings of every pending row in one call: step · 2^-k is exact, so
            # each row sees solve's trials and takes the first that helps
            trial = np.clip(qa[pending] + step[pending] * scales, limits[:, 0], limits[:, 1])
            e_trial = xa[pending] - forward(trial.reshape(-1, n)).reshape(len(scales),
                                                                         len(pending), -1)
            better = np.linalg.norm(e_trial, axis=2) < norm[pending] * (1 - 1e-9)
            found = better.any(axis=0)
            first = better.argmax(axis=0)[found]
            rows = np.flatnonzero(found)
            q_next[pending[rows]] = trial[first, rows]
            e_next[pending[rows]] = e_trial[first, rows]
            pending = pending[~found]
            if len(pending) == 0:
                break
        stalled = active[pending]   # a local minimum, or a singular pose
        finished = stalled[nudges[stalled] == 0]
        nudge = pending[nudges[stalled] > 0]
        if len(nudge):
            nudges[active[nudge]] -= 1
            q_next[nudge] = _nudge(qa[nudge], limits)
            e_next[nudge] = xa[nudge] - forward(q_next[nudge])
        moving = np.setdiff1d(np.arange(len(qa)), np.searchsorted(active, finished))
        rows = active[moving]
        q[rows], error[rows] = q_next[moving], e_next[moving]
        norm_next = np.linalg.norm(error[rows], axis=1)
        improved = norm_next < best_norm[rows]
        best_q[rows[improved]], best_norm[rows[improved]] = q[rows[improved]], \
            norm_next[improved]
        active = rows
    return best_q, best_norm


def _dls_steps(J, error, damping):
    """:func:`_dls_step` for a stack of Jacobians (rows, m, n) and errors (rows, m)."""
    m = J.shape[1]
    JJt = J @ J.transpose(0, 2, 1) + damping ** 2 * np.eye(m)
    return (J.transpose(0, 2, 1) @ np.linalg.solve(JJt, error[:, :, None]))[:, :, 0]


def solve_path(forward, points, q_start, joint_limits, **options):
    """Joint angles for each task point of a path, each solve warm-started at the previous
    solution (so the arm keeps one elbow configuration along a line): ``(Q, residuals)``."""
    q = np.asarray(q_start, dtype=np.float64)
    solutions, residuals = [], []
    for point in np.asarray(points, dtype=np.float64):
        q, residual = solve(forward, point, q, joint_limits, **options)
        solutions.append(q)
        residuals.append(residual)
    return np.array(solutions).reshape(len(residuals), len(q)), np.array(residuals)
