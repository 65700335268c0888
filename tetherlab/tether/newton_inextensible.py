"""Structured Newton matrix of the inextensible chain for RADAU5: O(n) form, factorisation, solve.

docs/inextensible.md section 8 derives it.  In joint coordinates x_j (x_0 the root, x_j = x_{j-1}
+ 2 sqrt3 d_j) the inextensible chain is M x'' + G^T nu = F with M the uniform bars' constant
consistent mass matrix (m/3, m/6, the tip's m_f) and one multiplier nu_i per rod; RADAU5's
Newton system (g I - J) z = b becomes, with z_q = (b_q + w)/g,

    (g M + K/g) w + G^T mu = M b_v - K b_q / g
    (g G + E/g + F_v) w     = G b_v - E b_q / g                              (J3)

K the multipliers' geometric stiffness, E and F_v the linearised stabilised constraint.  Ordered
per rod as (w_i, mu_i) it is block tridiagonal with 4x4 blocks: block Thomas from the tip to the
root.  The loads' derivative is left out (zero for uniform gravity; not stiff otherwise), as the
elastic chain's matrix (tether/newton.py) leaves it out.

Understood: one inextensible tether from the centre of a root point mass, fixed or free (a free
root's joint x_0 is one more 3x3 block, padded to 4x4, at the end of the elimination), with a
point mass or nothing at its end, in Cowell's inertial formulation or in the frame turning with
the orbit (cowell-orbit: the mass blocks become M (g I + W)^2 / g, as tether/newton.py's;
docs/inextensible.md 8).  :func:`structure_supported` says why not otherwise.

Storage per rod (BLK_SIZE): u (3), nu/|D| (1), e = (D'' + 2aD' + a^2 D)/|D| (3), f = 2(D' + aD)/|D|
(3), m (1).  Factors per block (FAC_SIZE): S^-1 of its 4x4 block (16); the free root's block first.
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import njit
from ..bodies.registry import part_named
from ..kernel.layout import (
    BT_RIGID,
    BT_SIZE,
    FORM_COWELL,
    FORM_COWELL_ORBIT,
    H_FORM,
    H_LEN,
    H_NBODY,
    H_NREEL,
    H_NRIGID,
    H_NRODS,
    H_NROOT,
    H_NQT,
    H_NSTATE,
    H_NTETH,
    H_OFF_BODY,
    H_OFF_FORM,
    H_OFF_ROD,
    H_OFF_ROOTS,
    H_OFF_SCR,
    H_OFF_TETH,
    H_ROOT_INV_M,
    H_ROOT_M,
    H_SIZE,
    RT_CRATE,
    RT_M,
    RT_SIZE,
    SJ_J,
    SJ_SIZE,
    SR_FE,
    SR_SIZE,
    TT_CHILD,
    TT_NRODS,
    TT_PA,
    TT_PARENT,
    TT_PART,
    TT_ROD0,
    TT_SIZE,
    TT_TIP_M,
)
from .newton import FRAME_OP_W, _frame_shift
from .registry import PARTS
from .solve import accelerations

SQ3 = math.sqrt(3.0)
B_U, B_KG, B_E, B_F, B_M = 0, 3, 4, 7, 10
BLK_SIZE = 11
FAC_SIZE = 16
INEXTENSIBLE_PART = [pt.code for pt in PARTS if pt.name == "inextensible"][0]
_POINT = part_named("point").code


def has_inextensible(p):
    """True when any tether of the parameter block is an inextensible chain."""
    if p.size < H_SIZE or int(p[H_LEN]) != p.size:
        return False
    offt = int(p[H_OFF_TETH])
    return any(int(p[offt + k * TT_SIZE + TT_PART]) == INEXTENSIBLE_PART for k in range(int(p[H_NTETH])))


def structure_supported(p, n_state, second_order):
    """'' if this module's Newton matrix applies to the model and state, else the reason."""
    if second_order is True:
        second_order = n_state // 2
    if not second_order:
        return "the state is not declared second order (y = [q, q'])"
    if int(p[H_FORM]) not in (FORM_COWELL, FORM_COWELL_ORBIT):
        return f"formulation code {int(p[H_FORM])} is not Cowell's (inertial or turning with the orbit)"
    if int(p[H_NTETH]) != 1 or int(p[H_NROOT]) != 1 or int(p[H_NRIGID]) != 0 or int(p[H_NREEL]) != 0:
        return "not one inextensible tether between point masses (several tethers, roots, rigid bodies or reels)"
    nrods = int(p[H_NRODS])
    m1 = 3 * int(p[H_NROOT]) + 3 * nrods  # the root's position, then each rod's d (one root: checked above)
    if int(p[H_NSTATE]) != n_state or int(second_order) != m1 or int(p[H_NQT]) != m1 or n_state != 2 * m1:
        return f"state of {n_state} components is not [r0, d_1..d_{nrods}, rates]"
    offb = int(p[H_OFF_BODY])
    for b in range(int(p[H_NBODY])):
        if int(p[offb + b * BT_SIZE + BT_RIGID]) != _POINT:
            return f"body {b} is not a point mass"
    if int(p[int(p[H_OFF_ROOTS])]) != 0:
        return "the root is not body 0"
    tb = int(p[H_OFF_TETH])
    if int(p[tb + TT_PART]) != INEXTENSIBLE_PART:
        return "the tether is not inextensible"
    if int(p[tb + TT_PARENT]) != 0 or any(p[tb + TT_PA + c] != 0.0 for c in range(3)):
        return "the tether does not hang from the root's centre"
    return ""


