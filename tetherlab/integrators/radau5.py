"""RADAU5: implicit Runge-Kutta Radau IIA of order 5 for stiff problems, compiled.

Reference: E. Hairer, G. Wanner, "Solving Ordinary Differential Equations II", 2nd ed., Springer
1996, section IV.8, and Hairer's Fortran code RADAU5 (routine RADCOR, version of 2002), followed
closely so the kernel can be read against it; Fortran names are kept for the scalars.

* Simplified Newton iteration on the stage increments Z, transformed with T so the 3n x 3n system
  splits into one real n x n system (U1/h - J) and one complex one ((ALPH + i BETA)/h - J).
* Jacobian by forward differences of the rhs, column increment sqrt(eps*max(1e-5, |y_j|)), kept
  across steps while the Newton contraction rate theta stays <= THET (Hairer's reuse rule); the
  LU factors are kept while h changes by less than the factor QUOT1..QUOT2.
* Error estimate of Hairer (IV.8, (8.19)-(8.20)) including the extra solve with f(t, y + err) on
  the first step and after a rejection ("stiff" filtering), Gustafsson's predictive controller.
* Dense output: the collocation polynomial (CONTR5).
* Tolerances are transformed as in RADAU5's driver, rtol' = 0.1 rtol^(2/3) and
  atol' = atol rtol'/rtol: the estimate is of an embedded order-3 solution, which overstates the
  error of the order-5 result; Hairer calibrated this map so the global error tracks rtol.

Dense LU with partial pivoting (real and complex) is written here because numba offers only
``np.linalg.solve``, which refactorises every call; the factors are reused across many Newton
iterations and steps.

Two entry points: :func:`radau5_run` has the common kernel ABI and starts fresh on every call.
:func:`radau5_core` additionally takes a workspace (:func:`radau5_workspace`) holding the Jacobian,
LU factors, the last collocation polynomial and the controller state, and can resume from it:
the driver uses that, so splitting a run into calls changes neither the steps nor the result.
"""

from __future__ import annotations

import numpy as np

from tetherlab._jit import njit, ptr, row_ptr

from .common import (
    EPS,
    EVENT,
    H_FLOOR,
    MAX_BAD_TRIALS,
    MAX_CONSECUTIVE_REJECTS,
    MAX_STEPS,
    NON_FINITE,
    OK,
    RHS_FAILED,
    ST_ACCEPTED,
    ST_NEWTON_FAIL,
    ST_NJAC,
    ST_NLU,
    ST_NRHS,
    ST_REJECTED,
    ST_RHS_STATUS,
    STEP_UNDERFLOW,
    UNDERFLOW_FACTOR,
    all_finite,
    event_time_tolerance,
    fill_start_outputs,
    first_crossing,
    start_events,
    hinit,
    scaled_sq,
)
from ..tether import newton as _nw
from .tableau import (
    ALPH,
    BETA,
    C1,
    C1M1,
    C1MC2,
    C2,
    C2M1,
    DD1,
    DD2,
    DD3,
    RADAU_T,
    RADAU_TI,
    U1,
)

# Transformation matrices as scalars (numba folds them into the arithmetic).
T11, T12, T13 = (float(v) for v in RADAU_T[0])
T21, T22, T23 = (float(v) for v in RADAU_T[1])
T31 = float(RADAU_T[2, 0])  # T32 = 1, T33 = 0 (used implicitly below)
TI11, TI12, TI13 = (float(v) for v in RADAU_TI[0])
TI21, TI22, TI23 = (float(v) for v in RADAU_TI[1])
TI31, TI32, TI33 = (float(v) for v in RADAU_TI[2])

# RADAU5 defaults (Hairer's IWORK/WORK defaults).
NIT = 7  # max Newton iterations per step
THET = 0.01  # Jacobian is recomputed when the Newton rate exceeds this
SAFE = 0.9
QUOT1 = 1.0  # keep h (and the LU) when hnew/h is in [QUOT1, QUOT2]
QUOT2 = 1.2
FACL = 5.0  # hnew/h >= 1/FACL
FACR = 0.125  # hnew/h <= 1/FACR
MAX_SINGULAR = 5  # consecutive singular matrices before giving up
#: Target contraction rate of the simplified Newton iteration for the step-size cap (docs/
#: integrators.md, section 7): the rate grows like h^2 on a rotating stiff tether, so after an
#: accepted step with a fresh Jacobian and a measured rate theta the next step is at most
#: h sqrt(THETA_STEP / theta).  Without the cap Hairer's error-based controller proposes steps the
#: iteration cannot converge on, and nearly every accepted step followed a Newton failure.
#: Tried on the structured path (docs/integrators.md section 11): on an undamped tether theta grows
#: like h^4 rather than h^2, and a cap h (0.15 / theta)^(1/4) saved 13-16 % of the rhs calls
#: (de-orbit n = 16: 855k -> 741k); but at rtol 1e-11 theta has a round-off floor near 0.2, above
#: that target, so the cap shrank every step (libration n = 128, 2 orbits: > 20 min against 5.6 s).
THETA_STEP = 0.3
#: Structured Jacobian (O(n), cheaper than one rhs call): 0 Hairer's reuse rule, 1 refreshed on
#: every step at its start, 2 refreshed on every step at the middle of the coming step (on the
#: extrapolated collocation polynomial), which halves the rotation of the stiff axial direction
#: between the Jacobian and the stages (docs/integrators.md, section 7; measured best).
STRUCT_JAC_EVERY_STEP = 2
#: Newton iterations allowed with the structured matrix (an iteration costs 3 rhs calls and two
#: O(n) solves; docs/integrators.md section 7: 7, 10, 14 measured, 10 kept).
NIT_STRUCT = 10
#: A stalled Newton iteration (rate >= 0.99, or a predicted miss of the iteration limit) whose
#: increment is within this factor of the round-off floor (:func:`_increment_noise`) is taken as
#: converged: the three stages' noise enters each transformed increment through rows of T^-1 of
#: norm ~4.4, and the floor is one realisation of it (docs/integrators.md section 12).
FLOOR_GAIN = 10.0

