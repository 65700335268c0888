"""The rod chain: a tether of n TMED rods as one part of the reaction solve (compiled).

Generalised coordinates (paper eq. 23): the half-separation vector d_i of every rod; the joints
follow from the attachment point A_1 on the parent body,

    r_G,i = r_A,i + sqrt3 d_i,   r_B,i = r_A,i + 2 sqrt3 d_i = r_A,i+1,   r_f = r_B,n.

Equations of a rod (docs/model.md 2-4, from paper eqs. 9-10, 16-19; tether/rod.py):

    m_i a_G,i  = R_i + T_A,i + T_B,i                                    (eq. 25)
    m_i d''_i  = Q_i + C_i (T_B,i - T_A,i)                              (eq. 26, corrected)

Reactions.  With J_k the force the element on the root side of joint k exerts on the element on
the tip side (T_A,i = J_{i-1}, T_B,i = -J_i), the acceleration-level joint constraints (the
system L_2m of section 2.3, eqs. 27-34) are block tridiagonal with 3x3 blocks alpha I + beta u u^T:

    row 0:   P_1 J_0 + M_1 J_1                                   = a_A - alpha_A,1
    row k:   M_k J_{k-1} + (P_k + P_{k+1}) J_k + M_{k+1} J_{k+1}  = alpha_B,k - alpha_A,k+1
    row n:   M_n J_{n-1} + (P_n + C_tip) J_n                     = alpha_B,n - f_tip

    P_i = (I + sqrt3 C_i)/m_i,  M_i = (sqrt3 C_i - I)/m_i,  alpha_A/B,i = (R_i -/+ sqrt3 Q_i)/m_i,

with a_B = C_tip J_n + f_tip the compliance of the body at its end (bodies/parts.py) and no row n
at a free end (J_n = 0).  The part interface of the chain:

* :func:`chain_walk`: the walk from A_1 to B_n, every rod's forces on the way (tether/rod.py);
* :func:`chain_reduce`: block Thomas from the tip to the root (O(n)), leaving J_0 = W (s_0 + a_A):
  W = S_0^-1 and s_0 in joint 0's scratch are the chain's compliance contribution to its parent;
* :func:`chain_back_substitute`: given a_A, every J_k and every rod's d'' (eq. 26);
* :func:`chain_share`: the rods' energy and momentum shares (tether/rod.py, rod_share).

The forest driver that calls them in elimination order is tether/solve.py.
"""

from __future__ import annotations

import math

from .._jit import njit, njit_hot
from ..kernel.layout import (
    BS_C,
    BS_CF,
    BS_SIZE,
    FAIL_NONFINITE,
    FAIL_SINGULAR,
    H_NRODS,
    H_OFF_BSCR,
    H_OFF_ROD,
    H_OFF_SCR,
    H_OFF_TETH,
    MODEL_ENERGY,
    MODEL_PRINTED,
    RT_M,
    RT_SIZE,
    SJ_J,
    SJ_S,
    SJ_SINV,
    SJ_SIZE,
    SR_C,
    SR_M,
    SR_Q,
    SR_R1,
    SR_R2,
    SR_SIZE,
    SR_U,
    TT_CHILD,
    TT_MODEL,
    TT_NRODS,
    TT_REEL,
    TT_ROD0,
    TT_SIZE,
    TT_TENSION_ONLY,
)
from ..kernel.vec3 import add9, inv3_9, iuu9, iuu_vec, load9, mat9_vec, mat_vec, store9, sub_iuu_sandwich9
from .reel import reel_rod_load
from .rod import SQ3, fail, next_joint, rod_constants, rod_force, rod_share

__all__ = ["SQ3", "next_joint", "chain_walk", "chain_reduce", "chain_back_substitute", "chain_share",
           "walk", "reduce", "back_substitute", "share"]


