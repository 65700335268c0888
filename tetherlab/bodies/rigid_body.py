"""The rigid body with its wheel set: one part of the reaction solve (paper eqs. 44-47;
docs/model.md 12.2-12.5; eqs. 45-46 with the wheels, eq. 48-49 the attached tethers).  Kinematics helpers are in bodies/rigid.py, the wheel set in
bodies/wheels.py, the control law in bodies/control.py.

Its generalised acceleration a6 = (a_G, alpha) (inertial axes) obeys

    M6 a6 = F6 + sum_P G_P^T F_P,   M6 = diag(m I, R J_s R^T),
    F6 = (R_B, R [M_gg - sum a_k tau_k - omega_b x (J_s omega_b + h_w)]),

with G_P = [I, -[rho]x] for a force F_P at the body-fixed point rho_b (rho = R rho_b).  The part
interface, called through bodies/parts.py:

* :func:`rigid_attitude`, :func:`rigid_offset`: R, omega and the attachment kinematics (eq. 47');
* :func:`rigid_setup`: M6, F6 with the wheel set's torques (its derivatives h_k' = tau_k);
* :func:`rigid_add_child`: M6 += G^T W G, F6 -= G^T W (s_0 + kappa) for an eliminated child tether;
* :func:`rigid_compliance`: seen from its parent tether, a_B = C J_n + f with
  C = G M6^-1 G^T, f = G M6^-1 F6 + kappa;
* :func:`rigid_root_solve`, :func:`rigid_back_substitute`: a6 (6x6);
* :func:`rigid_point_acceleration`: a_A = a_G + alpha x rho + kappa of a tether's attachment;
* :func:`rigid_derivatives`: q' = 1/2 q (x) omega_b, omega_b' = R^T alpha;
* :func:`rigid_share`: translational share plus R (J_s omega + h_w), 1/2 omega.J_s omega +
  sum h_k^2/(2 I_k) and the gravity-gradient potential.
"""

from __future__ import annotations

import math

from .._jit import njit
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
    BT_JB,
    BT_JS,
    BT_M,
    BT_NW,
    BT_PT,
    BT_SIZE,
    BT_W0,
    DEFECT_NO_CENTRIPETAL,
    DEFECT_UNROTATED_ATTACHMENT,
    DEFECT_WHEELS_NO_GYRO,
    H_DEFECT,
    H_MU_GG,
    H_NBODY,
    H_NTETH,
    H_OFF_ATT,
    H_OFF_BODY,
    H_OFF_BSCR,
    H_OFF_WHL,
    TS_KAP,
    TS_RHO,
    TS_SIZE,
    TT_PA,
)
from ..kernel.shares import SH_HX, SH_HY, SH_HZ, SH_KE, SH_KROT, SH_VG
from ..kernel.vec3 import cross, inv_n, mat_t_vec, mat_vec, mat_vec_n
from .common import set_body_state
from .control import pd_torque
from .point import point_force, point_share
from .rigid import gravity_gradient_potential, gravity_gradient_torque, quat_rate, rotation
from .wheels import wheel_set_share, wheel_set_torques


@njit(cache=True)
def rigid_attitude(att, p, b):
    """R(q) and omega (inertial axes) of rigid body b into its scratch."""
    bt = int(p[H_OFF_BODY]) + b * BT_SIZE
    bs = int(p[H_OFF_BSCR]) + b * BS_SIZE
    ao = int(p[bt + BT_AOFF]) - int(p[H_OFF_ATT])
    rotation(p, bs + BS_ROT, att[ao], att[ao + 1], att[ao + 2], att[ao + 3])
    wx, wy, wz = mat_vec(p, bs + BS_ROT, att[ao + 4], att[ao + 5], att[ao + 6])
    p[bs + BS_W] = wx
    p[bs + BS_W + 1] = wy
    p[bs + BS_W + 2] = wz


@njit(cache=True)
def _rho(p, b, bx, by, bz):
    """rho = R rho_b of a body-fixed point (the defect switch of the negative controls leaves it
    unrotated)."""
    if int(p[H_DEFECT]) == DEFECT_UNROTATED_ATTACHMENT:
        return bx, by, bz
    return mat_vec(p, int(p[H_OFF_BSCR]) + b * BS_SIZE + BS_ROT, bx, by, bz)


