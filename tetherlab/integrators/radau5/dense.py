"""The dense Newton matrix: forward-difference Jacobian, LU with partial pivoting (real and
complex) and the reduced systems of the second-order structure (Hairer's DECOMR/DECOMC, SLVRAD).

The LU is written here because numba offers only ``np.linalg.solve``, which refactorises every
call; the factors are reused across many Newton iterations and steps.
"""

from __future__ import annotations

import numpy as np

from tetherlab._jit import njit, ptr

from ..common import EPS, ST_NJAC, ST_NLU, ST_NRHS, all_finite
from .constants import ALPH, BETA, U1


@njit(cache=True)
def lu_factor(a, piv):
    """In-place LU of a square C-ordered matrix, row pivoting as LAPACK getrf (whole rows are
    swapped).  Returns 0, or k+1 when column k has no nonzero pivot (singular)."""
    n = a.shape[0]
    for k in range(n):
        pk = k
        amax = abs(a[k, k])
        for i in range(k + 1, n):
            v = abs(a[i, k])
            if v > amax:
                amax = v
                pk = i
        piv[k] = pk
        if not amax > 0.0:  # also catches NaN
            return k + 1
        if pk != k:
            for j in range(n):
                tmp = a[k, j]
                a[k, j] = a[pk, j]
                a[pk, j] = tmp
        inv = 1.0 / a[k, k]
        for i in range(k + 1, n):
            lik = a[i, k] * inv
            a[i, k] = lik
            if lik != 0.0:
                for j in range(k + 1, n):
                    a[i, j] -= lik * a[k, j]
    return 0


@njit(cache=True)
def lu_solve(a, piv, b):
    """Solve (LU) x = b in place, with the factors and pivots of :func:`lu_factor`."""
    n = a.shape[0]
    for k in range(n):
        pk = piv[k]
        if pk != k:
            tmp = b[k]
            b[k] = b[pk]
            b[pk] = tmp
    for i in range(n):
        s = b[i]
        for j in range(i):
            s -= a[i, j] * b[j]
        b[i] = s
    for i in range(n - 1, -1, -1):
        s = b[i]
        for j in range(i + 1, n):
            s -= a[i, j] * b[j]
        b[i] = s / a[i, i]



@njit(cache=True)
def _jacobian(rhs, t, y, f0, p, fjac, tmp, stats):
    """Forward differences, column j with increment sqrt(eps*max(1e-5, |y_j|)) (RADAU5).

    If the model fails at the perturbed state (e.g. a constraint at its boundary), the backward
    difference is tried before giving up.  Returns 0, a nonzero rhs status, or -1 (non-finite).
    """
    n = y.shape[0]
    for j in range(n):
        ysafe = y[j]
        delt = np.sqrt(EPS * max(1e-5, abs(ysafe)))
        y[j] = ysafe + delt
        st = rhs(t, ptr(y), ptr(tmp), ptr(p))
        stats[ST_NRHS] += 1
        if st != 0:
            delt = -delt
            y[j] = ysafe + delt
            st = rhs(t, ptr(y), ptr(tmp), ptr(p))
            stats[ST_NRHS] += 1
        y[j] = ysafe
        if st != 0:
            return st
        for i in range(n):
            fjac[i, j] = (tmp[i] - f0[i]) / delt
    stats[ST_NJAC] += 1
    for i in range(n):
        if not all_finite(fjac[i]):
            return -1
    return 0


@njit(cache=True)
def _decompose(fjac, h, e1, e2, ip1, ip2, stats, m1):
    """E1 = U1/h I - J and E2 = (ALPH + i BETA)/h I - J, both factorised (one "LU" in stats,
    as Hairer's NDEC counts the pair).

    With the second-order structure (m1 > 0, J = [[0, I], [A_q, A_v]]) the system
    (g I - J) [z_q; z_v] = [b_q; b_v] is equivalent to z_q = (b_q + z_v)/g and
    (g I - A_v - A_q/g) z_v = b_v + A_q b_q/g: only the m1 x m1 matrix g I - A_v - A_q/g is
    factorised (Hairer's DECOMR/DECOMC with M1 = M2).
    """
    n = fjac.shape[0]
    fac1 = U1 / h
    fac2 = complex(ALPH / h, BETA / h)
    if m1 == 0:
        for i in range(n):
            for j in range(n):
                e1[i, j] = -fjac[i, j]
                e2[i, j] = -fjac[i, j]
            e1[i, i] += fac1
            e2[i, i] += fac2
    else:
        inv1 = 1.0 / fac1
        inv2 = 1.0 / fac2
        ne = n - m1  # v rows (m1) then any first-order rows appended after [q, v] (Hairer's M1 < n/2)
        for i in range(ne):
            for j in range(ne):
                aq = fjac[m1 + i, j] if j < m1 else 0.0
                av = fjac[m1 + i, m1 + j]
                e1[i, j] = -av - aq * inv1
                e2[i, j] = -av - aq * inv2
            e1[i, i] += fac1
            e2[i, i] += fac2
    stats[ST_NLU] += 1
    ier = lu_factor(e1, ip1)
    if ier != 0:
        return ier
    return lu_factor(e2, ip2)


@njit(cache=True)
def _solve(e, ip, fjac, g, m1, b):
    """Solve (g I - J) x = b in place with the factors of :func:`_decompose` (real or complex
    g and b alike), using the reduced form when m1 > 0."""
    if m1 == 0:
        lu_solve(e, ip, b)
        return
    inv = 1.0 / g
    for i in range(fjac.shape[0] - m1):
        s = 0.0 * b[0]
        for j in range(m1):
            s += fjac[m1 + i, j] * b[j]
        b[m1 + i] += s * inv
    lu_solve(e, ip, b[m1:])
    for i in range(m1):
        b[i] = (b[i] + b[m1 + i]) * inv

