"""One TMED rod (paper section 2.1; docs/model.md sections 2-3): strain, forces, energy share.

Rod g has its end A at r_A (the walk along its tether supplies it), its centre of mass at
r_G = r_A + sqrt3 d and its end B at r_B = r_A + 2 sqrt3 d (eq. 23), with d = q[3+3g : 6+3g].
:func:`rod_force` writes what the reaction solve needs into the rod's scratch: the half-rod loads
R_1, R_2, the forcing Q of eq. 26 (= R* of eq. 32), C = J_2 = c1 I + c2 u u^T (eq. 20 corrected),
u, F_E (eq. 1), the strain (eq. 2) and its rate.

The equivalence of the rod and its two masses (eqs. 11-18): the pair F_T = F_TP + F_T* (eq. 11)
with F_T* (eq. 12) folded into C and F_TP (eq. 13) from the moment's perpendicular part (eq. 14)
through the projector J(u) = I - u u^T (eq. 15); the masses' equations (eqs. 16-17) summed give
eq. 18 and subtracted eq. 19, whose printed double F_T* and J_2 sign docs/model.md corrects.
"""

from __future__ import annotations

import math

from .._jit import njit
from ..kernel.effects import (
    count_rod_nodes,
    potential_per_mass,
    rod_central_gravity_density,
    rod_central_gravity_only,
    rod_force_density,
)
from ..kernel.layout import (
    FAIL_ROD_COLLAPSE,
    H_FAIL_CODE,
    H_FAIL_ROD,
    H_FAIL_T,
    H_FAIL_VAL,
    H_MIN_STRAIN,
    H_MUTANT,
    H_NQ,
    H_OFF_QUAD,
    H_OFF_ROD,
    H_OFF_SCR,
    MUT_DAMPING_SIGN,
    MUT_EQ19_DOUBLED,
    MUT_FTP_DROPPED,
    RT_D,
    RT_EA,
    RT_LU,
    RT_M,
    RT_SIZE,
    SR_C,
    SR_EPS,
    SR_EPSD,
    SR_FE,
    SR_Q,
    SR_R1,
    SR_R2,
    SR_SIZE,
    SR_U,
)
from ..kernel.shares import SH_HX, SH_HY, SH_HZ, SH_KE, SH_PX, SH_PY, SH_PZ, SH_VE, SH_VG
from ..kernel.vec3 import dot, norm

SQ3 = math.sqrt(3.0)


@njit(cache=True)
def fail(p, code, rod, t, val):
    """Record a failure of the right-hand side in p's header; returns the code."""
    p[H_FAIL_CODE] = code
    p[H_FAIL_ROD] = rod
    p[H_FAIL_T] = t
    p[H_FAIL_VAL] = val
    return code


@njit(cache=True, inline="always")
def strain(dn, lu):
    """Strain of a rod of half-separation |d| = dn and unstretched length lu: eq. 2 with the
    stretched length of eq. 3, eps = L_a/L_u - 1, L_a = 2 sqrt3 |d|."""
    la = 2.0 * SQ3 * dn
    return la / lu - 1.0


@njit(cache=True, inline="always")
def next_joint(q, qd, g, ax, ay, az, avx, avy, avz):
    """The one joint step of every walk along a tether (eq. 23): from end A of rod g to its end B,
    r_B = r_A + 2 sqrt3 d_g (position and velocity)."""
    k = 2.0 * SQ3
    return (
        ax + k * q[3 + 3 * g], ay + k * q[4 + 3 * g], az + k * q[5 + 3 * g],
        avx + k * qd[3 + 3 * g], avy + k * qd[4 + 3 * g], avz + k * qd[5 + 3 * g],
    )


@njit(cache=True, inline="always")
def rod_constants(p):
    """What every rod of a walk reads from the block's header, read once per walk: the rod table,
    rod scratch and quadrature offsets, the nodes per half rod, the minimum strain, the defect code
    and central gravity's parameter offset when it is the only effect (else -1).  Read per rod,
    they are reloaded after every store to the scratch (the compiler cannot tell them apart)."""
    return (int(p[H_OFF_ROD]), int(p[H_OFF_SCR]), int(p[H_OFF_QUAD]), int(p[H_NQ]), p[H_MIN_STRAIN],
            int(p[H_MUTANT]), rod_central_gravity_only(p))