@njit(cache=True)
def rigid_offset(p, b, bx, by, bz):
    """Inertial offset rho = R rho_b of a body-fixed point of body b (attitude in its scratch),
    the velocity term omega x rho and kappa = omega x (omega x rho).  The defect switch (negative
    controls only) uses rho_b unrotated or drops kappa."""
    bs = int(p[H_OFF_BSCR]) + b * BS_SIZE
    rx, ry, rz = _rho(p, b, bx, by, bz)
    wx = p[bs + BS_W]
    wy = p[bs + BS_W + 1]
    wz = p[bs + BS_W + 2]
    vx, vy, vz = cross(wx, wy, wz, rx, ry, rz)
    kx, ky, kz = cross(wx, wy, wz, vx, vy, vz)
    if int(p[H_DEFECT]) == DEFECT_NO_CENTRIPETAL:
        kx = 0.0
        ky = 0.0
        kz = 0.0
    return rx, ry, rz, vx, vy, vz, kx, ky, kz


@njit(cache=True)
def rigid_setup(t, att, p, b, datt):
    """M6 = diag(m I, R J_s R^T) and F6 = (R, R tau_b) with tau_b = M_gg - sum_k a_k tau_k -
    omega_b x (J_s omega_b + h_w) (docs/model.md 12), before its children are added; the control
    torque and the wheel set's torques (and derivatives) on the way."""
    bt = int(p[H_OFF_BODY]) + b * BT_SIZE
    bs = int(p[H_OFF_BSCR]) + b * BS_SIZE
    m = p[bt + BT_M]
    rx = p[bs + BS_R]
    ry = p[bs + BS_R + 1]
    rz = p[bs + BS_R + 2]
    vx = p[bs + BS_V]
    vy = p[bs + BS_V + 1]
    vz = p[bs + BS_V + 2]
    fx, fy, fz = point_force(t, p, b)
    M = bs + BS_M
    F = bs + BS_F
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
    whl = int(p[H_OFF_WHL]) - int(p[H_OFF_ATT])
    wscr = int(p[H_OFF_BSCR]) + int(p[H_NBODY]) * BS_SIZE + int(p[H_NTETH]) * TS_SIZE
    hwx, hwy, hwz, tqx, tqy, tqz = wheel_set_torques(
        p, t, att, int(p[bt + BT_W0]), int(p[bt + BT_NW]), wbx, wby, wbz, ux, uy, uz, wscr, whl, datt
    )
    js = bt + BT_JS
    jx, jy, jz = mat_vec(p, js, wbx, wby, wbz)
    if int(p[H_DEFECT]) == DEFECT_WHEELS_NO_GYRO:  # the negative control of the wheels' share (0 in user runs)
        hwx = 0.0
        hwy = 0.0
        hwz = 0.0
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
def rigid_add_child(p, b, k, W, s0):
    """Add the eliminated child tether k (J_0 = W (s_0 + a_A), attached at rho in its tether
    scratch): M6 += G^T W G = [[W, -W X], [X W, -X W X]], F6 -= G^T W (s_0 + kappa) = (v, rho x v)."""
    bs = int(p[H_OFF_BSCR]) + b * BS_SIZE
    M = bs + BS_M
    F = bs + BS_F
    ts = int(p[H_OFF_BSCR]) + int(p[H_NBODY]) * BS_SIZE + k * TS_SIZE
    rx = p[ts + TS_RHO]
    ry = p[ts + TS_RHO + 1]
    rz = p[ts + TS_RHO + 2]
    v0, v1, v2 = mat_vec(p, W, p[s0] + p[ts + TS_KAP], p[s0 + 1] + p[ts + TS_KAP + 1], p[s0 + 2] + p[ts + TS_KAP + 2])
    c0, c1, c2 = cross(rx, ry, rz, v0, v1, v2)
    p[F] -= v0
    p[F + 1] -= v1
    p[F + 2] -= v2
    p[F + 3] -= c0
    p[F + 4] -= c1
    p[F + 5] -= c2
    for col in range(3):
        # column col of W, of W X (= -(W col of X)) and of X W X
        ex = 1.0 if col == 0 else 0.0
        ey = 1.0 if col == 1 else 0.0
        ez = 1.0 if col == 2 else 0.0
        xbx, xby, xbz = cross(rx, ry, rz, ex, ey, ez)  # X e_col
        wcx = p[W + col]
        wcy = p[W + 3 + col]
        wcz = p[W + 6 + col]
        wxx, wxy, wxz = mat_vec(p, W, xbx, xby, xbz)  # W X e_col
        xwx, xwy, xwz = cross(rx, ry, rz, wcx, wcy, wcz)  # X W e_col
        xwxx, xwxy, xwxz = cross(rx, ry, rz, wxx, wxy, wxz)  # X W X e_col
        p[M + col] += wcx
        p[M + 6 + col] += wcy
        p[M + 12 + col] += wcz
        p[M + 3 + col] -= wxx
        p[M + 9 + col] -= wxy
        p[M + 15 + col] -= wxz
        p[M + 18 + col] += xwx
        p[M + 24 + col] += xwy
        p[M + 30 + col] += xwz
        p[M + 21 + col] -= xwxx
        p[M + 27 + col] -= xwxy
        p[M + 33 + col] -= xwxz


