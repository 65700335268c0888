"""A reel: the tether's first rod has a varying unstretched length (compiled; docs/deployment.md).

A reel on a body pays its tether out (or hauls it in) at the tether's end A_1.  The deployed
unstretched length L(t) is prescribed by the reel's law; the rods other than the first keep
their lengths, so the first rod, next to the reel, has l(t) = L(t) - (the others' lengths) and
mass rho l(t).  The stored tether, rho (line - L), stays part of the carrying body's mass.

What the reel changes in an evaluation, in the order the driver (tether/solve.py) calls it:

* :func:`reel_update`, before anything else: L, L', L'' from the law; the first rod's length and
  mass and the body's mass written where every other kernel reads them;
* :func:`reel_rod_load`, right after the first rod's forces (tether/chain.py): the material of a
  rod that grows at its end A moves with the affine field of the TMED rod plus (1 - s) w,
  w = lambda D, lambda = l'/l (docs/deployment.md 3); the difference of accelerations enters as
  the apparent distributed load -rho l (1 - s) E, E = 2 lambda D' + kappa D, kappa = l''/l - 2
  lambda^2, integrated exactly into the rod's R_1, R_2 and Q; and the strain rate gets its l'
  term, eps' = (u.D' - (1 + eps) l')/l;
* :func:`reel_body_forces`, after the bodies' set-up: the momentum flux through the exit,
  -rho l'^2 (1 + eps) u on the carrying body (docs/deployment.md 4), the same for a drum and a
  canister on a point body (they differ in where the energy goes, not in the forces); on a rigid
  body also the stored tether's inertia and the flux's moment (tether/reel_hub.py).

Scenes without a reel never call any of them (the count H_NREEL is 0).
"""

from __future__ import annotations

import math

from .._jit import njit
from ..kernel.layout import (
    BS_F,
    BS_SIZE,
    BT_INV_M,
    BT_M,
    BT_RIGID,
    BT_SIZE,
    DEFECT_REEL_FROZEN,
    DEFECT_REEL_NO_LDOT,
    DEFECT_REEL_ONE_STORED,
    DEFECT_REEL_RESCALED,
    FAIL_REEL_EMPTY,
    FAIL_REEL_SPENT,
    H_MUTANT,
    H_NREEL,
    H_OFF_BODY,
    H_OFF_BSCR,
    H_OFF_REEL,
    H_OFF_ROD,
    H_OFF_RSCR,
    H_OFF_SCR,
    H_OFF_TETH,
    H_ROOT_INV_M,
    H_ROOT_M,
    MUT_DAMPING_SIGN,
    REEL_LAW_CONSTANT,
    REEL_LAW_EXPONENTIAL,
    REEL_LAW_TABLE,
    RL_BODY,
    RL_FIXED,
    RL_L0,
    RL_LAW,
    RL_LINE,
    RL_MBODY,
    RL_RATE,
    RL_RHO,
    RL_ROD,
    RL_SIZE,
    RL_SOFF,
    RL_SPEED,
    RL_TETH,
    RL_TN,
    RL_TOFF,
    RS_JUMP,
    RS_KAP,
    RS_L,
    RS_LAM,
    RS_LD,
    RS_LDD,
    RS_LROD,
    RS_SIZE,
    RT_D,
    RT_EA,
    RT_LU,
    RT_M,
    RT_SIZE,
    SR_EPS,
    SR_EPSD,
    SR_FE,
    SR_Q,
    SR_R1,
    SR_R2,
    SR_SIZE,
    SR_U,
    TT_NRODS,
    TT_ROD0,
    TT_SIZE,
)
from ..kernel.vec3 import dot
from .reel_hub import reel_hub_terms
from .rod import SQ3, fail


@njit(cache=True, inline="always")
def reel_law(p, rb, t):
    """(L, L', L'') of the reel whose record starts at rb, at time t."""
    law = int(p[rb + RL_LAW])
    l0 = p[rb + RL_L0]
    if int(p[H_MUTANT]) == DEFECT_REEL_FROZEN:  # the negative control of the retrieval gate
        return l0, 0.0, 0.0
    if law == REEL_LAW_EXPONENTIAL:
        r = p[rb + RL_RATE]
        e = l0 * math.exp(r * t)
        return e, r * e, r * r * e
    if law == REEL_LAW_CONSTANT:
        v = p[rb + RL_SPEED]
        return l0 + v * t, v, 0.0
    if law == REEL_LAW_TABLE:
        # the interval k with t_k <= t (the first before the table, the last after it); each holds
        # t_k and L = a0 + a1 s + a2 s^2 + a3 s^3, s = t - t_k
        off = int(p[rb + RL_TOFF])
        n = int(p[rb + RL_TN])
        k = 0
        while k + 1 < n and p[off + 5 * (k + 1)] <= t:
            k += 1
        b = off + 5 * k
        s = t - p[b]
        a0 = p[b + 1]
        a1 = p[b + 2]
        a2 = p[b + 3]
        a3 = p[b + 4]
        return a0 + s * (a1 + s * (a2 + s * a3)), a1 + s * (2.0 * a2 + 3.0 * s * a3), 2.0 * a2 + 6.0 * s * a3
    return l0, 0.0, 0.0


