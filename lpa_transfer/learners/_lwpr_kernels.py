"""Compiled kernels of LWPR (:mod:`lpa_transfer.learners.lwpr`): learn samples one after the
other, predict, and find the receptive fields (RFs) a query activates.

Why compiled: one online step of LWPR updates a few RFs with short loops over projections
and inputs. In numpy every such step is an array call with its own overhead, and that
overhead, not the arithmetic, dominated an online step. Compiled by numba
(``@njit(cache=True)``: a new process loads the machine code from ``__pycache__`` instead of
compiling again) the loops cost little more than their arithmetic. ``LWPR`` keeps the Python
API and the input checks and owns the arrays; the kernels update them in place.

The algorithm is that of Vijayakumar, D'Souza & Schaal (2005, Tables 3-5), with the numerical
heuristics of the reference library (docs/library.md, "LWPR"). Each RF is updated with the
same operations in the same order as the numpy implementation these kernels replace (kept as
test/oracles/reference_lwpr.py and compared with it by test/test_lwpr.py), so results agree to
rounding; only sums whose order numpy leaves to its SIMD loops or BLAS may differ in the last
bits. No fast-math: it would reorder operations. The arrays' layout (row k = RF k; blocks of
rows with bounding boxes that let a query skip RFs it cannot activate): docs/library.md.
"""
import math

import numpy as np
from numba import njit

# proj_stats rows
BETA, SSS2, SSY, H, RR, SUM_W, N_DATA, LAM, SUM_ECV2 = range(9)
# proj_axes rows
U, P, SXY, SSX, T = range(5)
# points rows
C, X0 = range(2)
# metric rows: M, α, log α (meta learning), meta traces h
MET, ALPHA, LOG_ALPHA, HM = range(4)
# scalars columns
BETA0, SUM_E2, SSP = range(3)
# boxes rows
LO, HI, MM = range(3)
# params entries
(P_W_GEN, P_W_PRUNE, P_INIT_LAMBDA, P_FINAL_LAMBDA, P_TAU_LAMBDA, P_GAMMA, P_META_RATE,
 P_ADD_THRESHOLD, P_INIT_S2, P_UPDATE_D, P_META, P_DIAG, P_N_PROJ_MAX, P_ZERO_EMPTY,
 N_PARAMS) = range(15)

#: RFs per bounding box (``boxes``); capacities are multiples of it.
BLOCK = 32
#: Only RFs activated above this are updated (reference library).
UPDATE_CUTOFF = 1e-3
#: Initial sufficient statistics of a new RF (reference library).
TINY = 1e-10
#: Relative slack of the box bounds against rounding: a block is skipped only when its
#: bound exceeds the distance of interest by more than this.
_SLACK = 1e-9


# ------------------------------------------------------------------------- distances
# The helpers index the whole arrays (RF k, block b) instead of taking row views (a view costs
# reference counting), and leave their loops by return (with break, numba's code for the
# reversed loops was much slower).
@njit(cache=True)
def _distance_diag(x, points, metric, k, limit):
    """q = Σ_j M_j² (x_j - c_j)² of RF k, accumulated from the last input backwards; returns
    early (a value >= ``limit``) as soon as the partial sum reaches ``limit``."""
    q = 0.0
    for j in range(x.size - 1, -1, -1):
        v = metric[k, MET, j] * (x[j] - points[k, C, j])
        q += v * v
        if q >= limit:
            return q
    return q


@njit(cache=True)
def _distance_full(x, points, metric, k, limit):
    """q = |M (x - c)|² of RF k (M upper triangular, row-major), early return as above.

    Row i of M (x - c) depends on inputs i.. only, so every partial sum over the rows
    d-1 .. i is a lower bound of q.
    """
    d = x.size
    q = 0.0
    for i in range(d - 1, -1, -1):
        v = 0.0
        for j in range(i, d):
            v += metric[k, MET, i * d + j] * (x[j] - points[k, C, j])
        q += v * v
        if q >= limit:
            return q
    return q


@njit(cache=True)
def _distance(x, points, metric, k, diag, limit):
    if diag:
        return _distance_diag(x, points, metric, k, limit)
    return _distance_full(x, points, metric, k, limit)


