"""Tethers of TMED rods on a root body: geometry, forces and the reaction solve (compiled).

The system is a root body (mass m0, or fixed: the catenary's "nail") carrying ``ntether`` tethers
(hub and spoke, paper section 2.4; one tether between two point masses is the case of section 2.3).
Each tether is a chain of n TMED rods (section 2.1) ending on a tip body of mass mf (or a free end).

Generalised coordinates (paper eq. 23, 3n + 3 dof for one tether): the root position r0 and the
half-separation vector d_i of every rod.  Joint positions follow (eq. 23):

    r_A,1 = r0,   r_G,i = r_A,i + sqrt(3) d_i,   r_B,i = r_A,i + 2 sqrt(3) d_i = r_A,i+1,   r_f = r_B,n.

Equations of a rod (docs/model.md, derived from paper eqs. 9-10, 16-19):

    m_i a_G,i  = R_i + T_A,i + T_B,i                                    (eq. 25)
    m_i d''_i  = Q_i + C_i (T_B,i - T_A,i)                              (eq. 26, corrected)

with C_i = c1 I + c2 u u^T:  "paper"  (eq. 20 with its sign corrected) c1 = sqrt 3, c2 = 1 - sqrt 3;
"energy" (ideal joints, Lagrangian) c1 = sqrt 3, c2 = 0.  Q_i gathers the elastic force and the
distributed external forces (docs/model.md, section 3).

Reactions.  With J_k the force the element on the root side of joint k exerts on the element on
the tip side (T_A,i = J_{i-1}, T_B,i = -J_i, force on the root -J_0, on the tip +J_n), the
acceleration-level joint constraints (the linear system L_2m of section 2.3) are block
tridiagonal with 3x3 blocks of the form alpha I + beta u u^T:

    row 0:   P_1 J_0 + M_1 J_1                         = a_0 - alpha_A,1
    row k:   M_k J_{k-1} + (P_k + P_{k+1}) J_k + M_{k+1} J_{k+1} = alpha_B,k - alpha_A,k+1
    row n:   M_n J_{n-1} + (P_n + I/mf) J_n            = alpha_B,n - R_f/mf

    P_i = (I + sqrt3 C_i)/m_i,  M_i = (sqrt3 C_i - I)/m_i,  alpha_A/B,i = (R_i -/+ sqrt3 Q_i)/m_i.

It is eliminated from the tip towards the root (block Thomas, O(n) per call), leaving for each
tether J_0 = W (s_0 + a_A), a_A the acceleration of its root-side attachment point.

Trees (issue 10, docs/model.md section 12).  Tethers are processed leaves first: a body at the end
B_n of a tether enters its last row through the compliance of its attachment point, a_B = C J_n + f
(point mass without children: C = I/m, f = R/m; with children: C = M_eff^-1, f = M_eff^-1 R_eff,
M_eff = m I + sum W_c, R_eff = R - sum W_c s_c; rigid: C = G M6eff^-1 G^T, f = G M6eff^-1 F6eff +
kappa with G = [I, -[rho]x], kappa = omega x (omega x rho)); each eliminated tether adds W (or
G^T W G) to its parent.  The roots solve their 3x3 or 6x6 systems; back substitution runs root to
leaves.  Cost: linear in the total number of rods plus a constant per body.
"""

from __future__ import annotations

import math

from .._jit import njit
from ..bodies.control import pd_torque
from ..bodies.rigid import cross, gravity_gradient_torque, mat_t_vec, mat_vec, quat_rate, rotation
from ..bodies.wheels import motor_torque
from ..kernel.effects import body_force, rod_force_density
from ..kernel.layout import (
    BS_A,
    BS_C,
    BS_CF,
    BS_F,
    BS_M,
    BS_MI,
    BS_R,
    BS_ROT,
    BS_SIZE,
    BS_TQ,
    BS_U,
    BS_V,
    BS_W,
    BT_AOFF,
    BT_CTRL,
    BT_INV_M,
    BT_JB,
    BT_JS,
    BT_M,
    BT_NCHILD,
    BT_NW,
    BT_PT,
    BT_QOFF,
    BT_RIGID,
    BT_SIZE,
    BT_W0,
    DEFECT_NO_CENTRIPETAL,
    DEFECT_UNROTATED_ATTACHMENT,
    FAIL_NONFINITE,
    FAIL_ROD_COLLAPSE,
    FAIL_SINGULAR,
    H_DEFECT,
    H_FAIL_CODE,
    H_FAIL_ROD,
    H_FAIL_T,
    H_FAIL_VAL,
    H_MIN_STRAIN,
    H_MU_GG,
    H_NBODY,
    H_NQ,
    H_NROOT,
    H_NRODS,
    H_NTETH,
    H_NWHEEL,
    H_OFF_ATT,
    H_OFF_BODY,
    H_OFF_BSCR,
    H_OFF_ORDER,
    H_OFF_QUAD,
    H_OFF_ROD,
    H_OFF_ROOTS,
    H_OFF_SCR,
    H_OFF_TETH,
    H_OFF_WHL,
    H_OFF_WT,
    MODEL_ENERGY,
    MODEL_PRINTED,
    RT_D,
    RT_EA,
    RT_LU,
    RT_M,
    RT_SIZE,
    SJ_J,
    SJ_S,
    SJ_SINV,
    SJ_SIZE,
    SR_C,
    SR_EPS,
    SR_EPSD,
    SR_FE,
    SR_Q,
    SR_R1,
    SR_R2,
    SR_SIZE,
    SR_U,
    TS_A,
    TS_B,
    TS_KAP,
    TS_RHO,
    TS_SIZE,
    TT_CHILD,
    TT_MODEL,
    TT_NRODS,
    TT_PA,
    TT_PARENT,
    TT_ROD0,
    TT_SIZE,
    TT_TENSION_ONLY,
    WS_SAT,
    WS_SIZE,
    WS_TAU,
    WT_AX,
    WT_SIZE,
)

SQ3 = math.sqrt(3.0)


@njit(cache=True)
def _inv3(a, ao, out, oo):
    """Inverse of the 3x3 row-major block a[ao:ao+9] into out[oo:oo+9]; returns the determinant."""
    a00 = a[ao]
    a01 = a[ao + 1]
    a02 = a[ao + 2]
    a10 = a[ao + 3]
    a11 = a[ao + 4]
    a12 = a[ao + 5]
    a20 = a[ao + 6]
    a21 = a[ao + 7]
    a22 = a[ao + 8]
    c00 = a11 * a22 - a12 * a21
    c01 = a12 * a20 - a10 * a22
    c02 = a10 * a21 - a11 * a20
    det = a00 * c00 + a01 * c01 + a02 * c02
    if det == 0.0:
        return 0.0
    inv = 1.0 / det
    out[oo] = c00 * inv
    out[oo + 1] = (a02 * a21 - a01 * a22) * inv
    out[oo + 2] = (a01 * a12 - a02 * a11) * inv
    out[oo + 3] = c01 * inv
    out[oo + 4] = (a00 * a22 - a02 * a20) * inv
    out[oo + 5] = (a02 * a10 - a00 * a12) * inv
    out[oo + 6] = c02 * inv
    out[oo + 7] = (a01 * a20 - a00 * a21) * inv
    out[oo + 8] = (a00 * a11 - a01 * a10) * inv
    return det