# Workspace scalar slots (float fs[], int is_[]).
_F_HOLD = 0
_F_THETA = 1
_F_FACCON = 2
_F_HACC = 3
_F_ERRACC = 4
_F_HLU = 5
_F_THSTEP = 6  # Newton-rate step cap target (0: off, Hairer's controller alone); set by the workspace
_F_JACEVERY = 7  # > 0: a fresh Jacobian on every step (set by the workspace; structured default)
_F_NIT = 8  # max Newton iterations (0: NIT); set by the workspace
_F_FLOOR = 9  # FLOOR_GAIN (0: a stalled Newton iteration is always a failure); set by the workspace
_I_FIRST = 0
_I_NEED_JAC = 1
_I_LU_VALID = 2
_I_NACCPT = 3
_I_NSING = 4
_I_STARTED = 5
_I_M1 = 6  # second-order structure: y'_i = y_{i+M1} for i < M1 (0 = none), set by the workspace
_I_STRUCT = 7  # 1: structured Newton matrix of a tether state (tether/newton.py), O(n) per step
_I_NBORDER = 8  # structured: number of first-order unknowns w bordering it (n - 2 m1; section 13)
_F_TBASE = 10  # structured with a border: time of the border's base state
#: rows of the border's float work array: base state y_J, f(t_J, y_J), then scratch
_B_Y, _B_F, _B_YT, _B_FT, _B_XR, _B_XI, _B_OR, _B_OI = 0, 1, 2, 3, 4, 5, 6, 7
_B_ROWS = 8
#: relative increment of the border's directional differences (forward: sqrt(eps))
_SQRT_EPS = float(np.sqrt(EPS))


def radau5_workspace(n, m1=0, p=None):
    """Arrays that carry RADAU5's state between calls of :func:`radau5_core`.

    With ``p`` (a tether model's parameter block, Cowell layout, ``m1 = n/2``) the Newton matrix
    is the structured one of :mod:`tetherlab.tether.newton` (analytic rod blocks, block-Thomas
    factorisation and solve, O(n) per step) and no dense n x n array is allocated; the caller
    checks :func:`tetherlab.tether.newton.structure_supported` first.  With rigid bodies
    (n > 2 m1: their attitude and wheel states w appended) the structured solve is bordered by the
    n - 2 m1 unknowns w and completed by a Schur complement on them (docs/integrators.md section
    13; the workspace's last element, a tuple of arrays).

    ``m1 > 0`` declares Hairer's special structure (RADAU5's M1 = M2): the first m1 components have
    the next m1 as their exact derivatives (y = [q, v, w], q' = v, as in Cowell's formulation; w:
    first-order components appended, e.g. attitude and wheels, n >= 2 m1).  Then
    J = [[0, I, 0], [A_q, A_v, A_w], [B_q, B_v, B_w]] and both Newton systems reduce to
    (n - m1) x (n - m1) ones (docs/integrators.md): for n = 2 m1 the LU work falls by 8x and each
    solve by about 4x.
    """
    if m1 < 0 or 2 * m1 > n:
        raise ValueError(f"m1: expected 0 <= m1 <= n/2 = {n / 2:g} (second-order structure); got {m1}")
    structured = p is not None
    if structured and (m1 == 0 or _nw.structure_supported(p, n, m1)):
        raise ValueError("p: the structured Newton matrix needs a Cowell tether state with m1 = 3 + 3 rods "
                         "(and n - 2 m1 attitude and wheel components when bodies are rigid)")
    nb = n - 2 * m1 if structured else 0  # border unknowns (docs/integrators.md section 13)
    ne = 1 if structured else n - m1
    nd = 1 if structured else n
    blk, sf1, sf2 = _nw.workspace(p) if structured else (
        np.zeros((1, _nw.BLK_SIZE)), np.zeros((1, _nw.FAC_SIZE)),
        np.zeros((1, _nw.FAC_SIZE), dtype=np.complex128))  # fmt: skip
    ws = (
        np.zeros((nd, nd)),  # fjac
        np.zeros((ne, ne)),  # e1 (LU of U1/h - J, or of its reduced form)
        np.zeros((ne, ne), dtype=np.complex128),  # e2 (LU of (ALPH+iBETA)/h - J, or reduced)
        np.zeros(ne, dtype=np.int64),  # ip1
        np.zeros(ne, dtype=np.int64),  # ip2
        np.zeros((4, n)),  # cont: y_new and the 3 coefficients of the collocation polynomial
        np.zeros(n),  # f0 = f(t, y)
        np.zeros(12),  # float scalars
        np.zeros(10, dtype=np.int64),  # int scalars
        blk,  # structured: rod blocks (tether/newton.py)
        sf1,  # structured: real factors
        sf2,  # structured: complex factors
        # the border (docs/integrators.md section 13), one tuple: a kernel call of more than 30
        # arguments is compiled by CPython as f(*args), and numba warns on the tuple of a
        # first-class function that this builds
        (np.zeros((n, max(nb, 1))),  # border: finite-difference columns of J for the w unknowns
        np.zeros((max(nb, 1), n)),  # border: z^j = S_t(0, A_w e_j), real shift
        np.zeros((max(nb, 1), n), dtype=np.complex128),  # border: the same, complex shift
        np.zeros((max(nb, 1), max(nb, 1))),  # border: LU of Sigma, real
        np.zeros((max(nb, 1), max(nb, 1)), dtype=np.complex128),  # border: LU of Sigma, complex
        np.zeros(max(nb, 1), dtype=np.int64),  # border: pivots, real
        np.zeros(max(nb, 1), dtype=np.int64),  # border: pivots, complex
        np.zeros((_B_ROWS, n))),  # border: base state, f there, scratch (rows _B_*)
    )
    ws[8][_I_M1] = m1
    ws[8][_I_STRUCT] = 1 if structured else 0
    ws[8][_I_NBORDER] = nb
    ws[7][_F_THSTEP] = THETA_STEP
    ws[7][_F_NIT] = NIT_STRUCT if structured else NIT
    ws[7][_F_JACEVERY] = float(STRUCT_JAC_EVERY_STEP) if structured else 0.0
    ws[7][_F_FLOOR] = FLOOR_GAIN
    return ws