@njit(cache=True)
def _box_bound(x, boxes, b, limit):
    """Lower bound of q for the RFs of block b (see ``boxes``); early return above limit."""
    q = 0.0
    for j in range(x.size - 1, -1, -1):
        t = boxes[b, LO, j] - x[j]
        if t <= 0.0:
            t = x[j] - boxes[b, HI, j]
            if t <= 0.0:
                continue
        q += boxes[b, MM, j] * t * t
        if q > limit:
            return q
    return q


@njit(cache=True)
def _box_include(boxes, k, points, metric, diag):
    """Widen the box of RF k's block to its centre and lower its ``mm`` to its metric."""
    d = points.shape[2]
    b = k // BLOCK
    for j in range(d):
        boxes[b, LO, j] = min(boxes[b, LO, j], points[k, C, j])
        boxes[b, HI, j] = max(boxes[b, HI, j], points[k, C, j])
    if diag:
        for j in range(d):
            boxes[b, MM, j] = min(boxes[b, MM, j], metric[k, MET, j] * metric[k, MET, j])
    else:
        last = metric[k, MET, d * d - 1]
        boxes[b, MM, d - 1] = min(boxes[b, MM, d - 1], last * last)


@njit(cache=True)
def _box_reset(boxes, b, diag):
    d = boxes.shape[2]
    for j in range(d):
        boxes[b, LO, j] = np.inf
        boxes[b, HI, j] = -np.inf
        boxes[b, MM, j] = np.inf if diag or j == d - 1 else 0.0


@njit(cache=True)
def _box_refresh(b, n, points, metric, boxes, diag):
    """Recompute block b's box from its rows < n (after a row was removed)."""
    _box_reset(boxes, b, diag)
    for k in range(b * BLOCK, min(n, (b + 1) * BLOCK)):
        _box_include(boxes, k, points, metric, diag)