@njit(cache=True)
def _fail(p, code, rod, t, val):
    p[H_FAIL_CODE] = code
    p[H_FAIL_ROD] = rod
    p[H_FAIL_T] = t
    p[H_FAIL_VAL] = val
    return code


@njit(cache=True)
def _add_block(p, o, alpha, beta, ux, uy, uz):
    """p[o:o+9] += alpha I + beta u u^T."""
    p[o] += alpha + beta * ux * ux
    p[o + 1] += beta * ux * uy
    p[o + 2] += beta * ux * uz
    p[o + 3] += beta * uy * ux
    p[o + 4] += alpha + beta * uy * uy
    p[o + 5] += beta * uy * uz
    p[o + 6] += beta * uz * ux
    p[o + 7] += beta * uz * uy
    p[o + 8] += alpha + beta * uz * uz


@njit(cache=True)
def _invn(p, a, out, n):
    """Inverse of the n x n row-major block p[a:a+n*n] into p[out:...] by Gauss-Jordan with
    partial pivoting; destroys the block at a.  Returns the product of the pivots (0: singular)."""
    for i in range(n * n):
        p[out + i] = 0.0
    for i in range(n):
        p[out + i * n + i] = 1.0
    det = 1.0
    for c in range(n):
        piv = c
        big = abs(p[a + c * n + c])
        for r in range(c + 1, n):
            v = abs(p[a + r * n + c])
            if v > big:
                big = v
                piv = r
        if big == 0.0:
            return 0.0
        if piv != c:
            for j in range(n):
                tmp = p[a + c * n + j]
                p[a + c * n + j] = p[a + piv * n + j]
                p[a + piv * n + j] = tmp
                tmp = p[out + c * n + j]
                p[out + c * n + j] = p[out + piv * n + j]
                p[out + piv * n + j] = tmp
            det = -det
        d = p[a + c * n + c]
        det *= d
        inv = 1.0 / d
        for j in range(n):
            p[a + c * n + j] *= inv
            p[out + c * n + j] *= inv
        for r in range(n):
            if r != c:
                f = p[a + r * n + c]
                if f != 0.0:
                    for j in range(n):
                        p[a + r * n + j] -= f * p[a + c * n + j]
                        p[out + r * n + j] -= f * p[out + c * n + j]
    return det


@njit(cache=True)
def next_joint(q, qd, g, ax, ay, az, avx, avy, avz):
    """The one joint step of every walk along a tether (eq. 23): from end A of rod g to its end B,
    r_B = r_A + 2 sqrt3 d_g (position and velocity)."""
    k = 2.0 * SQ3
    return (
        ax + k * q[3 + 3 * g], ay + k * q[4 + 3 * g], az + k * q[5 + 3 * g],
        avx + k * qd[3 + 3 * g], avy + k * qd[4 + 3 * g], avz + k * qd[5 + 3 * g],
    )


@njit(cache=True)
def _rod_force(t, q, qd, p, g, tension_only, energy, printed, ax, ay, az, avx, avy, avz):
    """Geometry, elastic force and distributed forces of rod g whose end A is at (ax.., avx..):
    writes R_1, R_2, Q, C, u, F_E, strain and strain rate to its scratch.  Returns a failure code."""
    offr = int(p[H_OFF_ROD])
    scr = int(p[H_OFF_SCR])
    offq = int(p[H_OFF_QUAD])
    nq = int(p[H_NQ])
    min_strain = p[H_MIN_STRAIN]
    rb = offr + g * RT_SIZE
    m = p[rb + RT_M]
    lu = p[rb + RT_LU]
    ea = p[rb + RT_EA]
    damp = p[rb + RT_D]
    dx = q[3 + 3 * g]
    dy = q[4 + 3 * g]
    dz = q[5 + 3 * g]
    ddx = qd[3 + 3 * g]
    ddy = qd[4 + 3 * g]
    ddz = qd[5 + 3 * g]
    dn = math.sqrt(dx * dx + dy * dy + dz * dz)
    la = 2.0 * SQ3 * dn  # stretched length, eq. 3
    eps = la / lu - 1.0  # eq. 2
    if not (eps > min_strain):  # also catches NaN
        return _fail(p, FAIL_ROD_COLLAPSE, g, t, eps)
    ux = dx / dn
    uy = dy / dn
    uz = dz / dn
    epsd = 2.0 * SQ3 * (ux * ddx + uy * ddy + uz * ddz) / lu
    fe = ea * eps + damp * epsd  # eq. 1: T = EA eps + D eps'
    if tension_only and (eps <= 0.0 or fe < 0.0):
        # A slack tether neither pushes nor damps in compression, and damping cannot make
        # a taut one push.  The switch is a kink in the rhs; kernel/events.py makes the
        # integrators stop exactly on it (g = min(EA eps, T) changes sign there).
        fe = 0.0
    # distributed forces: Gauss-Legendre on each half rod, xi in [-1, 0] and [0, 1];
    # node position r = r_A + (1 + xi) sqrt3 d, velocity likewise, tangent dr/dxi = sqrt3 d
    r1x = 0.0
    r1y = 0.0
    r1z = 0.0
    r2x = 0.0
    r2y = 0.0
    r2z = 0.0
    qlx = 0.0
    qly = 0.0
    qlz = 0.0
    mxi = 0.5 * m  # mass per unit xi
    tx = SQ3 * dx
    ty = SQ3 * dy
    tz = SQ3 * dz
    for j in range(2 * nq):
        xi = p[offq + j]
        w = p[offq + 2 * nq + j]
        s = 1.0 + xi
        fx, fy, fz = rod_force_density(
            p, t, g,
            ax + s * tx, ay + s * ty, az + s * tz,
            avx + s * SQ3 * ddx, avy + s * SQ3 * ddy, avz + s * SQ3 * ddz,
            tx, ty, tz, mxi,
        )
        if xi < 0.0:
            r1x += w * fx
            r1y += w * fy
            r1z += w * fz
        else:
            r2x += w * fx
            r2y += w * fy
            r2z += w * fz
        qlx += SQ3 * xi * w * fx
        qly += SQ3 * xi * w * fy
        qlz += SQ3 * xi * w * fz
    sb = scr + g * SR_SIZE
    p[sb + SR_R1] = r1x
    p[sb + SR_R1 + 1] = r1y
    p[sb + SR_R1 + 2] = r1z
    p[sb + SR_R2] = r2x
    p[sb + SR_R2 + 1] = r2y
    p[sb + SR_R2 + 2] = r2z
    if energy:
        # generalised force of the distributed load on d (exact for the quadrature), and
        # the elastic force dV/dd = 2 sqrt3 EA eps u  (docs/model.md, section 5)
        c1 = SQ3
        c2 = 0.0
        qx = qlx - 2.0 * SQ3 * fe * ux
        qy = qly - 2.0 * SQ3 * fe * uy
        qz = qlz - 2.0 * SQ3 * fe * uz
    else:
        # paper eq. 26: axial part (R_2 - R_1).u, transverse part R_2 - R_1 + 2 F_TP with
        # F_TP of eq. 13, which reduces to J(u) Q_lag (docs/model.md, section 3).
        # C = J_2 = c1 I + c2 u u^T with eq. 20's sign corrected; "printed" keeps eq. 20
        # exactly as printed (wrong transverse inertia), only for docs/model.md's evidence.
        if printed:
            c1 = 2.0 - SQ3
            c2 = SQ3 - 1.0
        else:
            c1 = SQ3
            c2 = 1.0 - SQ3
        ax_ = (r2x - r1x) * ux + (r2y - r1y) * uy + (r2z - r1z) * uz
        ql_u = qlx * ux + qly * uy + qlz * uz
        qx = ax_ * ux + (qlx - ql_u * ux) - 2.0 * fe * ux
        qy = ax_ * uy + (qly - ql_u * uy) - 2.0 * fe * uy
        qz = ax_ * uz + (qlz - ql_u * uz) - 2.0 * fe * uz
    p[sb + SR_Q] = qx
    p[sb + SR_Q + 1] = qy
    p[sb + SR_Q + 2] = qz
    p[sb + SR_C] = c1
    p[sb + SR_C + 1] = c2
    p[sb + SR_U] = ux
    p[sb + SR_U + 1] = uy
    p[sb + SR_U + 2] = uz
    p[sb + SR_FE] = fe
    p[sb + SR_EPS] = eps
    p[sb + SR_EPSD] = epsd
    return 0


