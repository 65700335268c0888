"""What a reel reports at every output (compiled; docs/deployment.md 4-5).

Per reel and row (columns ``REEL_COLUMNS``): the deployed length L and its rate, the first rod's
length, the exit speed L'(1 + eps), the tension the line pulls the exit with (-J_0.u), the
momentum flux through the exit rho L'^2 (1 + eps), the pull the body feels (their difference),
the power the exit takes out of the mechanical energy

    D = T L'(1 + eps) - 1/2 rho L'^3 (1 + eps)^2 - 1/2 EA eps^2 L'       (docs/deployment.md 5),

its Carnot part (a canister: 1/2 rho |L'|^3 (1 + eps)^2; a drum: 0), under a spool law its L'',
torque, friction, the power taken by brake and friction, the spool's kinetic energy, the exit's
own loss, the tension law's command, the motor's torque before its limit, the regulating brake's
force and which limit is active (docs/deployment.md 10), and the material corrections
of the first rod's shares: the TMED shares (tether/rod.py) count the affine field v_A + xi D', the
material moves with v_A + xi D' + (1 - xi) w, w = lambda D, which adds

    momentum m w/2,   angular momentum r_A x m w/2,   kinetic energy m w.(v_A/2 + D'/6) + m |w|^2/6,

and on a rigid body the stored tether's own share off the centre of mass (tether/reel_hub.py).
"""

from __future__ import annotations

from .._jit import njit
from ..kernel.layout import (
    BS_SIZE,
    BT_RIGID,
    BT_SIZE,
    H_NBODY,
    H_OFF_BODY,
    H_NQT,
    H_NREEL,
    H_NRODS,
    H_OFF_BSCR,
    H_OFF_REEL,
    H_OFF_ROD,
    H_OFF_RSCR,
    H_OFF_SCR,
    H_OFF_TETH,
    REEL_EXIT_CANISTER,
    RL_BODY,
    RL_EXIT,
    RL_QMAX,
    RL_RHO,
    RL_ROD,
    RL_SOFF,
    RL_SIZE,
    RL_TETH,
    RL_VMAX,
    RL_VW,
    RS_FV,
    RS_JUMP,
    RS_L,
    RS_LAM,
    RS_FB,
    RS_FR,
    RS_LD,
    RS_LDD,
    RS_LROD,
    RS_MEFF,
    RS_QCMD,
    RS_TAU,
    RS_TCMD,
    RS_SIZE,
    RT_EA,
    RT_M,
    RT_SIZE,
    SJ_J,
    SJ_SIZE,
    SR_EPS,
    SR_FE,
    SR_SIZE,
    SR_U,
    TS_A,
    TS_SIZE,
    TT_ROD0,
    TT_SIZE,
)
from .reel_hub import reel_hub_share
from .rod import SQ3
from .solve import system_accelerations

REEL_COLUMNS = (
    "deployed_length_m", "speed_m_s", "rod_length_m", "exit_speed_m_s", "exit_tension_N", "exit_jump_N",
    "body_pull_N", "exit_power_W", "carnot_power_W", "dpx", "dpy", "dpz", "dhx", "dhy", "dhz", "dke", "rod_force_N",
    "accel_m_s2", "torque_N_m", "friction_N", "brake_power_W", "spool_kinetic_J", "exit_loss_power_W", "command_N",
    "torque_command_N_m", "speed_brake_N", "limit_active",
)  # fmt: skip
R_NCOL = len(REEL_COLUMNS)


@njit(cache=True)
def material_momentum(p, q, i, o, c0):
    """Reel i's material corrections of momentum and angular momentum (the first rod's transport
    w = lambda D: m w/2 and r_A x m w/2) into o[c0 .. c0 + 5], from the scratch of a right-hand side
    evaluation at the state q; returns w.  Shared by :func:`reel_rows` and the momenta-only pass of
    tetherlab/momentum_remap.py, so both make the same products in the same order."""
    rb = int(p[H_OFF_REEL]) + i * RL_SIZE
    rs = int(p[H_OFF_RSCR]) + i * RS_SIZE
    k = int(p[rb + RL_TETH])
    g = int(p[rb + RL_ROD])
    m = p[int(p[H_OFF_ROD]) + g * RT_SIZE + RT_M]
    lam = p[rs + RS_LAM]
    # w = lambda D, D = 2 sqrt3 d
    wx = lam * 2.0 * SQ3 * q[3 + 3 * g]
    wy = lam * 2.0 * SQ3 * q[4 + 3 * g]
    wz = lam * 2.0 * SQ3 * q[5 + 3 * g]
    ts_ = int(p[H_OFF_BSCR]) + int(p[H_NBODY]) * BS_SIZE + k * TS_SIZE + TS_A
    ax = p[ts_]
    ay = p[ts_ + 1]
    az = p[ts_ + 2]
    hm = 0.5 * m
    o[c0] = hm * wx
    o[c0 + 1] = hm * wy
    o[c0 + 2] = hm * wz
    o[c0 + 3] = ay * o[c0 + 2] - az * o[c0 + 1]
    o[c0 + 4] = az * o[c0] - ax * o[c0 + 2]
    o[c0 + 5] = ax * o[c0 + 1] - ay * o[c0]
    return wx, wy, wz