@njit(cache=True, inline="always")
def rod_force(t, q, qd, p, g, rc, tension_only, energy, printed, ax, ay, az, avx, avy, avz):
    """Geometry, elastic force and distributed forces of rod g whose end A is at (ax.., avx..):
    writes R_1, R_2, Q, C, u, F_E, strain and strain rate to its scratch (rc: rod_constants).
    Returns a failure code."""
    offr, scr, offq, nq, min_strain, mutant, cg = rc
    rb = offr + g * RT_SIZE
    m = p[rb + RT_M]
    lu = p[rb + RT_LU]
    ea = p[rb + RT_EA]
    damp = p[rb + RT_D]
    # mutant: 0 in every user run (tetherlab/mutants.py: negative controls)
    if mutant == MUT_DAMPING_SIGN:
        damp = -damp
    dx = q[3 + 3 * g]
    dy = q[4 + 3 * g]
    dz = q[5 + 3 * g]
    ddx = qd[3 + 3 * g]
    ddy = qd[4 + 3 * g]
    ddz = qd[5 + 3 * g]
    dn = norm(dx, dy, dz)
    eps = strain(dn, lu)
    if not (eps > min_strain):  # also catches NaN
        return fail(p, FAIL_ROD_COLLAPSE, g, t, eps)
    ux = dx / dn
    uy = dy / dn
    uz = dz / dn
    epsd = 2.0 * SQ3 * dot(ux, uy, uz, ddx, ddy, ddz) / lu
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
    if cg >= 0:
        # central gravity alone (the common case): the same sums in a loop of its own, with no
        # effect dispatch and no call in it, so its sums stay in registers
        mu = p[cg]
        count_rod_nodes(p, 2.0 * nq)
        for j in range(2 * nq):
            xi = p[offq + j]
            w = p[offq + 2 * nq + j]
            s = 1.0 + xi
            fx, fy, fz = rod_central_gravity_density(p, mu, t, ax + s * tx, ay + s * ty, az + s * tz, mxi)
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
    else:
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
        elif mutant == MUT_EQ19_DOUBLED:  # J_2 + (sqrt3 - 1) J(u): F_T* twice (model.md 2.4)
            c1 = 2.0 * SQ3 - 1.0
            c2 = 2.0 - 2.0 * SQ3
        else:
            c1 = SQ3
            c2 = 1.0 - SQ3
        if mutant == MUT_FTP_DROPPED:  # (R_2 - R_1) + 2 F_TP without F_TP (model.md 3)
            qlx = r2x - r1x
            qly = r2y - r1y
            qlz = r2z - r1z
        ax_ = dot(r2x - r1x, r2y - r1y, r2z - r1z, ux, uy, uz)
        ql_u = dot(qlx, qly, qlz, ux, uy, uz)
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
def rod_share(t, q, qd, p, g, tension_only, elastic, ax, ay, az, avx, avy, avz, sh):
    """Add rod g's share (end A at (ax.., avx..); its strain in the scratch) to ``sh``
    (kernel/shares.py): momentum m v_G, angular momentum m r_G x v_G + m d x d' (two masses m/2
    at r_G -/+ d), kinetic energy, the potential of the effects with the nodes of the force
    quadrature (so it is the exact potential of the discretised forces) and the elastic energy of
    the bar it stands for, 1/2 EA L_u eps^2 (a slack tension-only rod stores nothing)."""
    rb = int(p[H_OFF_ROD]) + g * RT_SIZE
    offq = int(p[H_OFF_QUAD])
    nq = int(p[H_NQ])
    m = p[rb + RT_M]
    dx = q[3 + 3 * g]
    dy = q[4 + 3 * g]
    dz = q[5 + 3 * g]
    ddx = qd[3 + 3 * g]
    ddy = qd[4 + 3 * g]
    ddz = qd[5 + 3 * g]
    gx = ax + SQ3 * dx
    gy = ay + SQ3 * dy
    gz = az + SQ3 * dz
    gvx = avx + SQ3 * ddx
    gvy = avy + SQ3 * ddy
    gvz = avz + SQ3 * ddz
    sh[SH_PX] += m * gvx
    sh[SH_PY] += m * gvy
    sh[SH_PZ] += m * gvz
    sh[SH_HX] += m * (gy * gvz - gz * gvy + dy * ddz - dz * ddy)
    sh[SH_HY] += m * (gz * gvx - gx * gvz + dz * ddx - dx * ddz)
    sh[SH_HZ] += m * (gx * gvy - gy * gvx + dx * ddy - dy * ddx)
    sh[SH_KE] += 0.5 * m * (gvx**2 + gvy**2 + gvz**2 + ddx**2 + ddy**2 + ddz**2)
    for j in range(2 * nq):
        xi = p[offq + j]
        w = p[offq + 2 * nq + j]
        s = 1.0 + xi
        sh[SH_VG] += w * 0.5 * m * potential_per_mass(p, t, ax + s * SQ3 * dx, ay + s * SQ3 * dy, az + s * SQ3 * dz)
    eps = p[int(p[H_OFF_SCR]) + g * SR_SIZE + SR_EPS]
    if elastic and (eps > 0.0 or not tension_only):
        sh[SH_VE] += 0.5 * p[rb + RT_EA] * p[rb + RT_LU] * eps * eps