@njit(cache=True)
def _body_kinematics(q, qd, att, p, b, rx, ry, rz, vx, vy, vz):
    """Body b's centre of mass (given) into its scratch, and, if rigid, R(q) and omega (inertial)."""
    offb = int(p[H_OFF_BODY])
    bt = offb + b * BT_SIZE
    bs = int(p[H_OFF_BSCR]) + b * BS_SIZE
    p[bs + BS_R] = rx
    p[bs + BS_R + 1] = ry
    p[bs + BS_R + 2] = rz
    p[bs + BS_V] = vx
    p[bs + BS_V + 1] = vy
    p[bs + BS_V + 2] = vz
    if p[bt + BT_RIGID] != 0.0:
        ao = int(p[bt + BT_AOFF]) - int(p[H_OFF_ATT])
        rotation(p, bs + BS_ROT, att[ao], att[ao + 1], att[ao + 2], att[ao + 3])
        wx, wy, wz = mat_vec(p, bs + BS_ROT, att[ao + 4], att[ao + 5], att[ao + 6])
        p[bs + BS_W] = wx
        p[bs + BS_W + 1] = wy
        p[bs + BS_W + 2] = wz


@njit(cache=True)
def _offset(p, b, bx, by, bz):
    """Inertial offset rho = R rho_b of a body-fixed point of body b (body scratch filled), the
    velocity term omega x rho and kappa = omega x (omega x rho).  The defect switch (negative
    controls only) uses rho_b unrotated or drops kappa."""
    bs = int(p[H_OFF_BSCR]) + b * BS_SIZE
    defect = int(p[H_DEFECT])
    if defect == DEFECT_UNROTATED_ATTACHMENT:
        rx, ry, rz = bx, by, bz
    else:
        rx, ry, rz = mat_vec(p, bs + BS_ROT, bx, by, bz)
    wx = p[bs + BS_W]
    wy = p[bs + BS_W + 1]
    wz = p[bs + BS_W + 2]
    vx, vy, vz = cross(wx, wy, wz, rx, ry, rz)
    kx, ky, kz = cross(wx, wy, wz, vx, vy, vz)
    if defect == DEFECT_NO_CENTRIPETAL:
        kx = 0.0
        ky = 0.0
        kz = 0.0
    return rx, ry, rz, vx, vy, vz, kx, ky, kz


@njit(cache=True)
def forward(t, q, qd, att, p, with_forces):
    """Kinematics of the whole forest, roots to leaves: every body's centre of mass (and attitude),
    every tether's attachment point A_1 and end B_n, and (with_forces) every rod's forces.
    Returns a failure code."""
    offb = int(p[H_OFF_BODY])
    offt = int(p[H_OFF_TETH])
    bscr = int(p[H_OFF_BSCR])
    nbody = int(p[H_NBODY])
    nteth = int(p[H_NTETH])
    tscr = bscr + nbody * BS_SIZE
    order = int(p[H_OFF_ORDER])
    roots = int(p[H_OFF_ROOTS])
    for i in range(int(p[H_NROOT])):
        b = int(p[roots + i])
        qo = int(p[offb + b * BT_SIZE + BT_QOFF])
        _body_kinematics(q, qd, att, p, b, q[qo], q[qo + 1], q[qo + 2], qd[qo], qd[qo + 1], qd[qo + 2])
    for i in range(nteth - 1, -1, -1):  # roots first
        k = int(p[order + i])
        tb = offt + k * TT_SIZE
        ts = tscr + k * TS_SIZE
        par = int(p[tb + TT_PARENT])
        pbt = offb + par * BT_SIZE
        pbs = bscr + par * BS_SIZE
        ax = p[pbs + BS_R]
        ay = p[pbs + BS_R + 1]
        az = p[pbs + BS_R + 2]
        avx = p[pbs + BS_V]
        avy = p[pbs + BS_V + 1]
        avz = p[pbs + BS_V + 2]
        if p[pbt + BT_RIGID] != 0.0:
            rx, ry, rz, vx, vy, vz, kx, ky, kz = _offset(p, par, p[tb + TT_PA], p[tb + TT_PA + 1], p[tb + TT_PA + 2])
            ax += rx
            ay += ry
            az += rz
            avx += vx
            avy += vy
            avz += vz
            p[ts + TS_RHO] = rx
            p[ts + TS_RHO + 1] = ry
            p[ts + TS_RHO + 2] = rz
            p[ts + TS_KAP] = kx
            p[ts + TS_KAP + 1] = ky
            p[ts + TS_KAP + 2] = kz
        p[ts + TS_A] = ax
        p[ts + TS_A + 1] = ay
        p[ts + TS_A + 2] = az
        p[ts + TS_A + 3] = avx
        p[ts + TS_A + 4] = avy
        p[ts + TS_A + 5] = avz
        n = int(p[tb + TT_NRODS])
        g0 = int(p[tb + TT_ROD0])
        tension_only = p[tb + TT_TENSION_ONLY] != 0.0
        energy = int(p[tb + TT_MODEL]) == MODEL_ENERGY
        printed = int(p[tb + TT_MODEL]) == MODEL_PRINTED
        for g in range(g0, g0 + n):
            if with_forces:
                code = _rod_force(t, q, qd, p, g, tension_only, energy, printed, ax, ay, az, avx, avy, avz)
                if code != 0:
                    return code
            ax, ay, az, avx, avy, avz = next_joint(q, qd, g, ax, ay, az, avx, avy, avz)
        p[ts + TS_B] = ax
        p[ts + TS_B + 1] = ay
        p[ts + TS_B + 2] = az
        p[ts + TS_B + 3] = avx
        p[ts + TS_B + 4] = avy
        p[ts + TS_B + 5] = avz
        c = int(p[tb + TT_CHILD])
        if c >= 0:
            cbt = offb + c * BT_SIZE
            if p[cbt + BT_RIGID] != 0.0:
                # the centre of mass follows from the end point: r_G = r_B - R rho_b
                cbs = bscr + c * BS_SIZE
                ao = int(p[cbt + BT_AOFF]) - int(p[H_OFF_ATT])
                rotation(p, cbs + BS_ROT, att[ao], att[ao + 1], att[ao + 2], att[ao + 3])
                wx, wy, wz = mat_vec(p, cbs + BS_ROT, att[ao + 4], att[ao + 5], att[ao + 6])
                p[cbs + BS_W] = wx
                p[cbs + BS_W + 1] = wy
                p[cbs + BS_W + 2] = wz
                rx, ry, rz, vx, vy, vz, kx, ky, kz = _offset(p, c, p[cbt + BT_PT], p[cbt + BT_PT + 1], p[cbt + BT_PT + 2])
                _body_kinematics(q, qd, att, p, c, ax - rx, ay - ry, az - rz, avx - vx, avy - vy, avz - vz)
            else:
                _body_kinematics(q, qd, att, p, c, ax, ay, az, avx, avy, avz)
    return 0


