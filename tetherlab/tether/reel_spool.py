"""A reel as a dynamical system: the spool's balance gives L'' (compiled; docs/deployment.md 10).

Under the laws ``spool`` and ``tension`` the deployed length L and its rate L' are state (the
StateLayout block ``reel.<tether>``) and L'' comes from the balance of the spool, in force units
at the rim (docs/deployment.md 10.1):

    m_s L'' = T - j - F_b,

* T = -J_0.u the line's tension at the exit (the reaction solve's);
* j the momentum the exit gives the material through the line: rho L'^2 eps on a drum (the turns
  are unstretched at rim speed L', the line leaves at L'(1 + eps)), rho L'^2 (1 + eps) paying out
  through a canister (the material leaves from rest) and 0 hauling in through one (the heap it
  falls on stops it; docs/deployment.md 9.8);
* on a drum on a rigid hub, T is replaced by T - (J/R + rho s R)(a.alpha), the hub's angular
  acceleration along the axle (docs/deployment.md 9.7), affine in L'' like T;
* m_s = J/R^2 + rho (stored length) on a drum (the spool and the turns still on it), 0 on a
  canister (no spool: the brake holds the line where it leaves);
* F_b = tau/R + c L' + F_c tanh(L'/v_s) + F_v the force of the brake or motor, the friction and
  the speed-regulating brake against the pay-out; the law ``tension`` sets tau/R to the commanded
  tension T_c = m* Omega^2 [3 l_c + k1 (L - l_c) + k2 L'/Omega], smoothly limited; the motor's
  torque tau is smoothly limited to |tau| <= tau_max and F_v engages smoothly above |L'| = v_max
  (docs/deployment.md 10.4).  Every term is a function of (L, L') alone, so the L'' solve stays
  exact and the work of the limited torque and of the regulating brake is in W_b.

T depends on L'' through the first rod's apparent load (kappa = l''/l - 2 lambda^2, tether/reel.py),
and on nothing else that L'' changes: every reaction is affine in it.  So the solve is exact, not
lagged: one evaluation at L'' = 0 gives T_0, one per spool reel with its L'' = 1 the column of the
sensitivity S = dT/dL'', then (diag(m_s) - S) L'' = T_0 - j - F_b is solved and the system
evaluated once more at the solution (so that every scratch value is that of the true state).
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import njit
from ..kernel.layout import (
    DEFECT_CANISTER_AS_DRUM,
    DEFECT_DRUM_NO_TURNS,
    DEFECT_SPOOL_NO_SPEED_BRAKE,
    DEFECT_SPOOL_TORQUE_ONE_SIDED,
    DEFECT_SPOOL_TORQUE_UNLIMITED,
    DEFECT_SPOOL_UNCOUPLED,
    DEFECT_TENSION_3L,
    DEFECT_TENSION_K2_SIGN,
    H_MUTANT,
    H_NREEL,
    H_NRODS,
    H_OFF_REEL,
    H_OFF_RSCR,
    H_OFF_SCR,
    H_OFF_TETH,
    REEL_EXIT_DRUM,
    REEL_LAW_TENSION,
    RL_CV,
    RL_EXIT,
    RL_FC,
    RL_K1,
    RL_K2,
    RL_LAW,
    RL_LC,
    RL_LINE,
    RL_MEFF,
    RL_MSTAR,
    RL_OMEGA,
    RL_QMAX,
    RL_QW,
    RL_R,
    RL_RHO,
    RL_ROD,
    RL_SIZE,
    RL_SOFF,
    RL_TAU,
    RL_TETH,
    RL_TMAX,
    RL_TMIN,
    RL_TW,
    RL_VGAIN,
    RL_VMAX,
    RL_VS,
    RL_VW,
    RS_FB,
    RS_FR,
    RS_FV,
    RS_LDD,
    RS_MEFF,
    RS_QCMD,
    RS_SIZE,
    RS_TAU,
    RS_TCMD,
    RS_TEX,
    SJ_J,
    SJ_SIZE,
    SR_EPS,
    SR_SIZE,
    SR_U,
    TT_ROD0,
    TT_SIZE,
)
from .reel_hub import drum_axle_force


@njit(cache=True, inline="always")
def n_spools(p):
    """Number of reels whose length is state."""
    n = 0
    for i in range(int(p[H_NREEL])):
        if p[int(p[H_OFF_REEL]) + i * RL_SIZE + RL_SOFF] >= 0.0:
            n += 1
    return n


@njit(cache=True, inline="always")
def _softplus(x, w):
    """w ln(1 + e^(x/w)), without overflow: a smooth max(x, 0) within w ln 2 of it."""
    z = x / w
    if z > 30.0:
        return x
    return w * math.log1p(math.exp(z))


@njit(cache=True)
def tension_command(p, rb, L, Ld):
    """The commanded tension of the law ``tension`` (Rupp/Kissel family), within its smooth
    limits: T_c = m* Omega^2 [3 l_c + k1 (L - l_c) + k2 L'/Omega]; below T_min and above T_max
    it bends onto the limit over the width w (softplus corners: within w ln 2 at the limit, and
    e^(-d/w) w off the linear law at a distance d from it)."""
    om = p[rb + RL_OMEGA]
    lc = p[rb + RL_LC]
    k2 = -p[rb + RL_K2] if int(p[H_MUTANT]) == DEFECT_TENSION_K2_SIGN else p[rb + RL_K2]
    hold = L if int(p[H_MUTANT]) == DEFECT_TENSION_3L else lc
    tc = p[rb + RL_MSTAR] * om * om * (3.0 * hold + p[rb + RL_K1] * (L - lc) + k2 * Ld / om)
    w = p[rb + RL_TW]
    if w > 0.0:
        lo = p[rb + RL_TMIN]
        tc = lo + _softplus(tc - lo, w)
        hi = p[rb + RL_TMAX]
        if hi > lo:
            tc = hi - _softplus(hi - tc, w)
    return tc


@njit(cache=True)
def limited_torque(tau, tmax, w):
    """The motor's torque within |tau| <= tau_max through softplus corners of width w
    (docs/deployment.md 10.4): first bent above -tau_max, then below +tau_max; the result is
    below tau_max always and above -tau_max - w e^(-2 tau_max/w)."""
    lo = -tmax + _softplus(tau + tmax, w)
    return tmax - _softplus(tmax - lo, w)


@njit(cache=True)
def speed_brake(Ld, vmax, gain, w):
    """The speed-regulating brake's force against the pay-out (docs/deployment.md 10.4):
    gain [softplus(L' - v_max) - softplus(-L' - v_max)], odd in L', so its power F L' >= 0 (it only
    dissipates); below v_max it is within gain w e^(-(v_max - |L'|)/w) of zero."""
    return gain * (_softplus(Ld - vmax, w) - _softplus(-Ld - vmax, w))


@njit(cache=True)
def spool_forces(p, i, L, Ld, eps):
    """Reel i's (m_s, j, F_b) of the balance m_s L'' = T - j - F_b (module docstring), and its
    torque, friction and command into the scratch."""
    rb = int(p[H_OFF_REEL]) + i * RL_SIZE
    rs = int(p[H_OFF_RSCR]) + i * RS_SIZE
    rho = p[rb + RL_RHO]
    drum = int(p[rb + RL_EXIT]) == REEL_EXIT_DRUM
    if drum:
        ms = p[rb + RL_MEFF] + rho * (p[rb + RL_LINE] - L)
        if int(p[H_MUTANT]) == DEFECT_DRUM_NO_TURNS:  # negative control of the YES2-like energy balance
            ms = p[rb + RL_MEFF]
        jump = rho * Ld * Ld * eps
    else:
        ms = 0.0
        # paying out, the line's tension jerks the material from rest to the line's speed; hauling
        # in, the material is stopped by the stored heap it falls on, which can push it but not
        # pull the line: the jump is the body's (reel_body_forces), not the line's (docs 9.8)
        jump = rho * Ld * Ld * (1.0 + eps) if Ld > 0.0 else 0.0
        if int(p[H_MUTANT]) == DEFECT_CANISTER_AS_DRUM:  # negative control of the SEDS-like comparison
            jump = rho * Ld * Ld * eps
    fr = p[rb + RL_CV] * Ld
    vs = p[rb + RL_VS]
    if p[rb + RL_FC] > 0.0:
        fr += p[rb + RL_FC] * math.tanh(Ld / vs)
    R = p[rb + RL_R]
    if int(p[rb + RL_LAW]) == REEL_LAW_TENSION:
        tc = tension_command(p, rb, L, Ld)
        p[rs + RS_TCMD] = tc
        tau_r = tc  # the motor's torque over R
        p[rs + RS_QCMD] = tc * R
    else:
        tau_r = p[rb + RL_TAU] / R if R > 0.0 else 0.0
        p[rs + RS_TCMD] = 0.0
        p[rs + RS_QCMD] = p[rb + RL_TAU]
    tau = p[rs + RS_QCMD]
    if p[rb + RL_QMAX] > 0.0:  # the scene asks for a drum radius with a torque limit
        if int(p[H_MUTANT]) == DEFECT_SPOOL_TORQUE_ONE_SIDED:
            tau = -p[rb + RL_QMAX] + _softplus(tau + p[rb + RL_QMAX], p[rb + RL_QW])
        else:
            tau = limited_torque(tau, p[rb + RL_QMAX], p[rb + RL_QW])
        tau_r = tau / R
    p[rs + RS_TAU] = tau
    fv = 0.0
    if p[rb + RL_VW] > 0.0:
        fv = speed_brake(Ld, p[rb + RL_VMAX], p[rb + RL_VGAIN], p[rb + RL_VW])
    p[rs + RS_FV] = fv
    p[rs + RS_FR] = fr
    p[rs + RS_FB] = tau_r + fr + fv
    p[rs + RS_MEFF] = ms
    defect = int(p[H_MUTANT])
    if defect == DEFECT_SPOOL_TORQUE_UNLIMITED and p[rb + RL_QMAX] > 0.0:
        return ms, jump, p[rs + RS_QCMD] / R + fr + fv
    if defect == DEFECT_SPOOL_NO_SPEED_BRAKE:
        return ms, jump, tau_r + fr
    return ms, jump, tau_r + fr + fv


@njit(cache=True)
def exit_tension(p, i):
    """The line's tension at reel i's exit, -J_0.u, from the last reaction solve."""
    rb = int(p[H_OFF_REEL]) + i * RL_SIZE
    k = int(p[rb + RL_TETH])
    g = int(p[rb + RL_ROD])
    g0 = int(p[int(p[H_OFF_TETH]) + k * TT_SIZE + TT_ROD0])
    sb = int(p[H_OFF_SCR]) + g * SR_SIZE
    j0 = int(p[H_OFF_SCR]) + int(p[H_NRODS]) * SR_SIZE + (g0 + k) * SJ_SIZE + SJ_J
    return -(p[j0] * p[sb + SR_U] + p[j0 + 1] * p[sb + SR_U + 1] + p[j0 + 2] * p[sb + SR_U + 2])


@njit(cache=True)
def first_rod_strain(p, i):
    rb = int(p[H_OFF_REEL]) + i * RL_SIZE
    return p[int(p[H_OFF_SCR]) + int(p[rb + RL_ROD]) * SR_SIZE + SR_EPS]


@njit(cache=True)
def set_trial(p, idx, values):
    """L'' of every spool reel (idx: their reel indices) into the scratch, read by reel_update."""
    for a in range(idx.shape[0]):
        p[int(p[H_OFF_RSCR]) + idx[a] * RS_SIZE + RS_LDD] = values[a]


@njit(cache=True)
def spool_system(p, idx, att, T0, S):
    """The matrix and right-hand side of the L'' solve (module docstring) from T_0 and S."""
    ns = idx.shape[0]
    A = np.zeros((ns, ns))
    b = np.zeros(ns)
    coupled = int(p[H_MUTANT]) != DEFECT_SPOOL_UNCOUPLED
    for a in range(ns):
        i = idx[a]
        so = int(p[int(p[H_OFF_REEL]) + i * RL_SIZE + RL_SOFF])
        ms, jump, fb = spool_forces(p, i, att[so], att[so + 1], first_rod_strain(p, i))
        for c in range(ns):
            A[a, c] = -S[a, c] if coupled else 0.0
        A[a, a] += ms
        b[a] = T0[a] - jump - fb
    return A, b


@njit(cache=True)
def spool_indices(p):
    ns = n_spools(p)
    idx = np.empty(ns, np.int64)
    a = 0
    for i in range(int(p[H_NREEL])):
        if p[int(p[H_OFF_REEL]) + i * RL_SIZE + RL_SOFF] >= 0.0:
            idx[a] = i
            a += 1
    return idx


@njit(cache=True)
def record_tensions(p, idx, out):
    """The line's force in each spool reel's balance into out: the exit tension T (kept in the
    scratch), less, for a drum on a rigid hub, the hub's angular acceleration along the axle,
    (J/R + rho s R)(a.alpha) (docs/deployment.md 9.7).  Both are affine in the L'' of the
    evaluation, so the solve of 10.2 stays exact with this in place of T."""
    for a in range(idx.shape[0]):
        T = exit_tension(p, idx[a])
        p[int(p[H_OFF_RSCR]) + idx[a] * RS_SIZE + RS_TEX] = T
        out[a] = T - drum_axle_force(p, idx[a])


@njit(cache=True)
def write_spool_derivatives(p, idx, att, datt, ldd):
    """d/dt [L, L'] = [L', L''] of every spool reel into datt."""
    for a in range(idx.shape[0]):
        so = int(p[int(p[H_OFF_REEL]) + idx[a] * RL_SIZE + RL_SOFF])
        datt[so] = att[so + 1]
        datt[so + 1] = ldd[a]

