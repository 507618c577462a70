"""The smoothing parameter of a cubic smoothing spline by generalised cross-validation (GCV),
fast and bit for bit as scipy's ``make_smoothing_spline(x, y)`` chooses it.

Why: §5.4.1's spline correspondences (:mod:`~lpa_transfer.inverse_dynamics.interpolation`) fit
one smoothing spline per column and stretch, and scipy evaluates GCV ~35 times per spline with
a Python loop over the samples (the band inverse of Hutchinson & de Hoog, "Smoothing noisy data
with spline functions", Numer. Math. 47:99-106, 1985). That loop took 59 % of an in-process
chapter 5 seed. Here the loops run compiled (numba, no fast-math: every sum keeps scipy's order)
and what depends only on the abscissae (the natural-spline design X, the penalty E and the
products XᵀX, XᵀE: Wahba 1990, Spline models for observational data, ch. 4) is computed once per
stretch length. The minimiser is scipy's own bounded Brent search over [0, n] on the same GCV
values, so the chosen λ is scipy's to the last bit (test/test_id_interpolation.py checks it);
the spline itself is then built by scipy with that λ. Unit weights only (what the chapter uses).
"""
from functools import lru_cache

import numpy as np
from numba import njit
from scipy.interpolate import BSpline
from scipy.linalg import cholesky_banded, solve_banded
from scipy.optimize import minimize_scalar


@njit(cache=True)
def _divided_difference_weights(x):
    """Weights of the divided difference over the points x: 1 / Π_{k≠i} (x_i - x_k)."""
    out = np.empty(len(x))
    for i in range(len(x)):
        product = 1.0
        for k in range(len(x)):
            if k != i:
                product *= x[i] - x[k]
        out[i] = 1.0 / product
    return out


@njit(cache=True)
def _banded_gram(A, B):
    """The 4 unique bands of the symmetric 7-band product AᵀB of two 5-band matrices (LAPACK
    banded storage, (5, n)); each entry the left-to-right sum of its 5 - j products."""
    n = A.shape[1]
    out = np.zeros((4, n))
    for i in range(n):
        for j in range(min(n - i, 4)):
            total = 0.0
            for r in range(5 - j):
                total += A[j + r, i] * B[r, i + j]
            out[3 - j, i + j] = total
    return out


@njit(cache=True)
def _penalty_times(wE, c):
    """E c for the 5-band penalty E (banded storage) and coefficients c."""
    n = wE.shape[1]
    out = np.zeros(n)
    for i in range(n):
        for j in range(max(0, i - n + 3), min(5, i + 3)):
            out[i] += wE[j, i + 2 - j] * c[i + 2 - j]
    return out


@njit(cache=True)
def _trace_of_inverse_times(U, D, gram):
    """tr(A⁻¹ XᵀX) for A = Uᵀ D⁻¹ U (U unit upper triangular, 4 bands; D its pivots), from the
    3 central bands of A⁻¹ by Hutchinson & de Hoog's backward recurrence."""
    n = U.shape[1]
    B = np.zeros((4, n))
    for i in range(n - 1, -1, -1):
        reach = min(3, n - i - 1)
        for j in range(reach, -1, -1):
            total = 0.0
            if j == 0:
                for k in range(1, reach + 1):
                    total -= U[3 - k, i + k] * B[3 - k, i + k]
                total += D[i]
                B[3, i] = total
            else:
                for k in range(1, reach + 1):
                    diag = abs(k - j)
                    total -= U[3 - k, i + k] * B[3 - diag, i + min(k, j) + diag]
                B[3 - j, i + j] = total
    trace = 0.0          # off-diagonal bands count twice; band 0 is unused (zero)
    for i in range(n):
        column = 0.0
        for r in range(4):
            term = (0.0 * gram[0, i]) if r == 0 else B[r, i] * gram[r, i]
            if r < 3:
                term *= 2
            column += term
        trace += column
    return trace


