"""Momentum wheels: motor torques with their limits (paper eqs. 45-46; docs/model.md section 12).

State of wheel k: its axial angular momentum h_k = I_k (a_k . omega_b + Omega_k) (absolute: the
wheel's own spin Omega_k relative to the body plus the body's rate about the axis).  With a
symmetric wheel and a motor torque tau_k between body and wheel, h_k' = tau_k exactly; the body
feels -tau_k a_k.  The relative speed Omega_k = h_k/I_k - a_k . omega_b is an output.
"""

from __future__ import annotations

from .._jit import njit
from ..kernel.layout import (
    H_INTERVAL_END,
    H_OFF_WT,
    WMODE_CONTROL,
    WMODE_TABLE,
    WT_AX,
    WT_I,
    WT_LOCKT,
    WT_LOCKW,
    WT_MAXT,
    WT_MAXW,
    WT_MODE,
    WT_PINV,
    WT_TAU,
    WT_TN,
    WT_TOFF,
    WS_CMD,
    WS_SAT,
    WS_SIZE,
    WS_SPEED,
    WS_TAU,
    WT_SIZE,
)


@njit(cache=True)
def table_value(p, off, n, t):
    """Piecewise-linear value of the table (times p[off:off+n], values p[off+n:off+2n]) at t,
    held constant outside.  A time written twice is a jump: the value is right-continuous, except
    at the end of the smooth interval being integrated (p[H_INTERVAL_END], a breakpoint the steps
    land on), where it is the left limit, so no stage of a step ending at a jump sees the value
    after it."""
    if t == p[H_INTERVAL_END]:
        # left limit: the first index with time >= t
        lo = 0
        hi = n
        while lo < hi:
            mid = (lo + hi) // 2
            if p[off + mid] < t:
                lo = mid + 1
            else:
                hi = mid
        k = lo
        if k == 0:
            return p[off + n]
        if k == n:
            return p[off + 2 * n - 1]
        if p[off + k] == t:
            return p[off + n + k]
    else:
        # right limit: the first index with time > t
        if t < p[off]:
            return p[off + n]
        if t >= p[off + n - 1]:
            return p[off + 2 * n - 1]
        lo = 0
        hi = n
        while lo < hi:
            mid = (lo + hi) // 2
            if p[off + mid] <= t:
                lo = mid + 1
            else:
                hi = mid
        k = lo
    t0 = p[off + k - 1]
    t1 = p[off + k]
    v0 = p[off + n + k - 1]
    v1 = p[off + n + k]
    if v0 == v1:
        return v0  # a flat piece is its value exactly (a phase of constant torque, bit for bit)
    f = (t - t0) / (t1 - t0)
    return (1.0 - f) * v0 + f * v1


@njit(cache=True)
def motor_torque(p, wb, t, h, wx, wy, wz, ux, uy, uz):
    """Motor torque on wheel (table entry at wb), its saturation flag (0 none, 1 torque limit,
    2 speed limit), the torque commanded before the limits and the speed relative to the body.
    (ux, uy, uz): the controller's commanded body torque (body axes).

    The limits switch where the event components of :func:`limit_events` change side.  When the
    integrator locates them (kernel/events.py), each limit's branch is locked between events
    (WT_LOCKT, WT_LOCKW: 0 off, 1 on; set from the components' sides by the driver's
    ``at_sides``), so every stage of a step sees the branch the step started on and the step's
    dense output, on which the switch is located, is that of a smooth right-hand side
    (discontinuity locking).  Unlocked (-1: diagnostics, scipy, the other formulations) the branch
    is decided at each evaluation."""
    mode = int(p[wb + WT_MODE])
    if mode == WMODE_CONTROL:
        # least squares: the body feels -A tau = u, tau = -A^+ u (row k of A^+ in the table)
        tau = -(p[wb + WT_PINV] * ux + p[wb + WT_PINV + 1] * uy + p[wb + WT_PINV + 2] * uz)
    elif mode == WMODE_TABLE:
        tau = table_value(p, int(p[wb + WT_TOFF]), int(p[wb + WT_TN]), t)
    else:
        tau = p[wb + WT_TAU]
    cmd = tau
    sat = 0
    maxt = p[wb + WT_MAXT]
    lock = p[wb + WT_LOCKT]
    if maxt > 0.0:
        if lock < 0.0:
            if tau > maxt:
                tau = maxt
                sat = 1
            elif tau < -maxt:
                tau = -maxt
                sat = 1
        elif lock > 0.0:
            tau = maxt if cmd >= 0.0 else -maxt
            sat = 1
    speed = h / p[wb + WT_I] - (p[wb + WT_AX] * wx + p[wb + WT_AX + 1] * wy + p[wb + WT_AX + 2] * wz)
    maxw = p[wb + WT_MAXW]
    lock = p[wb + WT_LOCKW]
    if maxw > 0.0:
        if lock < 0.0:
            if (speed >= maxw and tau > 0.0) or (speed <= -maxw and tau < 0.0):
                tau = 0.0
                sat = 2
        elif lock > 0.0:
            tau = 0.0
            sat = 2
    return tau, sat, cmd, speed


