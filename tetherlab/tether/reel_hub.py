"""A reel on a rigid body: the body's equations with the stored tether (compiled; docs/deployment.md 9).

The carrying body S is the rigid hub (mass M, inertia J_s about its centre of mass O, the point
the state follows) plus the tether still on the reel, of mass m_s = rho (line - L): a thin ring of
radius R_s about the axis a, centred at the exit point e (body-fixed, e = R e_b from O).  The line
leaves S at e with the velocity v_O + omega x e + w, w = l'(1 + eps) u (docs/deployment.md 2.1).
With m = M + m_s, m c = m_s e and J_O = J_s + m_s K, K = (|e|^2 I - e e^T) + R_s^2 (I + a a^T)/2,
the balances of S with the flux m' = rho L' through e give (docs/deployment.md 9.2)

    m a_O - (m c) x alpha = F + (line) - m' w - m_s omega x (omega x e)
    (m c) x a_O + J_O alpha = M_O + e x (line) - e x m' w - omega x (J_O omega + h_d) - h_d'
                              + m' R_s^2 (omega + a (a.omega))/2

where h_d = m_s R_s L' a is the spin of a drum's stored turns relative to the body (0 for a
canister), plus under a spool law the drum's own J (L'/R) a (docs/deployment.md 9.7;
:func:`drum_axle_force` is the hub's alpha in the spool's balance) and the last term is the ring's angular momentum, left behind in the body by the
material that goes from the rim to the exit at the centre.  :func:`reel_hub_terms` adds every term
that the hub's set-up (bodies/rigid_body.py: diag(m I, R J_s R^T), the dry body's F6) and the point
body's flux (tether/reel.py: -m' w) do not have; the reaction solve brings the line's force and
its moment e x (line) as for any tether.  :func:`reel_hub_share` gives what the stored tether adds
to the hub's momentum, angular momentum and kinetic energy (the body's share counts m v_O and
J_s omega).
"""

from __future__ import annotations

from .._jit import njit
from ..kernel.layout import (
    BS_A,
    BS_F,
    BS_M,
    BS_R,
    BS_ROT,
    BS_SIZE,
    BS_V,
    BS_W,
    BT_RIGID,
    BT_SIZE,
    DEFECT_HUB_DRUM_NO_SPIN,
    DEFECT_REEL_NO_EXIT_TORQUE,
    DEFECT_REEL_NO_RING,
    DEFECT_REEL_RING_FULL,
    H_MUTANT,
    H_NBODY,
    H_OFF_BODY,
    H_OFF_BSCR,
    H_OFF_REEL,
    H_OFF_RSCR,
    REEL_EXIT_DRUM,
    RL_AX,
    RL_BODY,
    RL_EXIT,
    RL_LINE,
    RL_MEFF,
    RL_R,
    RL_RHO,
    RL_SIZE,
    RL_SOFF,
    RL_SPR,
    RL_TETH,
    RS_L,
    RS_LD,
    RS_LDD,
    RS_SIZE,
    TS_KAP,
    TS_RHO,
    TS_SIZE,
)
from ..kernel.vec3 import cross, mat_vec


