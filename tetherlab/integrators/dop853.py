"""DOP853: explicit Runge-Kutta of order 8(5,3) with 7th-order dense output, compiled.

Reference: E. Hairer, S.P. Norsett, G. Wanner, "Solving Ordinary Differential Equations I",
2nd ed., Springer 1993, section II.10, and Hairer's Fortran code DOP853 (step-size controller,
error norm, HINIT, dense output CONTD8).  The coefficients come from :mod:`.tableau` (checked at
import).

This module holds the method's own pieces (stages, solution, Hairer's error norm, the dense
output CONTD8); the step loop, shared with Vern9, is :func:`tetherlab.integrators.erk.erk_core`:
the loop, the calls of the right-hand side (a cfunc with :data:`tetherlab._jit.RHS_SIG`) and the
dense output are one compiled function, so no Python runs between steps.

The helpers shared by every kernel (status codes, statistics slots, HINIT, output at the start
time, event bookkeeping) live in :mod:`.common`; the names below are re-exported from there for
one release so code that imported them from here keeps working (import them from ``common``).
"""

from __future__ import annotations

import numpy as np

from tetherlab._jit import njit, ptr, row_ptr

from .common import (
    ST_NRHS,
    all_finite,
    scaled_sq,
)
from .tableau import DOP_A, DOP_B, DOP_C, DOP_D, DOP_E3, DOP_E5

# Module-level copies as plain float64 arrays: numba freezes global arrays into the compiled code.
_A = DOP_A
_B = DOP_B
_C = DOP_C
_D = DOP_D
_E3 = DOP_E3
_E5 = DOP_E5


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
