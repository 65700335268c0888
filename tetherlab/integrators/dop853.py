"""DOP853: explicit Runge-Kutta of order 8(5,3) with 7th-order dense output, compiled.

Reference: E. Hairer, S.P. Norsett, G. Wanner, "Solving Ordinary Differential Equations I",
2nd ed., Springer 1993, section II.10, and Hairer's Fortran code DOP853 (step-size controller,
error norm, HINIT, dense output CONTD8).  The coefficients come from :mod:`.tableau` (checked at
import).

This module holds the method's own pieces (stages, solution, Hairer's error norm, the dense
output CONTD8); the step loop, shared with Vern9, is :func:`tetherlab.integrators.erk.erk_core`:
the loop, the calls of the right-hand side (a cfunc with :data:`tetherlab._jit.RHS_SIG`) and the
dense output are one compiled function, so no Python runs between steps.

It also holds the small helpers shared by every kernel (status codes, HINIT, output at the start
time, event bookkeeping), so all kernels behave the same at their boundaries.
"""

from __future__ import annotations

import numpy as np

from tetherlab._jit import njit, ptr, row_ptr

from .tableau import DOP_A, DOP_B, DOP_C, DOP_D, DOP_E3, DOP_E5

# Return codes of every kernel (see tetherlab.integrators.driver for their messages).
OK = 0
MAX_STEPS = 1
STEP_UNDERFLOW = 2
RHS_FAILED = 3
NON_FINITE = 4
EVENT = 5  # an event function changed sign in the step; see erk_core / radau5_core

# stats[] slots (int64[8], accumulated across calls).
ST_ACCEPTED = 0
ST_REJECTED = 1
ST_NRHS = 2
ST_NJAC = 3
ST_NLU = 4
ST_RHS_STATUS = 5
ST_NEWTON_FAIL = 6

EPS = float(np.finfo(np.float64).eps)
#: Consecutive failed trials caused by the rhs (nonzero status or non-finite values) after which
#: a kernel gives up.  Each failure divides h by 4, so 20 of them shrink it by 4**20 ~ 1e12: if
#: that has not moved the trial stages off the bad region, the step is not the problem.
MAX_BAD_TRIALS = 20
#: Consecutive rejections of any kind after which a kernel reports STEP_UNDERFLOW.  Rejections
#: for error or Newton convergence normally come in ones and twos; a hundred in a row means the
#: controller is not converging (and guards the case t = 0, where 16*eps*|t| never triggers).
MAX_CONSECUTIVE_REJECTS = 100
#: Step-size floor relative to |t|, below which t + h == t is near and the step is meaningless.
UNDERFLOW_FACTOR = 16.0 * EPS
#: Absolute floor (for t = 0): smaller steps are denormal-range nonsense for any model.
H_FLOOR = 1e-300

# Module-level copies as plain float64 arrays: numba freezes global arrays into the compiled code.
_A = DOP_A
_B = DOP_B
_C = DOP_C
_D = DOP_D
_E3 = DOP_E3
_E5 = DOP_E5


@njit(cache=True)
def fill_start_outputs(t, y, t_out, y_out):
    """Rows for output times <= t (i.e. == t, after validation) get y; returns how many."""
    k = 0
    m = t_out.shape[0]
    while k < m and t_out[k] <= t:
        y_out[k, :] = y
        k += 1
    return k


@njit(cache=True)
def all_finite(v):
    for i in range(v.shape[0]):
        if not np.isfinite(v[i]):
            return False
    return True


@njit(cache=True)
def scaled_sq(v, sk):
    """(v/sk)^2 with the convention 0/0 -> 0: atol_i = 0 is allowed, and a component that is
    exactly zero (a planar problem's z) must not poison the norm with NaN."""
    if sk > 0.0:
        r = v / sk
        return r * r
    if v == 0.0:
        return 0.0
    return np.inf