# --------------------------------------------------------------------------------------------
# Dense LU with partial pivoting (works for float64 and complex128 arrays: numba specialises).
# --------------------------------------------------------------------------------------------
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
def _collocation(y_new, z1, z2, z3, cont):
    """The step's collocation polynomial in Hairer's CONTR5 form: y(t_new + s h) =
    cont0 + s (cont1 + (s - C2M1)(cont2 + (s - C1M1) cont3)), s in [-1, 0]."""
    for i in range(y_new.shape[0]):
        z1i = z1[i]
        z2i = z2[i]
        c1 = (z2i - z3[i]) / C2M1
        ak = (z1i - z2i) / C1MC2
        acont3 = (ak - z1i / C1) / C2
        c2 = (ak - c1) / C1M1
        cont[0, i] = y_new[i]
        cont[1, i] = c1
        cont[2, i] = c2
        cont[3, i] = c2 - acont3


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


@njit(cache=True)
def _lin(struct, e, ip, fjac, g, m1, b, p, blk, sfac, rhs, nb, bz, bs, bp, bw, tb, iu, stats):
    """(g I - J) x = b in place: the structured solve (bordered when nb > 0), or the dense
    factors' one.  ``iu``: 0.0 for the real system, 1j for the complex one (typed like b)."""
    if struct:
        _nw.solve(p, blk, g, sfac, m1, b)
        if nb > 0:
            _border_solve(rhs, tb, p, m1, nb, b, bz, bs, bp, bw, iu, stats)
    else:
        _solve(e, ip, fjac, g, m1, b)


# --------------------------------------------------------------------------------------------
# The border of the structured matrix: rigid bodies' attitude and wheel unknowns w
# (docs/integrators.md section 13).  With y = [q, v, w] the Newton system (g I - J) z = b is
#     [ E_tt     -A_w   ] [z_v]   [b_v + A_q b_q/g]
#     [ -B_qv   g - B_w ] [z_w] = [b_w + B_q b_q/g],   z_q = (b_q + z_v)/g,
# B_qv x = B_q x_q + B_v x_v.  E_tt is the tether solve S_t of tether/newton.py (bodies as point
# masses of their translational mass at their joints).  Schur complement on the few w:
#     z0 = S_t(b_q, b_v),  z^j = S_t(0, A_w e_j),  Sigma = g - B_w - [B_qv z^j]_j,
#     z_w = Sigma^-1 (b_w + B_qv z0),  (z_q, z_v) = z0 + sum_j z_w,j z^j.
# --------------------------------------------------------------------------------------------
@njit(cache=True)
def _border_jacobian(rhs, t, ybase, p, m1, nb, bcol, bw, stats):
    """Base of the border at (t, ybase): f there, and the nb finite-difference columns of J for
    the w unknowns (rows: A_w and B_w; Hairer's increments sqrt(eps max(1e-5, |y_j|))).  nb + 1
    rhs calls.  Returns 0, an rhs status or -1 (non-finite)."""
    n = ybase.shape[0]
    yb = bw[_B_Y]
    fb = bw[_B_F]
    yt = bw[_B_YT]
    ft = bw[_B_FT]
    for i in range(n):
        yb[i] = ybase[i]
        yt[i] = ybase[i]
    st = rhs(t, row_ptr(bw, _B_Y), row_ptr(bw, _B_F), ptr(p))
    stats[ST_NRHS] += 1
    if st != 0:
        return st
    if not all_finite(fb):
        return -1
    n2 = 2 * m1
    for j in range(nb):
        c = n2 + j
        delt = np.sqrt(EPS * max(1e-5, abs(yb[c])))
        yt[c] = yb[c] + delt
        st = rhs(t, row_ptr(bw, _B_YT), row_ptr(bw, _B_FT), ptr(p))
        stats[ST_NRHS] += 1
        if st != 0:
            delt = -delt
            yt[c] = yb[c] + delt
            st = rhs(t, row_ptr(bw, _B_YT), row_ptr(bw, _B_FT), ptr(p))
            stats[ST_NRHS] += 1
        yt[c] = yb[c]
        if st != 0:
            return st
        for i in range(n):
            bcol[i, j] = (ft[i] - fb[i]) / delt
        if not all_finite(bcol[:, j]):
            return -1
    return 0


@njit(cache=True)
def _border_dir(rhs, t, p, m1, nb, bw, rx, ro, stats):
    """bw[ro, :nb] = B_qv x for the real direction x = bw[rx, :2 m1] (a forward difference of w'
    along x from the border's base; increment sqrt(eps) in the norm max_i |x_i| / max(1, |y_i|)).
    One rhs call (two if the model fails forward); a failed or non-finite difference gives 0."""
    n = bw.shape[1]
    n2 = 2 * m1
    yb = bw[_B_Y]
    fb = bw[_B_F]
    yt = bw[_B_YT]
    ft = bw[_B_FT]
    x = bw[rx]
    out = bw[ro]
    xm = 0.0
    for i in range(n2):
        r = abs(x[i]) / max(1.0, abs(yb[i]))
        if r > xm:
            xm = r
    for j in range(nb):
        out[j] = 0.0
    if not (xm > 0.0 and np.isfinite(xm)):
        return
    d = _SQRT_EPS / xm
    for sgn in (1.0, -1.0):
        for i in range(n2):
            yt[i] = yb[i] + sgn * d * x[i]
        for i in range(n2, n):
            yt[i] = yb[i]
        st = rhs(t, row_ptr(bw, _B_YT), row_ptr(bw, _B_FT), ptr(p))
        stats[ST_NRHS] += 1
        if st == 0 and all_finite(ft):
            for j in range(nb):
                out[j] = (ft[n2 + j] - fb[n2 + j]) / (sgn * d)
            return