@njit(cache=True, inline="always")
def _stored(p, i, spin):
    """(m_s, m', e (inertial), a (inertial), R_s, h_d (inertial), h_d' (inertial)) of reel i on its
    rigid body, its attitude and its tether's attachment already in the scratch.  On a drum under a
    spool law h_d also carries the drum's own spin J (L'/R) a relative to the hub (``spin``; docs
    9.7), J/R = RL_MEFF R (RL_MEFF = J/R^2, 0 for a prescribed drum and a canister)."""
    rb = int(p[H_OFF_REEL]) + i * RL_SIZE
    rs = int(p[H_OFF_RSCR]) + i * RS_SIZE
    b = int(p[rb + RL_BODY])
    bs = int(p[H_OFF_BSCR]) + b * BS_SIZE
    ts = int(p[H_OFF_BSCR]) + int(p[H_NBODY]) * BS_SIZE + int(p[rb + RL_TETH]) * TS_SIZE
    rho = p[rb + RL_RHO]
    L = p[rs + RS_L]
    Ld = p[rs + RS_LD]
    Ldd = p[rs + RS_LDD]
    stored = p[rb + RL_LINE] - L
    ms = rho * stored
    md = rho * Ld
    ax, ay, az = mat_vec(p, bs + BS_ROT, p[rb + RL_AX], p[rb + RL_AX + 1], p[rb + RL_AX + 2])
    rsp = p[rb + RL_SPR]
    hd = 0.0
    hdd = 0.0
    if int(p[rb + RL_EXIT]) == REEL_EXIT_DRUM:
        # the turns on the drum move at the rim speed L' (unstretched line on the drum): spin
        # m_s R_s^2 (L'/R_s) about a, and its rate with m_s' = -rho L'
        hd = ms * rsp * Ld
        hdd = rsp * rho * (stored * Ldd - Ld * Ld)
        jr = p[rb + RL_MEFF] * p[rb + RL_R]
        if spin and jr > 0.0:
            # the drum itself turns at L'/R relative to the hub (its inertia J about the axle with
            # the hub's rotation is in the hub's J_s): J (L'/R) a, and its rate J (L''/R) a
            hd += jr * Ld
            hdd += jr * Ldd
    return (ms, md, p[ts + TS_RHO], p[ts + TS_RHO + 1], p[ts + TS_RHO + 2], ax, ay, az, rsp,
            hd * ax, hd * ay, hd * az, hdd * ax, hdd * ay, hdd * az)  # fmt: skip


@njit(cache=True, inline="always")
def _stored_inertia_times(ms, ex, ey, ez, ax, ay, az, rsp, wx, wy, wz):
    """J_st w = m_s [(|e|^2 w - e (e.w)) + R_s^2 (w + a (a.w))/2] (inertial axes)."""
    ee = ex * ex + ey * ey + ez * ez
    ew = ex * wx + ey * wy + ez * wz
    aw = ax * wx + ay * wy + az * wz
    r2 = 0.5 * rsp * rsp
    return (ms * (ee * wx - ex * ew + r2 * (wx + ax * aw)),
            ms * (ee * wy - ey * ew + r2 * (wy + ay * aw)),
            ms * (ee * wz - ez * ew + r2 * (wz + az * aw)))  # fmt: skip