@njit_hot(cache=True)
def chain_walk(t, q, qd, p, k, with_forces, ax, ay, az, avx, avy, avz):
    """Walk tether k from its attachment point A_1 (position, velocity given) to its end B_n
    (eq. 23), computing (with_forces) every rod's forces on the way.  Returns (failure code,
    r_B, v_B)."""
    tb = int(p[H_OFF_TETH]) + k * TT_SIZE
    n = int(p[tb + TT_NRODS])
    g0 = int(p[tb + TT_ROD0])
    tension_only = p[tb + TT_TENSION_ONLY] != 0.0
    energy = int(p[tb + TT_MODEL]) == MODEL_ENERGY
    printed = int(p[tb + TT_MODEL]) == MODEL_PRINTED
    reel = int(p[tb + TT_REEL]) - 1  # the first rod of a tether paid out by a reel varies in length
    rc = rod_constants(p)
    for g in range(g0, g0 + n):
        if with_forces:
            code = rod_force(t, q, qd, p, g, rc, tension_only, energy, printed, ax, ay, az, avx, avy, avz)
            if code != 0:
                return code, ax, ay, az, avx, avy, avz
            if reel >= 0 and g == g0:
                reel_rod_load(q, qd, p, reel, g, tension_only, energy)
        ax, ay, az, avx, avy, avz = next_joint(q, qd, g, ax, ay, az, avx, avy, avz)
    return 0, ax, ay, az, avx, avy, avz


@njit(cache=True, inline="always")
def _rod_coefficients(p, g):
    """What rod g brings to the rows of its two joints: P = pa I + be u u^T, M = al I + be u u^T,
    alpha_A and alpha_B (docs/model.md 4.3), computed once per rod per evaluation."""
    sb = int(p[H_OFF_SCR]) + g * SR_SIZE
    m = p[int(p[H_OFF_ROD]) + g * RT_SIZE + RT_M]
    c1 = p[sb + SR_C]
    c2 = p[sb + SR_C + 1]
    ux = p[sb + SR_U]
    uy = p[sb + SR_U + 1]
    uz = p[sb + SR_U + 2]
    rx = p[sb + SR_R1] + p[sb + SR_R2]
    ry = p[sb + SR_R1 + 1] + p[sb + SR_R2 + 1]
    rz = p[sb + SR_R1 + 2] + p[sb + SR_R2 + 2]
    qx = p[sb + SR_Q]
    qy = p[sb + SR_Q + 1]
    qz = p[sb + SR_Q + 2]
    pa = (1.0 + SQ3 * c1) / m
    be = SQ3 * c2 / m
    al = (SQ3 * c1 - 1.0) / m
    return (
        pa, be, al, ux, uy, uz,
        (rx - SQ3 * qx) / m, (ry - SQ3 * qy) / m, (rz - SQ3 * qz) / m,  # alpha_A
        (rx + SQ3 * qx) / m, (ry + SQ3 * qy) / m, (rz + SQ3 * qz) / m,  # alpha_B
    )