@njit(cache=True)
def rod_forces(t, q, qd, p):
    """Forces of every rod into the scratch (point-mass scenes: no attitude block).  Returns a
    failure code (0 = fine)."""
    return forward(t, q, qd, q[:0], p, True)


@njit(cache=True)
def tip_position_velocity(q, qd, p, k):
    """Position and velocity of the far end B_n of tether k (point-mass scenes), eq. 23."""
    forward(0.0, q, qd, q[:0], p, False)
    ts = int(p[H_OFF_BSCR]) + int(p[H_NBODY]) * BS_SIZE + k * TS_SIZE + TS_B
    return p[ts], p[ts + 1], p[ts + 2], p[ts + 3], p[ts + 4], p[ts + 5]


@njit(cache=True)
def accelerations(t, q, qd, p, acc):
    """Accelerations of q_trans (roots' positions, rods' d_i) into ``acc``, for a scene without an
    attitude block (point masses).  See :func:`system_accelerations`."""
    return system_accelerations(t, q, qd, q[:0], p, acc, acc[:0])


@njit(cache=True)
def _setup_body(t, att, p, b, datt):
    """External force, torques and the initial effective system of body b (before its children):
    point mass M = m I, F = R (3x3); rigid M6 = diag(m I, R J_s R^T), F6 = (R, R tau_b) with
    tau_b = M_gg - sum_k a_k tau_k - omega_b x (J_s omega_b + h_w) (docs/model.md 12)."""
    offb = int(p[H_OFF_BODY])
    bt = offb + b * BT_SIZE
    bs = int(p[H_OFF_BSCR]) + b * BS_SIZE
    m = p[bt + BT_M]
    rx = p[bs + BS_R]
    ry = p[bs + BS_R + 1]
    rz = p[bs + BS_R + 2]
    vx = p[bs + BS_V]
    vy = p[bs + BS_V + 1]
    vz = p[bs + BS_V + 2]
    if p[bt + BT_INV_M] > 0.0:
        fx, fy, fz = body_force(p, t, b, rx, ry, rz, vx, vy, vz, m)
    else:
        fx = 0.0
        fy = 0.0
        fz = 0.0
    M = bs + BS_M
    F = bs + BS_F
    if p[bt + BT_RIGID] == 0.0:
        for c in range(9):
            p[M + c] = 0.0
        p[M] = m
        p[M + 4] = m
        p[M + 8] = m
        p[F] = fx
        p[F + 1] = fy
        p[F + 2] = fz
        return
    ao = int(p[bt + BT_AOFF]) - int(p[H_OFF_ATT])
    qw = att[ao]
    qx = att[ao + 1]
    qy = att[ao + 2]
    qz = att[ao + 3]
    wbx = att[ao + 4]
    wby = att[ao + 5]
    wbz = att[ao + 6]
    ux = 0.0
    uy = 0.0
    uz = 0.0
    if p[bt + BT_CTRL] != 0.0:
        qn = math.sqrt(qw * qw + qx * qx + qy * qy + qz * qz)
        ux, uy, uz = pd_torque(p, bt, bs + BS_MI, qw / qn, qx / qn, qy / qn, qz / qn, wbx, wby, wbz, rx, ry, rz, vx, vy, vz)
    p[bs + BS_U] = ux
    p[bs + BS_U + 1] = uy
    p[bs + BS_U + 2] = uz
    # wheels: h_w = sum a_k h_k, motor reaction sum a_k tau_k (body axes)
    offw = int(p[H_OFF_WT])
    nw = int(p[bt + BT_NW])
    w0 = int(p[bt + BT_W0])
    whl = int(p[H_OFF_WHL]) - int(p[H_OFF_ATT])
    wscr = int(p[H_OFF_BSCR]) + int(p[H_NBODY]) * BS_SIZE + int(p[H_NTETH]) * TS_SIZE
    hwx = 0.0
    hwy = 0.0
    hwz = 0.0
    tqx = 0.0
    tqy = 0.0
    tqz = 0.0
    for j in range(w0, w0 + nw):
        wt = offw + j * WT_SIZE
        h = att[whl + j]
        tau, sat = motor_torque(p, wt, t, h, wbx, wby, wbz, ux, uy, uz)
        p[wscr + j * WS_SIZE + WS_TAU] = tau
        p[wscr + j * WS_SIZE + WS_SAT] = sat
        if datt.shape[0] > 0:
            datt[whl + j] = tau
        a0 = p[wt + WT_AX]
        a1 = p[wt + WT_AX + 1]
        a2 = p[wt + WT_AX + 2]
        hwx += a0 * h
        hwy += a1 * h
        hwz += a2 * h
        tqx += a0 * tau
        tqy += a1 * tau
        tqz += a2 * tau
    js = bt + BT_JS
    jx, jy, jz = mat_vec(p, js, wbx, wby, wbz)
    gx, gy, gz = cross(wbx, wby, wbz, jx + hwx, jy + hwy, jz + hwz)
    mgx = 0.0
    mgy = 0.0
    mgz = 0.0
    mu = p[H_MU_GG]
    R = bs + BS_ROT
    if mu > 0.0:
        rbx, rby, rbz = mat_t_vec(p, R, rx, ry, rz)
        mgx, mgy, mgz = gravity_gradient_torque(p, bt + BT_JB, mu, rbx, rby, rbz)
    p[bs + BS_TQ] = mgx
    p[bs + BS_TQ + 1] = mgy
    p[bs + BS_TQ + 2] = mgz
    tix, tiy, tiz = mat_vec(p, R, mgx - tqx - gx, mgy - tqy - gy, mgz - tqz - gz)
    for c in range(36):
        p[M + c] = 0.0
    p[M] = m
    p[M + 7] = m
    p[M + 14] = m
    # R J_s R^T into the lower right block
    for a in range(3):
        for c in range(3):
            s = 0.0
            for k in range(3):
                for l in range(3):
                    s += p[R + 3 * a + k] * p[js + 3 * k + l] * p[R + 3 * c + l]
            p[M + 6 * (3 + a) + 3 + c] = s
    p[F] = fx
    p[F + 1] = fy
    p[F + 2] = fz
    p[F + 3] = tix
    p[F + 4] = tiy
    p[F + 5] = tiz