@lru_cache(maxsize=32)
def _design(n, dt):
    """(X, E, XᵀX, XᵀE) of the natural cubic spline through n points dt apart (unit weights):
    X the design in the natural-spline basis, E the penalty, both 5-band (banded storage)."""
    x = np.arange(n) * dt
    knots = np.r_[[x[0]] * 3, x, [x[-1]] * 3]
    bspl = BSpline.design_matrix(x, knots, 3).toarray()
    X = np.zeros((5, n))
    inner = np.arange(n - 4)
    for i in range(1, 4):
        X[i, 2:-2] = bspl[i + inner, 3 + inner]
    # the first and last two natural-spline basis functions (scipy's construction)
    X[1, 1] = bspl[0, 0]
    X[2, :2] = ((x[2] + x[1] - 2 * x[0]) * bspl[0, 0], bspl[1, 1] + bspl[1, 2])
    X[3, :2] = ((x[2] - x[0]) * bspl[1, 1], bspl[2, 2])
    X[1, -2:] = (bspl[-3, -3], (x[-1] - x[-3]) * bspl[-2, -2])
    X[2, -2:] = (bspl[-2, -3] + bspl[-2, -2], (2 * x[-1] - x[-2] - x[-3]) * bspl[-1, -1])
    X[3, -2] = bspl[-1, -1]
    E = np.zeros((5, n))
    E[2:, 0] = _divided_difference_weights(x[:3]) / 1.0
    E[1:, 1] = _divided_difference_weights(x[:4]) / 1.0
    for j in range(2, n - 2):
        E[:, j] = (x[j + 2] - x[j - 2]) * _divided_difference_weights(x[j - 2:j + 3]) / 1.0
    E[:-1, -2] = -_divided_difference_weights(x[-4:]) / 1.0
    E[:-2, -1] = _divided_difference_weights(x[-3:]) / 1.0
    E *= 6
    for array in (knots, X, E):
        array.flags.writeable = False
    return knots, X, E, _banded_gram(X, X), _banded_gram(X, E)


def _gcv(lam, y, X, E, gram, gram_E):
    """GCV(λ) = (1/n) |y - f_λ|² / (1 - tr(H_λ)/n)² (Wahba 1990, eq. 4.3.1)."""
    n = len(y)
    c = solve_banded((2, 2), X + lam * E, y)
    residual = np.linalg.norm(lam * _penalty_times(E, c)) ** 2 / n
    U = cholesky_banded(gram + lam * gram_E)
    for i in range(2, 5):
        U[-i, i - 1:] /= U[-1, :-i + 1]
    D = 1. / U[-1] ** 2
    U[-1] /= U[-1]
    trace = np.float64(_trace_of_inverse_times(U, D, gram))
    return residual / (1 - trace / n) ** 2


def gcv_smoothing(y, dt):
    """λ of the cubic smoothing spline through ``y`` sampled every ``dt``, chosen by GCV over
    [0, n] as scipy's ``make_smoothing_spline(np.arange(n) * dt, y)`` chooses it."""
    y = np.ascontiguousarray(y, dtype=float)
    _, *design = _design(len(y), float(dt))          # the knots are not needed here
    found = minimize_scalar(_gcv, bounds=(0, len(y)), method="Bounded", args=(y, *design))
    if not found.success:
        raise ValueError(f"Unable to find minimum of the GCV function: {found.message}")
    return found.x


def smoothing_spline(y, dt, lam=None):
    """The cubic smoothing spline (a scipy ``BSpline``) through ``y`` sampled every ``dt``
    from 0, with smoothing ``lam`` (None: by GCV): scipy's ``make_smoothing_spline`` to the
    bit, its design computed once per length (at least 5 samples)."""
    y = np.ascontiguousarray(y, dtype=float)
    if lam is None:
        lam = gcv_smoothing(y, dt)
    knots, X, E = _design(len(y), float(dt))[:3]
    c = solve_banded((2, 2), X + lam * E, y)
    # from the natural-spline basis back to B-splines (the two end coefficients each side)
    coefficients = np.r_[c[0] * (knots[5] + knots[4] - 2 * knots[3]) + c[1],
                         c[0] * (knots[5] - knots[3]) + c[1],
                         c[1:-1],
                         c[-1] * (knots[-4] - knots[-6]) + c[-2],
                         c[-1] * (2 * knots[-4] - knots[-5] - knots[-6]) + c[-2]]
    return BSpline.construct_fast(knots, coefficients, 3)
