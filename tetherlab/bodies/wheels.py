"""Momentum wheels: motor torques with their limits (paper eqs. 45-46; docs/model.md section 12).

State of wheel k: its axial angular momentum h_k = I_k (a_k . omega_b + Omega_k) (absolute: the
wheel's own spin Omega_k relative to the body plus the body's rate about the axis).  With a
symmetric wheel and a motor torque tau_k between body and wheel, h_k' = tau_k exactly; the body
feels -tau_k a_k.  The relative speed Omega_k = h_k/I_k - a_k . omega_b is an output.
"""

from __future__ import annotations

from .._jit import njit
from ..kernel.layout import (
    WMODE_CONTROL,
    WMODE_TABLE,
    WT_AX,
    WT_I,
    WT_MAXT,
    WT_MAXW,
    WT_MODE,
    WT_PINV,
    WT_TAU,
    WT_TN,
    WT_TOFF,
)


@njit(cache=True)
def table_value(p, off, n, t):
    """Piecewise-linear value of the table (times p[off:off+n], values p[off+n:off+2n]) at t,
    held constant outside."""
    if t <= p[off]:
        return p[off + n]
    if t >= p[off + n - 1]:
        return p[off + 2 * n - 1]
    lo = 0
    hi = n - 1
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if p[off + mid] <= t:
            lo = mid
        else:
            hi = mid
    t0 = p[off + lo]
    t1 = p[off + hi]
    f = (t - t0) / (t1 - t0)
    return (1.0 - f) * p[off + n + lo] + f * p[off + n + hi]


@njit(cache=True)
def motor_torque(p, wb, t, h, wx, wy, wz, ux, uy, uz):
    """Motor torque on wheel (table entry at wb) and its saturation flag (0 none, 1 torque limit,
    2 speed limit).  (ux, uy, uz): the controller's commanded body torque (body axes)."""
    mode = int(p[wb + WT_MODE])
    if mode == WMODE_CONTROL:
        # least squares: the body feels -A tau = u, tau = -A^+ u (row k of A^+ in the table)
        tau = -(p[wb + WT_PINV] * ux + p[wb + WT_PINV + 1] * uy + p[wb + WT_PINV + 2] * uz)
    elif mode == WMODE_TABLE:
        tau = table_value(p, int(p[wb + WT_TOFF]), int(p[wb + WT_TN]), t)
    else:
        tau = p[wb + WT_TAU]
    sat = 0
    maxt = p[wb + WT_MAXT]
    if maxt > 0.0:
        if tau > maxt:
            tau = maxt
            sat = 1
        elif tau < -maxt:
            tau = -maxt
            sat = 1
    maxw = p[wb + WT_MAXW]
    if maxw > 0.0:
        speed = h / p[wb + WT_I] - (p[wb + WT_AX] * wx + p[wb + WT_AX + 1] * wy + p[wb + WT_AX + 2] * wz)
        if (speed >= maxw and tau > 0.0) or (speed <= -maxw and tau < 0.0):
            tau = 0.0
            sat = 2
    return tau, sat