@njit(cache=True)
def reel_hub_terms(p, i, jump, ux, uy, uz):
    """Add to the 6x6 system of reel i's rigid body (after its set-up and the flux -m' w = -jump u
    on its centre of mass) the stored tether's mass matrix terms and forces (module docstring)."""
    rb = int(p[H_OFF_REEL]) + i * RL_SIZE
    b = int(p[rb + RL_BODY])
    bs = int(p[H_OFF_BSCR]) + b * BS_SIZE
    spin = int(p[H_MUTANT]) != DEFECT_HUB_DRUM_NO_SPIN  # the negative control: the old model, no drum spin
    ms, md, ex, ey, ez, ax, ay, az, rsp, hx, hy, hz, hdx, hdy, hdz = _stored(p, i, spin)
    ts = int(p[H_OFF_BSCR]) + int(p[H_NBODY]) * BS_SIZE + int(p[rb + RL_TETH]) * TS_SIZE
    wx = p[bs + BS_W]
    wy = p[bs + BS_W + 1]
    wz = p[bs + BS_W + 2]
    M = bs + BS_M
    F = bs + BS_F
    mi = ms
    if int(p[H_MUTANT]) == DEFECT_REEL_RING_FULL:  # the negative control of the shrinking inertia
        mi = p[rb + RL_RHO] * p[rb + RL_LINE]
    # J_st into the lower right block, column by column
    for col in range(3):
        cx = 1.0 if col == 0 else 0.0
        cy = 1.0 if col == 1 else 0.0
        cz = 1.0 if col == 2 else 0.0
        jx, jy, jz = _stored_inertia_times(mi, ex, ey, ez, ax, ay, az, rsp, cx, cy, cz)
        p[M + 6 * 3 + 3 + col] += jx
        p[M + 6 * 4 + 3 + col] += jy
        p[M + 6 * 5 + 3 + col] += jz
    # the coupling of translation and rotation: upper right -[m c]x, lower left +[m c]x
    cx = ms * ex
    cy = ms * ey
    cz = ms * ez
    p[M + 4] += cz
    p[M + 5] -= cy
    p[M + 9] -= cz
    p[M + 11] += cx
    p[M + 15] += cy
    p[M + 16] -= cx
    p[M + 19] -= cz
    p[M + 20] += cy
    p[M + 24] += cz
    p[M + 26] -= cx
    p[M + 30] -= cy
    p[M + 31] += cx
    # forces: the centripetal term of the stored mass off O
    p[F] -= ms * p[ts + TS_KAP]
    p[F + 1] -= ms * p[ts + TS_KAP + 1]
    p[F + 2] -= ms * p[ts + TS_KAP + 2]
    # torques: the flux's moment about O, the stored inertia's and the drum's gyroscopic terms, the
    # drum's spin rate and the ring's angular momentum left in the body
    jx, jy, jz = _stored_inertia_times(mi, ex, ey, ez, ax, ay, az, rsp, wx, wy, wz)
    gx, gy, gz = cross(wx, wy, wz, jx + hx, jy + hy, jz + hz)
    r2 = 0.5 * md * rsp * rsp
    if int(p[H_MUTANT]) == DEFECT_REEL_NO_RING:  # the negative control of the on-axis spin-up
        r2 = 0.0
    aw = ax * wx + ay * wy + az * wz
    tx = -gx - hdx + r2 * (wx + ax * aw)
    ty = -gy - hdy + r2 * (wy + ay * aw)
    tz = -gz - hdz + r2 * (wz + az * aw)
    if int(p[H_MUTANT]) != DEFECT_REEL_NO_EXIT_TORQUE:
        fx, fy, fz = cross(ex, ey, ez, jump * ux, jump * uy, jump * uz)
        tx -= fx
        ty -= fy
        tz -= fz
    p[F + 3] += tx
    p[F + 4] += ty
    p[F + 5] += tz