@njit(cache=True)
def _child_compliance(p, c, work):
    """For a body c at the end of its parent tether: a_B = C J_n + f, into BS_C and BS_CF.
    Returns 0 or -1 (singular).  Leaf point masses are handled inline by the caller."""
    offb = int(p[H_OFF_BODY])
    cbt = offb + c * BT_SIZE
    bs = int(p[H_OFF_BSCR]) + c * BS_SIZE
    M = bs + BS_M
    Mi = bs + BS_MI
    F = bs + BS_F
    C = bs + BS_C
    f = bs + BS_CF
    if p[cbt + BT_RIGID] == 0.0:
        det = _inv3(p, M, p, Mi)
        if det == 0.0 or not math.isfinite(det):
            return -1
        for a in range(9):
            p[C + a] = p[Mi + a]
        for a in range(3):
            p[f + a] = p[Mi + 3 * a] * p[F] + p[Mi + 3 * a + 1] * p[F + 1] + p[Mi + 3 * a + 2] * p[F + 2]
        return 0
    det = _invn(p, M, Mi, 6)
    if det == 0.0 or not math.isfinite(det):
        return -1
    rx, ry, rz, vx, vy, vz, kx, ky, kz = _offset(p, c, p[cbt + BT_PT], p[cbt + BT_PT + 1], p[cbt + BT_PT + 2])
    # T = Mi G^T (6x3), G^T = [I; X], X v = rho x v:  column b of X is rho x e_b
    for b in range(3):
        ex = 1.0 if b == 0 else 0.0
        ey = 1.0 if b == 1 else 0.0
        ez = 1.0 if b == 2 else 0.0
        xx, xy, xz = cross(rx, ry, rz, ex, ey, ez)
        for a in range(6):
            p[work + 3 * a + b] = p[Mi + 6 * a + b] + p[Mi + 6 * a + 3] * xx + p[Mi + 6 * a + 4] * xy + p[Mi + 6 * a + 5] * xz
    # C = G T = T_top - rho x T_bottom (column by column)
    for b in range(3):
        cx, cy, cz = cross(rx, ry, rz, p[work + 9 + b], p[work + 12 + b], p[work + 15 + b])
        p[C + b] = p[work + b] - cx
        p[C + 3 + b] = p[work + 3 + b] - cy
        p[C + 6 + b] = p[work + 6 + b] - cz
    # f = G Mi F + kappa
    v = work + 18
    for a in range(6):
        s = 0.0
        for j in range(6):
            s += p[Mi + 6 * a + j] * p[F + j]
        p[v + a] = s
    cx, cy, cz = cross(rx, ry, rz, p[v + 3], p[v + 4], p[v + 5])
    p[f] = p[v] - cx + kx
    p[f + 1] = p[v + 1] - cy + ky
    p[f + 2] = p[v + 2] - cz + kz
    return 0


@njit(cache=True)
def _to_parent(p, par, k, W, s0):
    """Add the eliminated tether k (J_0 = W (s_0 + a_A)) to its parent body's effective system."""
    offb = int(p[H_OFF_BODY])
    pbt = offb + par * BT_SIZE
    if p[pbt + BT_INV_M] == 0.0:  # fixed: a_A = 0, nothing to add
        return
    bs = int(p[H_OFF_BSCR]) + par * BS_SIZE
    M = bs + BS_M
    F = bs + BS_F
    if p[pbt + BT_RIGID] == 0.0:
        for a in range(3):
            for b in range(3):
                p[M + 3 * a + b] += p[W + 3 * a + b]
            p[F + a] -= p[W + 3 * a] * p[s0] + p[W + 3 * a + 1] * p[s0 + 1] + p[W + 3 * a + 2] * p[s0 + 2]
        return
    ts = int(p[H_OFF_BSCR]) + int(p[H_NBODY]) * BS_SIZE + k * TS_SIZE
    rx = p[ts + TS_RHO]
    ry = p[ts + TS_RHO + 1]
    rz = p[ts + TS_RHO + 2]
    # M6 += G^T W G = [[W, -W X], [X W, -X W X]];  F6 -= G^T W (s_0 + kappa) = (v, rho x v)
    e0 = p[s0] + p[ts + TS_KAP]
    e1 = p[s0 + 1] + p[ts + TS_KAP + 1]
    e2 = p[s0 + 2] + p[ts + TS_KAP + 2]
    v0 = p[W] * e0 + p[W + 1] * e1 + p[W + 2] * e2
    v1 = p[W + 3] * e0 + p[W + 4] * e1 + p[W + 5] * e2
    v2 = p[W + 6] * e0 + p[W + 7] * e1 + p[W + 8] * e2
    c0, c1, c2 = cross(rx, ry, rz, v0, v1, v2)
    p[F] -= v0
    p[F + 1] -= v1
    p[F + 2] -= v2
    p[F + 3] -= c0
    p[F + 4] -= c1
    p[F + 5] -= c2
    for b in range(3):
        # column b of W, of W X (= -(W col of X)) and of X W X
        ex = 1.0 if b == 0 else 0.0
        ey = 1.0 if b == 1 else 0.0
        ez = 1.0 if b == 2 else 0.0
        xbx, xby, xbz = cross(rx, ry, rz, ex, ey, ez)  # X e_b
        wcx = p[W + b]
        wcy = p[W + 3 + b]
        wcz = p[W + 6 + b]
        # W X e_b
        wxx = p[W] * xbx + p[W + 1] * xby + p[W + 2] * xbz
        wxy = p[W + 3] * xbx + p[W + 4] * xby + p[W + 5] * xbz
        wxz = p[W + 6] * xbx + p[W + 7] * xby + p[W + 8] * xbz
        xwx, xwy, xwz = cross(rx, ry, rz, wcx, wcy, wcz)  # X W e_b
        xwxx, xwxy, xwxz = cross(rx, ry, rz, wxx, wxy, wxz)  # X W X e_b
        p[M + b] += wcx
        p[M + 6 + b] += wcy
        p[M + 12 + b] += wcz
        p[M + 3 + b] -= wxx
        p[M + 9 + b] -= wxy
        p[M + 15 + b] -= wxz
        p[M + 18 + b] += xwx
        p[M + 24 + b] += xwy
        p[M + 30 + b] += xwz
        p[M + 21 + b] -= xwxx
        p[M + 27 + b] -= xwxy
        p[M + 33 + b] -= xwxz