def workspace(p):
    """Work arrays: rod data, real and complex factors (a row per rod and one for a free root)."""
    n = int(p[H_NRODS])
    return (np.zeros((n, BLK_SIZE)), np.zeros((n + 1, FAC_SIZE)), np.zeros((n + 1, FAC_SIZE), dtype=np.complex128))


@njit(cache=True)
def form_blocks(t, y, p, m1, blk):
    """The rod data of (J3) at the state y: one rhs evaluation gives every multiplier lambda (the
    axial-force slot), the reactions J and d''; nu = (lambda + (1 - sqrt3) u.S / 2) / sqrt3
    (docs/inextensible.md (J0)).  In the frame turning with the orbit (cowell-orbit) y holds the
    frame's components and frame-relative rates: the rhs is evaluated on the same configuration
    read as inertial at this instant (rates v + omega x q), which leaves the multipliers (scalars)
    as they are, and the frame's d'' is that acceleration less the Coriolis and centrifugal terms
    (docs/inextensible.md 8).  Returns 0, or 1 if the rhs fails there."""
    acc = np.empty(m1)
    if int(p[H_FORM]) == FORM_COWELL_ORBIT:
        o = int(p[H_OFF_FORM]) + FRAME_OP_W
        wx = p[o]
        wy = p[o + 1]
        wz = p[o + 2]
        vin = np.empty(m1)
        for k in range(0, m1, 3):
            vin[k] = y[m1 + k] + wy * y[k + 2] - wz * y[k + 1]
            vin[k + 1] = y[m1 + k + 1] + wz * y[k] - wx * y[k + 2]
            vin[k + 2] = y[m1 + k + 2] + wx * y[k + 1] - wy * y[k]
        if accelerations(t, y[:m1], vin, p, acc) != 0:
            return 1
        for k in range(0, m1, 3):
            # a_frame = a - 2 w x v - w x (w x q), v the frame-relative rate
            vx = y[m1 + k]
            vy = y[m1 + k + 1]
            vz = y[m1 + k + 2]
            cx = wy * y[k + 2] - wz * y[k + 1]  # w x q
            cy = wz * y[k] - wx * y[k + 2]
            cz = wx * y[k + 1] - wy * y[k]
            acc[k] -= 2.0 * (wy * vz - wz * vy) + (wy * cz - wz * cy)
            acc[k + 1] -= 2.0 * (wz * vx - wx * vz) + (wz * cx - wx * cz)
            acc[k + 2] -= 2.0 * (wx * vy - wy * vx) + (wx * cy - wy * cx)
    elif accelerations(t, y[:m1], y[m1 : 2 * m1], p, acc) != 0:
        return 1
    tb = int(p[H_OFF_TETH])
    n = int(p[tb + TT_NRODS])
    g0 = int(p[tb + TT_ROD0])
    scr = int(p[H_OFF_SCR])
    ja = scr + int(p[H_NRODS]) * SR_SIZE + g0 * SJ_SIZE + SJ_J  # J_0 (tether 0)
    k2 = 2.0 * SQ3
    for i in range(n):
        g = g0 + i
        rb = int(p[H_OFF_ROD]) + g * RT_SIZE
        a = p[rb + RT_CRATE]
        o = 3 + 3 * g
        dx = k2 * y[o]
        dy = k2 * y[o + 1]
        dz = k2 * y[o + 2]
        ln = math.sqrt(dx * dx + dy * dy + dz * dz)
        if not ln > 0.0:
            return 1
        ux = dx / ln
        uy = dy / ln
        uz = dz / ln
        jb = ja + SJ_SIZE
        us = (p[ja] + p[jb]) * ux + (p[ja + 1] + p[jb + 1]) * uy + (p[ja + 2] + p[jb + 2]) * uz
        lam = p[scr + g * SR_SIZE + SR_FE]
        nu = (lam + 0.5 * (1.0 - SQ3) * us) / SQ3
        b = blk[i]
        b[B_U] = ux
        b[B_U + 1] = uy
        b[B_U + 2] = uz
        b[B_KG] = nu / ln
        for c in range(3):
            dd = k2 * y[m1 + o + c]
            ddd = k2 * acc[o + c]
            dc = k2 * y[o + c]
            b[B_E + c] = (ddd + 2.0 * a * dd + a * a * dc) / ln
            b[B_F + c] = 2.0 * (dd + a * dc) / ln
        b[B_M] = p[rb + RT_M]
        ja = jb
    return 0


