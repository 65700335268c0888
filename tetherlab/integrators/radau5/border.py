"""The border of a handed-in structured Newton matrix: the first-order unknowns w of the state
(rigid bodies' attitude and wheels) that the structured solver does not cover, completed by a
Schur complement on them (docs/integrators.md section 13).

With y = [q, v, w] the Newton system (g I - J) z = b is
    [ E_tt     -A_w   ] [z_v]   [b_v + A_q b_q/g]
    [ -B_qv   g - B_w ] [z_w] = [b_w + B_q b_q/g],   z_q = (b_q + z_v)/g,
B_qv x = B_q x_q + B_v x_v.  E_tt is the handed-in solve S_t of the (q, v) block (for a tether
model, tetherlab/tether/newton.py: bodies as point masses of their translational mass at their
joints).  Schur complement on the few w:
    z0 = S_t(b_q, b_v),  z^j = S_t(0, A_w e_j),  Sigma = g - B_w - [B_qv z^j]_j,
    z_w = Sigma^-1 (b_w + B_qv z0),  (z_q, z_v) = z0 + sum_j z_w,j z^j.
Everything here is finite differences of the rhs and dense algebra on the n_w unknowns: it knows
nothing of the model.
"""

from __future__ import annotations

import numpy as np

from tetherlab._jit import njit, ptr, row_ptr

from ..common import EPS, ST_NRHS, all_finite
from ..linear_solver import data_ptr
from .constants import _B_F, _B_OI, _B_OR, _B_XI, _B_XR, _B_Y, _B_YT, _B_FT, _SQRT_EPS
from .dense import lu_factor, lu_solve


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
def _border_factor(rhs, t, p, blk, m1, nb, g, sfac, solve, bcol, bz, bs, bp, bw, iu, stats):
    """The border's part of the factorisation for the shift g (real or complex; ``solve`` the
    handed-in structured solve of that type, linear_solver.py): the columns
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
        solve(g.real, g.imag, ptr(p), data_ptr(blk), data_ptr(sfac), m1, data_ptr(z))
        _border_apply(rhs, t, p, m1, nb, z, bw, iu, stats, col)
        for i in range(nb):
            bs[i, j] = -bcol[n2 + i, j] - col[i]
        bs[j, j] += g
    return lu_factor(bs, bp)


@njit(cache=True)
def _border_solve(rhs, t, p, m1, nb, b, bz, bs, bp, bw, iu, stats):
    """Complete the structured solve already done in b[:2 m1] (z0) with the border: z_w and
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