@njit(cache=True)
def hinit(rhs, t, y, f0, p, rtol, atol, iord, h_cap, y1, f1, stats):
    """Initial step, Hairer's HINIT (DOP853 source; also "Solving ODEs I", II.4).

    Uses one extra rhs evaluation (an explicit Euler step) to estimate the second derivative.
    Norms are Hairer's: unnormalised sums with sk = atol + rtol*|y|.  If the probing evaluation
    fails, the first estimate is returned and the step loop's failure handling shrinks it.
    """
    n = y.shape[0]
    dnf = 0.0
    dny = 0.0
    for i in range(n):
        sk = atol[i] + rtol * abs(y[i])
        dnf += scaled_sq(f0[i], sk)
        dny += scaled_sq(y[i], sk)
    if dnf <= 1e-10 or dny <= 1e-10 or not np.isfinite(dnf) or not np.isfinite(dny):
        h = 1e-6
    else:
        h = np.sqrt(dny / dnf) * 0.01
    h = min(h, h_cap)
    for i in range(n):
        y1[i] = y[i] + h * f0[i]
    st = rhs(t + h, ptr(y1), ptr(f1), ptr(p))
    stats[ST_NRHS] += 1
    if st != 0:
        stats[ST_RHS_STATUS] = st
        return h
    der2 = 0.0
    for i in range(n):
        sk = atol[i] + rtol * abs(y[i])
        der2 += scaled_sq(f1[i] - f0[i], sk)
    if not np.isfinite(der2):
        return h
    der2 = np.sqrt(der2) / h
    der12 = max(abs(der2), np.sqrt(dnf))
    if der12 <= 1e-15:
        h1 = max(1e-6, h * 1e-3)
    else:
        h1 = (0.01 / der12) ** (1.0 / iord)
    return min(100.0 * h, h1, h_cap)


@njit(cache=True, inline="always")
def rk_stages(A, C, lo, hi, rhs, t, y, h, p, K, ys, check_finite, stats):
    """Explicit stages lo..hi-1 of the tableau (A, C) into K[lo..hi-1] (K[0..lo-1] known).
    Returns the first nonzero rhs status, -1 if ``check_finite`` and a stage came out
    non-finite, or 0.  (Shared by DOP853 and Vern9; the step's own stages are checked through
    y_new and the error norm instead.)"""
    n = y.shape[0]
    for s in range(lo, hi):
        for i in range(n):
            ys[i] = y[i]
        # j-outer loop: skips the many zero entries of A and runs contiguously over K[j].
        for j in range(s):
            a = A[s, j] * h
            if a != 0.0:
                for i in range(n):
                    ys[i] += a * K[j, i]
        st = rhs(t + C[s] * h, ptr(ys), row_ptr(K, s), ptr(p))
        stats[ST_NRHS] += 1
        if st != 0:
            return st
        if check_finite and not all_finite(K[s]):
            return -1
    return 0


@njit(cache=True)
def _dop_stages(rhs, t, y, h, p, K, ys, stats):
    """Stages 1..11 into K[1..11] (K[0] = f(t, y) on entry).  Returns the first nonzero rhs
    status, or 0."""
    return rk_stages(_A, _C, 1, 12, rhs, t, y, h, p, K, ys, False, stats)


@njit(cache=True)
def _dop_combine(y, K, h, y_new):
    """The 8th-order solution y + h sum_j b_j K[j] (b_12.. are zero)."""
    for i in range(y.shape[0]):
        acc = 0.0
        for j in range(12):
            acc += _B[j] * K[j, i]
        y_new[i] = y[i] + h * acc


@njit(cache=True)
def dop853_step(rhs, t, y, h, p, K, ys, y_new, stats):
    """One DOP853 step of size h from (t, y) into y_new, without error control: for a caller
    that lands exactly on a point inside a step the error control already accepted (so its error
    is within tolerance).  K (16, n) and ys (n,) are workspaces.  Returns the first nonzero rhs
    status, -1 for non-finite values, or 0."""
    st = rhs(t, ptr(y), row_ptr(K, 0), ptr(p))
    stats[ST_NRHS] += 1
    if st != 0:
        return st
    st = _dop_stages(rhs, t, y, h, p, K, ys, stats)
    if st != 0:
        return st
    _dop_combine(y, K, h, y_new)
    return 0 if all_finite(y_new) else -1