@njit(cache=True)
def limit_events(p, wb, cmd, speed):
    """The two switching functions of a wheel's limits, negative while the limit acts.

    Torque limit: max_torque - |command| (1.0 without one).  Speed cut-off (1.0 without one):
    while it does not act, min(max(max_speed - speed, -tau), max(max_speed + speed, tau)),
    negative once |speed| passes max_speed with a torque tau (after its limit) that would spin
    the wheel further; while it acts (branch locked on, WT_LOCKW = 1), -tau sign(speed), which
    stays negative until the motor's command turns round.  The cut wheel keeps its momentum, so
    its speed relative to the body follows the body's rate about its axis and may dip below
    max_speed: releasing the cut there (and cutting again as the motor pushes it back over) would
    be a sliding mode, an event at every ulp of the body's motion, so the cut holds until the
    command reverses."""
    g_t = 1.0
    g_w = 1.0
    maxt = p[wb + WT_MAXT]
    tau = cmd
    if maxt > 0.0:
        g_t = maxt - abs(cmd)
        tau = min(maxt, max(-maxt, cmd))
    maxw = p[wb + WT_MAXW]
    if maxw > 0.0:
        if p[wb + WT_LOCKW] > 0.0:
            g_w = -tau if speed >= 0.0 else tau
        else:
            g_w = min(max(maxw - speed, -tau), max(maxw + speed, tau))
    return g_t, g_w


@njit(cache=True)
def wheel_set_torques(p, t, att, w0, nw, wbx, wby, wbz, ux, uy, uz, wscr, whl, datt):
    """The wheel set of a body (wheels w0 .. w0+nw-1; body rate omega_b, commanded torque u, body
    axes): every motor torque with its limits into the wheel scratch (torque, saturation flag) and,
    when ``datt`` is not empty, into the wheels' derivatives h_k' = tau_k (eq. 46').  Returns the
    body-axes sums h_w = sum a_k h_k and sum a_k tau_k that enter the body's eq. 45'."""
    offw = int(p[H_OFF_WT])
    hwx = 0.0
    hwy = 0.0
    hwz = 0.0
    tqx = 0.0
    tqy = 0.0
    tqz = 0.0
    for j in range(w0, w0 + nw):
        wt = offw + j * WT_SIZE
        h = att[whl + j]
        tau, sat, cmd, speed = motor_torque(p, wt, t, h, wbx, wby, wbz, ux, uy, uz)
        p[wscr + j * WS_SIZE + WS_TAU] = tau
        p[wscr + j * WS_SIZE + WS_SAT] = sat
        p[wscr + j * WS_SIZE + WS_CMD] = cmd
        p[wscr + j * WS_SIZE + WS_SPEED] = speed
        if datt.shape[0] > 0:
            datt[whl + j] = tau
        a0 = p[wt + WT_AX]
        a1 = p[wt + WT_AX + 1]
        a2 = p[wt + WT_AX + 2]
        hwx += a0 * h
        hwy += a1 * h
        hwz += a2 * h
        tqx += a0 * tau
        tqy += a1 * tau
        tqz += a2 * tau
    return hwx, hwy, hwz, tqx, tqy, tqz


@njit(cache=True)
def wheel_set_share(p, att, w0, nw, whl, jx, jy, jz, er):
    """Add the wheel set's share to a body's angular momentum about G (body axes, J_s omega given
    in (jx, jy, jz)) and rotational energy er: h_w = sum a_k h_k and sum h_k^2 / (2 I_k)
    (docs/model.md 12.2)."""
    offw = int(p[H_OFF_WT])
    for k in range(w0, w0 + nw):
        wt = offw + k * WT_SIZE
        hk = att[whl + k]
        jx += p[wt + WT_AX] * hk
        jy += p[wt + WT_AX + 1] * hk
        jz += p[wt + WT_AX + 2] * hk
        er += 0.5 * hk * hk / p[wt + WT_I]
    return jx, jy, jz, er