@njit(cache=True)
def rigid_compliance(p, c, work):
    """a_B = C J_n + f of the attachment point of body c on its parent tether, into BS_C and
    BS_CF (``work``: 24 floats of scratch).  Returns det M6 (0: singular)."""
    bt = int(p[H_OFF_BODY]) + c * BT_SIZE
    bs = int(p[H_OFF_BSCR]) + c * BS_SIZE
    Mi = bs + BS_MI
    F = bs + BS_F
    C = bs + BS_C
    f = bs + BS_CF
    det = inv_n(p, bs + BS_M, Mi, 6)
    if det == 0.0 or not math.isfinite(det):
        return det
    rx, ry, rz, vx, vy, vz, kx, ky, kz = rigid_offset(p, c, p[bt + BT_PT], p[bt + BT_PT + 1], p[bt + BT_PT + 2])
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
    mat_vec_n(p, Mi, F, v, 6)
    cx, cy, cz = cross(rx, ry, rz, p[v + 3], p[v + 4], p[v + 5])
    p[f] = p[v] - cx + kx
    p[f + 1] = p[v + 1] - cy + ky
    p[f + 2] = p[v + 2] - cz + kz
    return det


@njit(cache=True)
def rigid_root_solve(p, b):
    """A root's a6 from M6 a6 = F6 into BS_A; returns det M6 (0: singular)."""
    bs = int(p[H_OFF_BSCR]) + b * BS_SIZE
    det = inv_n(p, bs + BS_M, bs + BS_MI, 6)
    if det == 0.0 or not math.isfinite(det):
        return det
    mat_vec_n(p, bs + BS_MI, bs + BS_F, bs + BS_A, 6)
    return det


@njit(cache=True)
def rigid_back_substitute(p, c, jn):
    """Body c's a6 = M6eff^-1 (F6eff + G^T J_n) once its parent tether's J_n (at p[jn]) is known."""
    bt = int(p[H_OFF_BODY]) + c * BT_SIZE
    bs = int(p[H_OFF_BSCR]) + c * BS_SIZE
    Mi = bs + BS_MI
    F = bs + BS_F
    A = bs + BS_A
    rx, ry, rz = _rho(p, c, p[bt + BT_PT], p[bt + BT_PT + 1], p[bt + BT_PT + 2])
    tx, ty, tz = cross(rx, ry, rz, p[jn], p[jn + 1], p[jn + 2])
    gf = (p[jn], p[jn + 1], p[jn + 2], tx, ty, tz)
    for a in range(6):
        s = 0.0
        for j in range(6):
            s += p[Mi + 6 * a + j] * (p[F + j] + gf[j])
        p[A + a] = s


@njit(cache=True)
def rigid_point_acceleration(p, b, ts):
    """a_A = a_G + alpha x rho + kappa of the attachment point of the tether whose scratch is at
    ts (rho, kappa there), from body b's a6."""
    A = int(p[H_OFF_BSCR]) + b * BS_SIZE + BS_A
    cx, cy, cz = cross(p[A + 3], p[A + 4], p[A + 5], p[ts + TS_RHO], p[ts + TS_RHO + 1], p[ts + TS_RHO + 2])
    return p[A] + (cx + p[ts + TS_KAP]), p[A + 1] + (cy + p[ts + TS_KAP + 1]), p[A + 2] + (cz + p[ts + TS_KAP + 2])


@njit(cache=True)
def rigid_derivatives(att, p, b, datt):
    """omega_b' = R^T alpha, q' = 1/2 q (x) omega_b into ``datt``.  False if not finite."""
    bt = int(p[H_OFF_BODY]) + b * BT_SIZE
    bs = int(p[H_OFF_BSCR]) + b * BS_SIZE
    ao = int(p[bt + BT_AOFF]) - int(p[H_OFF_ATT])
    dwx, dwy, dwz = mat_t_vec(p, bs + BS_ROT, p[bs + BS_A + 3], p[bs + BS_A + 4], p[bs + BS_A + 5])
    if not (math.isfinite(dwx) and math.isfinite(dwy) and math.isfinite(dwz)):
        return False
    dqw, dqx, dqy, dqz = quat_rate(att[ao], att[ao + 1], att[ao + 2], att[ao + 3], att[ao + 4], att[ao + 5], att[ao + 6])
    datt[ao] = dqw
    datt[ao + 1] = dqx
    datt[ao + 2] = dqy
    datt[ao + 3] = dqz
    datt[ao + 4] = dwx
    datt[ao + 5] = dwy
    datt[ao + 6] = dwz
    return True