@njit(cache=True)
def _activations(x, n, points, metric, boxes, diag, q_max, near, act):
    """The RFs with q < q_max (activation w = exp(-q/2) > exp(-q_max/2)), in row order:
    rows in ``near[:count]``, activations in ``act[:count]``; returns count."""
    count = 0
    limit = q_max * (1.0 + _SLACK)
    for b in range((n + BLOCK - 1) // BLOCK):
        if _box_bound(x, boxes, b, limit) > limit:
            continue
        for k in range(b * BLOCK, min(n, (b + 1) * BLOCK)):
            q = _distance(x, points, metric, k, diag, q_max)
            if q < q_max:
                near[count] = k
                act[count] = math.exp(-0.5 * q)
                count += 1
    return count


# ------------------------------------------------------------------------- prediction
@njit(cache=True)
def _combine(x, near, act, count, cutoff, n, points, metric, scalars, lin_coef, out, trust,
             boxes, diag, Y, row, weight, best_k, best_v, zero_empty):
    """Y[row]: the activation-weighted mean of the predictions of the trustworthy RFs with
    w > cutoff, per output (normalised units); outputs without one get the fallback, or 0
    with ``zero_empty`` (as the authors' reference library)."""
    d = x.size
    m = Y.shape[1]
    for o in range(m):
        weight[o] = 0.0
        Y[row, o] = 0.0                            # Σ w ŷ until divided
    for i in range(count):
        k = near[i]
        if act[i] > cutoff and trust[k]:
            local = 0.0
            for j in range(d):
                local += x[j] * lin_coef[k, j]
            local += lin_coef[k, d]
            o = out[k]
            weight[o] += act[i]
            Y[row, o] += act[i] * local
    missing = False
    for o in range(m):
        if weight[o] > 0.0:
            Y[row, o] /= weight[o]
        else:
            Y[row, o] = 0.0
            missing = True
    if missing and not zero_empty:
        _fallback(x, near, act, count, n, points, metric, scalars, out, boxes, diag, Y, row,
                  weight, best_k, best_v)


@njit(cache=True)
def _fallback(x, near, act, count, n, points, metric, scalars, out, boxes, diag, Y, row,
              weight, best_k, best_v):
    """Outputs with no trustworthy active RF (weight 0): β0 of the most active RF among the
    pairs (first row on ties), else of the RF with the smallest Mahalanobis distance among
    all RFs of the output (first row on ties); 0 if the output has no RF."""
    m = Y.shape[1]
    best_k[:] = -1
    for i in range(count):
        k = near[i]
        o = out[k]
        if weight[o] <= 0.0 and (best_k[o] < 0 or act[i] > best_v[o]):
            best_k[o] = k
            best_v[o] = act[i]
    search = False
    for o in range(m):
        if weight[o] <= 0.0:
            if best_k[o] >= 0:
                Y[row, o] = scalars[best_k[o], BETA0]
                weight[o] = 1.0                     # done
            else:
                best_v[o] = np.inf                  # now: the smallest q so far
                search = True
    if not search:
        return
    for b in range((n + BLOCK - 1) // BLOCK):
        worst = 0.0
        for o in range(m):
            if weight[o] <= 0.0:
                worst = max(worst, best_v[o])
        limit = worst * (1.0 + _SLACK)
        if _box_bound(x, boxes, b, limit) > limit:
            continue
        for k in range(b * BLOCK, min(n, (b + 1) * BLOCK)):
            o = out[k]
            if weight[o] <= 0.0:
                q = _distance(x, points, metric, k, diag, best_v[o])
                if q < best_v[o]:
                    best_v[o] = q
                    best_k[o] = k
    for o in range(m):
        if weight[o] <= 0.0 and best_k[o] >= 0:
            Y[row, o] = scalars[best_k[o], BETA0]


@njit(cache=True)
def lwpr_predict(X, n, cutoff, points, metric, scalars, lin_coef, out, trust, boxes, near,
                 act, diag, Y, zero_empty):
    """Predictions (normalised units) for the rows of X into Y (len(X), m)."""
    m = Y.shape[1]
    weight, best_v = np.empty(m), np.empty(m)
    best_k = np.empty(m, np.int64)
    q_max = -2.0 * math.log(cutoff) if cutoff > 0 else np.inf
    for i in range(X.shape[0]):
        x = X[i]
        count = _activations(x, n, points, metric, boxes, diag, q_max, near, act)
        _combine(x, near, act, count, cutoff, n, points, metric, scalars, lin_coef, out,
                 trust, boxes, diag, Y, i, weight, best_k, best_v, zero_empty)


@njit(cache=True)
def lwpr_activations(x, n, w_min, points, metric, boxes, diag, near, act):
    """The RFs activated above w_min by x: rows into near[:count], w into act[:count]."""
    q_max = -2.0 * math.log(w_min) if w_min > 0 else np.inf
    return _activations(x, n, points, metric, boxes, diag, q_max, near, act)


# ------------------------------------------------------------------------- learning
# Scratch rows: per projection (wk, (7, S)) and per metric entry (mk, (9, L)).
S_OLD, FITTED, RES, S_NEW, PS, COUPLING, OK = range(7)
DQ, DJ2, DWDM, DJDM, D2Q, D2J2, XC, DD, Z0 = range(9)


@njit(cache=True)
def _project(pa, k, first, n_used, wk):
    """T (s = T z_1) of RF k's slots first..n_used-1 by forward substitution,
    T_r = u_r - Σ_{q<r} (u_r·p_q) T_q (the PLS recursion z_{r+1} = z_r - s_r p_r, Table 3)."""
    d = pa.shape[3]
    for r in range(first, n_used):
        for q in range(r):
            acc = 0.0
            for i in range(d):
                acc += pa[k, P, q, i] * pa[k, U, r, i]
            wk[COUPLING, q] = acc
        for i in range(d):
            acc = 0.0
            for q in range(r):
                acc += wk[COUPLING, q] * pa[k, T, q, i]
            pa[k, T, r, i] = pa[k, U, r, i] - acc


@njit(cache=True)
def _update_rf(k, w, x, yk, ps, pa, points, metric, scalars, lin_coef, n_reg, trust, boxes,
               params, init, wk, z, mk):
    """Learn the normalised sample (x, yk) in RF k with activation w (Table 5, steps 1-3).

    ``ps``/``pa``: proj_stats/proj_axes; ``wk``, ``z`` (S, d) and ``mk``: scratch arrays.
    """
    d = x.size
    n = n_reg[k]
    # 1. means (Table 3, step 1): W_new = λ W + w; x0 and β0 move by w / W_new
    share = w / (ps[k, SUM_W, 0] * ps[k, LAM, 0] + w)
    for i in range(d):
        points[k, X0, i] += share * (x[i] - points[k, X0, i])
        mk[Z0, i] = x[i] - points[k, X0, i]
    scalars[k, BETA0] += share * (yk - scalars[k, BETA0])
    yz = yk - scalars[k, BETA0]
    # 2. incremental PLS (Table 3, step 2); s, z and res are those of the model before
    for r in range(n):
        acc = 0.0
        for i in range(d):
            acc += pa[k, T, r, i] * mk[Z0, i]
        wk[S_OLD, r] = acc
    for i in range(d):
        z[0, i] = mk[Z0, i]
    for r in range(1, n):
        for i in range(d):
            z[r, i] = z[r - 1, i] - wk[S_OLD, r - 1] * pa[k, P, r - 1, i]
    cum = 0.0
    for r in range(n):
        wk[FITTED, r] = ps[k, BETA, r] * wk[S_OLD, r]
        cum += wk[FITTED, r]
        wk[RES, r] = yz - cum                      # residual after stage r
    ssp = 0.0
    for r in range(n):
        lr = ps[k, LAM, r]
        s = wk[S_OLD, r]
        w_res = w * (wk[RES, r] + wk[FITTED, r])   # w times the residual before stage r
        w_s = w * s
        slower = 0.9 + 0.1 * lr                    # u_r's statistics forget more slowly
        norm = 0.0
        for i in range(d):
            v = pa[k, SXY, r, i] * slower + w_res * z[r, i]
            pa[k, SXY, r, i] = v
            norm += v * v
        norm = math.sqrt(norm)
        if norm > 1e-12:
            for i in range(d):
                pa[k, U, r, i] = pa[k, SXY, r, i] / norm
        ps[k, SSS2, r] = ps[k, SSS2, r] * lr + w_s * s
        ps[k, SSY, r] = ps[k, SSY, r] * lr + w_res * s
        ss2 = ps[k, SSS2, r]
        for i in range(d):
            pa[k, SSX, r, i] = pa[k, SSX, r, i] * lr + w_s * z[r, i]
            pa[k, P, r, i] = pa[k, SSX, r, i] / ss2
        ps[k, BETA, r] = ps[k, SSY, r] / ss2
        ssp += w_s * s / ss2
    scalars[k, SSP] = ps[k, LAM, n - 1] * scalars[k, SSP] + w * ssp
    _project(pa, k, 0, n, wk)
    # projections of the updated model; the last one counts only after 2 d samples
    last_ok = ps[k, N_DATA, n - 1] > 2 * d
    fit = 0.0
    for r in range(n):
        acc = 0.0
        if r < n - 1 or last_ok:
            for i in range(d):
                acc += pa[k, T, r, i] * mk[Z0, i]
        wk[S_NEW, r] = acc
        fit += ps[k, BETA, r] * acc
    e = yz - fit                                   # error after the update
    # leave-one-out errors (of the model before), once 0.1 / (1 - λ) samples are in
    if ps[k, N_DATA, 0] * (1 - ps[k, LAM, 0]) > 0.1:
        for r in range(n):
            ps[k, SUM_ECV2, r] = (ps[k, LAM, r] * ps[k, SUM_ECV2, r]
                                  + w * wk[RES, r] * wk[RES, r])
        scalars[k, SUM_E2] = ps[k, LAM, n - 1] * scalars[k, SUM_E2] + w * e * e
    if ps[k, N_DATA, 0] > 2 * d:
        trust[k] = True
    if params[P_UPDATE_D] != 0.0:
        _update_metric(k, w, x, wk[RES, n - 1], e, n, ps, points, metric, scalars, boxes,
                       params, init, wk, mk)
    # 3. add a projection while the last one still cut the leave-one-out error a lot
    if n >= 2 and n < int(params[P_N_PROJ_MAX]):
        ratio = ((ps[k, SUM_ECV2, n - 1] / ps[k, SUM_W, n - 1] + TINY)
                 / (ps[k, SUM_ECV2, n - 2] / ps[k, SUM_W, n - 2] + TINY))
        if (ratio < params[P_ADD_THRESHOLD] and ps[k, N_DATA, n - 1] / ps[k, N_DATA, 0] > 0.99
                and ps[k, N_DATA, n - 1] * (1 - ps[k, LAM, n - 1]) > 0.5):
            pa[k, U, n, n] = 1.0                   # the new slot keeps its initial stats
            pa[k, P, n, n] = 1.0
            scalars[k, SSP] = 0.0
            n += 1
            n_reg[k] = n
            _project(pa, k, n - 1, n, wk)
    # discounted counts; anneal λ
    tau, final = params[P_TAU_LAMBDA], params[P_FINAL_LAMBDA]
    for r in range(n):
        lr = ps[k, LAM, r]
        ps[k, SUM_W, r] = ps[k, SUM_W, r] * lr + w
        ps[k, N_DATA, r] = ps[k, N_DATA, r] * lr + 1.0
        ps[k, LAM, r] = lr + ((tau - 1) * lr + final * (1 - tau))
    # the cached affine prediction ŷ = β0 + Σ_r β_r s_r = (x, 1)·lin_coef
    last_ok = ps[k, N_DATA, n - 1] > 2 * d
    offset = 0.0
    for i in range(d):
        slope = 0.0
        for r in range(n):
            usable = 1.0 if r < n - 1 or last_ok else 0.0
            slope += ps[k, BETA, r] * usable * pa[k, T, r, i]
        lin_coef[k, i] = slope
        offset += slope * points[k, X0, i]
    lin_coef[k, d] = scalars[k, BETA0] - offset


@njit(cache=True)
def _update_metric(k, w, x, e_cv, e, n, ps, points, metric, scalars, boxes, params, init, wk,
                   mk):
    """One gradient step on M of the penalised leave-one-out cost J (Table 4), with the
    memory traces H and r and, if ``meta``, delta-bar-delta on the rates (Table 4).

    s = wk[S_NEW] (projections of the updated model). An RF whose first projection has seen
    fewer than 0.1 / (1 - λ) samples is not changed (transient multiplier 0).
    """
    d = x.size
    L = metric.shape[2]
    diag = params[P_DIAG] != 0.0
    ok0 = ps[k, N_DATA, 0] > 0.1 / (1 - ps[k, LAM, 0])
    sps = 0.0
    for r in range(n):
        ok = ok0 and ps[k, N_DATA, r] > 0.1 / (1 - ps[k, LAM, r])
        wk[OK, r] = 1.0 if ok else 0.0
        wk[PS, r] = wk[S_NEW, r] / ps[k, SSS2, r] if ok else 0.0
        sps += wk[PS, r] * wk[S_NEW, r]
    h = min(w * sps, 1 - 1e-6)                     # leverage, capped
    W = ps[k, SUM_W, 0] * ps[k, LAM, 0] + w
    E = ps[k, SUM_ECV2, n - 1]
    tm = min(1.0, math.pow(scalars[k, SUM_E2] / (E + TINY), 4.0)) * (1.0 if ok0 else 0.0)
    ps_h, ps2_r = 0.0, 0.0
    for r in range(n):
        ps_h += wk[PS, r] * ps[k, H, r]
        ps2_r += wk[PS, r] * wk[PS, r] * ps[k, RR, r]
    dJ1dw = (e_cv * e_cv - 2 * e * ps_h - 2 * ps2_r) / W - E / (W * W)
    gamma = params[P_GAMMA]
    for i in range(d):
        mk[XC, i] = x[i] - points[k, C, i]
    if diag:                                       # dq/dM and dJ2/dM (Table 4)
        for i in range(d):
            M, xc = metric[k, MET, i], mk[XC, i]
            mk[DQ, i] = 2.0 * M * xc * xc
            mk[DJ2, i] = 4.0 * gamma * M * M * M
    else:
        for a in range(d):                         # D = Mᵀ M
            for b in range(d):
                acc = 0.0
                for i in range(d):
                    acc += metric[k, MET, i * d + a] * metric[k, MET, i * d + b]
                mk[DD, a * d + b] = acc
        for i in range(d):
            mx = 0.0
            for j in range(d):
                mx += metric[k, MET, i * d + j] * mk[XC, j]
            for j in range(d):
                md = 0.0
                for a in range(d):
                    md += metric[k, MET, i * d + a] * mk[DD, a * d + j]
                mask = init[0, 2, i * d + j]
                mk[DQ, i * d + j] = 2.0 * mx * mk[XC, j] * mask
                mk[DJ2, i * d + j] = 4.0 * gamma * md * mask
    for j in range(L):
        mk[DWDM, j] = -0.5 * w * mk[DQ, j]
        mk[DJDM, j] = mk[DWDM, j] * dJ1dw + w / W * mk[DJ2, j]
    if params[P_META] != 0.0:
        # ∂²J/∂M² (element-wise, Table 4)
        pse_s, a_sum, b_sum = 0.0, 0.0, 0.0
        for r in range(n):
            pse_s += wk[S_NEW, r] * (wk[PS, r] * e)
        for r in range(n):
            pse = wk[PS, r] * e
            a_sum += (-pse / W - 2 * wk[PS, r] * pse_s) * ps[k, H, r]
            b_sum += pse * ps[k, H, r]
        d2J1dw2 = (-(e_cv * e_cv) / (W * W) - 2 / W * a_sum + 2 / W * (e * e) * h / w
                   - (e_cv * e_cv - 2 * b_sum) / (W * W) + E / math.pow(W, 3.0))
        if diag:
            for i in range(d):
                M = metric[k, MET, i]
                mk[D2Q, i] = 2.0 * mk[XC, i] * mk[XC, i]
                mk[D2J2, i] = 12.0 * gamma * M * M
        else:
            for i in range(d):
                row_sq = 0.0
                for j in range(d):
                    row_sq += metric[k, MET, i * d + j] * metric[k, MET, i * d + j]
                for j in range(d):
                    mij, mask = metric[k, MET, i * d + j], init[0, 2, i * d + j]
                    mk[D2Q, i * d + j] = 2.0 * (mk[XC, j] * mk[XC, j]) * mask
                    mk[D2J2, i * d + j] = (4.0 * gamma * (mk[DD, j * d + j] + row_sq + mij * mij)
                                           * mask)
        rate = params[P_META_RATE] * tm
        for j in range(L):
            dq, dwdM, dJdM = mk[DQ, j], mk[DWDM, j], mk[DJDM, j]
            d2wdM2 = 0.25 * w * dq * dq - 0.5 * w * mk[D2Q, j]
            d2JdM2 = d2wdM2 * dJ1dw + dwdM * dwdM * d2J1dw2 + w / W * mk[D2J2, j]
            # incremental delta-bar-delta on α = exp(log α)
            g = min(max(rate * dJdM * metric[k, HM, j], -0.1), 0.1)
            metric[k, LOG_ALPHA, j] = min(max(metric[k, LOG_ALPHA, j] - g, -10.0), 10.0)
            alpha = math.exp(metric[k, LOG_ALPHA, j])
            metric[k, ALPHA, j] = alpha
            metric[k, HM, j] = (metric[k, HM, j] * max(0.0, 1 - alpha * d2JdM2 * tm)
                                - alpha * dJdM * tm)
    # the gradient step; a step larger than 0.1 max|M| is skipped and its rate halved
    biggest = 0.0
    for j in range(L):
        biggest = max(biggest, abs(metric[k, MET, j]))
    too_big = 0.1 * biggest
    for j in range(L):
        step = metric[k, ALPHA, j] * mk[DJDM, j] * tm
        if abs(step) > too_big:
            metric[k, ALPHA, j] /= 2
        else:
            metric[k, MET, j] -= step
    trace = w / (1 - h) * tm
    for r in range(n):
        if wk[OK, r] != 0.0:
            s = wk[S_NEW, r]
            tr = trace * s
            ps[k, H, r] = ps[k, LAM, r] * ps[k, H, r] + tr * e_cv
            ps[k, RR, r] = ps[k, LAM, r] * ps[k, RR, r] + tr * s * (w * e_cv * e_cv)
    _box_include(boxes, k, points, metric, diag)


@njit(cache=True)
def _add_rf(row, o, x, y0, src, k, proj_stats, proj_axes, points, metric, scalars, lin_coef,
            out, n_reg, trust, boxes, params, init):
    """A new RF at row ``row`` for output o: centre x, β0 = y0, M and α of RF k if ``src``
    is ``metric``, else (``src`` = ``init``, k = 0) init M and init α.

    Statistics start at init_S2 / 1e-10 and λ at init_lambda; the first two projections
    (U = P = T = unit vectors) are in use.
    """
    d = x.size
    diag = params[P_DIAG] != 0.0
    n_use = min(2, int(params[P_N_PROJ_MAX]))
    out[row], n_reg[row], trust[row] = o, n_use, False
    for i in range(d):
        points[row, C, i] = x[i]
        points[row, X0, i] = x[i]
        lin_coef[row, i] = 0.0
    lin_coef[row, d] = y0
    scalars[row, BETA0], scalars[row, SUM_E2], scalars[row, SSP] = y0, 0.0, 0.0
    for j in range(metric.shape[2]):
        alpha = src[k, 1, j]                       # metric[k] and init: M, α first
        metric[row, MET, j] = src[k, 0, j]
        metric[row, ALPHA, j] = alpha
        metric[row, LOG_ALPHA, j] = math.log(alpha + TINY) if init[0, 2, j] != 0.0 else 0.0
        metric[row, HM, j] = 0.0
    proj_stats[row] = 0.0
    proj_stats[row, SSS2] = params[P_INIT_S2]
    proj_stats[row, LAM] = params[P_INIT_LAMBDA]
    proj_stats[row, SUM_W] = TINY
    proj_axes[row] = 0.0
    for r in range(n_use):
        proj_stats[row, N_DATA, r] = TINY
        proj_axes[row, U, r, r] = 1.0
        proj_axes[row, P, r, r] = 1.0
        proj_axes[row, T, r, r] = 1.0
    if row % BLOCK == 0:
        _box_reset(boxes, row // BLOCK, diag)
    _box_include(boxes, row, points, metric, diag)


@njit(cache=True)
def _remove_rf(k, n, proj_stats, proj_axes, points, metric, scalars, lin_coef, out, n_reg,
               trust, boxes, diag):
    """Delete RF k by moving the last RF into its row; returns the new count."""
    last = n - 1
    proj_stats[k] = proj_stats[last]
    proj_axes[k] = proj_axes[last]
    points[k] = points[last]
    metric[k] = metric[last]
    scalars[k] = scalars[last]
    lin_coef[k] = lin_coef[last]
    out[k], n_reg[k], trust[k] = out[last], n_reg[last], trust[last]
    _box_refresh(k // BLOCK, last, points, metric, boxes, diag)
    if last // BLOCK != k // BLOCK and last % BLOCK:
        _box_refresh(last // BLOCK, last, points, metric, boxes, diag)
    return last


@njit(cache=True)
def _victim(k1, k2, proj_stats, metric, n_reg, d, diag):
    """Of two overlapping RFs, the narrower one (larger det D), else the worse one (larger
    leave-one-out MSE)."""
    ld1, ld2 = 0.0, 0.0
    for i in range(d):
        j = i if diag else i * d + i
        ld1 += math.log(abs(metric[k1, MET, j]))
        ld2 += math.log(abs(metric[k2, MET, j]))
    ld1, ld2 = 2.0 * ld1, 2.0 * ld2
    if abs(ld1 - ld2) > 1e-9 * max(1.0, abs(ld1)):
        return k1 if ld1 > ld2 else k2
    r1, r2 = n_reg[k1] - 1, n_reg[k2] - 1
    mse1 = proj_stats[k1, SUM_ECV2, r1] / proj_stats[k1, SUM_W, r1]
    mse2 = proj_stats[k2, SUM_ECV2, r2] / proj_stats[k2, SUM_W, r2]
    return k1 if mse1 > mse2 else k2


@njit(cache=True)
def _create_and_prune(near, act, count, x, y, n, proj_stats, proj_axes, points, metric,
                      scalars, lin_coef, out, n_reg, trust, boxes, n_pruned, params, init,
                      best1, best2, w1, w2, n_above):
    """Table 5, step 4: a new RF for every output whose most active RF is at or below w_gen
    (copying M and α of that RF if it is trustworthy and above 0.1 w_gen, as the reference
    library), then of the two most active RFs of an output, both above w_prune, one is
    removed. ``near``/``act``: the RFs active before the update. Returns the new count."""
    m = y.size
    w_gen, w_prune = params[P_W_GEN], params[P_W_PRUNE]
    best1[:] = -1
    best2[:] = -1
    n_above[:] = 0                             # activations above w_gen, above w_prune
    for i in range(count):
        k, w = near[i], act[i]
        o = out[k]
        if w > w_gen:
            n_above[o, 0] += 1
        if w > w_prune:
            n_above[o, 1] += 1
        if best1[o] < 0 or w > w1[o]:          # most active first, then the lower row
            best2[o], w2[o] = best1[o], w1[o]
            best1[o], w1[o] = k, w
        elif best2[o] < 0 or w > w2[o]:
            best2[o], w2[o] = k, w
    todo = False
    for o in range(m):
        if n_above[o, 0] == 0 or n_above[o, 1] >= 2:
            todo = True
    if not todo:
        return n                               # the common case
    for o in range(m):
        top_w = w1[o] if best1[o] >= 0 else 0.0
        if top_w <= w_gen:
            k = best1[o]
            if k >= 0 and top_w > 0.1 * w_gen and trust[k]:
                src = metric
            else:
                src, k = init, 0
            _add_rf(n, o, x, y[o], src, k, proj_stats, proj_axes, points, metric, scalars,
                    lin_coef, out, n_reg, trust, boxes, params, init)
            n += 1
    d = x.size
    diag = params[P_DIAG] != 0.0
    victims = np.empty(m, np.int64)
    n_victims = 0
    for o in range(m):
        if best2[o] >= 0 and w2[o] > w_prune:
            victims[n_victims] = _victim(best1[o], best2[o], proj_stats, metric, n_reg, d,
                                         diag)
            n_victims += 1
    for k in np.sort(victims[:n_victims])[::-1]:   # highest row first: rows stay valid
        n_pruned[out[k]] += 1
        n = _remove_rf(k, n, proj_stats, proj_axes, points, metric, scalars, lin_coef, out,
                       n_reg, trust, boxes, diag)
    return n


@njit(cache=True)
def lwpr_learn(X, Y, start, before, n, cutoff, proj_stats, proj_axes, points, metric,
               scalars, lin_coef, out, n_reg, trust, boxes, n_pruned, near, act, params,
               init):
    """Learn the normalised samples X[start:], Y[start:] in order (Table 5); before[i] gets
    the prediction for X[i] made before learning it.

    Returns (next row, RF count, widen). Stops before a sample when the arrays might not hold
    the new RFs it can create (one per output), and after a sample that used the last
    projection slot of an RF while more are allowed (widen): the caller grows the arrays
    and calls again.
    """
    d, m = X.shape[1], Y.shape[1]
    S, L = proj_stats.shape[2], metric.shape[2]
    cap = out.size
    diag = params[P_DIAG] != 0.0
    zero_empty = params[P_ZERO_EMPTY] != 0.0
    n_max = int(params[P_N_PROJ_MAX])
    w_min = min(cutoff, UPDATE_CUTOFF, params[P_W_GEN])
    q_max = -2.0 * math.log(w_min) if w_min > 0 else np.inf
    wk, z, mk = np.zeros((7, S)), np.zeros((S, d)), np.zeros((9, L))
    weight, best_v, w1, w2 = np.empty(m), np.empty(m), np.empty(m), np.empty(m)
    best_k, best1, best2 = np.empty(m, np.int64), np.empty(m, np.int64), np.empty(m, np.int64)
    n_above = np.empty((m, 2), np.int64)
    i = start
    while i < X.shape[0]:
        if n + m > cap:
            return i, n, False
        x, y = X[i], Y[i]
        count = _activations(x, n, points, metric, boxes, diag, q_max, near, act)
        _combine(x, near, act, count, cutoff, n, points, metric, scalars, lin_coef, out,
                 trust, boxes, diag, before, i, weight, best_k, best_v, zero_empty)
        top = 0
        for p in range(count):
            if act[p] > UPDATE_CUTOFF:
                k = near[p]
                _update_rf(k, act[p], x, y[out[k]], proj_stats, proj_axes, points, metric,
                           scalars, lin_coef, n_reg, trust, boxes, params, init, wk, z, mk)
                top = max(top, n_reg[k])
        n = _create_and_prune(near, act, count, x, y, n, proj_stats, proj_axes, points,
                              metric, scalars, lin_coef, out, n_reg, trust, boxes, n_pruned,
                              params, init, best1, best2, w1, w2, n_above)
        i += 1
        if top == S and S < n_max:
            return i, n, True
    return i, n, False