@njit(cache=True)
def _border_apply(rhs, t, p, m1, nb, z, bw, iu, stats, out):
    """out = B_qv z for a real or complex z (length >= 2 m1): real and imaginary parts apart
    (``iu`` 0.0 or 1j, typed like z and out)."""
    n2 = 2 * m1
    xr = bw[_B_XR]
    xi = bw[_B_XI]
    cplx = False
    for i in range(n2):
        v = z[i]
        xr[i] = v.real
        xi[i] = v.imag
        if v.imag != 0.0:
            cplx = True
    _border_dir(rhs, t, p, m1, nb, bw, _B_XR, _B_OR, stats)
    if cplx:
        _border_dir(rhs, t, p, m1, nb, bw, _B_XI, _B_OI, stats)
    else:
        for j in range(nb):
            bw[_B_OI, j] = 0.0
    for j in range(nb):
        out[j] = bw[_B_OR, j] + iu * bw[_B_OI, j]


@njit(cache=True)
def _border_factor(rhs, t, p, blk, m1, nb, g, sfac, bcol, bz, bs, bp, bw, iu, stats):
    """The border's part of the factorisation for the shift g (real or complex): the columns
    z^j = S_t(0, A_w e_j), D_j = B_qv z^j, and the LU of Sigma = g I - B_w - D.  3 nb rhs calls
    for a complex g, nb for a real one.  Returns 0, or k + 1 for a singular Sigma."""
    n2 = 2 * m1
    n = bz.shape[1]
    col = np.zeros(nb, dtype=bz.dtype)
    for j in range(nb):
        z = bz[j]
        for i in range(n):
            z[i] = 0.0
        for i in range(m1):
            z[m1 + i] = bcol[m1 + i, j]
        _nw.solve(p, blk, g, sfac, m1, z)
        _border_apply(rhs, t, p, m1, nb, z, bw, iu, stats, col)
        for i in range(nb):
            bs[i, j] = -bcol[n2 + i, j] - col[i]
        bs[j, j] += g
    return lu_factor(bs, bp)


@njit(cache=True)
def _border_solve(rhs, t, p, m1, nb, b, bz, bs, bp, bw, iu, stats):
    """Complete the tether solve already done in b[:2 m1] (z0) with the border: z_w and
    z += sum_j z_w,j z^j (b[2 m1:] holds b_w on entry, z_w on return)."""
    n2 = 2 * m1
    rw = np.zeros(nb, dtype=b.dtype)
    _border_apply(rhs, t, p, m1, nb, b, bw, iu, stats, rw)
    for j in range(nb):
        rw[j] += b[n2 + j]
    lu_solve(bs, bp, rw)
    for j in range(nb):
        zj = bz[j]
        c = rw[j]
        for i in range(n2):
            b[i] += c * zj[i]
        b[n2 + j] = rw[j]


@njit(cache=True)
def _increment_noise(rhs, t, y, f0, p, scal, tmp, out, struct, e1, ip1, fjac, fac1, m1, blk, sfac1, nb, bz1,
                     bs1, bp1, bw, tb, stats):  # fmt: skip
    """RMS (tolerance units) of the change of the real Newton system's solution when y moves by
    one rounding unit: the floor below which the increments of the simplified Newton iteration
    are round-off (docs/integrators.md section 12).  One rhs call and one linear solve."""
    n = y.size
    for i in range(n):
        # a fixed +-1 pattern, so the floor is reproducible (restarts stay bit for bit)
        sgn = 1.0 if (i * 40503) % 7 < 4 else -1.0
        tmp[i] = y[i] + sgn * EPS * abs(y[i])
    st = rhs(t, ptr(tmp), ptr(out), ptr(p))
    stats[ST_NRHS] += 1
    if st != 0:
        return 0.0
    for i in range(n):
        out[i] -= f0[i]
    _lin(struct, e1, ip1, fjac, fac1, m1, out, p, blk, sfac1, rhs, nb, bz1, bs1, bp1, bw, tb, 0.0, stats)
    acc = 0.0
    for i in range(n):
        acc += scaled_sq(out[i], scal[i])
    r = np.sqrt(acc / n)
    return r if np.isfinite(r) else 0.0