@njit_hot(cache=True)
def chain_reduce(t, p, k):
    """Block Thomas elimination of tether k from its tip to its root (docs/model.md 4.3, 12.4):
    joint j's scratch gets S_j^-1 and s_j; joint 0's are W and s_0 of J_0 = W (s_0 + a_A).  The
    tip body's compliance (BS_C, BS_CF) must be in its scratch.  Each rod's M = al I + be u u^T
    is kept in its scratch (SR_M) for the back substitution.  Returns a failure code."""
    tb = int(p[H_OFF_TETH]) + k * TT_SIZE
    n = int(p[tb + TT_NRODS])
    g0 = int(p[tb + TT_ROD0])
    c = int(p[tb + TT_CHILD])
    scr = int(p[H_OFF_SCR])
    j0 = scr + int(p[H_NRODS]) * SR_SIZE + (g0 + k) * SJ_SIZE  # n + 1 joint blocks
    has_tip = c >= 0
    last = n if has_tip else n - 1
    cbs = int(p[H_OFF_BSCR]) + c * BS_SIZE if has_tip else 0
    # the rod on the tip side of the current row (rod row+1), carried from the row before
    npa = nbe = nal = nux = nuy = nuz = nax = nay = naz = 0.0
    if not has_tip:
        npa, nbe, nal, nux, nuy, nuz, nax, nay, naz, _, _, _ = _rod_coefficients(p, g0 + n - 1)
        _keep_m(p, scr, g0 + n - 1, nal, nbe)
    # the joint eliminated before this row (row + 1): S^-1 and s, carried in registers
    zero = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    nsi = zero
    nsx = nsy = nsz = 0.0
    for row in range(last, -1, -1):
        jb = j0 + row * SJ_SIZE
        S = zero  # the diagonal block, assembled in registers and inverted at the end of the row
        bx = 0.0
        by = 0.0
        bz = 0.0
        if row >= 1:  # rod `row`: P and alpha_B
            pa, be, al, ux, uy, uz, aax, aay, aaz, abx, aby, abz = _rod_coefficients(p, g0 + row - 1)
            _keep_m(p, scr, g0 + row - 1, al, be)
            S = add9(S, iuu9(pa, be, ux, uy, uz))
            bx += abx
            by += aby
            bz += abz
        if row < n:  # rod row+1: P and -alpha_A
            S = add9(S, iuu9(npa, nbe, nux, nuy, nuz))
            bx -= nax
            by -= nay
            bz -= naz
        else:  # row == n: the tip body, a_B = C J_n + f
            S = add9(S, load9(p, cbs + BS_C))
            bx -= p[cbs + BS_CF]
            by -= p[cbs + BS_CF + 1]
            bz -= p[cbs + BS_CF + 2]
        # eliminate J_{row+1}: S -= M_{row+1} S_{row+1}^-1 M_{row+1}, b -= M S^-1 s
        if row < last:
            S = sub_iuu_sandwich9(S, nsi, nal, nbe, nux, nuy, nuz)
            v0, v1, v2 = mat9_vec(nsi, nsx, nsy, nsz)
            mx, my, mz = iuu_vec(nal, nbe, nux, nuy, nuz, v0, v1, v2)
            bx -= mx
            by -= my
            bz -= mz
        p[jb + SJ_S] = bx
        p[jb + SJ_S + 1] = by
        p[jb + SJ_S + 2] = bz
        det, nsi = inv3_9(S)
        if det == 0.0 or not math.isfinite(det):
            store9(p, jb + SJ_SINV, S)
            return fail(p, FAIL_SINGULAR, g0 + (row if row < n else n - 1), t, det)
        store9(p, jb + SJ_SINV, nsi)
        nsx = bx
        nsy = by
        nsz = bz
        if row >= 1:
            npa = pa
            nbe = be
            nal = al
            nux = ux
            nuy = uy
            nuz = uz
            nax = aax
            nay = aay
            naz = aaz
    return 0


@njit(cache=True, inline="always")
def _keep_m(p, scr, g, al, be):
    """Rod g's M = al I + be u u^T into its scratch: the back substitution reads it there."""
    sb = scr + g * SR_SIZE
    p[sb + SR_M] = al
    p[sb + SR_M + 1] = be


@njit(cache=True, inline="always")
def _rod_acceleration(p, scr, offr, acc, g, ja):
    """d'' of rod g from eq. 26, m d'' = Q - C (J_{i-1} + J_i), J_{i-1} at p[ja], J_i after it
    (scr, offr: the rod scratch and rod table offsets)."""
    sb = scr + g * SR_SIZE
    m = p[offr + g * RT_SIZE + RT_M]
    jbb = ja + SJ_SIZE
    sx = p[ja] + p[jbb]
    sy = p[ja + 1] + p[jbb + 1]
    sz = p[ja + 2] + p[jbb + 2]
    cx, cy, cz = iuu_vec(p[sb + SR_C], p[sb + SR_C + 1], p[sb + SR_U], p[sb + SR_U + 1], p[sb + SR_U + 2], sx, sy, sz)
    ax_ = (p[sb + SR_Q] - cx) / m
    ay_ = (p[sb + SR_Q + 1] - cy) / m
    az_ = (p[sb + SR_Q + 2] - cz) / m
    if not (math.isfinite(ax_) and math.isfinite(ay_) and math.isfinite(az_)):
        return False
    acc[3 + 3 * g] = ax_
    acc[4 + 3 * g] = ay_
    acc[5 + 3 * g] = az_
    return True


