"""The inextensible rod chain: TMED rods whose lengths are held by constraints (compiled).

Each rod keeps its unstretched length, |D_i| = l_i with D_i = 2 sqrt3 d_i the rod vector; its
tension is no longer EA eps + D eps' (paper eq. 1) but the Lagrange multiplier lambda_i of that
constraint, solved with the joint reactions in the same block Thomas elimination as the elastic
chain (tether/chain.py).  docs/inextensible.md derives it; in short, with u = d/|d|, S = J_{i-1} + J_i
and h = l / (2 sqrt3) the constrained |d|:

    elastic rod (eq. 26):   m d'' = Q0 - 2 lambda u - C S,       C = sqrt3 I + (1 - sqrt3) u u^T
    constraint (phi = (|d|^2 - h^2)/2, stabilised):   phi'' + 2 a phi' + a^2 phi = 0
                             u.d'' = -kappa,  kappa = (|d'|^2 + 2 a d.d' + a^2 phi) / |d|

Eliminating lambda (u^T C = u^T):

    m d'' = J(u) Q0 - mkappa u - sqrt3 J(u) S                   (I1)
    2 lambda = u.Q0 - u.S + m kappa                              (I2)

(I1) is eq. 26 with Q -> J(u) Q0 - m kappa u and C -> sqrt3 J(u) = sqrt3 I - sqrt3 u u^T, so the
joint rows, the elimination and the back substitution of the chain run unchanged on these
coefficients (O(n)); (I2) gives each rod's tension from the reactions once they are known.  The
walk writes u.Q0 + m kappa into the rod's axial-force slot, the back substitution replaces it with
lambda: the axial-force output of an inextensible tether is its tension multiplier.

Constraint stabilisation: Baumgarte's, critically damped, with the rate a of each rod's record
(RT_CRATE; 0 switches it off, and the constraint is then only held at the acceleration level).
"""

from __future__ import annotations

from .._jit import njit
from ..kernel.layout import (
    DEFECT_INEXT_NO_VSQ,
    H_MUTANT,
    H_NRODS,
    H_OFF_ROD,
    H_OFF_SCR,
    H_OFF_TETH,
    RT_CRATE,
    RT_LU,
    RT_M,
    RT_SIZE,
    SJ_J,
    SJ_SIZE,
    SR_C,
    SR_FE,
    SR_Q,
    SR_SIZE,
    SR_U,
    TT_NRODS,
    TT_ROD0,
    TT_SIZE,
)
from .chain import chain_back_substitute, chain_reduce
from .rod import SQ3, next_joint, rod_constants, rod_force, rod_share

__all__ = ["inextensible_walk", "inextensible_back_substitute", "walk", "reduce", "back_substitute", "share"]


@njit(cache=True, inline="always")
def _constrain(q, qd, p, g):
    """Turn rod g's elastic coefficients (written by rod_force, paper model) into the constrained
    ones of (I1): Q <- J(u) Q - m kappa u, C <- sqrt3 J(u); the axial-force slot <- u.Q0 + m kappa,
    the part of 2 lambda (I2) that does not depend on the reactions."""
    sb = int(p[H_OFF_SCR]) + g * SR_SIZE
    rb = int(p[H_OFF_ROD]) + g * RT_SIZE
    m = p[rb + RT_M]
    a = p[rb + RT_CRATE]
    hh = p[rb + RT_LU] / (2.0 * SQ3)
    dx = q[3 + 3 * g]
    dy = q[4 + 3 * g]
    dz = q[5 + 3 * g]
    vx = qd[3 + 3 * g]
    vy = qd[4 + 3 * g]
    vz = qd[5 + 3 * g]
    ux = p[sb + SR_U]
    uy = p[sb + SR_U + 1]
    uz = p[sb + SR_U + 2]
    dn = dx * ux + dy * uy + dz * uz  # |d|
    phi = 0.5 * (dn - hh) * (dn + hh)  # (|d|^2 - h^2) / 2, without the cancellation of dn^2 - hh^2
    phid = dx * vx + dy * vy + dz * vz
    vv = vx * vx + vy * vy + vz * vz  # |d'|^2: the centripetal part of (C2)
    if int(p[H_MUTANT]) == DEFECT_INEXT_NO_VSQ:  # 0 in every user run (tetherlab/mutants.py)
        vv = 0.0
    kappa = (vv + 2.0 * a * phid + a * a * phi) / dn
    qx = p[sb + SR_Q]
    qy = p[sb + SR_Q + 1]
    qz = p[sb + SR_Q + 2]
    qu = qx * ux + qy * uy + qz * uz
    # u.Q0: rod_force put -2 F_E u in Q (eq. 26); the constrained rod has no elastic force
    p[sb + SR_FE] = qu + 2.0 * p[sb + SR_FE] + m * kappa
    s = qu + m * kappa
    p[sb + SR_Q] = qx - s * ux
    p[sb + SR_Q + 1] = qy - s * uy
    p[sb + SR_Q + 2] = qz - s * uz
    p[sb + SR_C] = SQ3
    p[sb + SR_C + 1] = -SQ3