@njit(cache=True)
def reel_update(t, att, p):
    """Every reel at time t: its law, the first rod's length and mass, the body's mass (its own
    plus the stored tether).  A spool law's L and L' are read from the first-order block ``att``
    and its L'' from the scratch, where the spool solve put it (tether/reel_spool.py).  Returns a
    failure code (the rod at the reel at zero length)."""
    # a body may carry several reels (hub-and-spoke): its mass is its own plus every reel's stored
    # tether, so each reel's body starts from its dry mass and each reel adds its own below
    for i in range(int(p[H_NREEL])):
        rb = int(p[H_OFF_REEL]) + i * RL_SIZE
        bt = int(p[H_OFF_BODY]) + int(p[rb + RL_BODY]) * BT_SIZE
        if p[bt + BT_INV_M] > 0.0:
            p[bt + BT_M] = p[rb + RL_MBODY]
    for i in range(int(p[H_NREEL])):
        rb = int(p[H_OFF_REEL]) + i * RL_SIZE
        rs = int(p[H_OFF_RSCR]) + i * RS_SIZE
        so = int(p[rb + RL_SOFF])
        if so >= 0:
            if so + 1 < att.shape[0]:
                L, Ld, Ldd = att[so], att[so + 1], p[rs + RS_LDD]
            else:  # a kinematic use without the first-order block (statics): the law's start, at rest
                L, Ld, Ldd = p[rb + RL_L0], 0.0, 0.0
            # beyond the whole line only a trial stage goes (the event reel.<tether>.spent ends
            # the run there); the body's mass must stay positive for it
            if not p[rb + RL_MBODY] + p[rb + RL_RHO] * (p[rb + RL_LINE] - L) > 0.0:
                return fail(p, FAIL_REEL_SPENT, int(p[rb + RL_ROD]), t, L)
        else:
            L, Ld, Ldd = reel_law(p, rb, t)
        g = int(p[rb + RL_ROD])
        l = L - p[rb + RL_FIXED]
        if not (l > 0.0):
            return fail(p, FAIL_REEL_EMPTY, g, t, l)
        rho = p[rb + RL_RHO]
        gb = int(p[H_OFF_ROD]) + g * RT_SIZE
        p[gb + RT_LU] = l
        p[gb + RT_M] = rho * l
        b = int(p[rb + RL_BODY])
        bt = int(p[H_OFF_BODY]) + b * BT_SIZE
        m = p[bt + BT_M] + rho * (p[rb + RL_LINE] - L)
        if int(p[H_MUTANT]) == DEFECT_REEL_ONE_STORED:  # the negative control of several reels on a body
            m = p[rb + RL_MBODY] + rho * (p[rb + RL_LINE] - L)
        if p[bt + BT_INV_M] > 0.0:  # a fixed body stays fixed
            p[bt + BT_M] = m
            p[bt + BT_INV_M] = 1.0 / m
            if b == 0:
                p[H_ROOT_M] = m
                p[H_ROOT_INV_M] = 1.0 / m
        lam = Ld / l
        if int(p[H_MUTANT]) == DEFECT_REEL_RESCALED:
            # the negative control of the momentum gate: every rod L/n and rho L/n, the mass
            # appearing in place at the local velocity, no flux through the exit
            tb = int(p[H_OFF_TETH]) + int(p[rb + RL_TETH]) * TT_SIZE
            n = int(p[tb + TT_NRODS])
            g0 = int(p[tb + TT_ROD0])
            for gg in range(g0, g0 + n):
                p[int(p[H_OFF_ROD]) + gg * RT_SIZE + RT_LU] = L / n
                p[int(p[H_OFF_ROD]) + gg * RT_SIZE + RT_M] = rho * L / n
            l = L / n
            lam = 0.0
            Ld = 0.0
            Ldd = 0.0
        p[rs + RS_L] = L
        p[rs + RS_LD] = Ld
        p[rs + RS_LDD] = Ldd
        p[rs + RS_LROD] = l
        p[rs + RS_LAM] = lam
        p[rs + RS_KAP] = Ldd / l - 2.0 * lam * lam
    return 0