@njit(cache=True)
def _inv4(s, out):
    """out = s^-1 for a flat 4x4 (real or complex), Gauss-Jordan with partial pivoting; returns
    False when singular."""
    a = np.empty((4, 8), dtype=s.dtype)
    for r in range(4):
        for c in range(4):
            a[r, c] = s[4 * r + c]
            a[r, 4 + c] = 1.0 if r == c else 0.0
    for c in range(4):
        piv = c
        for r in range(c + 1, 4):
            if abs(a[r, c]) > abs(a[piv, c]):
                piv = r
        if not abs(a[piv, c]) > 0.0 or not np.isfinite(abs(a[piv, c])):
            return False
        if piv != c:
            for k in range(8):
                tmp = a[c, k]
                a[c, k] = a[piv, k]
                a[piv, k] = tmp
        inv = 1.0 / a[c, c]
        for k in range(8):
            a[c, k] *= inv
        for r in range(4):
            if r != c:
                f = a[r, c]
                if f != 0.0:
                    for k in range(8):
                        a[r, k] -= f * a[c, k]
    for r in range(4):
        for c in range(4):
            out[4 * r + c] = a[r, 4 + c]
    return True


@njit(cache=True)
def _diag(blk, i, n, mf, sg, g, out):
    """The 4x4 diagonal block of rod i (joint x_{i+1}'s rows and rod i's constraint row).  The mass
    terms are M S, S the shift of :func:`.newton._frame_shift` (g I; (g I + W)^2 / g in the frame
    turning with the orbit, its Coriolis and centrifugal terms)."""
    ginv = 1.0 / g
    b = blk[i]
    mass = b[B_M] / 3.0 + (blk[i + 1][B_M] / 3.0 if i < n - 1 else mf)
    for r in range(16):
        out[r] = 0.0 * g
    for r in range(3):
        for c in range(3):
            uu = b[B_U + r] * b[B_U + c]
            de = 1.0 if r == c else 0.0
            v = mass * sg[3 * r + c] + b[B_KG] * (de - uu) * ginv
            if i < n - 1:
                bn = blk[i + 1]
                v += bn[B_KG] * (de - bn[B_U + r] * bn[B_U + c]) * ginv
            out[4 * r + c] = v
        out[4 * r + 3] = b[B_U + r]
        out[12 + r] = g * b[B_U + r] + b[B_E + r] * ginv + b[B_F + r]


@njit(cache=True)
def _diag_root(blk, m0, sg, g, out):
    """The 4x4 block of a free root's joint x_0: (m0 + m_1/3) S + K_1/g, and a unit row and column
    for a fourth unknown that is identically zero (the root carries no multiplier; padding it
    keeps every block of the elimination 4x4)."""
    ginv = 1.0 / g
    b = blk[0]
    mass = m0 + b[B_M] / 3.0
    for r in range(16):
        out[r] = 0.0 * g
    for r in range(3):
        for c in range(3):
            de = 1.0 if r == c else 0.0
            out[4 * r + c] = mass * sg[3 * r + c] + b[B_KG] * (de - b[B_U + r] * b[B_U + c]) * ginv
    out[15] = 1.0 + 0.0 * g


@njit(cache=True)
def _block_diag(blk, j, nr, n, mf, m0, sg, g, out):
    """Diagonal block j of the elimination: the free root's (j < nr), else rod j - nr's."""
    if j < nr:
        _diag_root(blk, m0, sg, g, out)
    else:
        _diag(blk, j - nr, n, mf, sg, g, out)


