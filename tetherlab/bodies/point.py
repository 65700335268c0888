"""The point body: a mass at the root of a tree or at the end of a tether (paper eqs. 24, 35, 40).

Its part of the reaction solve (docs/model.md 12.4), called through bodies/parts.py:

* :func:`point_setup`: external force R and the effective system M = m I, F = R;
* :func:`point_add_child`: an eliminated child tether, J_0 = W (s_0 + a), adds M += W, F -= W s_0;
* :func:`point_compliance`: seen from the tether it hangs on, a = C J_n + f: without children
  C = I/m, f = R/m; with children C = M^-1, f = M^-1 F;
* :func:`point_root_solve`: a root's own 3x3, M a = F;
* :func:`point_back_substitute`: its acceleration once its parent tether's J_n is known;
* :func:`point_share`: its momentum, angular momentum, kinetic and potential energy.

It has no state of its own (a non-root's position follows from its tether, a root's is in q).
"""

from __future__ import annotations

from .._jit import njit
from ..kernel.effects import body_force, potential_per_mass
from ..kernel.layout import (
    BS_A,
    BS_C,
    BS_CF,
    BS_F,
    BS_M,
    BS_MI,
    BS_R,
    BS_SIZE,
    BS_V,
    BT_INV_M,
    BT_M,
    BT_NCHILD,
    BT_SIZE,
    H_OFF_BODY,
    H_OFF_BSCR,
)
from ..kernel.shares import SH_HX, SH_HY, SH_HZ, SH_KE, SH_PX, SH_PY, SH_PZ, SH_VG
from ..kernel.vec3 import inv3, mat_vec
from .common import set_body_state


@njit(cache=True)
def point_force(t, p, b):
    """The external force on body b at its centre of mass (its scratch holds r, v); zero on a
    fixed body."""
    bt = int(p[H_OFF_BODY]) + b * BT_SIZE
    bs = int(p[H_OFF_BSCR]) + b * BS_SIZE
    if p[bt + BT_INV_M] > 0.0:
        return body_force(
            p, t, b, p[bs + BS_R], p[bs + BS_R + 1], p[bs + BS_R + 2],
            p[bs + BS_V], p[bs + BS_V + 1], p[bs + BS_V + 2], p[bt + BT_M],
        )
    return 0.0, 0.0, 0.0


@njit(cache=True)
def point_setup(t, p, b):
    """M = m I, F = R (before its children are added)."""
    bt = int(p[H_OFF_BODY]) + b * BT_SIZE
    bs = int(p[H_OFF_BSCR]) + b * BS_SIZE
    m = p[bt + BT_M]
    fx, fy, fz = point_force(t, p, b)
    M = bs + BS_M
    F = bs + BS_F
    for c in range(9):
        p[M + c] = 0.0
    p[M] = m
    p[M + 4] = m
    p[M + 8] = m
    p[F] = fx
    p[F + 1] = fy
    p[F + 2] = fz


@njit(cache=True)
def point_add_child(p, b, W, s0):
    """Add the eliminated child tether J_0 = W (s_0 + a) (W at p[W], s_0 at p[s0])."""
    bs = int(p[H_OFF_BSCR]) + b * BS_SIZE
    M = bs + BS_M
    F = bs + BS_F
    for a in range(3):
        for c in range(3):
            p[M + 3 * a + c] += p[W + 3 * a + c]
        p[F + a] -= p[W + 3 * a] * p[s0] + p[W + 3 * a + 1] * p[s0 + 1] + p[W + 3 * a + 2] * p[s0 + 2]


@njit(cache=True)
def point_compliance(p, c):
    """a = C J_n + f of body c at the end of its parent tether, into BS_C and BS_CF.  Returns the
    determinant of the system inverted (1.0 without children: nothing is inverted)."""
    bt = int(p[H_OFF_BODY]) + c * BT_SIZE
    bs = int(p[H_OFF_BSCR]) + c * BS_SIZE
    C = bs + BS_C
    f = bs + BS_CF
    F = bs + BS_F
    if p[bt + BT_NCHILD] == 0.0:
        inv_m = p[bt + BT_INV_M]
        for a in range(9):
            p[C + a] = 0.0
        p[C] = inv_m
        p[C + 4] = inv_m
        p[C + 8] = inv_m
        p[f] = p[F] * inv_m
        p[f + 1] = p[F + 1] * inv_m
        p[f + 2] = p[F + 2] * inv_m
        return 1.0
    Mi = bs + BS_MI
    det = inv3(p, bs + BS_M, p, Mi)
    if det == 0.0:
        return det
    for a in range(9):
        p[C + a] = p[Mi + a]
    fx, fy, fz = mat_vec(p, Mi, p[F], p[F + 1], p[F + 2])
    p[f] = fx
    p[f + 1] = fy
    p[f + 2] = fz
    return det