@njit(cache=True)
def rigid_share(t, att, p, b, sh):
    """Add body b's share to ``sh``: the translational one of a point body, then its own angular
    momentum R (J_s omega_b + h_w), the rotational energy 1/2 omega_b.J_s omega_b + sum h_k^2/(2 I_k)
    (also in SH_KROT) and the gravity-gradient potential (MacCullagh)."""
    point_share(t, p, b, sh)
    bt = int(p[H_OFF_BODY]) + b * BT_SIZE
    bs = int(p[H_OFF_BSCR]) + b * BS_SIZE
    ao = int(p[bt + BT_AOFF]) - int(p[H_OFF_ATT])
    wx = att[ao + 4]
    wy = att[ao + 5]
    wz = att[ao + 6]
    jx, jy, jz = mat_vec(p, bt + BT_JS, wx, wy, wz)
    er = 0.5 * (wx * jx + wy * jy + wz * jz)
    whl = int(p[H_OFF_WHL]) - int(p[H_OFF_ATT])
    jx, jy, jz, er = wheel_set_share(p, att, int(p[bt + BT_W0]), int(p[bt + BT_NW]), whl, jx, jy, jz, er)
    lx, ly, lz = mat_vec(p, bs + BS_ROT, jx, jy, jz)
    sh[SH_HX] += lx
    sh[SH_HY] += ly
    sh[SH_HZ] += lz
    sh[SH_KE] += er
    sh[SH_KROT] += er
    mu_gg = p[H_MU_GG]
    if mu_gg > 0.0:
        rbx, rby, rbz = mat_t_vec(p, bs + BS_ROT, p[bs + BS_R], p[bs + BS_R + 1], p[bs + BS_R + 2])
        sh[SH_VG] += gravity_gradient_potential(p, bt + BT_JB, mu_gg, rbx, rby, rbz)


# -- the part interface (bodies/registry.py; the dispatcher bodies/parts.py calls these) -----------
@njit(cache=True, inline="always")
def root_state(att, p, b):
    """A root's attitude (its centre of mass is already in its scratch)."""
    rigid_attitude(att, p, b)


@njit(cache=True, inline="always")
def end_state(att, p, c, bx, by, bz, bvx, bvy, bvz):
    """Body c at the end B_n (position, velocity) of its parent tether: its centre of mass
    r_G = r_B - R rho_b (and its velocity) and attitude into its scratch."""
    rigid_attitude(att, p, c)
    pt = int(p[H_OFF_BODY]) + c * BT_SIZE + BT_PT
    rx, ry, rz, vx, vy, vz, kx, ky, kz = rigid_offset(p, c, p[pt], p[pt + 1], p[pt + 2])
    set_body_state(p, c, bx - rx, by - ry, bz - rz, bvx - vx, bvy - vy, bvz - vz)


@njit(cache=True, inline="always")
def attach(p, b, tb, ts, ax, ay, az, avx, avy, avz):
    """The attachment point A_1 of the tether (table tb, scratch ts): the centre of mass plus
    rho = R rho_b (rho and kappa kept in ts for the back substitution)."""
    rx, ry, rz, vx, vy, vz, kx, ky, kz = rigid_offset(p, b, p[tb + TT_PA], p[tb + TT_PA + 1], p[tb + TT_PA + 2])
    p[ts + TS_RHO] = rx
    p[ts + TS_RHO + 1] = ry
    p[ts + TS_RHO + 2] = rz
    p[ts + TS_KAP] = kx
    p[ts + TS_KAP + 1] = ky
    p[ts + TS_KAP + 2] = kz
    return ax + rx, ay + ry, az + rz, avx + vx, avy + vy, avz + vz


@njit(cache=True, inline="always")
def setup(t, att, p, b, datt):
    rigid_setup(t, att, p, b, datt)


@njit(cache=True, inline="always")
def add_child(p, b, k, W, s0):
    rigid_add_child(p, b, k, W, s0)


@njit(cache=True, inline="always")
def compliance(p, c, work):
    return rigid_compliance(p, c, work)


@njit(cache=True, inline="always")
def root_solve(p, b):
    return rigid_root_solve(p, b)


@njit(cache=True, inline="always")
def point_acceleration(p, b, ts):
    return rigid_point_acceleration(p, b, ts)


@njit(cache=True, inline="always")
def back_substitute(p, c, jn):
    rigid_back_substitute(p, c, jn)


@njit(cache=True, inline="always")
def derivatives(att, p, b, datt):
    return rigid_derivatives(att, p, b, datt)


@njit(cache=True, inline="always")
def share(t, att, p, b, sh):
    rigid_share(t, att, p, b, sh)