@njit_hot(cache=True)
def chain_back_substitute(t, p, k, aax, aay, aaz, acc):
    """Given the acceleration a_A of tether k's attachment point: J_0 = W (s_0 + a_A), then
    J_k = S_k^-1 (s_k - M_k J_{k-1}) to the tip (J_n = 0 at a free end), and every rod's d'' into
    ``acc`` (eq. 26).  Returns a failure code."""
    tb = int(p[H_OFF_TETH]) + k * TT_SIZE
    n = int(p[tb + TT_NRODS])
    g0 = int(p[tb + TT_ROD0])
    has_tip = int(p[tb + TT_CHILD]) >= 0
    last = n if has_tip else n - 1
    offr = int(p[H_OFF_ROD])
    scr = int(p[H_OFF_SCR])
    j0 = scr + int(p[H_NRODS]) * SR_SIZE + (g0 + k) * SJ_SIZE
    s0 = j0 + SJ_S
    jx, jy, jz = mat_vec(p, j0 + SJ_SINV, p[s0] + aax, p[s0 + 1] + aay, p[s0 + 2] + aaz)
    p[j0 + SJ_J] = jx
    p[j0 + SJ_J + 1] = jy
    p[j0 + SJ_J + 2] = jz
    for row in range(1, last + 1):
        jb = j0 + row * SJ_SIZE
        g = g0 + row - 1  # rod `row` couples J_{row-1} and J_row
        sb = scr + g * SR_SIZE
        al = p[sb + SR_M]  # M of rod `row`, kept by chain_reduce
        be = p[sb + SR_M + 1]
        pj = jb - SJ_SIZE + SJ_J
        mx, my, mz = iuu_vec(al, be, p[sb + SR_U], p[sb + SR_U + 1], p[sb + SR_U + 2], p[pj], p[pj + 1], p[pj + 2])
        jx, jy, jz = mat_vec(p, jb + SJ_SINV, p[jb + SJ_S] - mx, p[jb + SJ_S + 1] - my, p[jb + SJ_S + 2] - mz)
        p[jb + SJ_J] = jx
        p[jb + SJ_J + 1] = jy
        p[jb + SJ_J + 2] = jz
        if not _rod_acceleration(p, scr, offr, acc, g, pj):
            return fail(p, FAIL_NONFINITE, g, t, 0.0)
    if not has_tip:  # free end: no reaction at B_n
        jn = j0 + n * SJ_SIZE + SJ_J
        p[jn] = 0.0
        p[jn + 1] = 0.0
        p[jn + 2] = 0.0
        if not _rod_acceleration(p, scr, offr, acc, g0 + n - 1, jn - SJ_SIZE):
            return fail(p, FAIL_NONFINITE, g0 + n - 1, t, 0.0)
    return 0


@njit(cache=True)
def chain_share(t, q, qd, p, k, elastic, ax, ay, az, avx, avy, avz, sh):
    """Add the energy and momentum shares of tether k's rods to ``sh`` (kernel/shares.py),
    walking from its attachment point A_1 (given)."""
    tb = int(p[H_OFF_TETH]) + k * TT_SIZE
    n = int(p[tb + TT_NRODS])
    g0 = int(p[tb + TT_ROD0])
    tension_only = p[tb + TT_TENSION_ONLY] != 0.0
    for g in range(g0, g0 + n):
        rod_share(t, q, qd, p, g, tension_only, elastic, ax, ay, az, avx, avy, avz, sh)
        ax, ay, az, avx, avy, avz = next_joint(q, qd, g, ax, ay, az, avx, avy, avz)


# -- the tether part interface (tether/registry.py; the dispatcher tether/parts.py calls these) ----
@njit(cache=True, inline="always")
def walk(t, q, qd, p, k, with_forces, ax, ay, az, avx, avy, avz):
    return chain_walk(t, q, qd, p, k, with_forces, ax, ay, az, avx, avy, avz)


@njit(cache=True, inline="always")
def reduce(t, p, k):
    return chain_reduce(t, p, k)


@njit(cache=True, inline="always")
def back_substitute(t, p, k, aax, aay, aaz, acc):
    return chain_back_substitute(t, p, k, aax, aay, aaz, acc)


@njit(cache=True, inline="always")
def share(t, q, qd, p, k, elastic, ax, ay, az, avx, avy, avz, sh):
    chain_share(t, q, qd, p, k, elastic, ax, ay, az, avx, avy, avz, sh)
