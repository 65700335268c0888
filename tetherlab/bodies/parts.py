"""The body parts' registry: every interface function of a body, dispatched on its part kind.

Each body carries one part-kind code, written once by build_model (layout BT_PART: PART_POINT,
PART_RIGID).  Numba has no virtual calls, so each interface function below is one branch per
kind into the part's own module (bodies/point.py, bodies/rigid_body.py); the forest driver
(tether/solve.py) calls only these.  A new body part type: its module with these functions, its
kind code in kernel/layout.py, and one branch in each function here.

The interface, in the driver's order (docs/model.md 12.4):

    body_root_state / body_end_state   kinematics (a root from q; a child from its tether's end)
    body_attach                        the attachment point of a child tether on the body
    body_setup                         external forces, own torques and derivatives, M and F
    body_add_child                     an eliminated child tether's compliance into M, F
    body_compliance                    a_B = C J_n + f, as its parent tether's tip row needs it
    body_root_solve                    a root's own system M a = F
    body_point_acceleration            a_A of a child tether's attachment point
    body_back_substitute               its acceleration once its parent's J_n is known
    body_derivatives                   its own state's derivatives (attitude)
    body_share                         its energy and momentum share
"""

from __future__ import annotations

from .._jit import njit
from ..kernel.layout import (
    BS_A,
    BS_R,
    BS_SIZE,
    BS_V,
    BT_INV_M,
    BT_M,
    BT_PART,
    BT_PT,
    BT_SIZE,
    H_OFF_BODY,
    H_OFF_BSCR,
    PART_RIGID,
    TS_KAP,
    TS_RHO,
    TT_PA,
)
from .point import point_add_child, point_back_substitute, point_compliance, point_root_solve, point_setup, point_share
from .rigid_body import (
    rigid_add_child,
    rigid_attitude,
    rigid_back_substitute,
    rigid_compliance,
    rigid_derivatives,
    rigid_offset,
    rigid_point_acceleration,
    rigid_root_solve,
    rigid_setup,
    rigid_share,
)


@njit(cache=True, inline="always")
def body_kind(p, b):
    return int(p[int(p[H_OFF_BODY]) + b * BT_SIZE + BT_PART])


@njit(cache=True, inline="always")
def _set_state(p, b, rx, ry, rz, vx, vy, vz):
    bs = int(p[H_OFF_BSCR]) + b * BS_SIZE
    p[bs + BS_R] = rx
    p[bs + BS_R + 1] = ry
    p[bs + BS_R + 2] = rz
    p[bs + BS_V] = vx
    p[bs + BS_V + 1] = vy
    p[bs + BS_V + 2] = vz


@njit(cache=True, inline="always")
def body_root_state(att, p, b, rx, ry, rz, vx, vy, vz):
    """A root's centre of mass (from q) into its scratch, and its attitude."""
    _set_state(p, b, rx, ry, rz, vx, vy, vz)
    if body_kind(p, b) == PART_RIGID:
        rigid_attitude(att, p, b)


@njit(cache=True, inline="always")
def body_end_state(att, p, c, bx, by, bz, bvx, bvy, bvz):
    """Body c at the end B_n (position, velocity) of its parent tether: its centre of mass
    (r_G = r_B - R rho_b on a rigid body) and attitude into its scratch."""
    if body_kind(p, c) == PART_RIGID:
        rigid_attitude(att, p, c)
        pt = int(p[H_OFF_BODY]) + c * BT_SIZE + BT_PT
        rx, ry, rz, vx, vy, vz, kx, ky, kz = rigid_offset(p, c, p[pt], p[pt + 1], p[pt + 2])
        _set_state(p, c, bx - rx, by - ry, bz - rz, bvx - vx, bvy - vy, bvz - vz)
    else:
        _set_state(p, c, bx, by, bz, bvx, bvy, bvz)


@njit(cache=True, inline="always")
def body_attach(p, b, tb, ts, ax, ay, az, avx, avy, avz):
    """The attachment point A_1 of the tether (table tb, scratch ts) on body b, from b's centre
    of mass (ax.., avx..): a rigid body adds rho = R rho_b (and keeps rho, kappa in ts)."""
    if body_kind(p, b) == PART_RIGID:
        rx, ry, rz, vx, vy, vz, kx, ky, kz = rigid_offset(p, b, p[tb + TT_PA], p[tb + TT_PA + 1], p[tb + TT_PA + 2])
        p[ts + TS_RHO] = rx
        p[ts + TS_RHO + 1] = ry
        p[ts + TS_RHO + 2] = rz
        p[ts + TS_KAP] = kx
        p[ts + TS_KAP + 1] = ky
        p[ts + TS_KAP + 2] = kz
        return ax + rx, ay + ry, az + rz, avx + vx, avy + vy, avz + vz
    return ax, ay, az, avx, avy, avz


@njit(cache=True, inline="always")
def body_setup(t, att, p, b, datt):
    if body_kind(p, b) == PART_RIGID:
        rigid_setup(t, att, p, b, datt)
    else:
        point_setup(t, p, b)


@njit(cache=True, inline="always")
def body_add_child(p, b, k, W, s0):
    """Add the eliminated child tether k (J_0 = W (s_0 + a_A)) to body b; nothing on a fixed body."""
    if p[int(p[H_OFF_BODY]) + b * BT_SIZE + BT_INV_M] == 0.0:
        return
    if body_kind(p, b) == PART_RIGID:
        rigid_add_child(p, b, k, W, s0)
    else:
        point_add_child(p, b, W, s0)


@njit(cache=True, inline="always")
def body_compliance(p, c, work):
    """Returns the determinant of what it inverted (0 or non-finite: singular)."""
    if body_kind(p, c) == PART_RIGID:
        return rigid_compliance(p, c, work)
    return point_compliance(p, c)


@njit(cache=True, inline="always")
def body_root_solve(p, b):
    """A root's accelerations into BS_A (zero on a fixed body); returns the determinant."""
    A = int(p[H_OFF_BSCR]) + b * BS_SIZE + BS_A
    for c in range(6):
        p[A + c] = 0.0
    if not p[int(p[H_OFF_BODY]) + b * BT_SIZE + BT_INV_M] > 0.0:
        return 1.0
    if body_kind(p, b) == PART_RIGID:
        return rigid_root_solve(p, b)
    return point_root_solve(p, b)


@njit(cache=True, inline="always")
def body_point_acceleration(p, b, ts):
    """Acceleration of the attachment point of the tether with scratch ts on body b."""
    if body_kind(p, b) == PART_RIGID:
        return rigid_point_acceleration(p, b, ts)
    A = int(p[H_OFF_BSCR]) + b * BS_SIZE + BS_A
    return p[A], p[A + 1], p[A + 2]


@njit(cache=True, inline="always")
def body_back_substitute(p, c, jn):
    if body_kind(p, c) == PART_RIGID:
        rigid_back_substitute(p, c, jn)
    else:
        point_back_substitute(p, c, jn)


@njit(cache=True, inline="always")
def body_derivatives(att, p, b, datt):
    """False if a derivative came out non-finite."""
    if body_kind(p, b) == PART_RIGID:
        return rigid_derivatives(att, p, b, datt)
    return True


@njit(cache=True, inline="always")
def body_share(t, att, p, b, sh):
    """Body b's energy and momentum share (nothing for a fixed body)."""
    if not p[int(p[H_OFF_BODY]) + b * BT_SIZE + BT_M] > 0.0:
        return
    if body_kind(p, b) == PART_RIGID:
        rigid_share(t, att, p, b, sh)
    else:
        point_share(t, p, b, sh)