@njit(cache=True)
def _couple(blk, i, sg, g, out):
    """The 4x4 block coupling joint x_{i+1}'s rows (rod i's block; i = -1: the free root's joint
    x_0) with rod i+1's unknowns (upper, C_i) -- and, by the symmetry of M (scalar per joint pair)
    and K, the 3x3 joint part of rod i+1's rows on the unknowns of block i (lower B_{i+1}), whose
    constraint row is the diagonal's with the sign changed."""
    ginv = 1.0 / g
    bn = blk[i + 1]
    for r in range(16):
        out[r] = 0.0 * g
    for r in range(3):
        for c in range(3):
            uu = bn[B_U + r] * bn[B_U + c]
            de = 1.0 if r == c else 0.0
            out[4 * r + c] = bn[B_M] / 6.0 * sg[3 * r + c] - bn[B_KG] * (de - uu) * ginv
        out[4 * r + 3] = -bn[B_U + r]


@njit(cache=True)
def _layout(p):
    """(rods, tip mass, root mass, blocks before the rods' (1 for a free root, else 0))."""
    tb = int(p[H_OFF_TETH])
    n = int(p[tb + TT_NRODS])
    mf = p[tb + TT_TIP_M] if int(p[tb + TT_CHILD]) >= 0 else 0.0
    free = p[H_ROOT_INV_M] > 0.0
    return n, mf, (p[H_ROOT_M] if free else 0.0), (1 if free else 0)


@njit(cache=True)
def factor(p, blk, g, fac):
    """Blocks j = 0 .. nb-1 (the free root's first, then the rods'), from the tip:
    S_{nb-1} = A_{nb-1}, S_j = A_j - C_j S_{j+1}^-1 B_{j+1}; S_j^-1 into fac[j].  B_{j+1}: joint
    rows [m/6 S - K/g, 0], constraint row [-c^T, 0].  Returns 0, or 1 for a singular block."""
    n, mf, m0, nr = _layout(p)
    sg = np.empty(9, dtype=fac.dtype)
    _frame_shift(p, g, sg)
    s = np.empty(16, dtype=fac.dtype)
    cu = np.empty(16, dtype=fac.dtype)
    bl = np.empty(16, dtype=fac.dtype)
    dn = np.empty(16, dtype=fac.dtype)
    tmp = np.empty(16, dtype=fac.dtype)
    nb = n + nr
    for j in range(nb - 1, -1, -1):
        _block_diag(blk, j, nr, n, mf, m0, sg, g, s)
        if j < nb - 1:
            _couple(blk, j - nr, sg, g, cu)
            _block_diag(blk, j + 1, nr, n, mf, m0, sg, g, dn)
            for r in range(16):
                bl[r] = 0.0 * g
            for r in range(3):
                for c in range(3):
                    bl[4 * r + c] = cu[4 * r + c]  # the 3x3 joint part is the same
                bl[12 + r] = -dn[12 + r]
            f = fac[j + 1]
            for r in range(4):
                for c in range(4):
                    v = 0.0 * g
                    for e in range(4):
                        v += f[4 * r + e] * bl[4 * e + c]
                    tmp[4 * r + c] = v
            for r in range(4):
                for c in range(4):
                    v = 0.0 * g
                    for e in range(4):
                        v += cu[4 * r + e] * tmp[4 * e + c]
                    s[4 * r + c] -= v
        if not _inv4(s, fac[j]):
            return 1
    return 0


