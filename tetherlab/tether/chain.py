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
tether J_0 = W (s_0 + a_0); the root then solves (m0 I + sum_k W_k) a_0 = R_0 - sum_k W_k s_0,k,
which is where hub-and-spoke tethers (and, with a 6x6 root, a rigid body) plug in.
"""

from __future__ import annotations

import math

from .._jit import njit
from ..kernel.effects import body_force, rod_force_density
from ..kernel.layout import (
    FAIL_NONFINITE,
    FAIL_ROD_COLLAPSE,
    FAIL_SINGULAR,
    H_FAIL_CODE,
    H_FAIL_ROD,
    H_FAIL_T,
    H_FAIL_VAL,
    H_MIN_STRAIN,
    H_MUTANT,
    H_NQ,
    H_NRODS,
    H_NTETH,
    H_OFF_QUAD,
    H_OFF_ROD,
    H_OFF_SCR,
    H_OFF_TETH,
    H_ROOT_INV_M,
    H_ROOT_M,
    MODEL_ENERGY,
    MODEL_PRINTED,
    MUT_DAMPING_SIGN,
    MUT_EQ19_DOUBLED,
    MUT_FTP_DROPPED,
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
    TT_MODEL,
    TT_NRODS,
    TT_TENSION_ONLY,
    TT_ROD0,
    TT_SIZE,
    TT_TIP_INV_M,
    TT_TIP_M,
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
def rod_forces(t, q, qd, p):
    """Geometry, elastic force and distributed external forces of every rod, into the scratch.

    Writes per rod: R_1, R_2 (half-rod totals), Q (d-equation forcing without reactions), the
    coupling matrix C, u, F_E, strain and strain rate.  Returns a failure code (0 = fine).
    """
    nteth = int(p[H_NTETH])
    offt = int(p[H_OFF_TETH])
    offr = int(p[H_OFF_ROD])
    scr = int(p[H_OFF_SCR])
    offq = int(p[H_OFF_QUAD])
    nq = int(p[H_NQ])
    min_strain = p[H_MIN_STRAIN]
    mutant = int(p[H_MUTANT])  # 0 in every user run (tetherlab/mutants.py: negative controls)
    damp_sign = -1.0 if mutant == MUT_DAMPING_SIGN else 1.0  # decided once, outside the loops
    eq19_doubled = mutant == MUT_EQ19_DOUBLED
    ftp_dropped = mutant == MUT_FTP_DROPPED
    for k in range(nteth):
        tb = offt + k * TT_SIZE
        n = int(p[tb + TT_NRODS])
        g0 = int(p[tb + TT_ROD0])
        tension_only = p[tb + TT_TENSION_ONLY] != 0.0
        energy = int(p[tb + TT_MODEL]) == MODEL_ENERGY
        printed = int(p[tb + TT_MODEL]) == MODEL_PRINTED
        # end A of the first rod sits on the root body (eq. 36)
        ax = q[0]
        ay = q[1]
        az = q[2]
        avx = qd[0]
        avy = qd[1]
        avz = qd[2]
        for i in range(n):
            g = g0 + i
            rb = offr + g * RT_SIZE
            m = p[rb + RT_M]
            lu = p[rb + RT_LU]
            ea = p[rb + RT_EA]
            damp = damp_sign * p[rb + RT_D]
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
                elif eq19_doubled:  # J_2 + (sqrt3 - 1) J(u): F_T* twice (model.md 2.4)
                    c1 = 2.0 * SQ3 - 1.0
                    c2 = 2.0 - 2.0 * SQ3
                else:
                    c1 = SQ3
                    c2 = 1.0 - SQ3
                if ftp_dropped:  # (R_2 - R_1) + 2 F_TP without F_TP (model.md 3)
                    qlx = r2x - r1x
                    qly = r2y - r1y
                    qlz = r2z - r1z
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
            # next rod starts at B_i
            ax += 2.0 * tx
            ay += 2.0 * ty
            az += 2.0 * tz
            avx += 2.0 * SQ3 * ddx
            avy += 2.0 * SQ3 * ddy
            avz += 2.0 * SQ3 * ddz
    return 0


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
def tip_position_velocity(q, qd, p, k):
    """Position and velocity of the far end B_n of tether k (its tip body), eq. 23."""
    offt = int(p[H_OFF_TETH])
    tb = offt + k * TT_SIZE
    n = int(p[tb + TT_NRODS])
    g0 = int(p[tb + TT_ROD0])
    x = q[0]
    y = q[1]
    z = q[2]
    vx = qd[0]
    vy = qd[1]
    vz = qd[2]
    for g in range(g0, g0 + n):
        x += 2.0 * SQ3 * q[3 + 3 * g]
        y += 2.0 * SQ3 * q[4 + 3 * g]
        z += 2.0 * SQ3 * q[5 + 3 * g]
        vx += 2.0 * SQ3 * qd[3 + 3 * g]
        vy += 2.0 * SQ3 * qd[4 + 3 * g]
        vz += 2.0 * SQ3 * qd[5 + 3 * g]
    return x, y, z, vx, vy, vz


@njit(cache=True)
def accelerations(t, q, qd, p, acc):
    """Accelerations of the generalised coordinates (r0, d_1 ... d_N) into ``acc``.

    Also leaves in the scratch area, per joint, the reaction J_k (used by the diagnostics).
    Returns 0 or a failure code (details in the header of p).
    """
    code = rod_forces(t, q, qd, p)
    if code != 0:
        return code
    nteth = int(p[H_NTETH])
    offt = int(p[H_OFF_TETH])
    offr = int(p[H_OFF_ROD])
    scr = int(p[H_OFF_SCR])
    nrods = int(p[H_NRODS])
    jscr = scr + nrods * SR_SIZE  # joint scratch follows the rod scratch
    inv_m0 = p[H_ROOT_INV_M]
    m0 = p[H_ROOT_M]

    # root body: external force, and the 3x3 system (m0 I + sum W_k) a0 = R0 - sum W_k s0_k
    if inv_m0 > 0.0:
        r0x, r0y, r0z = body_force(p, t, 0, q[0], q[1], q[2], qd[0], qd[1], qd[2], m0)
    else:
        r0x = 0.0
        r0y = 0.0
        r0z = 0.0
    # root accumulators live after the joint scratch: A (9) and b (3), inverse (9)
    nj_total = nrods + nteth
    ro = jscr + nj_total * SJ_SIZE
    for c in range(9):
        p[ro + c] = 0.0
    p[ro] = m0
    p[ro + 4] = m0
    p[ro + 8] = m0
    p[ro + 9] = r0x
    p[ro + 10] = r0y
    p[ro + 11] = r0z

    for k in range(nteth):
        tb = offt + k * TT_SIZE
        n = int(p[tb + TT_NRODS])
        g0 = int(p[tb + TT_ROD0])
        inv_mf = p[tb + TT_TIP_INV_M]
        mf = p[tb + TT_TIP_M]
        j0 = jscr + (g0 + k) * SJ_SIZE  # joints of this tether: n + 1 blocks
        has_tip = mf > 0.0
        last = n if has_tip else n - 1
        # tip body force
        if has_tip:
            fx_, fy_, fz_, fvx, fvy, fvz = tip_position_velocity(q, qd, p, k)
            rfx, rfy, rfz = body_force(p, t, 1 + k, fx_, fy_, fz_, fvx, fvy, fvz, mf)
        else:
            rfx = 0.0
            rfy = 0.0
            rfz = 0.0
        # ---- forward elimination from the last row to row 0 (block Thomas) -------------------
        for row in range(last, -1, -1):
            jb = j0 + row * SJ_SIZE
            S = jb + SJ_SINV  # assemble the diagonal block here, invert in place afterwards
            for c in range(9):
                p[S + c] = 0.0
            # contribution of rod `row` (B side of joint `row`), if row >= 1
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
            # contribution of rod row+1 (A side), or of the tip body on the last row
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
            else:  # row == n with a tip body
                _add_block(p, S, inv_mf, 0.0, 1.0, 0.0, 0.0)
                bx -= rfx * inv_mf
                by -= rfy * inv_mf
                bz -= rfz * inv_mf
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
                # X = S_next^-1 M  (M symmetric: M = al I + be u u^T)
                # Siu = S^-1 u
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
                # b -= M S^-1 s_next
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
            # invert the assembled block in place (copy through the J slot area is not needed:
            # _inv3 reads all nine entries before writing)
            det = _inv3(p, S, p, S)
            if det == 0.0 or not math.isfinite(det):
                return _fail(p, FAIL_SINGULAR, g0 + (row if row < n else n - 1), t, det)
        # root accumulation: J_0 = W (s_0 + a_0), W = S_0^-1
        W = j0 + SJ_SINV
        s0 = j0 + SJ_S
        for a in range(3):
            for b in range(3):
                p[ro + 3 * a + b] += p[W + 3 * a + b]
            p[ro + 9 + a] -= p[W + 3 * a] * p[s0] + p[W + 3 * a + 1] * p[s0 + 1] + p[W + 3 * a + 2] * p[s0 + 2]

    # ---- root acceleration --------------------------------------------------------------------
    if inv_m0 > 0.0:
        det = _inv3(p, ro, p, ro + 12)
        if det == 0.0 or not math.isfinite(det):
            return _fail(p, FAIL_SINGULAR, -1, t, det)
        Ai = ro + 12
        a0x = p[Ai] * p[ro + 9] + p[Ai + 1] * p[ro + 10] + p[Ai + 2] * p[ro + 11]
        a0y = p[Ai + 3] * p[ro + 9] + p[Ai + 4] * p[ro + 10] + p[Ai + 5] * p[ro + 11]
        a0z = p[Ai + 6] * p[ro + 9] + p[Ai + 7] * p[ro + 10] + p[Ai + 8] * p[ro + 11]
    else:
        a0x = 0.0
        a0y = 0.0
        a0z = 0.0
    acc[0] = a0x
    acc[1] = a0y
    acc[2] = a0z

    # ---- back substitution and rod accelerations ----------------------------------------------
    for k in range(nteth):
        tb = offt + k * TT_SIZE
        n = int(p[tb + TT_NRODS])
        g0 = int(p[tb + TT_ROD0])
        has_tip = p[tb + TT_TIP_M] > 0.0
        last = n if has_tip else n - 1
        j0 = jscr + (g0 + k) * SJ_SIZE
        # J_0 = W (s_0 + a_0)
        W = j0 + SJ_SINV
        s0 = j0 + SJ_S
        e0 = p[s0] + a0x
        e1 = p[s0 + 1] + a0y
        e2 = p[s0 + 2] + a0z
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
        if not has_tip:  # free end: no reaction at B_n
            jb = j0 + n * SJ_SIZE
            p[jb + SJ_J] = 0.0
            p[jb + SJ_J + 1] = 0.0
            p[jb + SJ_J + 2] = 0.0
        # d'' of every rod: m d'' = Q - C (J_{i-1} + J_i)
        for i in range(n):
            g = g0 + i
            sb = scr + g * SR_SIZE
            m = p[offr + g * RT_SIZE + RT_M]
            c1 = p[sb + SR_C]
            c2 = p[sb + SR_C + 1]
            u0 = p[sb + SR_U]
            u1 = p[sb + SR_U + 1]
            u2 = p[sb + SR_U + 2]
            ja = j0 + i * SJ_SIZE + SJ_J
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
    if not (math.isfinite(a0x) and math.isfinite(a0y) and math.isfinite(a0z)):
        return _fail(p, FAIL_NONFINITE, -1, t, 0.0)
    return 0