@njit(cache=True)
def reel_hub_share(p, i):
    """What reel i's stored tether adds to its rigid body's share (which counts m v_O and the dry
    J_s omega): momentum omega x m_s e; angular momentum about the origin r_O x (omega x m_s e) +
    m_s e x v_O + J_st omega + h_d; kinetic energy m_s v_O.(omega x e) + omega.J_st omega/2 and,
    for a drum, omega.h_d (+ m_s L'^2/2 under a prescribed law; under a spool law the relative
    kinetic energy of the drum and its turns is the spool's own K_s, docs/deployment.md 10.3, 9.7);
    the power the reel puts into the system besides the exit's (docs/deployment.md 9.3, 9.7):
    carrying the material from the ring to the exit at its centre, m' omega.K_ring omega/2, and for
    a drum alpha.h_d, with, under a prescribed law, its motor's work on the turns -rho L'^3/2 +
    m_s L' L'' (the body's accelerations already solved); and that ring term alone.  Returns the 9
    numbers."""
    rb = int(p[H_OFF_REEL]) + i * RL_SIZE
    rs = int(p[H_OFF_RSCR]) + i * RS_SIZE
    bs = int(p[H_OFF_BSCR]) + int(p[rb + RL_BODY]) * BS_SIZE
    ms, md, ex, ey, ez, ax, ay, az, rsp, hx, hy, hz, hdx, hdy, hdz = _stored(p, i, True)
    wx = p[bs + BS_W]
    wy = p[bs + BS_W + 1]
    wz = p[bs + BS_W + 2]
    rx = p[bs + BS_R]
    ry = p[bs + BS_R + 1]
    rz = p[bs + BS_R + 2]
    vx = p[bs + BS_V]
    vy = p[bs + BS_V + 1]
    vz = p[bs + BS_V + 2]
    px, py, pz = cross(wx, wy, wz, ms * ex, ms * ey, ms * ez)
    ax_, ay_, az_ = cross(rx, ry, rz, px, py, pz)
    bx, by, bz = cross(ms * ex, ms * ey, ms * ez, vx, vy, vz)
    jx, jy, jz = _stored_inertia_times(ms, ex, ey, ez, ax, ay, az, rsp, wx, wy, wz)
    ke = vx * px + vy * py + vz * pz + 0.5 * (wx * jx + wy * jy + wz * jz)
    drum = int(p[rb + RL_EXIT]) == REEL_EXIT_DRUM
    spool = p[rb + RL_SOFF] >= 0.0
    if drum:
        ld = p[rs + RS_LD]
        if spool:
            ke += wx * hx + wy * hy + wz * hz
        else:
            ke += wx * hx + wy * hy + wz * hz + 0.5 * ms * ld * ld
    # the work the reel does carrying the material from the ring to the exit at its centre (the
    # ring term of the torque, m' omega.K_ring omega, less the ring's kinetic energy it leaves with)
    aw = ax * wx + ay * wy + az * wz
    ring = 0.25 * md * rsp * rsp * (wx * wx + wy * wy + wz * wz + aw * aw)
    work = ring
    if drum:
        ld = p[rs + RS_LD]
        rho = p[rb + RL_RHO]
        A = bs + BS_A
        if spool:
            # the motor is inside the system: what is left besides the spool's balance is the
            # hub's angular acceleration against the drum's and turns' relative spin (docs 9.7)
            work += p[A + 3] * hx + p[A + 4] * hy + p[A + 5] * hz
        else:
            # the work of the drum's motor or brake on the turns it spins: d/dt(omega.h_d + m_s L'^2/2)
            # less the work its reaction does on the hub, -omega.h_d' (docs/deployment.md 9.3)
            work += p[A + 3] * hx + p[A + 4] * hy + p[A + 5] * hz - 0.5 * rho * ld * ld * ld + ms * ld * p[rs + RS_LDD]
    return px, py, pz, ax_ + bx + jx + hx, ay_ + by + jy + hy, az_ + bz + jz + hz, ke, work, ring


@njit(cache=True)
def drum_axle_force(p, i):
    """The hub's angular acceleration along the axle in the spool's balance of reel i, a drum under
    a spool law on a rigid body, in force units at the rim: (J/R + rho s R)(a.alpha) (docs/deployment.md
    9.7: about an axle turning with the hub, the drum and its turns turn at a.omega + L'/R).  0 on
    a point body, a canister or a prescribed law, and under the old model's negative control."""
    rb = int(p[H_OFF_REEL]) + i * RL_SIZE
    if int(p[rb + RL_EXIT]) != REEL_EXIT_DRUM or int(p[H_MUTANT]) == DEFECT_HUB_DRUM_NO_SPIN:
        return 0.0
    b = int(p[rb + RL_BODY])
    if p[int(p[H_OFF_BODY]) + b * BT_SIZE + BT_RIGID] == 0.0:
        return 0.0
    bs = int(p[H_OFF_BSCR]) + b * BS_SIZE
    ax, ay, az = mat_vec(p, bs + BS_ROT, p[rb + RL_AX], p[rb + RL_AX + 1], p[rb + RL_AX + 2])
    A = bs + BS_A
    stored = p[rb + RL_LINE] - p[int(p[H_OFF_RSCR]) + i * RS_SIZE + RS_L]
    mu = (p[rb + RL_MEFF] + p[rb + RL_RHO] * stored) * p[rb + RL_R]
    return mu * (ax * p[A + 3] + ay * p[A + 4] + az * p[A + 5])