@njit(cache=True)
def system_accelerations(t, q, qd, att, p, acc, datt):
    """Accelerations of q_trans into ``acc`` and the derivatives of the attitude and wheel block
    into ``datt`` (empty for a point-mass scene).  Leaves in the scratch area, per joint, the
    reaction J_k (used by the diagnostics).  Returns 0 or a failure code (details in p's header).
    """
    code = forward(t, q, qd, att, p, True)
    if code != 0:
        return code
    nteth = int(p[H_NTETH])
    offt = int(p[H_OFF_TETH])
    offr = int(p[H_OFF_ROD])
    scr = int(p[H_OFF_SCR])
    nrods = int(p[H_NRODS])
    jscr = scr + nrods * SR_SIZE  # joint scratch follows the rod scratch
    offb = int(p[H_OFF_BODY])
    bscr = int(p[H_OFF_BSCR])
    nbody = int(p[H_NBODY])
    tscr = bscr + nbody * BS_SIZE
    wscr = tscr + nteth * TS_SIZE
    order = int(p[H_OFF_ORDER])
    roots = int(p[H_OFF_ROOTS])

    for b in range(nbody):
        _setup_body(t, att, p, b, datt)
    work = wscr + WS_SIZE * int(p[H_NWHEEL])  # 6x6 work area (T = M6^-1 G^T and M6^-1 F)

    # ---- elimination, leaves first ------------------------------------------------------------
    for i in range(nteth):
        k = int(p[order + i])
        tb = offt + k * TT_SIZE
        n = int(p[tb + TT_NRODS])
        g0 = int(p[tb + TT_ROD0])
        c = int(p[tb + TT_CHILD])
        j0 = jscr + (g0 + k) * SJ_SIZE  # joints of this tether: n + 1 blocks
        has_tip = c >= 0
        last = n if has_tip else n - 1
        leaf_point = False
        inv_mf = 0.0
        if has_tip:
            cbt = offb + c * BT_SIZE
            cbs = bscr + c * BS_SIZE
            if p[cbt + BT_RIGID] == 0.0 and p[cbt + BT_NCHILD] == 0.0:
                leaf_point = True
                inv_mf = p[cbt + BT_INV_M]
            elif _child_compliance(p, c, work) != 0:
                return _fail(p, FAIL_SINGULAR, g0 + n - 1, t, 0.0)
        else:
            cbs = 0
        # ---- forward elimination from the last row to row 0 (block Thomas) -------------------
        for row in range(last, -1, -1):
            jb = j0 + row * SJ_SIZE
            S = jb + SJ_SINV  # assemble the diagonal block here, invert in place afterwards
            for cc in range(9):
                p[S + cc] = 0.0
            bx = 0.0
            by = 0.0
            bz = 0.0
            if row >= 1:
                g = g0 + row - 1
                sb = scr + g * SR_SIZE
                m = p[offr + g * RT_SIZE + RT_M]
                c1 = p[sb + SR_C]
                c2 = p[sb + SR_C + 1]
                ux = p[sb + SR_U]
                uy = p[sb + SR_U + 1]
                uz = p[sb + SR_U + 2]
                _add_block(p, S, (1.0 + SQ3 * c1) / m, SQ3 * c2 / m, ux, uy, uz)
                rx = p[sb + SR_R1] + p[sb + SR_R2]
                ry = p[sb + SR_R1 + 1] + p[sb + SR_R2 + 1]
                rz = p[sb + SR_R1 + 2] + p[sb + SR_R2 + 2]
                bx += (rx + SQ3 * p[sb + SR_Q]) / m  # alpha_B of rod `row`
                by += (ry + SQ3 * p[sb + SR_Q + 1]) / m
                bz += (rz + SQ3 * p[sb + SR_Q + 2]) / m
            if row < n:
                g = g0 + row
                sb = scr + g * SR_SIZE
                m = p[offr + g * RT_SIZE + RT_M]
                c1 = p[sb + SR_C]
                c2 = p[sb + SR_C + 1]
                ux = p[sb + SR_U]
                uy = p[sb + SR_U + 1]
                uz = p[sb + SR_U + 2]
                _add_block(p, S, (1.0 + SQ3 * c1) / m, SQ3 * c2 / m, ux, uy, uz)
                rx = p[sb + SR_R1] + p[sb + SR_R2]
                ry = p[sb + SR_R1 + 1] + p[sb + SR_R2 + 1]
                rz = p[sb + SR_R1 + 2] + p[sb + SR_R2 + 2]
                bx -= (rx - SQ3 * p[sb + SR_Q]) / m  # - alpha_A of rod row+1
                by -= (ry - SQ3 * p[sb + SR_Q + 1]) / m
                bz -= (rz - SQ3 * p[sb + SR_Q + 2]) / m
            elif leaf_point:  # row == n, a point mass without children: C = I/m, f = R/m
                _add_block(p, S, inv_mf, 0.0, 1.0, 0.0, 0.0)
                bx -= p[cbs + BS_F] * inv_mf
                by -= p[cbs + BS_F + 1] * inv_mf
                bz -= p[cbs + BS_F + 2] * inv_mf
            else:  # row == n, a body with children or rigid: a_B = C J_n + f
                for cc in range(9):
                    p[S + cc] += p[cbs + BS_C + cc]
                bx -= p[cbs + BS_CF]
                by -= p[cbs + BS_CF + 1]
                bz -= p[cbs + BS_CF + 2]
            # eliminate J_{row+1}: S -= M_{row+1} S_{row+1}^-1 M_{row+1}, b -= M S^-1 s
            if row < last:
                g = g0 + row  # rod row+1 couples joints row and row+1
                sb = scr + g * SR_SIZE
                m = p[offr + g * RT_SIZE + RT_M]
                c1 = p[sb + SR_C]
                c2 = p[sb + SR_C + 1]
                u0 = p[sb + SR_U]
                u1 = p[sb + SR_U + 1]
                u2 = p[sb + SR_U + 2]
                al = (SQ3 * c1 - 1.0) / m
                be = SQ3 * c2 / m
                nb = jb + SJ_SIZE  # next joint block (already eliminated: holds S^-1 and s)
                Si = nb + SJ_SINV
                siu0 = p[Si] * u0 + p[Si + 1] * u1 + p[Si + 2] * u2
                siu1 = p[Si + 3] * u0 + p[Si + 4] * u1 + p[Si + 5] * u2
                siu2 = p[Si + 6] * u0 + p[Si + 7] * u1 + p[Si + 8] * u2
                # M S^-1 M = al^2 S^-1 + al be (S^-1 u u^T + u u^T S^-1) + be^2 (u.S^-1 u) u u^T
                usu = u0 * siu0 + u1 * siu1 + u2 * siu2
                us = (u0, u1, u2)
                sus = (siu0, siu1, siu2)
                for a in range(3):
                    for b in range(3):
                        p[S + 3 * a + b] -= (
                            al * al * p[Si + 3 * a + b]
                            + al * be * (sus[a] * us[b] + us[a] * sus[b])
                            + be * be * usu * us[a] * us[b]
                        )
                sn = nb + SJ_S
                v0 = p[Si] * p[sn] + p[Si + 1] * p[sn + 1] + p[Si + 2] * p[sn + 2]
                v1 = p[Si + 3] * p[sn] + p[Si + 4] * p[sn + 1] + p[Si + 5] * p[sn + 2]
                v2 = p[Si + 6] * p[sn] + p[Si + 7] * p[sn + 1] + p[Si + 8] * p[sn + 2]
                uv = u0 * v0 + u1 * v1 + u2 * v2
                bx -= al * v0 + be * uv * u0
                by -= al * v1 + be * uv * u1
                bz -= al * v2 + be * uv * u2
            p[jb + SJ_S] = bx
            p[jb + SJ_S + 1] = by
            p[jb + SJ_S + 2] = bz
            det = _inv3(p, S, p, S)
            if det == 0.0 or not math.isfinite(det):
                return _fail(p, FAIL_SINGULAR, g0 + (row if row < n else n - 1), t, det)
        _to_parent(p, int(p[tb + TT_PARENT]), k, j0 + SJ_SINV, j0 + SJ_S)

    # ---- roots ------------------------------------------------------------------------------------
    for i in range(int(p[H_NROOT])):
        b = int(p[roots + i])
        bt = offb + b * BT_SIZE
        bs = bscr + b * BS_SIZE
        A = bs + BS_A
        for cc in range(6):
            p[A + cc] = 0.0
        if p[bt + BT_INV_M] > 0.0:
            if p[bt + BT_RIGID] == 0.0:
                det = _inv3(p, bs + BS_M, p, bs + BS_MI)
                nn = 3
            else:
                det = _invn(p, bs + BS_M, bs + BS_MI, 6)
                nn = 6
            if det == 0.0 or not math.isfinite(det):
                return _fail(p, FAIL_SINGULAR, -1, t, det)
            Mi = bs + BS_MI
            F = bs + BS_F
            if nn == 3:
                p[A] = p[Mi] * p[F] + p[Mi + 1] * p[F + 1] + p[Mi + 2] * p[F + 2]
                p[A + 1] = p[Mi + 3] * p[F] + p[Mi + 4] * p[F + 1] + p[Mi + 5] * p[F + 2]
                p[A + 2] = p[Mi + 6] * p[F] + p[Mi + 7] * p[F + 1] + p[Mi + 8] * p[F + 2]
            else:
                for a in range(6):
                    s = 0.0
                    for j in range(6):
                        s += p[Mi + 6 * a + j] * p[F + j]
                    p[A + a] = s
        qo = int(p[bt + BT_QOFF])
        acc[qo] = p[A]
        acc[qo + 1] = p[A + 1]
        acc[qo + 2] = p[A + 2]
        if not (math.isfinite(p[A]) and math.isfinite(p[A + 1]) and math.isfinite(p[A + 2])):
            return _fail(p, FAIL_NONFINITE, -1, t, 0.0)

    # ---- back substitution, roots to leaves, and rod accelerations ---------------------------------
    for i in range(nteth - 1, -1, -1):
        k = int(p[order + i])
        tb = offt + k * TT_SIZE
        ts = tscr + k * TS_SIZE
        n = int(p[tb + TT_NRODS])
        g0 = int(p[tb + TT_ROD0])
        c = int(p[tb + TT_CHILD])
        has_tip = c >= 0
        last = n if has_tip else n - 1
        j0 = jscr + (g0 + k) * SJ_SIZE
        par = int(p[tb + TT_PARENT])
        pbs = bscr + par * BS_SIZE
        PA = pbs + BS_A
        aax = p[PA]
        aay = p[PA + 1]
        aaz = p[PA + 2]
        if p[offb + par * BT_SIZE + BT_RIGID] != 0.0:
            # a_A = a_G + alpha x rho + kappa
            cx, cy, cz = cross(p[PA + 3], p[PA + 4], p[PA + 5], p[ts + TS_RHO], p[ts + TS_RHO + 1], p[ts + TS_RHO + 2])
            aax += cx + p[ts + TS_KAP]
            aay += cy + p[ts + TS_KAP + 1]
            aaz += cz + p[ts + TS_KAP + 2]
        # J_0 = W (s_0 + a_A)
        W = j0 + SJ_SINV
        s0 = j0 + SJ_S
        e0 = p[s0] + aax
        e1 = p[s0 + 1] + aay
        e2 = p[s0 + 2] + aaz
        p[j0 + SJ_J] = p[W] * e0 + p[W + 1] * e1 + p[W + 2] * e2
        p[j0 + SJ_J + 1] = p[W + 3] * e0 + p[W + 4] * e1 + p[W + 5] * e2
        p[j0 + SJ_J + 2] = p[W + 6] * e0 + p[W + 7] * e1 + p[W + 8] * e2
        for row in range(1, last + 1):
            jb = j0 + row * SJ_SIZE
            g = g0 + row - 1  # rod `row` couples J_{row-1} and J_row
            sb = scr + g * SR_SIZE
            m = p[offr + g * RT_SIZE + RT_M]
            c1 = p[sb + SR_C]
            c2 = p[sb + SR_C + 1]
            u0 = p[sb + SR_U]
            u1 = p[sb + SR_U + 1]
            u2 = p[sb + SR_U + 2]
            al = (SQ3 * c1 - 1.0) / m
            be = SQ3 * c2 / m
            pj = jb - SJ_SIZE + SJ_J
            uj = u0 * p[pj] + u1 * p[pj + 1] + u2 * p[pj + 2]
            e0 = p[jb + SJ_S] - (al * p[pj] + be * uj * u0)
            e1 = p[jb + SJ_S + 1] - (al * p[pj + 1] + be * uj * u1)
            e2 = p[jb + SJ_S + 2] - (al * p[pj + 2] + be * uj * u2)
            Si = jb + SJ_SINV
            p[jb + SJ_J] = p[Si] * e0 + p[Si + 1] * e1 + p[Si + 2] * e2
            p[jb + SJ_J + 1] = p[Si + 3] * e0 + p[Si + 4] * e1 + p[Si + 5] * e2
            p[jb + SJ_J + 2] = p[Si + 6] * e0 + p[Si + 7] * e1 + p[Si + 8] * e2
        jn = j0 + n * SJ_SIZE + SJ_J
        if not has_tip:  # free end: no reaction at B_n
            p[jn] = 0.0
            p[jn + 1] = 0.0
            p[jn + 2] = 0.0
        else:
            cbt = offb + c * BT_SIZE
            cbs = bscr + c * BS_SIZE
            rigid = p[cbt + BT_RIGID] != 0.0
            if rigid or p[cbt + BT_NCHILD] != 0.0:
                # the child's own acceleration: M_eff^-1 (F_eff + G^T J_n)
                Mi = cbs + BS_MI
                F = cbs + BS_F
                A = cbs + BS_A
                if not rigid:
                    f0 = p[F] + p[jn]
                    f1 = p[F + 1] + p[jn + 1]
                    f2 = p[F + 2] + p[jn + 2]
                    p[A] = p[Mi] * f0 + p[Mi + 1] * f1 + p[Mi + 2] * f2
                    p[A + 1] = p[Mi + 3] * f0 + p[Mi + 4] * f1 + p[Mi + 5] * f2
                    p[A + 2] = p[Mi + 6] * f0 + p[Mi + 7] * f1 + p[Mi + 8] * f2
                else:
                    rx, ry, rz = mat_vec(p, cbs + BS_ROT, p[cbt + BT_PT], p[cbt + BT_PT + 1], p[cbt + BT_PT + 2])
                    if int(p[H_DEFECT]) == DEFECT_UNROTATED_ATTACHMENT:
                        rx = p[cbt + BT_PT]
                        ry = p[cbt + BT_PT + 1]
                        rz = p[cbt + BT_PT + 2]
                    tx, ty, tz = cross(rx, ry, rz, p[jn], p[jn + 1], p[jn + 2])
                    gf = (p[jn], p[jn + 1], p[jn + 2], tx, ty, tz)
                    for a in range(6):
                        s = 0.0
                        for j in range(6):
                            s += p[Mi + 6 * a + j] * (p[F + j] + gf[j])
                        p[A + a] = s
        # d'' of every rod: m d'' = Q - C (J_{i-1} + J_i)
        for ii in range(n):
            g = g0 + ii
            sb = scr + g * SR_SIZE
            m = p[offr + g * RT_SIZE + RT_M]
            c1 = p[sb + SR_C]
            c2 = p[sb + SR_C + 1]
            u0 = p[sb + SR_U]
            u1 = p[sb + SR_U + 1]
            u2 = p[sb + SR_U + 2]
            ja = j0 + ii * SJ_SIZE + SJ_J
            jbb = ja + SJ_SIZE
            sx = p[ja] + p[jbb]
            sy = p[ja + 1] + p[jbb + 1]
            sz = p[ja + 2] + p[jbb + 2]
            us = u0 * sx + u1 * sy + u2 * sz
            ax_ = (p[sb + SR_Q] - (c1 * sx + c2 * us * u0)) / m
            ay_ = (p[sb + SR_Q + 1] - (c1 * sy + c2 * us * u1)) / m
            az_ = (p[sb + SR_Q + 2] - (c1 * sz + c2 * us * u2)) / m
            if not (math.isfinite(ax_) and math.isfinite(ay_) and math.isfinite(az_)):
                return _fail(p, FAIL_NONFINITE, g, t, 0.0)
            acc[3 + 3 * g] = ax_
            acc[4 + 3 * g] = ay_
            acc[5 + 3 * g] = az_

    # ---- attitude: omega_b' = R^T alpha, q' = 1/2 q (x) omega_b ----------------------------------
    if datt.shape[0] > 0:
        oatt = int(p[H_OFF_ATT])
        for b in range(nbody):
            bt = offb + b * BT_SIZE
            if p[bt + BT_RIGID] == 0.0:
                continue
            bs = bscr + b * BS_SIZE
            ao = int(p[bt + BT_AOFF]) - oatt
            dwx, dwy, dwz = mat_t_vec(p, bs + BS_ROT, p[bs + BS_A + 3], p[bs + BS_A + 4], p[bs + BS_A + 5])
            if not (math.isfinite(dwx) and math.isfinite(dwy) and math.isfinite(dwz)):
                return _fail(p, FAIL_NONFINITE, -1, t, 0.0)
            dqw, dqx, dqy, dqz = quat_rate(att[ao], att[ao + 1], att[ao + 2], att[ao + 3], att[ao + 4], att[ao + 5], att[ao + 6])
            datt[ao] = dqw
            datt[ao + 1] = dqx
            datt[ao + 2] = dqy
            datt[ao + 3] = dqz
            datt[ao + 4] = dwx
            datt[ao + 5] = dwy
            datt[ao + 6] = dwz
    return 0


