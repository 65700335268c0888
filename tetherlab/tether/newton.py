"""Structured Newton matrix of a Cowell tether state: O(n) factorisation and solve (compiled).

RADAU5's Newton systems with the second-order structure (M1) are (g I - A_v - A_q/g) z = b, with
A_q = da/dq and A_v = da/dq' the Jacobians of the accelerations of the generalised coordinates
q = (r0, d_1 ... d_N) (eq. 23).  In q every joint depends on all earlier d_j, so these Jacobians
are dense.  In joint coordinates x = (r0, r_B,1, ..., r_B,N) (x = T q, T block lower triangular of
"sums", T^-1 block bidiagonal of differences) the equations of motion are M_x(u) x'' = F(x, x') with
M_x block tridiagonal (each rod couples its two joints) and the elastic/damping forces of a rod
acting on its two joints only.  The Newton matrix used here is

    E = T^-1 M_x^-1 N T,   N = g M_x - C_x - K_x / g,

with K_x = dF_el/dx, C_x = dF_el/dx' the analytic Jacobians of the axial elastic and damping force
(3x3 per rod) and M_x frozen at the state where the matrix is formed: the distributed external
forces and the derivative of M_x(u) are left out (they are not stiff).  docs/integrators.md,
section 6, derives M_x and the blocks; solving E z = r costs two O(n) transforms and one block
tridiagonal solve of N (block Thomas from each tip to its root, the tethers' Schur complements
accumulated at the root body, as the reaction solve of chain.py does).

Only the state layout of Cowell's formulation (y = [q, q'], q = (r0, d_1..d_N, r_1, ...), one
position block per root body at its BT_QOFF, the first root's first) is understood:
:func:`structure_supported` says why not otherwise, and the caller then keeps the dense path.  A
forest (several roots) is block diagonal over its trees: the elimination ends at each root.

Storage (float64, per rod g, BLK_SIZE): MAA (9), MAB (9), KEL (9), KV (9).
Factors (dtype of g, real or complex; per rod g the joint B_g, FAC_SIZE): S^-1 (9), Q (9); row
``nrods + i`` holds root i's S^-1 (i in the order of the root list p[H_OFF_ROOTS]).
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import njit
from ..bodies.registry import part_named
from ..kernel.vec3 import inv3  # real or complex blocks: the complex shift of RADAU5's second system
from ..kernel.layout import (
    FORM_COWELL,
    FORM_COWELL_ORBIT,
    H_FORM,
    H_LEN,
    H_NREEL,
    H_NRODS,
    H_NQT,
    H_NSTATE,
    H_OFF_BODY,
    H_NBODY,
    H_NRIGID,
    H_NROOT,
    H_NTETH,
    H_OFF_FORM,
    H_OFF_ORDER,
    H_OFF_ROD,
    H_OFF_ROOTS,
    H_OFF_RSCR,
    H_OFF_TETH,
    H_ROOT_INV_M,
    H_ROOT_M,
    H_SIZE,
    MODEL_ENERGY,
    MODEL_PRINTED,
    RT_D,
    RT_EA,
    RT_LU,
    RT_M,
    RT_SIZE,
    RS_LAM,
    RS_SIZE,
    BT_INV_M,
    BT_M,
    BT_NCHILD,
    BT_QOFF,
    BT_RIGID,
    BT_SIZE,
    TT_MODEL,
    TT_PART,
    TT_PARENT,
    TT_CHILD,
    TT_PA,
    TT_NRODS,
    TT_REEL,
    TT_ROD0,
    TT_SIZE,
    TT_TENSION_ONLY,
    TT_TIP_M,
)
from .reel import reel_update
from .rod import strain

SQ3 = math.sqrt(3.0)
# the body part types whose bodies the structured matrix models (as point masses at their joints,
# a rigid body's attitude and wheels bordered on); any other part runs with the dense matrix
_STRUCTURED_PARTS = (part_named("point").code, part_named("rigid").code)
B_MAA, B_MAB, B_KEL, B_KV = 0, 9, 18, 27
BLK_SIZE = 36
F_SINV, F_Q = 0, 9
FAC_SIZE = 18


def structure_supported(p, n_state, second_order):
    """'' if the structured Newton matrix applies to this model and state, else the reason.

    ``second_order``: the integer M1 of y = [q, q', w] (True: M1 = n/2, no w), w the first-order
    block of attitude and wheel states of rigid bodies (docs/model.md section 12).
    Forests (several roots) are supported: the matrix is block diagonal over the trees.
    With rigid bodies (Cowell's inertial formulation) the structured matrix is the
    bordered one of docs/integrators.md section 13: the tether blocks of :func:`solve` with every
    body as a point mass of its translational mass at its joint, bordered by finite-difference
    columns of the w unknowns (tetherlab/integrators/radau5/border.py).
    """
    if second_order is True:
        second_order = n_state // 2
    if not second_order:
        return "the state is not declared second order (y = [q, q'])"
    if p.size < H_SIZE or int(p[H_LEN]) != p.size:
        return "p is not a tether model's parameter block"
    if int(p[H_FORM]) not in (FORM_COWELL, FORM_COWELL_ORBIT):
        # (in the frame turning with the orbit the rod blocks are the same functions of d, d')
        return f"formulation code {int(p[H_FORM])} is not Cowell's"
    nrods = int(p[H_NRODS])
    nrigid = int(p[H_NRIGID])
    nroot = int(p[H_NROOT])
    # q = (r_root0, d_1..d_N, r_root1, ...): one position block per root (tetherlab/system.py),
    # then q', then (rigid bodies only) 7 attitude components per body and the wheels
    m1 = 3 * nroot + 3 * nrods
    nw = n_state - 2 * m1
    if (int(p[H_NSTATE]) != n_state or int(second_order) != m1 or int(p[H_NQT]) != m1
            or (nw != 0 if nrigid == 0 else nw < 7 * nrigid)):  # fmt: skip
        return (f"state of {n_state} components with M1 = {int(second_order)} is not the Cowell "
                f"layout [q, q', attitude, wheels] with M1 = 3*{nroot} + 3*{nrods} = {m1} and "
                f"{nrigid} rigid bodies (components the structured solver does not know)")
    if nrigid > 0 and int(p[H_FORM]) != FORM_COWELL:
        return "rigid bodies in the frame turning with the orbit (the bordered matrix is built for Cowell's inertial frame)"
    if nrods < 1:
        return "no rods"
    # Forests: each tether hangs from a root body or from the tip body of another tether, and the
    # elimination runs leaves first (the tether order of chain.py) into each tree's root; the
    # trees do not couple, so the matrix is block diagonal over them (docs/integrators.md
    # section 13).  Rigid bodies enter the tether blocks as point masses at their joints, their
    # attitude and wheel states as the border (section 13).
    offt = int(p[H_OFF_TETH])
    offb = int(p[H_OFF_BODY])
    nteth = int(p[H_NTETH])
    nbody = int(p[H_NBODY])
    offroots = int(p[H_OFF_ROOTS])
    roots = [int(p[offroots + i]) for i in range(nroot)]
    for b in range(nbody):
        kind = int(p[offb + b * BT_SIZE + BT_RIGID])  # the BT_PART slot
        if kind not in _STRUCTURED_PARTS:
            return f"body {b} is a part of kind {kind} (bodies/registry.py), which the structured matrix does not model"
    if nroot < 1 or roots[0] != 0:
        return f"root list {roots} does not start with body 0"
    for i, b in enumerate(roots):
        qo = int(p[offb + b * BT_SIZE + BT_QOFF])
        if b < 0 or b >= nbody or (1 <= b <= nteth) or qo < 0 or qo + 3 > m1 or (qo != 0) != (i != 0):
            return f"root {i} (body {b}) has no position block of its own in q (offset {qo})"
    for k in range(nteth):
        tb = offt + k * TT_SIZE
        if int(p[tb + TT_PART]) != 0:
            return f"tether {k} is a part of kind {int(p[tb + TT_PART])} (tether/registry.py), which the structured matrix does not model"
        parent = int(p[tb + TT_PARENT])
        if parent < 0 or parent >= nbody or (parent > nteth and parent not in roots):
            return f"tether {k} hangs from body {parent}, neither a root nor a tether's tip"
        if 0 < parent <= nteth and int(p[offt + (parent - 1) * TT_SIZE + TT_CHILD]) != parent:
            return f"tether {k} hangs from body {parent}, which is not a point mass at a tether's tip"
        rigid_parent = nrigid > 0 and p[offb + parent * BT_SIZE + BT_RIGID] != 0.0
        if not rigid_parent and any(p[tb + TT_PA + c] != 0.0 for c in range(3)):
            return f"tether {k} is attached off its parent's centre (a rigid body's attachment point)"
    return ""


def workspace(p):
    """Arrays for the structured path: rod blocks, real and complex factors (rows nrods + i: the
    S^-1 of root i)."""
    nrods = int(p[H_NRODS])
    nroot = int(p[H_NROOT])
    return (
        np.zeros((nrods, BLK_SIZE)),
        np.zeros((nrods + nroot, FAC_SIZE)),
        np.zeros((nrods + nroot, FAC_SIZE), dtype=np.complex128),
    )


@njit(cache=True)
def _root(p, i):
    """(kernel body index, offset of its position block in q) of root i (tetherlab/system.py)."""
    rb = int(p[int(p[H_OFF_ROOTS]) + i])
    return rb, int(p[int(p[H_OFF_BODY]) + rb * BT_SIZE + BT_QOFF])


@njit(cache=True)
def _root_mass(p, b):
    """Mass of root body b, 0 when it is fixed (body 0: the header's root mass, as before forests)."""
    if b == 0:
        return p[H_ROOT_M] if p[H_ROOT_INV_M] > 0.0 else 0.0
    bt = int(p[H_OFF_BODY]) + b * BT_SIZE
    return p[bt + BT_M] if p[bt + BT_INV_M] > 0.0 else 0.0


@njit(cache=True)
def _free_parent(p, parent):
    """False when body ``parent`` is a fixed root (its joint is not an unknown of the elimination)."""
    if parent == 0:
        return p[H_ROOT_INV_M] > 0.0
    if parent <= int(p[H_NTETH]):
        return True  # a tether's tip body (structure_supported: a point mass)
    return p[int(p[H_OFF_BODY]) + parent * BT_SIZE + BT_INV_M] > 0.0


@njit(cache=True)
def rod_blocks(y, p, m1, blk):
    """Mass and stiffness blocks of every rod at the state y = [q, q'] (the "Jacobian").

    Returns 0, or 1 if a rod has zero length (the caller falls back as for a failed Jacobian).
    """
    nteth = int(p[H_NTETH])
    offt = int(p[H_OFF_TETH])
    offr = int(p[H_OFF_ROD])
    for k in range(nteth):
        tb = offt + k * TT_SIZE
        n = int(p[tb + TT_NRODS])
        g0 = int(p[tb + TT_ROD0])
        tension_only = p[tb + TT_TENSION_ONLY] != 0.0
        model = int(p[tb + TT_MODEL])
        if model == MODEL_ENERGY:
            c1 = SQ3
            c2 = 0.0
        elif model == MODEL_PRINTED:
            c1 = 2.0 - SQ3
            c2 = SQ3 - 1.0
        else:
            c1 = SQ3
            c2 = 1.0 - SQ3
        # C^-1 = I/c1 - c2/(c1 (c1 + c2)) u u^T;  Kc = C^-1 / (2 sqrt3)
        kc_i = 1.0 / (2.0 * SQ3 * c1)
        kc_u = -c2 / (2.0 * SQ3 * c1 * (c1 + c2))
        reel = int(p[tb + TT_REEL]) - 1
        # the first rod at a reel: its strain rate has the l' term (tether/reel.py), whose damping
        # force changes the tension the geometric stiffness fe/l is made of
        lam = p[int(p[H_OFF_RSCR]) + reel * RS_SIZE + RS_LAM] if reel >= 0 else 0.0
        for i in range(n):
            g = g0 + i
            rb = offr + g * RT_SIZE
            m = p[rb + RT_M]
            lu = p[rb + RT_LU]
            ea = p[rb + RT_EA]
            damp = p[rb + RT_D]
            d = (y[3 + 3 * g], y[4 + 3 * g], y[5 + 3 * g])
            dd = (y[m1 + 3 + 3 * g], y[m1 + 4 + 3 * g], y[m1 + 5 + 3 * g])
            dn = math.sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
            if not dn > 0.0:
                return 1
            u = (d[0] / dn, d[1] / dn, d[2] / dn)
            ell = 2.0 * SQ3 * dn
            eps = strain(dn, lu)  # eqs. 2-3, the rod's own formula
            vrel = (2.0 * SQ3 * dd[0], 2.0 * SQ3 * dd[1], 2.0 * SQ3 * dd[2])
            uv = u[0] * vrel[0] + u[1] * vrel[1] + u[2] * vrel[2]
            epsd = uv / lu
            ea_eff = ea  # d(fe)/d(eps): the l' term adds -D lambda at the reel
            if i == 0 and reel >= 0:
                epsd -= (1.0 + eps) * lam
                ea_eff = ea - damp * lam
            fe = ea * eps + damp * epsd
            slack = tension_only and (eps <= 0.0 or fe < 0.0)
            # w = (I - u u^T) v_rel / l : d(u . v_rel)/dx_B
            w = ((vrel[0] - uv * u[0]) / ell, (vrel[1] - uv * u[1]) / ell,
                 (vrel[2] - uv * u[2]) / ell)  # fmt: skip
            b = blk[g]
            for a in range(3):
                for c in range(3):
                    uu = u[a] * u[c]
                    de = 1.0 if a == c else 0.0
                    kc = kc_i * de + kc_u * uu
                    b[B_MAA + 3 * a + c] = m * (0.25 * de + 0.5 * kc)
                    b[B_MAB + 3 * a + c] = m * (0.25 * de - 0.5 * kc)
                    if slack:
                        b[B_KEL + 3 * a + c] = 0.0
                        b[B_KV + 3 * a + c] = 0.0
                    else:
                        # d(fe u)/d(x_B - x_A) and d(fe u)/d(v_B - v_A)
                        b[B_KEL + 3 * a + c] = (ea_eff / lu) * uu + (fe / ell) * (de - uu) + (
                            damp / lu) * u[a] * w[c]  # fmt: skip
                        b[B_KV + 3 * a + c] = (damp / lu) * uu
    return 0


@njit(cache=True)
def form_blocks(t, y, p, m1, blk):
    """:func:`rod_blocks` at the time t of the state y.  RADAU5 forms the matrix at a state of its
    own (the middle of the coming step, on the extrapolated polynomial), not at the last rhs
    evaluation, so a reel's first rod must first be set to its length and mass at t
    (reel_update, as the rhs does): its strain eps = |D|/l - 1 against the length of another
    time is off by l' dt/l, which on a light line is many times the true strain, and the
    geometric stiffness fe/l made of it is then wrong by as much (docs/deployment.md 8b)."""
    h = int(p[H_NQT])
    if int(p[H_NREEL]) > 0 and reel_update(t, y[2 * h : int(p[H_NSTATE])], p) != 0:
        return 1
    return rod_blocks(y, p, m1, blk)


#: offset of the frame's angular velocity in the cowell-orbit block (formulations/cowell_orbit.OP_W;
#: tests/test_orbit_frame.py checks that they agree)
FRAME_OP_W = 0


@njit(cache=True)
def _frame_shift(p, g, sg):
    """sg = S (flat 3x3): g I in the inertial frame; (g I + W)^2 / g in the frame turning with
    omega (W = [omega x]), where the Coriolis and centrifugal terms -2 W x' - W^2 x of every joint
    enter the Newton matrix as M_x (g + 2 W + W^2/g) (docs/integrators.md section 11).  Returns
    True when the frame turns."""
    for c in range(9):
        sg[c] = 0.0 * g
    for a in range(3):
        sg[4 * a] = g
    if int(p[H_FORM]) != FORM_COWELL_ORBIT:
        return False
    o = int(p[H_OFF_FORM]) + FRAME_OP_W
    wx = p[o]
    wy = p[o + 1]
    wz = p[o + 2]
    w = (0.0, -wz, wy, wz, 0.0, -wx, -wy, wx, 0.0)
    ginv = 1.0 / g
    for a in range(3):
        for c in range(3):
            w2 = 0.0
            for e in range(3):
                w2 += w[3 * a + e] * w[3 * e + c]
            sg[3 * a + c] += 2.0 * w[3 * a + c] + w2 * ginv
    return True


@njit(cache=True)
def _mass_times(b, off, sg, out):
    """out = (3x3 block of b at off) . sg, flat row-major."""
    for a in range(3):
        for c in range(3):
            acc = 0.0 * sg[0]
            for e in range(3):
                acc += b[off + 3 * a + e] * sg[3 * e + c]
            out[3 * a + c] = acc


@njit(cache=True)
def factor(p, blk, g, fac):
    """Block-Thomas factorisation of N = g M_x - C_x - K_x/g (g real or complex) into ``fac``.

    In the frame turning with the orbit every g M block is M S, S = (g I + W)^2/g
    (:func:`_frame_shift`).  Tethers leaves first (p[H_OFF_ORDER]); per tether from the tip joint to the first: S_n = P_n +
    g mf I + (the Schur terms of the tethers hanging from the tip body), S_j = P_j + P_{j+1} -
    Q_{j+1} S_{j+1}^-1 Q_{j+1}, with the rod blocks P = g MAA + KV + KEL/g, Q = g MAB - KV - KEL/g;
    each tether's first rod adds P_1 - Q_1 S_1^-1 Q_1 to its parent body's joint, and the root gets
    S_0 = g m0 I + those of its tethers.  A forest repeats this per root (block diagonal over its
    trees): root i's S^-1 goes to factor row nrods + i; a fixed root's block is g I.  Returns 0 or 1
    for a singular block.
    """
    nteth = int(p[H_NTETH])
    offt = int(p[H_OFF_TETH])
    offo = int(p[H_OFF_ORDER])
    nrods = int(p[H_NRODS])
    nroot = int(p[H_NROOT])
    offroots = int(p[H_OFF_ROOTS])
    ginv = 1.0 / g
    s = np.zeros(9, dtype=fac.dtype)
    tmp = np.zeros(9, dtype=fac.dtype)
    sg = np.zeros(9, dtype=fac.dtype)
    _frame_shift(p, g, sg)
    maa = np.zeros(9, dtype=fac.dtype)
    mab = np.zeros(9, dtype=fac.dtype)
    # Schur terms collected at each body's joint (rows: kernel body index; 0 the first root, 1 + k
    # the tip of tether k, then the other roots)
    acc = np.zeros((int(p[H_NBODY]), 9), dtype=fac.dtype)
    for i in range(nroot):
        rb = int(p[offroots + i])
        mr = _root_mass(p, rb)
        for c in range(9):
            acc[rb, c] = mr * sg[c] if mr > 0.0 else (g if c % 4 == 0 else 0.0)
    for j in range(nteth):
        k = int(p[offo + j])
        tb = offt + k * TT_SIZE
        n = int(p[tb + TT_NRODS])
        g0 = int(p[tb + TT_ROD0])
        mf = p[tb + TT_TIP_M]
        for i in range(n - 1, -1, -1):
            gr = g0 + i
            b = blk[gr]
            f = fac[gr]
            _mass_times(b, B_MAA, sg, maa)
            _mass_times(b, B_MAB, sg, mab)
            # Q of rod gr (couples its joints A and B), kept for the solve
            for c in range(9):
                f[F_Q + c] = mab[c] - b[B_KV + c] - b[B_KEL + c] * ginv
            # S of joint B_gr: P of rod gr, plus P of rod gr+1 minus its Schur term, or the tip
            for c in range(9):
                s[c] = maa[c] + b[B_KV + c] + b[B_KEL + c] * ginv
            if i == n - 1:
                if mf > 0.0:
                    for c in range(9):
                        s[c] += mf * sg[c]
                for c in range(9):
                    s[c] += acc[1 + k, c]
            else:
                bn = blk[gr + 1]
                fn = fac[gr + 1]
                _mass_times(bn, B_MAA, sg, maa)
                for c in range(9):
                    s[c] += maa[c] + bn[B_KV + c] + bn[B_KEL + c] * ginv
                _sub_qsq(s, fn, tmp)
            det = inv3(s, 0, tmp, 0)
            if det == 0.0 or not np.isfinite(abs(det)):
                return 1
            for c in range(9):
                f[F_SINV + c] = tmp[c]
        parent = int(p[tb + TT_PARENT])
        if _free_parent(p, parent):
            b = blk[g0]
            row = acc[parent]
            _mass_times(b, B_MAA, sg, maa)
            for c in range(9):
                row[c] += maa[c] + b[B_KV + c] + b[B_KEL + c] * ginv
            _sub_qsq(row, fac[g0], tmp)
    for i in range(nroot):
        det = inv3(acc[int(p[offroots + i])], 0, tmp, 0)
        if det == 0.0 or not np.isfinite(abs(det)):
            return 1
        for c in range(9):
            fac[nrods + i, F_SINV + c] = tmp[c]
    return 0


@njit(cache=True)
def _parent_joint(p, offt, k):
    """Offset in joint coordinates of the joint tether k hangs from: a root's position block in q
    (BT_QOFF; 0 for the first), else the last joint of the tether whose tip body is its parent."""
    parent = int(p[offt + k * TT_SIZE + TT_PARENT])
    if parent == 0:
        return 0
    if parent > int(p[H_NTETH]):
        return int(p[int(p[H_OFF_BODY]) + parent * BT_SIZE + BT_QOFF])
    tp = offt + (parent - 1) * TT_SIZE
    return 3 + 3 * (int(p[tp + TT_ROD0]) + int(p[tp + TT_NRODS]) - 1)


@njit(cache=True)
def _sub_qsq(s, f, tmp):
    """s -= Q S^-1 Q with Q = f[F_Q:], S^-1 = f[F_SINV:] (flat 3x3)."""
    for a in range(3):
        for c in range(3):
            acc = 0.0 * s[0]
            for e in range(3):
                acc += f[F_SINV + 3 * a + e] * f[F_Q + 3 * e + c]
            tmp[3 * a + c] = acc  # S^-1 Q
    for a in range(3):
        for c in range(3):
            acc = 0.0 * s[0]
            for e in range(3):
                acc += f[F_Q + 3 * a + e] * tmp[3 * e + c]
            s[3 * a + c] -= acc


@njit(cache=True)
def _tether_span(p, offt, k):
    """(rods, first global rod, offset of the joint it hangs from, whether that joint is free) of
    tether k."""
    tb = offt + k * TT_SIZE
    return (int(p[tb + TT_NRODS]), int(p[tb + TT_ROD0]), _parent_joint(p, offt, k),
            _free_parent(p, int(p[tb + TT_PARENT])))  # fmt: skip


@njit(cache=True)
def solve(p, blk, g, fac, m1, b):
    """Solve (g I - J) z = b in place for the second-order structure, J = [[0, I], [A_q, A_v]]
    replaced by the structured E of the module docstring:

        z_v = T^-1 N^-1 (M_x T b_v + K_x T b_q / g),   z_q = (b_q + z_v) / g.

    In a forest every root's joint is its own position block of q (BT_QOFF) and the elimination
    ends at each root separately (factor row nrods + i for root i).
    """
    nteth = int(p[H_NTETH])
    offt = int(p[H_OFF_TETH])
    offo = int(p[H_OFF_ORDER])
    nrods = int(p[H_NRODS])
    nroot = int(p[H_NROOT])
    ginv = 1.0 / g
    xv = np.empty(m1, dtype=b.dtype)  # T b_v, then the right-hand side s, then w
    xq = np.empty(m1, dtype=b.dtype)  # T b_q
    s = np.zeros(m1, dtype=b.dtype)
    # joint coordinates, parents before children: x_root = r_root, x_B = x_A + 2 sqrt3 d
    for i in range(nroot):
        _, qo = _root(p, i)
        for c in range(3):
            xv[qo + c] = b[m1 + qo + c]
            xq[qo + c] = b[qo + c]
    for j in range(nteth - 1, -1, -1):
        k = int(p[offo + j])
        n, g0, pa, _ = _tether_span(p, offt, k)
        for i in range(n):
            gr = g0 + i
            o = 3 + 3 * gr
            oa = pa if i == 0 else o - 3
            for c in range(3):
                xv[o + c] = xv[oa + c] + 2.0 * SQ3 * b[m1 + o + c]
                xq[o + c] = xq[oa + c] + 2.0 * SQ3 * b[o + c]
    # s = M_x xm + K_x xq / g, assembled rod by rod (root row: m0 xm, or xv itself when fixed);
    # xm = xv, or xv - W^2 xq / g in the frame turning with omega (the centrifugal term's share)
    sg = np.zeros(9, dtype=b.dtype)
    xm = xv
    if _frame_shift(p, g, sg):
        o = int(p[H_OFF_FORM]) + FRAME_OP_W
        wx = p[o]
        wy = p[o + 1]
        wz = p[o + 2]
        xm = np.empty(m1, dtype=b.dtype)
        for j in range(m1 // 3):
            q0 = xq[3 * j]
            q1 = xq[3 * j + 1]
            q2 = xq[3 * j + 2]
            wq = wx * q0 + wy * q1 + wz * q2
            ww = wx * wx + wy * wy + wz * wz
            # W^2 q = w (w . q) - |w|^2 q
            xm[3 * j] = xv[3 * j] - (wx * wq - ww * q0) * ginv
            xm[3 * j + 1] = xv[3 * j + 1] - (wy * wq - ww * q1) * ginv
            xm[3 * j + 2] = xv[3 * j + 2] - (wz * wq - ww * q2) * ginv
    for i in range(nroot):
        rb, qo = _root(p, i)
        mr = _root_mass(p, rb)
        for c in range(3):
            s[qo + c] = mr * xm[qo + c] if mr > 0.0 else xv[qo + c]
    for k in range(nteth):
        n, g0, pa, free_pa = _tether_span(p, offt, k)
        mf = p[offt + k * TT_SIZE + TT_TIP_M]
        for i in range(n):
            gr = g0 + i
            bl = blk[gr]
            oa = pa if i == 0 else 3 * gr  # joint A of rod gr
            ob = 3 + 3 * gr
            for a in range(3):
                ma = 0.0 * s[0]
                mb = 0.0 * s[0]
                ke = 0.0 * s[0]
                for c in range(3):
                    ma += bl[B_MAA + 3 * a + c] * xm[oa + c] + bl[B_MAB + 3 * a + c] * xm[ob + c]
                    mb += bl[B_MAB + 3 * a + c] * xm[oa + c] + bl[B_MAA + 3 * a + c] * xm[ob + c]
                    ke += bl[B_KEL + 3 * a + c] * (xq[ob + c] - xq[oa + c])
                if i > 0 or free_pa:
                    s[oa + a] += ma + ke * ginv
                s[ob + a] += mb - ke * ginv
            if i == n - 1 and mf > 0.0:
                for a in range(3):
                    s[ob + a] += mf * xm[ob + a]
    # forward elimination of the right-hand side, leaves first (tip -> parent joint)
    for j in range(nteth):
        k = int(p[offo + j])
        n, g0, pa, free_pa = _tether_span(p, offt, k)
        for i in range(n - 2, -1, -1):
            gr = g0 + i
            _sub_q_sinv_y(s, 3 + 3 * gr, fac[gr + 1], s, 3 + 3 * (gr + 1))
        if free_pa:
            _sub_q_sinv_y(s, pa, fac[g0], s, 3 + 3 * g0)
    for i in range(nroot):
        _, qo = _root(p, i)
        fr = fac[nrods + i]
        y0 = (s[qo], s[qo + 1], s[qo + 2])
        for a in range(3):
            xv[qo + a] = fr[3 * a] * y0[0] + fr[3 * a + 1] * y0[1] + fr[3 * a + 2] * y0[2]
    # back substitution, parents before children: w_j = S_j^-1 (y_j - Q_j w_{j-1})
    for j in range(nteth - 1, -1, -1):
        k = int(p[offo + j])
        n, g0, pa, _ = _tether_span(p, offt, k)
        for i in range(n):
            gr = g0 + i
            f = fac[gr]
            oa = pa if i == 0 else 3 * gr
            ob = 3 + 3 * gr
            e = (s[ob] - (f[F_Q] * xv[oa] + f[F_Q + 1] * xv[oa + 1] + f[F_Q + 2] * xv[oa + 2]),
                 s[ob + 1] - (f[F_Q + 3] * xv[oa] + f[F_Q + 4] * xv[oa + 1] + f[F_Q + 5] * xv[oa + 2]),
                 s[ob + 2] - (f[F_Q + 6] * xv[oa] + f[F_Q + 7] * xv[oa + 1] + f[F_Q + 8] * xv[oa + 2]))  # fmt: skip
            for a in range(3):
                xv[ob + a] = f[3 * a] * e[0] + f[3 * a + 1] * e[1] + f[3 * a + 2] * e[2]
    # back to q: z_v = T^-1 w, z_q = (b_q + z_v)/g
    for i in range(nroot):
        _, qo = _root(p, i)
        for c in range(3):
            b[m1 + qo + c] = xv[qo + c]
    for k in range(nteth):
        n, g0, pa, _ = _tether_span(p, offt, k)
        for i in range(n):
            gr = g0 + i
            oa = pa if i == 0 else 3 * gr
            ob = 3 + 3 * gr
            for c in range(3):
                b[m1 + ob + c] = (xv[ob + c] - xv[oa + c]) / (2.0 * SQ3)
    for i in range(m1):
        b[i] = (b[i] + b[m1 + i]) * ginv


@njit(cache=True)
def _sub_q_sinv_y(dst, od, f, ys, oy):
    """dst[od:od+3] -= Q S^-1 y with y = ys[oy:oy+3], Q and S^-1 from the factor row f of the
    joint the elimination comes from."""
    v0 = f[F_SINV] * ys[oy] + f[F_SINV + 1] * ys[oy + 1] + f[F_SINV + 2] * ys[oy + 2]
    v1 = f[F_SINV + 3] * ys[oy] + f[F_SINV + 4] * ys[oy + 1] + f[F_SINV + 5] * ys[oy + 2]
    v2 = f[F_SINV + 6] * ys[oy] + f[F_SINV + 7] * ys[oy + 1] + f[F_SINV + 8] * ys[oy + 2]
    for a in range(3):
        dst[od + a] -= f[F_Q + 3 * a] * v0 + f[F_Q + 3 * a + 1] * v1 + f[F_Q + 3 * a + 2] * v2
