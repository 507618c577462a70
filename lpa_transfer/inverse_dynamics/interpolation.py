"""Correspondences and experience by interpolating the tracked trajectories (thesis §5.4.1).

The thesis builds its chapter 5 correspondences as its ref. [8] does: the robots' tracked
trajectories are interpolated by cubic splines in joint and torque space, and the samples are
read off the splines. Our samples (rows of (q, q̇, q̈, τ), :mod:`~lpa_transfer.inverse_dynamics.online_learning`)
come at the control rate with q̈ the backward difference of two velocities, which carries the
PID's period-to-period chatter. :func:`spline_states` replaces, per stretch of consecutive
samples (one babbling line, one trial), q̇ and τ by a smoothing cubic spline through them and
q̈ by the derivative of q̇'s spline; q stays as measured. The spline's smoothing is chosen by
generalised cross-validation (scipy's ``make_smoothing_spline``, computed faster to the same
bits by :mod:`~lpa_transfer.inverse_dynamics._gcv`) unless ``lam`` is given.
"""
import numpy as np

from lpa_transfer.inverse_dynamics._gcv import smoothing_spline
from lpa_transfer._validation import check_float, check_int

#: which rows a spline runs through: 'none' keeps the samples as measured
INTERPOLATIONS = ("none", "spline")
MIN_STRETCH = 5          # a shorter stretch (the tail of a cut-off run) is left as measured


def spline_states(rows, stretch, dt, lam=None):
    """(N, 4n) rows (q, q̇, q̈, τ), sampled every ``dt`` seconds in stretches of ``stretch``
    consecutive rows, with q̇ and τ read off smoothing splines and q̈ = d/dt of q̇'s spline.

    A column that does not move within a stretch (a joint the task leaves still) is kept.
    Returns a new array; ``rows`` is not changed.
    """
    rows = np.asarray(rows, dtype=np.float64)
    if rows.ndim != 2 or rows.shape[1] % 4 or not np.isfinite(rows).all():
        raise ValueError(f"rows must be a finite (N, 4n) array of (q, q̇, q̈, τ), got shape "
                         f"{rows.shape}")
    check_int(stretch, "stretch", 1)
    for value, name in ((dt, "dt"), (lam, "lam")):
        if value is not None:
            check_float(value, name, 0.0)
            if value == 0:
                raise ValueError(f"{name} must be > 0, got {value!r}")
    n = rows.shape[1] // 4
    out = rows.copy()
    for start in range(0, len(rows), stretch):
        block = slice(start, min(start + stretch, len(rows)))
        m = block.stop - block.start
        if m < MIN_STRETCH:
            continue
        t = np.arange(m) * dt
        for j in range(n):
            velocity, torque = rows[block, n + j], rows[block, 3 * n + j]
            if np.ptp(velocity) > 0:
                spline = smoothing_spline(velocity, dt, lam)
                out[block, n + j] = spline(t)
                out[block, 2 * n + j] = spline.derivative()(t)
            if np.ptp(torque) > 0:
                out[block, 3 * n + j] = smoothing_spline(torque, dt, lam)(t)
    return out


def interpolated(rows, interpolation, stretch, dt):
    """``rows`` as the experiment's ``interpolation`` setting asks (:data:`INTERPOLATIONS`)."""
    if interpolation not in INTERPOLATIONS:
        raise ValueError(f"interpolation must be one of {INTERPOLATIONS}, got {interpolation!r}")
    return rows if interpolation == "none" else spline_states(rows, stretch, dt)