@njit(cache=True)
def radau5_core(
    rhs,
    t,
    y,
    t_out,
    p,
    rtol,
    atol,
    h,
    h_max,
    max_steps,
    y_out,
    stats,
    fixed_step,
    fjac,
    e1,
    e2,
    ip1,
    ip2,
    cont,
    f0,
    fs,
    is_,
    blk,
    sfac1,
    sfac2,
    border,
    resume,
    event,
    ne,
    ev,
):
    """RADAU5 with an explicit workspace; ``resume`` continues from the state it holds.

    Events (``event``, ``ne``, ``ev``) as in :func:`tetherlab.integrators.erk.erk_core`,
    located on the step's collocation polynomial; an EVENT return leaves the workspace of the
    uncommitted step, so the caller restarts fresh (``resume=False``) after it.

    Same contract as :func:`radau5_run` otherwise.  ``max_steps`` counts accepted steps and the
    call returns right after an accepted step, with everything the next step needs in the
    workspace, so resumed calls reproduce one long call exactly.
    """
    n = y.shape[0]
    m = t_out.shape[0]
    n_done = fill_start_outputs(t, y, t_out, y_out)
    if n_done == m:
        return OK, t, h, n_done
    t_end = t_out[m - 1]
    m1 = is_[_I_M1]
    struct = is_[_I_STRUCT] != 0
    nb = is_[_I_NBORDER] if struct else 0
    bcol, bz1, bz2, bs1, bs2, bp1, bp2, bw = border
    thstep = fs[_F_THSTEP]
    nit = int(fs[_F_NIT]) if fs[_F_NIT] > 0.0 else NIT
    jac_every = fs[_F_JACEVERY] > 0.0
    jac_mid = fs[_F_JACEVERY] > 1.0
    floor_gain = fs[_F_FLOOR]

    # Hairer's tolerance map (RADAU5 driver, EXPM = 2/3), and Newton's stopping tolerance FNEWT.
    rtol_i = 0.1 * rtol ** (2.0 / 3.0)
    atol_i = atol * (rtol_i / rtol)
    fnewt = max(10.0 * EPS / rtol_i, min(0.03, np.sqrt(rtol_i)))
    cfac = SAFE * (1 + 2 * nit)
    hmax = h_max if h_max > 0.0 else np.inf

    z1 = np.empty(n)
    z2 = np.empty(n)
    z3 = np.empty(n)
    f1 = np.empty(n)
    f2 = np.empty(n)
    f3 = np.empty(n)
    tmp = np.empty(n)
    scal = np.empty(n)
    wnoise = np.empty(n)
    w = np.empty(n, dtype=np.complex128)
    evc = np.zeros((4, n))
    st, gold, gnew, gtmp = start_events(event, t, y, p, ne, ev, stats)
    if st != 0:
        return RHS_FAILED, t, h, n_done

    if not (resume and is_[_I_STARTED] != 0):
        st = rhs(t, ptr(y), ptr(f0), ptr(p))
        stats[ST_NRHS] += 1
        if st != 0:
            stats[ST_RHS_STATUS] = st
            return RHS_FAILED, t, h, n_done
        if not all_finite(f0):
            return NON_FINITE, t, h, n_done
        if h <= 0.0:
            if fixed_step:
                return STEP_UNDERFLOW, t, h, n_done  # the driver rejects this before calling
            # HINIT with IORD = 4: the local error estimate of RADAU5 behaves like h^4.
            h = hinit(rhs, t, y, f0, p, rtol_i, atol_i, 4, min(hmax, t_end - t), z1, z2, stats)
        h = min(h, hmax)
        fs[_F_HOLD] = h
        fs[_F_THETA] = THET
        fs[_F_FACCON] = 1.0
        fs[_F_HACC] = h
        fs[_F_ERRACC] = 1e-2
        fs[_F_HLU] = 0.0
        is_[_I_FIRST] = 1
        is_[_I_NEED_JAC] = 1
        is_[_I_LU_VALID] = 0
        is_[_I_NACCPT] = 0
        is_[_I_NSING] = 0
        is_[_I_STARTED] = 1

    hold = fs[_F_HOLD]
    theta = fs[_F_THETA]
    faccon = fs[_F_FACCON]
    hacc = fs[_F_HACC]
    erracc = fs[_F_ERRACC]
    h_lu = fs[_F_HLU]
    first = is_[_I_FIRST] != 0
    need_jac = is_[_I_NEED_JAC] != 0
    lu_valid = is_[_I_LU_VALID] != 0
    naccpt = is_[_I_NACCPT]
    nsing = is_[_I_NSING]
    tb = fs[_F_TBASE]

    caljac = False  # the Jacobian in fjac was evaluated at the current (t, y)
    reject = False
    n_acc = 0
    n_rej = 0
    n_bad = 0
    bad_kind = 0
    land = 1.0 + 1e-9 if fixed_step else 1.01
    status = OK

    while True:
        # ------------------------------------------------ step size for this trial
        if h < UNDERFLOW_FACTOR * abs(t) or h < H_FLOOR or n_rej >= MAX_CONSECUTIVE_REJECTS:
            status = bad_kind if (n_rej > 0 and bad_kind != 0) else STEP_UNDERFLOW
            break
        h_unclipped = h
        last = False
        if t + land * h >= t_end:
            h = t_end - t
            last = True
        xph = t_end if last else t + h

        # ------------------------------------------------ Jacobian and LU (Hairer's 10 / 20)
        if need_jac:
            if struct:
                if jac_mid and not first:
                    # at the middle of the coming step, on the extrapolated collocation polynomial
                    cq = 0.5 * h / hold
                    for i in range(n):
                        tmp[i] = y[i] + cq * (cont[1, i] + (cq - C2M1) * (
                            cont[2, i] + (cq - C1M1) * cont[3, i]))  # fmt: skip
                    st = _nw.rod_blocks(tmp, p, m1, blk)
                    tb = t + 0.5 * h
                else:
                    st = _nw.rod_blocks(y, p, m1, blk)
                    tb = t
                    if nb > 0:
                        for i in range(n):
                            tmp[i] = y[i]
                stats[ST_NJAC] += 1
                if st != 0:
                    st = -1
                elif nb > 0:
                    # the border: f at the same base state and its nb columns (section 13)
                    st = _border_jacobian(rhs, tb, tmp, p, m1, nb, bcol, bw, stats)
                    if st != 0 and tb != t:
                        # the model failed at the extrapolated mid-step state: the border at
                        # (t, y) instead (an approximate matrix changes the rate, not the result)
                        tb = t
                        st = _border_jacobian(rhs, tb, y, p, m1, nb, bcol, bw, stats)
                    fs[_F_TBASE] = tb
            else:
                st = _jacobian(rhs, t, y, f0, p, fjac, tmp, stats)
            if st != 0:
                if st == -1:
                    status = NON_FINITE
                else:
                    stats[ST_RHS_STATUS] = st
                    status = RHS_FAILED
                break
            need_jac = False
            caljac = True
            lu_valid = False
        if not lu_valid or h != h_lu:
            if struct:
                stats[ST_NLU] += 1
                ier = _nw.factor(p, blk, U1 / h, sfac1)
                if ier == 0:
                    ier = _nw.factor(p, blk, complex(ALPH / h, BETA / h), sfac2)
                if ier == 0 and nb > 0:
                    ier = _border_factor(rhs, tb, p, blk, m1, nb, U1 / h, sfac1, bcol, bz1, bs1, bp1, bw,
                                         0.0, stats)  # fmt: skip
                    if ier == 0:
                        ier = _border_factor(rhs, tb, p, blk, m1, nb, complex(ALPH / h, BETA / h), sfac2,
                                             bcol, bz2, bs2, bp2, bw, 1j, stats)  # fmt: skip
            else:
                ier = _decompose(fjac, h, e1, e2, ip1, ip2, stats, m1)
            if ier != 0:
                lu_valid = False
                nsing += 1
                if nsing >= MAX_SINGULAR or fixed_step:
                    status = STEP_UNDERFLOW
                    break
                # Hairer's label 78: halve h; the Jacobian is refreshed unless it is current.
                h = 0.5 * h
                reject = True
                stats[ST_REJECTED] += 1
                n_rej += 1
                bad_kind = 0
                need_jac = not caljac
                continue
            lu_valid = True
            h_lu = h
        fac1 = U1 / h
        alphn = ALPH / h
        betan = BETA / h
        fac2 = complex(alphn, betan)

        for i in range(n):
            scal[i] = atol_i[i] + rtol_i * abs(y[i])

        # ------------------------------------------------ starting values for Newton
        if first:
            for i in range(n):
                z1[i] = 0.0
                z2[i] = 0.0
                z3[i] = 0.0
                f1[i] = 0.0
                f2[i] = 0.0
                f3[i] = 0.0
        else:
            # Extrapolate the previous step's collocation polynomial (CONTR5 form).
            c3q = h / hold
            c1q = C1 * c3q
            c2q = C2 * c3q
            for i in range(n):
                ak1 = cont[1, i]
                ak2 = cont[2, i]
                ak3 = cont[3, i]
                z1i = c1q * (ak1 + (c1q - C2M1) * (ak2 + (c1q - C1M1) * ak3))
                z2i = c2q * (ak1 + (c2q - C2M1) * (ak2 + (c2q - C1M1) * ak3))
                z3i = c3q * (ak1 + (c3q - C2M1) * (ak2 + (c3q - C1M1) * ak3))
                z1[i] = z1i
                z2[i] = z2i
                z3[i] = z3i
                f1[i] = TI11 * z1i + TI12 * z2i + TI13 * z3i
                f2[i] = TI21 * z1i + TI22 * z2i + TI23 * z3i
                f3[i] = TI31 * z1i + TI32 * z2i + TI33 * z3i

        # ------------------------------------------------ simplified Newton iteration
        newt = 0
        faccon = max(faccon, EPS) ** 0.8
        theta = THET
        dynold = 0.0
        thqold = 0.0
        fail = 0  # 0 ok, RHS_FAILED / NON_FINITE, 10 = Newton failure, 11 = Newton too slow
        hhfac = 1.0
        noise = -1.0  # the Newton increments' round-off floor at this step (computed on demand)
        at_floor = False
        while True:
            if newt >= nit:
                fail = 10
                break
            # Stage values y + z_k -> f, written back into z_k.
            for i in range(n):
                tmp[i] = y[i] + z1[i]
            st = rhs(t + C1 * h, ptr(tmp), ptr(z1), ptr(p))
            if st == 0:
                for i in range(n):
                    tmp[i] = y[i] + z2[i]
                st = rhs(t + C2 * h, ptr(tmp), ptr(z2), ptr(p))
                if st == 0:
                    for i in range(n):
                        tmp[i] = y[i] + z3[i]
                    st = rhs(xph, ptr(tmp), ptr(z3), ptr(p))
                    stats[ST_NRHS] += 3
                else:
                    stats[ST_NRHS] += 2
            else:
                stats[ST_NRHS] += 1
            if st != 0:
                stats[ST_RHS_STATUS] = st
                fail = RHS_FAILED
                break
            # Right-hand sides of the transformed systems, then the two solves (SLVRAD).
            for i in range(n):
                a1 = z1[i]
                a2 = z2[i]
                a3 = z3[i]
                s2 = -f2[i]
                s3 = -f3[i]
                z1[i] = -f1[i] * fac1 + TI11 * a1 + TI12 * a2 + TI13 * a3
                z2[i] = s2 * alphn - s3 * betan + TI21 * a1 + TI22 * a2 + TI23 * a3
                z3[i] = s3 * alphn + s2 * betan + TI31 * a1 + TI32 * a2 + TI33 * a3
            _lin(struct, e1, ip1, fjac, fac1, m1, z1, p, blk, sfac1, rhs, nb, bz1, bs1, bp1, bw, tb, 0.0, stats)
            for i in range(n):
                w[i] = complex(z2[i], z3[i])
            _lin(struct, e2, ip2, fjac, fac2, m1, w, p, blk, sfac2, rhs, nb, bz2, bs2, bp2, bw, tb, 1j, stats)
            for i in range(n):
                z2[i] = w[i].real
                z3[i] = w[i].imag
            newt += 1
            dyno = 0.0
            for i in range(n):
                dyno += scaled_sq(z1[i], scal[i]) + scaled_sq(z2[i], scal[i])
                dyno += scaled_sq(z3[i], scal[i])
            dyno = np.sqrt(dyno / (3 * n))
            if not np.isfinite(dyno):
                fail = NON_FINITE
                break
            # Convergence rate; bad convergence or a predicted miss of nit.
            if newt > 1 and newt < nit:
                thq = dyno / dynold
                if newt == 2:
                    theta = thq
                else:
                    theta = np.sqrt(thq * thqold)
                thqold = thq
                stalled = False
                if theta < 0.99:
                    faccon = theta / (1.0 - theta)
                    dyth = faccon * dyno * theta ** (nit - 1 - newt) / fnewt
                    if dyth >= 1.0 and not fixed_step:
                        qnewt = max(1e-4, min(20.0, dyth))
                        hhfac = 0.8 * qnewt ** (-1.0 / (4.0 + nit - 1 - newt))
                        stalled = True
                        fail = 11
                else:
                    stalled = True
                    fail = 10
                if stalled:
                    # Increments that stopped shrinking may have reached the round-off of the
                    # stage values themselves, which no smaller step lowers (docs/integrators.md
                    # section 12): then the iterate is as converged as double precision allows.
                    if floor_gain > 0.0:
                        if noise < 0.0:
                            noise = _increment_noise(rhs, t, y, f0, p, scal, tmp, wnoise, struct, e1,
                                                     ip1, fjac, fac1, m1, blk, sfac1, nb, bz1, bs1, bp1,
                                                     bw, tb, stats)  # fmt: skip
                        if dyno <= floor_gain * noise:
                            fail = 0
                            at_floor = True
                    if not at_floor:
                        break
            dynold = max(dyno, EPS)
            for i in range(n):
                f1i = f1[i] + z1[i]
                f2i = f2[i] + z2[i]
                f3i = f3[i] + z3[i]
                f1[i] = f1i
                f2[i] = f2i
                f3[i] = f3i
                z1[i] = T11 * f1i + T12 * f2i + T13 * f3i
                z2[i] = T21 * f1i + T22 * f2i + T23 * f3i
                z3[i] = T31 * f1i + f2i
            if faccon * dyno <= fnewt or at_floor:
                break

        if fail != 0:
            if fixed_step:
                status = STEP_UNDERFLOW if fail >= 10 else fail
                if fail >= 10:
                    stats[ST_NEWTON_FAIL] += 1
                break
            stats[ST_REJECTED] += 1
            n_rej += 1
            reject = True
            if fail >= 10:
                stats[ST_NEWTON_FAIL] += 1
                bad_kind = 0
                h = h * (hhfac if fail == 11 else 0.5)
            else:
                n_bad += 1
                bad_kind = fail
                if n_bad >= MAX_BAD_TRIALS:
                    status = fail
                    break
                h = 0.25 * h
            need_jac = not caljac
            continue

        # ------------------------------------------------ error estimate (ESTRAD)
        err = 0.0
        quot = 1.0
        if not fixed_step:
            hee1 = DD1 / h
            hee2 = DD2 / h
            hee3 = DD3 / h
            for i in range(n):
                f2[i] = hee1 * z1[i] + hee2 * z2[i] + hee3 * z3[i]
                tmp[i] = f2[i] + f0[i]
                # Weights for the error test use max(|y|, |y_new|), as the DOP853 kernel and
                # scipy do; f3 is free here and holds them.
                f3[i] = atol_i[i] + rtol_i * max(abs(y[i]), abs(y[i] + z3[i]))
            _lin(struct, e1, ip1, fjac, fac1, m1, tmp, p, blk, sfac1, rhs, nb, bz1, bs1, bp1, bw, tb, 0.0, stats)
            for i in range(n):
                err += scaled_sq(tmp[i], f3[i])
            err = max(np.sqrt(err / n), 1e-10)
            if err >= 1.0 and (first or reject):
                # Filter the estimate once more with the real system: without this, the
                # estimate is unbounded for very stiff components (Hairer & Wanner IV.8).
                for i in range(n):
                    tmp[i] = y[i] + tmp[i]
                st = rhs(t, ptr(tmp), ptr(f1), ptr(p))
                stats[ST_NRHS] += 1
                if st == 0 and all_finite(f1):
                    for i in range(n):
                        tmp[i] = f1[i] + f2[i]
                    _lin(struct, e1, ip1, fjac, fac1, m1, tmp, p, blk, sfac1, rhs, nb, bz1, bs1, bp1, bw, tb, 0.0, stats)
                    err = 0.0
                    for i in range(n):
                        err += scaled_sq(tmp[i], f3[i])
                    err = max(np.sqrt(err / n), 1e-10)
                # (If that probe fails, the unfiltered estimate stands: it is >= 1, so the
                # step is rejected either way.)
            if not np.isfinite(err):
                stats[ST_REJECTED] += 1
                n_rej += 1
                n_bad += 1
                bad_kind = NON_FINITE
                reject = True
                if n_bad >= MAX_BAD_TRIALS:
                    status = NON_FINITE
                    break
                h = 0.25 * h
                need_jac = not caljac
                continue
            fac = min(SAFE, cfac / (newt + 2 * nit))
            quot = max(FACR, min(FACL, err**0.25 / fac))
        hnew = h / quot

        if err < 1.0:
            # f at the new point before committing (it is the next step's f0 and Jacobian base):
            # if the model fails there the step is rejected, not half-accepted.
            for i in range(n):
                tmp[i] = y[i] + z3[i]
            st = rhs(xph, ptr(tmp), ptr(f1), ptr(p))
            stats[ST_NRHS] += 1
            fail = 0
            if st != 0:
                stats[ST_RHS_STATUS] = st
                fail = RHS_FAILED
            elif not (all_finite(f1) and all_finite(tmp)):
                fail = NON_FINITE
            if fail != 0:
                if fixed_step:
                    status = fail
                    break
                stats[ST_REJECTED] += 1
                n_rej += 1
                n_bad += 1
                bad_kind = fail
                reject = True
                if n_bad >= MAX_BAD_TRIALS:
                    status = fail
                    break
                h = 0.25 * h
                need_jac = not caljac
                continue

            # ---------------------------------------------- events (nothing committed yet)
            if ne > 0:
                st = event(xph, ptr(tmp), ptr(gnew), ptr(p))
                if st != 0:
                    stats[ST_RHS_STATUS] = st
                    status = RHS_FAILED
                    break
                if first_crossing(gold, gnew, ne):
                    _collocation(tmp, z1, z2, z3, evc)  # this step's polynomial, s in [-1, 0]
                    tol = event_time_tolerance(xph, h)
                    best = 0.0
                    comp = -1
                    for k in range(ne):
                        if (gold[k] < 0.0) == (gnew[k] < 0.0):
                            continue
                        a = -1.0
                        b = 0.0
                        for _ in range(200):
                            if (b - a) * h <= tol:
                                break
                            sm = 0.5 * (a + b)
                            for i in range(n):
                                f2[i] = evc[0, i] + sm * (
                                    evc[1, i] + (sm - C2M1) * (evc[2, i] + (sm - C1M1) * evc[3, i])
                                )
                            st = event(xph + sm * h, ptr(f2), ptr(gtmp), ptr(p))
                            if st != 0:
                                break
                            if (gtmp[k] < 0.0) == (gold[k] < 0.0):
                                a = sm
                            else:
                                b = sm
                        if st != 0:
                            break
                        if comp < 0 or b < best:
                            best = b
                            comp = k
                    if st != 0:
                        stats[ST_RHS_STATUS] = st
                        status = RHS_FAILED
                        break
                    ev[0] = xph if best >= 0.0 else xph + best * h
                    ev[1] = comp
                    ev[2] = comp
                    ev[3] = 0.0 if gold[comp] < 0.0 else -1.0
                    h = h_unclipped
                    status = EVENT
                    break
                for k in range(ne):
                    gold[k] = gnew[k]

            # ---------------------------------------------- accept
            fresh_jac = caljac
            first = False
            naccpt += 1
            if not fixed_step:
                # Predictive controller of Gustafsson (RADAU5, PRED = true).
                if naccpt > 1:
                    facgus = (hacc / h) * (err * err / erracc) ** 0.25 / SAFE
                    facgus = max(FACR, min(FACL, facgus))
                    quot = max(quot, facgus)
                    hnew = h / quot
                hacc = h
                erracc = max(1e-2, err)
                if newt >= 2 and fresh_jac and thstep > 0.0 and not at_floor:
                    # Newton-rate cap (THETA_STEP): a fresh Jacobian's rate grows like h^2 here
                    # (not after an iteration stopped at its round-off floor: its rate is noise)
                    hnew = min(hnew, h * np.sqrt(thstep / theta))
            hold = h
            t = xph
            for i in range(n):
                y[i] = tmp[i]
                f0[i] = f1[i]
            _collocation(y, z1, z2, z3, cont)
            # Outputs inside the step from the collocation polynomial, s = (t_o - t)/h in [-1, 0).
            while n_done < m and t_out[n_done] < t:
                s = (t_out[n_done] - t) / hold
                row = y_out[n_done]
                for i in range(n):
                    row[i] = cont[0, i] + s * (
                        cont[1, i] + (s - C2M1) * (cont[2, i] + (s - C1M1) * cont[3, i])
                    )
                n_done += 1
            while n_done < m and t_out[n_done] <= t:
                y_out[n_done, :] = y
                n_done += 1
            stats[ST_ACCEPTED] += 1
            n_acc += 1
            n_rej = 0
            n_bad = 0
            bad_kind = 0
            nsing = 0
            caljac = False

            hnew = min(hnew, hmax)
            if fixed_step:
                hnew = h_unclipped
            hopt = hnew
            if reject:
                hnew = min(hnew, h)
            reject = False
            need_jac = theta > THET or jac_every
            if last:
                h = min(max(hopt, h_unclipped), hmax)
                status = OK
                break
            qt = hnew / h
            if not (theta <= THET and qt >= QUOT1 and qt <= QUOT2):
                h = hnew  # else keep h: the LU factors stay valid (Hairer's label 30)
            if n_acc >= max_steps:
                status = MAX_STEPS
                break
        else:
            # ---------------------------------------------- reject (error test)
            reject = True
            if first:
                h = 0.1 * h
            else:
                h = hnew
            stats[ST_REJECTED] += 1
            n_rej += 1
            bad_kind = 0
            # Hairer refreshes the Jacobian here (need_jac = not caljac).  An error-test rejection
            # says the step was too long, not that J is stale: the Newton iteration converged with
            # it.  Keeping J (the LU is redone for the new h) saves n rhs calls per rejection (14 %
            # of all calls on bench-libration); a stale J still shows as a slow Newton rate
            # (theta > THET), which refreshes it after the next step, or as a Newton failure.
            need_jac = False

    fs[_F_HOLD] = hold
    fs[_F_THETA] = theta
    fs[_F_FACCON] = faccon
    fs[_F_HACC] = hacc
    fs[_F_ERRACC] = erracc
    fs[_F_HLU] = h_lu
    is_[_I_FIRST] = 1 if first else 0
    is_[_I_NEED_JAC] = 1 if need_jac else 0
    is_[_I_LU_VALID] = 1 if lu_valid else 0
    is_[_I_NACCPT] = naccpt
    is_[_I_NSING] = nsing
    return status, t, h, n_done