@njit(cache=True)
def reel_rod_load(q, qd, p, i, g, tension_only, energy):
    """Add to rod g (the first rod of reel i's tether; its forces just computed by rod_force) the
    apparent load of its growing material and the l' term of its strain rate (docs/deployment.md
    3.3).  The load per unit of the rod's coordinate xi in [-1, 1] (A at -1) is
    -(m/4)(1 - xi) E, linear, so its integrals are exact: R_1 = -3 m E/8, R_2 = -m E/8 and the
    moment sqrt3 int xi f = sqrt3 m E/6."""
    rs = int(p[H_OFF_RSCR]) + i * RS_SIZE
    if int(p[H_MUTANT]) == DEFECT_REEL_RESCALED:
        p[rs + RS_JUMP] = 0.0
        return
    rb = int(p[H_OFF_ROD]) + g * RT_SIZE
    sb = int(p[H_OFF_SCR]) + g * SR_SIZE
    lam = p[rs + RS_LAM]
    kap = p[rs + RS_KAP]
    m = p[rb + RT_M]
    k2 = 2.0 * SQ3
    # E = 2 lambda D' + kappa D with D = 2 sqrt3 d
    ex = k2 * (2.0 * lam * qd[3 + 3 * g] + kap * q[3 + 3 * g])
    ey = k2 * (2.0 * lam * qd[4 + 3 * g] + kap * q[4 + 3 * g])
    ez = k2 * (2.0 * lam * qd[5 + 3 * g] + kap * q[5 + 3 * g])
    r1x = -0.375 * m * ex
    r1y = -0.375 * m * ey
    r1z = -0.375 * m * ez
    r2x = -0.125 * m * ex
    r2y = -0.125 * m * ey
    r2z = -0.125 * m * ez
    c = SQ3 * m / 6.0
    qlx = c * ex
    qly = c * ey
    qlz = c * ez
    ux = p[sb + SR_U]
    uy = p[sb + SR_U + 1]
    uz = p[sb + SR_U + 2]
    eps = p[sb + SR_EPS]
    epsd = p[sb + SR_EPSD] - (1.0 + eps) * lam
    if int(p[H_MUTANT]) == DEFECT_REEL_NO_LDOT:  # the peers' strain rate (docs/deployment.md 3.3)
        epsd = p[sb + SR_EPSD]
    damp = p[rb + RT_D]
    if int(p[H_MUTANT]) == MUT_DAMPING_SIGN:
        damp = -damp
    fe = p[rb + RT_EA] * eps + damp * epsd
    if tension_only and (eps <= 0.0 or fe < 0.0):
        fe = 0.0
    dfe = fe - p[sb + SR_FE]
    if energy:
        k = 2.0 * SQ3 * dfe
        dqx = qlx - k * ux
        dqy = qly - k * uy
        dqz = qlz - k * uz
    else:  # paper eq. 26: axial (R_2 - R_1).u, transverse J(u) Q_lag, -2 F_E u
        ax_ = dot(r2x - r1x, r2y - r1y, r2z - r1z, ux, uy, uz)
        ql_u = dot(qlx, qly, qlz, ux, uy, uz)
        dqx = ax_ * ux + (qlx - ql_u * ux) - 2.0 * dfe * ux
        dqy = ax_ * uy + (qly - ql_u * uy) - 2.0 * dfe * uy
        dqz = ax_ * uz + (qlz - ql_u * uz) - 2.0 * dfe * uz
    p[sb + SR_R1] += r1x
    p[sb + SR_R1 + 1] += r1y
    p[sb + SR_R1 + 2] += r1z
    p[sb + SR_R2] += r2x
    p[sb + SR_R2 + 1] += r2y
    p[sb + SR_R2 + 2] += r2z
    p[sb + SR_Q] += dqx
    p[sb + SR_Q + 1] += dqy
    p[sb + SR_Q + 2] += dqz
    p[sb + SR_FE] = fe
    p[sb + SR_EPSD] = epsd
    # the momentum flux through the exit (reel_body_forces)
    ld = p[rs + RS_LD]
    p[rs + RS_JUMP] = p[int(p[H_OFF_REEL]) + i * RL_SIZE + RL_RHO] * ld * ld * (1.0 + eps)


@njit(cache=True)
def reel_body_forces(p):
    """Each reel's body feels the momentum flux through its exit, -rho l'^2 (1 + eps) u, besides
    the rod's reaction (docs/deployment.md 4): added to the body's effective force after its
    set-up.  A fixed body takes it into its support."""
    for i in range(int(p[H_NREEL])):
        rb = int(p[H_OFF_REEL]) + i * RL_SIZE
        rs = int(p[H_OFF_RSCR]) + i * RS_SIZE
        b = int(p[rb + RL_BODY])
        if not p[int(p[H_OFF_BODY]) + b * BT_SIZE + BT_INV_M] > 0.0:
            continue
        sb = int(p[H_OFF_SCR]) + int(p[rb + RL_ROD]) * SR_SIZE
        j = p[rs + RS_JUMP]
        F = int(p[H_OFF_BSCR]) + b * BS_SIZE + BS_F
        p[F] -= j * p[sb + SR_U]
        p[F + 1] -= j * p[sb + SR_U + 1]
        p[F + 2] -= j * p[sb + SR_U + 2]
        if p[int(p[H_OFF_BODY]) + b * BT_SIZE + BT_RIGID] != 0.0:  # the stored tether's inertia, the flux's moment
            reel_hub_terms(p, i, j, p[sb + SR_U], p[sb + SR_U + 1], p[sb + SR_U + 2])