@njit(cache=True)
def _dop_error(y, y_new, K, h, rtol, atol):
    """Hairer's DOP853 error norm: the 5th-order estimate damped by the 3rd-order one,
    err = |h| * E5n^2 / sqrt(n (E5n^2 + 0.01 E3n^2)), with weights atol + rtol*max(|y|,|y_new|)."""
    n = y.shape[0]
    err5 = 0.0
    err3 = 0.0
    for i in range(n):
        sk = atol[i] + rtol * max(abs(y[i]), abs(y_new[i]))
        e5 = 0.0
        e3 = 0.0
        for j in range(12):
            e5 += _E5[j] * K[j, i]
            e3 += _E3[j] * K[j, i]
        err5 += scaled_sq(e5, sk)
        err3 += scaled_sq(e3, sk)
    if err5 == 0.0 and err3 == 0.0:
        return 0.0
    deno = err5 + 0.01 * err3
    return abs(h) * err5 / np.sqrt(n * deno)


@njit(cache=True)
def _dop_dense_stages(rhs, t, y, h, p, K, ys, stats):
    """The three extra stages K[13..15] of the 7th-order interpolant (K[12] = f(t+h, y_new))."""
    return rk_stages(_A, _C, 13, 16, rhs, t, y, h, p, K, ys, True, stats)


@njit(cache=True)
def _dop_dense_coeffs(y, y_new, K, h, F):
    """F[0..6] of Hairer's CONTD8 (scipy's Dop853DenseOutput uses the same layout)."""
    n = y.shape[0]
    for i in range(n):
        dy = y_new[i] - y[i]
        F[0, i] = dy
        F[1, i] = h * K[0, i] - dy
        F[2, i] = 2.0 * dy - h * (K[12, i] + K[0, i])
    for r in range(4):
        for i in range(n):
            acc = 0.0
            for j in range(16):
                acc += _D[r, j] * K[j, i]
            F[3 + r, i] = h * acc


@njit(cache=True)
def _dop_dense_eval(y, F, x, out):
    """y(t_old + x h) = y + x(F0 + (1-x)(F1 + x(F2 + (1-x)(F3 + x(F4 + (1-x)(F5 + x F6))))))."""
    x1 = 1.0 - x
    for i in range(y.shape[0]):
        v = F[6, i] * x
        v = (v + F[5, i]) * x1
        v = (v + F[4, i]) * x
        v = (v + F[3, i]) * x1
        v = (v + F[2, i]) * x
        v = (v + F[1, i]) * x1
        v = (v + F[0, i]) * x
        out[i] = y[i] + v


@njit(cache=True)
def first_crossing(gold, gnew, ne):
    """True if any event component changed side: "side" is g < 0 versus g >= 0, so a restart
    exactly at a root (g = 0) counts as already on the non-negative side."""
    for i in range(ne):
        if (gold[i] < 0.0) != (gnew[i] < 0.0):
            return True
    return False


@njit(cache=True)
def start_events(event, t, y, p, ne, ev, stats):
    """Event buffers (g at the start, at the step end, scratch) and g(t, y) with the forced
    side of a just-located event applied; returns (status, gold, gnew, gtmp), status 0 or the
    event function's nonzero status (also stored in stats)."""
    gold = np.zeros(max(ne, 1))
    gnew = np.zeros(max(ne, 1))
    gtmp = np.zeros(max(ne, 1))
    st = 0
    if ne > 0:
        st = event(t, ptr(y), ptr(gold), ptr(p))
        if st != 0:
            stats[ST_RHS_STATUS] = st
        else:
            apply_forced_side(gold, ne, ev)
    return st, gold, gnew, gtmp


@njit(cache=True)
def apply_forced_side(gold, ne, ev):
    """Right after a located event the state sits within the bracket width of the root and may
    still evaluate on the old side; ev[2] >= 0 names that component and ev[3] its new-side value,
    used once for the start of the restarted integration (then cleared), so the same crossing is
    not found twice."""
    fc = int(ev[2])
    if fc >= 0 and fc < ne:
        gold[fc] = ev[3]
    ev[2] = -1.0


def event_time_tolerance(t, h):
    """Width of the bracket to which an event time is located (s): a few ulps of t, or of h."""
    return 64.0 * EPS * max(abs(t), abs(h))


event_time_tolerance = njit(cache=True)(event_time_tolerance)