@njit(cache=True)
def radau5_run(rhs, t, y, t_out, p, rtol, atol, h, h_max, max_steps, y_out, stats, fixed_step):
    """Kernel ABI entry: RADAU5 from a fresh start (new Jacobian, zero Newton predictor).

    A caller continuing from (t_end, y, h_next) gets a valid but not bit-identical continuation,
    because the Jacobian, LU factors and Newton predictor are rebuilt; use :func:`radau5_core`
    with a workspace (as the driver does) for exact continuation.
    """
    n = y.shape[0]
    fjac = np.zeros((n, n))
    e1 = np.zeros((n, n))
    e2 = np.zeros((n, n), dtype=np.complex128)
    ip1 = np.zeros(n, dtype=np.int64)
    ip2 = np.zeros(n, dtype=np.int64)
    cont = np.zeros((4, n))
    f0 = np.zeros(n)
    fs = np.zeros(12)
    fs[_F_THSTEP] = THETA_STEP
    fs[_F_NIT] = NIT
    fs[_F_FLOOR] = FLOOR_GAIN
    is_ = np.zeros(10, dtype=np.int64)
    ev = np.array([0.0, -1.0, -1.0, 0.0])
    blk = np.zeros((1, _nw.BLK_SIZE))
    sf1 = np.zeros((1, _nw.FAC_SIZE))
    sf2 = np.zeros((1, _nw.FAC_SIZE), dtype=np.complex128)
    border = (np.zeros((n, 1)), np.zeros((1, n)), np.zeros((1, n), dtype=np.complex128), np.zeros((1, 1)),
              np.zeros((1, 1), dtype=np.complex128), np.zeros(1, dtype=np.int64), np.zeros(1, dtype=np.int64),
              np.zeros((_B_ROWS, n)))  # fmt: skip
    return radau5_core(
        rhs, t, y, t_out, p, rtol, atol, h, h_max, max_steps, y_out, stats, fixed_step,
        fjac, e1, e2, ip1, ip2, cont, f0, fs, is_, blk, sf1, sf2, border, False, rhs, 0, ev,
    )  # fmt: skip