@njit(cache=True)
def joint_states(q, qd, att, p, out, bodies, rot):
    """Every joint's position and velocity (out: rows per tether A_1, B_1, ..., B_n, in the joint
    scratch order), every body's centre of mass (bodies: r, v) and rotation matrix (rot, 9 per
    body; zero for point masses), from the one forest walk (:func:`forward`, :func:`next_joint`)."""
    forward(0.0, q, qd, att, p, False)
    offt = int(p[H_OFF_TETH])
    bscr = int(p[H_OFF_BSCR])
    nbody = int(p[H_NBODY])
    tscr = bscr + nbody * BS_SIZE
    offb = int(p[H_OFF_BODY])
    for k in range(int(p[H_NTETH])):
        tb = offt + k * TT_SIZE
        ts = tscr + k * TS_SIZE
        n = int(p[tb + TT_NRODS])
        g0 = int(p[tb + TT_ROD0])
        ax = p[ts + TS_A]
        ay = p[ts + TS_A + 1]
        az = p[ts + TS_A + 2]
        avx = p[ts + TS_A + 3]
        avy = p[ts + TS_A + 4]
        avz = p[ts + TS_A + 5]
        row = g0 + k
        out[row, 0] = ax
        out[row, 1] = ay
        out[row, 2] = az
        out[row, 3] = avx
        out[row, 4] = avy
        out[row, 5] = avz
        for g in range(g0, g0 + n):
            ax, ay, az, avx, avy, avz = next_joint(q, qd, g, ax, ay, az, avx, avy, avz)
            row += 1
            out[row, 0] = ax
            out[row, 1] = ay
            out[row, 2] = az
            out[row, 3] = avx
            out[row, 4] = avy
            out[row, 5] = avz
    for b in range(nbody):
        bs = bscr + b * BS_SIZE
        for j in range(6):
            bodies[b, j] = p[bs + BS_R + j]
        if p[offb + b * BT_SIZE + BT_RIGID] != 0.0:
            for j in range(9):
                rot[b, j] = p[bs + BS_ROT + j]