@njit(cache=True)
def solve(p, blk, g, fac, m1, b):
    """b[:2 m1] <- (g I - J)^-1 b through (J3) (module docstring), in place."""
    n, mf, m0, nr = _layout(p)
    sg = np.empty(9, dtype=b.dtype)
    frame = _frame_shift(p, g, sg)
    ginv = 1.0 / g
    k2 = 2.0 * SQ3
    nb = n + nr
    # joints 0..n: x_0 the root (a fixed root's perturbation moves nothing: 0), x_j = x_{j-1} + 2 sqrt3 d_j
    xv = np.zeros(3 * (n + 1), dtype=b.dtype)
    xq = np.zeros(3 * (n + 1), dtype=b.dtype)
    if nr:
        for c in range(3):
            xv[c] = b[m1 + c]
            xq[c] = b[c]
    for i in range(n):
        for c in range(3):
            xv[3 * i + 3 + c] = xv[3 * i + c] + k2 * b[m1 + 3 + 3 * i + c]
            xq[3 * i + 3 + c] = xq[3 * i + c] + k2 * b[3 + 3 * i + c]
    # xm = xv, or xv - W^2 xq / g in the frame turning with omega (the centrifugal term's share)
    xm = xv.copy()
    if frame:
        o = int(p[H_OFF_FORM]) + FRAME_OP_W
        wx = p[o]
        wy = p[o + 1]
        wz = p[o + 2]
        w2 = wx * wx + wy * wy + wz * wz
        for j in range(n + 1):
            wq = wx * xq[3 * j] + wy * xq[3 * j + 1] + wz * xq[3 * j + 2]
            # W^2 q = w (w . q) - |w|^2 q
            xm[3 * j] -= (wx * wq - w2 * xq[3 * j]) * ginv
            xm[3 * j + 1] -= (wy * wq - w2 * xq[3 * j + 1]) * ginv
            xm[3 * j + 2] -= (wz * wq - w2 * xq[3 * j + 2]) * ginv
    r = np.zeros(4 * nb, dtype=b.dtype)
    if nr:
        for c in range(3):
            r[c] += m0 * xm[c]
    for i in range(n):  # rod i between joints i and i+1 (joint j's unknowns are block j - 1 + nr)
        bl = blk[i]
        m = bl[B_M]
        ia = 3 * i
        ib = 3 * i + 3
        jb = 4 * (i + nr)
        ja = 4 * (i - 1 + nr)
        dvq = (xq[ib] - xq[ia], xq[ib + 1] - xq[ia + 1], xq[ib + 2] - xq[ia + 2])
        udq = bl[B_U] * dvq[0] + bl[B_U + 1] * dvq[1] + bl[B_U + 2] * dvq[2]
        for c in range(3):
            kq = bl[B_KG] * (dvq[c] - udq * bl[B_U + c])  # K_i (x_B - x_A)
            r[jb + c] += m / 3.0 * xm[ib + c] + m / 6.0 * xm[ia + c] - kq * ginv
            if ja >= 0:  # joint A is an unknown (a rod's joint, or the free root's)
                r[ja + c] += m / 3.0 * xm[ia + c] + m / 6.0 * xm[ib + c] + kq * ginv
        if i == n - 1 and mf > 0.0:
            for c in range(3):
                r[jb + c] += mf * xm[ib + c]
        gv = 0.0 * g
        eq = 0.0 * g
        for c in range(3):
            gv += bl[B_U + c] * (xv[ib + c] - xv[ia + c])
            eq += bl[B_E + c] * (xq[ib + c] - xq[ia + c])
        r[jb + 3] = gv - eq * ginv
    # forward: y_j = r_j - C_j S_{j+1}^-1 y_{j+1}, tip first
    cu = np.empty(16, dtype=b.dtype)
    v = np.empty(4, dtype=b.dtype)
    for j in range(nb - 2, -1, -1):
        f = fac[j + 1]
        for a in range(4):
            acc = 0.0 * g
            for e in range(4):
                acc += f[4 * a + e] * r[4 * (j + 1) + e]
            v[a] = acc
        _couple(blk, j - nr, sg, g, cu)
        for a in range(4):
            acc = 0.0 * g
            for e in range(4):
                acc += cu[4 * a + e] * v[e]
            r[4 * j + a] -= acc
    # back: w_0 = S_0^-1 y_0, w_j = S_j^-1 (y_j - B_j w_{j-1})
    w = np.zeros(4 * nb, dtype=b.dtype)
    dn = np.empty(16, dtype=b.dtype)
    e4 = np.empty(4, dtype=b.dtype)
    for j in range(nb):
        for a in range(4):
            e4[a] = r[4 * j + a]
        if j > 0:
            _couple(blk, j - 1 - nr, sg, g, cu)  # its 3x3 part is B_j's joint part
            _block_diag(blk, j, nr, n, mf, m0, sg, g, dn)
            for a in range(3):
                acc = 0.0 * g
                for c in range(3):
                    acc += cu[4 * a + c] * w[4 * (j - 1) + c]
                e4[a] -= acc
            acc = 0.0 * g
            for c in range(3):
                acc += -dn[12 + c] * w[4 * (j - 1) + c]
            e4[3] -= acc
        f = fac[j]
        for a in range(4):
            acc = 0.0 * g
            for e in range(4):
                acc += f[4 * a + e] * e4[e]
            w[4 * j + a] = acc
    # back to q: z_v(root) = w_0 (free) or b_v / g (fixed); z_v(d_i) = (w of joint i+1 - of joint i) / (2 sqrt3)
    for c in range(3):
        b[m1 + c] = w[c] if nr else b[m1 + c] * ginv
    for i in range(n):
        for c in range(3):
            wa = w[4 * (i - 1 + nr) + c] if i - 1 + nr >= 0 else 0.0 * g
            b[m1 + 3 + 3 * i + c] = (w[4 * (i + nr) + c] - wa) / k2
    for i in range(m1):
        b[i] = (b[i] + b[m1 + i]) * ginv