@njit(cache=True)
def point_root_solve(p, b):
    """A root's acceleration from M a = F into BS_A; returns det M (0: singular)."""
    bs = int(p[H_OFF_BSCR]) + b * BS_SIZE
    Mi = bs + BS_MI
    det = inv3(p, bs + BS_M, p, Mi)
    if det == 0.0:
        return det
    F = bs + BS_F
    ax, ay, az = mat_vec(p, Mi, p[F], p[F + 1], p[F + 2])
    p[bs + BS_A] = ax
    p[bs + BS_A + 1] = ay
    p[bs + BS_A + 2] = az
    return det


@njit(cache=True)
def point_back_substitute(p, c, jn):
    """Body c's acceleration once the reaction J_n (at p[jn]) of its parent tether is known:
    a = M^-1 (F + J_n).  A body without children needs none (nothing hangs on it)."""
    bt = int(p[H_OFF_BODY]) + c * BT_SIZE
    if p[bt + BT_NCHILD] == 0.0:
        return
    bs = int(p[H_OFF_BSCR]) + c * BS_SIZE
    F = bs + BS_F
    ax, ay, az = mat_vec(p, bs + BS_MI, p[F] + p[jn], p[F + 1] + p[jn + 1], p[F + 2] + p[jn + 2])
    p[bs + BS_A] = ax
    p[bs + BS_A + 1] = ay
    p[bs + BS_A + 2] = az


@njit(cache=True)
def point_share(t, p, b, sh):
    """Add body b's translational share to ``sh`` (kernel/shares.py): m v, m r x v, 1/2 m v^2 and
    m times the potential per unit mass of the effects at r."""
    bt = int(p[H_OFF_BODY]) + b * BT_SIZE
    bs = int(p[H_OFF_BSCR]) + b * BS_SIZE
    m = p[bt + BT_M]
    rx = p[bs + BS_R]
    ry = p[bs + BS_R + 1]
    rz = p[bs + BS_R + 2]
    vx = p[bs + BS_V]
    vy = p[bs + BS_V + 1]
    vz = p[bs + BS_V + 2]
    sh[SH_PX] += m * vx
    sh[SH_PY] += m * vy
    sh[SH_PZ] += m * vz
    sh[SH_HX] += m * (ry * vz - rz * vy)
    sh[SH_HY] += m * (rz * vx - rx * vz)
    sh[SH_HZ] += m * (rx * vy - ry * vx)
    sh[SH_KE] += 0.5 * m * (vx * vx + vy * vy + vz * vz)
    sh[SH_VG] += m * potential_per_mass(p, t, rx, ry, rz)


# -- the part interface (bodies/registry.py; the dispatcher bodies/parts.py calls these) -----------
@njit(cache=True, inline="always")
def root_state(att, p, b):
    """Nothing beyond the centre of mass the driver wrote: a point has no attitude."""


@njit(cache=True, inline="always")
def end_state(att, p, c, bx, by, bz, bvx, bvy, bvz):
    """A point at the end B_n of its tether is at B_n."""
    set_body_state(p, c, bx, by, bz, bvx, bvy, bvz)


@njit(cache=True, inline="always")
def attach(p, b, tb, ts, ax, ay, az, avx, avy, avz):
    """A tether attached to a point starts at the point."""
    return ax, ay, az, avx, avy, avz


@njit(cache=True, inline="always")
def setup(t, att, p, b, datt):
    point_setup(t, p, b)


@njit(cache=True, inline="always")
def add_child(p, b, k, W, s0):
    point_add_child(p, b, W, s0)


@njit(cache=True, inline="always")
def compliance(p, c, work):
    return point_compliance(p, c)


@njit(cache=True, inline="always")
def root_solve(p, b):
    return point_root_solve(p, b)


@njit(cache=True, inline="always")
def point_acceleration(p, b, ts):
    """Every attachment on a point moves with it."""
    A = int(p[H_OFF_BSCR]) + b * BS_SIZE + BS_A
    return p[A], p[A + 1], p[A + 2]


@njit(cache=True, inline="always")
def back_substitute(p, c, jn):
    point_back_substitute(p, c, jn)


@njit(cache=True, inline="always")
def derivatives(att, p, b, datt):
    """No state of its own: nothing to differentiate."""
    return True


@njit(cache=True, inline="always")
def share(t, att, p, b, sh):
    point_share(t, p, b, sh)