@njit(cache=True)
def reel_rows(ts, Y, p, out, acc, datt):
    """Fill out[row, reel, :] (columns REEL_COLUMNS) for every state row of Y.  Returns the index
    of the first row whose right-hand side failed, or -1."""
    h = int(p[H_NQT])
    nrods = int(p[H_NRODS])
    jscr = int(p[H_OFF_SCR]) + nrods * SR_SIZE
    tscr = int(p[H_OFF_BSCR]) + int(p[H_NBODY]) * BS_SIZE
    for row in range(Y.shape[0]):
        t = ts[row]
        q = Y[row, :h]
        qd = Y[row, h : 2 * h]
        att = Y[row, 2 * h :]
        if system_accelerations(t, q, qd, att, p, acc, datt) != 0:
            return row
        for i in range(int(p[H_NREEL])):
            rb = int(p[H_OFF_REEL]) + i * RL_SIZE
            rs = int(p[H_OFF_RSCR]) + i * RS_SIZE
            k = int(p[rb + RL_TETH])
            g = int(p[rb + RL_ROD])
            g0 = int(p[int(p[H_OFF_TETH]) + k * TT_SIZE + TT_ROD0])
            sb = int(p[H_OFF_SCR]) + g * SR_SIZE
            m = p[int(p[H_OFF_ROD]) + g * RT_SIZE + RT_M]
            ea = p[int(p[H_OFF_ROD]) + g * RT_SIZE + RT_EA]
            rho = p[rb + RL_RHO]
            ux = p[sb + SR_U]
            uy = p[sb + SR_U + 1]
            uz = p[sb + SR_U + 2]
            eps = p[sb + SR_EPS]
            ld = p[rs + RS_LD]
            j0 = jscr + (g0 + k) * SJ_SIZE + SJ_J
            tens = -(p[j0] * ux + p[j0 + 1] * uy + p[j0 + 2] * uz)
            sp = ld * (1.0 + eps)
            o = out[row, i]
            o[0] = p[rs + RS_L]
            o[1] = ld
            o[2] = p[rs + RS_LROD]
            o[3] = sp
            o[4] = tens
            o[5] = p[rs + RS_JUMP]
            o[6] = tens - p[rs + RS_JUMP]
            o[7] = tens * sp - 0.5 * rho * ld * sp * sp - 0.5 * ea * eps * eps * ld
            o[8] = 0.5 * rho * abs(ld) * sp * sp if int(p[rb + RL_EXIT]) == REEL_EXIT_CANISTER else 0.0
            wx, wy, wz = material_momentum(p, q, i, o, 9)
            ts_ = tscr + k * TS_SIZE + TS_A
            vx = p[ts_ + 3]
            vy = p[ts_ + 4]
            vz = p[ts_ + 5]
            ddx = 2.0 * SQ3 * qd[3 + 3 * g]
            ddy = 2.0 * SQ3 * qd[4 + 3 * g]
            ddz = 2.0 * SQ3 * qd[5 + 3 * g]
            o[15] = m * (wx * (0.5 * vx + ddx / 6.0) + wy * (0.5 * vy + ddy / 6.0) + wz * (0.5 * vz + ddz / 6.0)) + m * (
                wx * wx + wy * wy + wz * wz
            ) / 6.0
            o[16] = p[sb + SR_FE]
            ring = 0.0
            if p[int(p[H_OFF_BODY]) + int(p[rb + RL_BODY]) * BT_SIZE + BT_RIGID] != 0.0:
                # the stored tether on a rigid body: off its centre of mass, with its inertia
                s0, s1, s2, s3, s4, s5, s6, s7, ring = reel_hub_share(p, i)
                o[7] -= s7
                o[9] += s0
                o[10] += s1
                o[11] += s2
                o[12] += s3
                o[13] += s4
                o[14] += s5
                o[15] += s6
            o[17] = p[rs + RS_LDD]
            if p[rb + RL_SOFF] >= 0.0:  # a spool law (docs/deployment.md 10.3)
                ms = p[rs + RS_MEFF]
                fb = p[rs + RS_FB]
                o[18] = p[rs + RS_TAU]
                o[19] = p[rs + RS_FR]
                o[20] = fb * ld  # taken by the brake and the friction (a motor gives it when negative)
                o[21] = 0.5 * ms * ld * ld
                # the exit's own loss, from the jumps of strain and speed there (10.3)
                if int(p[rb + RL_EXIT]) == REEL_EXIT_CANISTER:
                    if ld > 0.0:
                        o[22] = ld * eps * (tens - 0.5 * ea * eps) + 0.5 * rho * ld * ld * ld * (1.0 - eps * eps)
                    else:  # hauling in: the jump is stopped by the heap, the line feels none (docs 9.8)
                        o[22] = ld * eps * (tens - 0.5 * ea * eps) - 0.5 * rho * ld * ld * ld * (1.0 + eps) * (1.0 + eps)
                else:
                    o[22] = ld * eps * (tens - 0.5 * ea * eps) - 0.5 * rho * ld * ld * ld * eps * eps
                if ring != 0.0:
                    # on a rigid body the work of carrying the material from the ring to the exit
                    # is not in (10.3)'s P_loss: it goes into E (docs/deployment.md 9.5, 9.7)
                    o[22] -= ring
                o[23] = p[rs + RS_TCMD]
                # the limits (10.4): the motor's torque before its limit, the regulating brake, and
                # which limit the law is beyond (1: the torque's, 2: the speed's, 3: both)
                o[24] = p[rs + RS_QCMD]
                o[25] = p[rs + RS_FV]
                active = 0.0
                if p[rb + RL_QMAX] > 0.0 and abs(p[rs + RS_QCMD]) > p[rb + RL_QMAX]:
                    active += 1.0
                if p[rb + RL_VW] > 0.0 and abs(ld) > p[rb + RL_VMAX]:
                    active += 2.0
                o[26] = active
            else:
                for c in range(18, R_NCOL):
                    o[c] = 0.0
    return -1