@njit(cache=True)
def inextensible_walk(t, q, qd, p, k, with_forces, ax, ay, az, avx, avy, avz):
    """Walk tether k from A_1 to B_n (eq. 23), computing (with_forces) every rod's distributed
    loads (tether/rod.py, the paper model's coefficients) and its constrained coefficients.
    Returns (failure code, r_B, v_B)."""
    tb = int(p[H_OFF_TETH]) + k * TT_SIZE
    n = int(p[tb + TT_NRODS])
    g0 = int(p[tb + TT_ROD0])
    rc = rod_constants(p)
    for g in range(g0, g0 + n):
        if with_forces:
            code = rod_force(t, q, qd, p, g, rc, False, False, False, ax, ay, az, avx, avy, avz)
            if code != 0:
                return code, ax, ay, az, avx, avy, avz
            _constrain(q, qd, p, g)
        ax, ay, az, avx, avy, avz = next_joint(q, qd, g, ax, ay, az, avx, avy, avz)
    return 0, ax, ay, az, avx, avy, avz


@njit(cache=True)
def inextensible_back_substitute(t, p, k, aax, aay, aaz, acc):
    """The chain's back substitution (every J_k and d'') on the constrained coefficients, then
    each rod's tension lambda = (u.Q0 + m kappa - u.(J_{i-1} + J_i)) / 2 (I2) into its
    axial-force slot.  Returns a failure code."""
    code = chain_back_substitute(t, p, k, aax, aay, aaz, acc)
    if code != 0:
        return code
    tb = int(p[H_OFF_TETH]) + k * TT_SIZE
    n = int(p[tb + TT_NRODS])
    g0 = int(p[tb + TT_ROD0])
    scr = int(p[H_OFF_SCR])
    ja = scr + int(p[H_NRODS]) * SR_SIZE + (g0 + k) * SJ_SIZE + SJ_J  # J_0 of this tether
    for g in range(g0, g0 + n):
        sb = scr + g * SR_SIZE
        jb = ja + SJ_SIZE
        su = ((p[ja] + p[jb]) * p[sb + SR_U] + (p[ja + 1] + p[jb + 1]) * p[sb + SR_U + 1]
              + (p[ja + 2] + p[jb + 2]) * p[sb + SR_U + 2])  # fmt: skip
        p[sb + SR_FE] = 0.5 * (p[sb + SR_FE] - su)
        ja = jb
    return 0


@njit(cache=True)
def inextensible_share(t, q, qd, p, k, elastic, ax, ay, az, avx, avy, avz, sh):
    """The rods' energy and momentum shares (tether/rod.py, rod_share): kinetic and potential;
    an inextensible rod stores no elastic energy."""
    tb = int(p[H_OFF_TETH]) + k * TT_SIZE
    n = int(p[tb + TT_NRODS])
    g0 = int(p[tb + TT_ROD0])
    for g in range(g0, g0 + n):
        rod_share(t, q, qd, p, g, False, False, ax, ay, az, avx, avy, avz, sh)
        ax, ay, az, avx, avy, avz = next_joint(q, qd, g, ax, ay, az, avx, avy, avz)


# -- the tether part interface (tether/registry.py; the dispatcher tether/parts.py calls these) ----
@njit(cache=True, inline="always")
def walk(t, q, qd, p, k, with_forces, ax, ay, az, avx, avy, avz):
    return inextensible_walk(t, q, qd, p, k, with_forces, ax, ay, az, avx, avy, avz)


@njit(cache=True, inline="always")
def reduce(t, p, k):
    return chain_reduce(t, p, k)


@njit(cache=True, inline="always")
def back_substitute(t, p, k, aax, aay, aaz, acc):
    return inextensible_back_substitute(t, p, k, aax, aay, aaz, acc)


@njit(cache=True, inline="always")
def share(t, q, qd, p, k, elastic, ax, ay, az, avx, avy, avz, sh):
    inextensible_share(t, q, qd, p, k, elastic, ax, ay, az, avx, avy, avz, sh)
