"""Attitude control: quaternion-feedback PD law (Wie, Weiss and Arapostathis, "Quaternion feedback
regulator for spacecraft eigenaxis rotations", J. Guidance 12(3), 1989, eq. 8 without the
gyroscopic term):  u = -k_p e - k_d (omega_b - omega_t,b),  e = 2 sign(dq_w) dq_vec,
dq = q_t^-1 (x) q, the rotation from the target to the body (2 dq_vec ~ the error angles in rad).
u is the commanded torque on the body, body axes; the wheels realise it (wheels.py).
"""

from __future__ import annotations

from .._jit import njit
from ..kernel.layout import BT_CTRL, BT_KD, BT_KP, BT_QT, CTRL_ORBIT
from .rigid import orbit_frame, quat_from_matrix


@njit(cache=True)
def pd_torque(p, bt, work, qw, qx, qy, qz, wx, wy, wz, rx, ry, rz, vx, vy, vz):
    """Commanded body torque (body axes) of the body whose table starts at bt; ``work``: 9 floats
    of scratch.  q must be unit (the caller passes q/|q|)."""
    if int(p[bt + BT_CTRL]) == CTRL_ORBIT:
        ox, oy, oz = orbit_frame(p, work, rx, ry, rz, vx, vy, vz)
        tw, tx, ty, tz = quat_from_matrix(p, work)
        # target rate in body axes: R^T omega_o, with R of q (rebuilt from q, not the scratch)
        tbx, tby, tbz = _rotate_t(qw, qx, qy, qz, ox, oy, oz)
    else:
        tw = p[bt + BT_QT]
        tx = p[bt + BT_QT + 1]
        ty = p[bt + BT_QT + 2]
        tz = p[bt + BT_QT + 3]
        tbx = 0.0
        tby = 0.0
        tbz = 0.0
    # dq = conj(qt) (x) q
    dw = tw * qw + tx * qx + ty * qy + tz * qz
    dx = tw * qx - tx * qw - ty * qz + tz * qy
    dy = tw * qy - ty * qw - tz * qx + tx * qz
    dz = tw * qz - tz * qw - tx * qy + ty * qx
    s = 2.0 if dw >= 0.0 else -2.0
    kp = p[bt + BT_KP]
    kd = p[bt + BT_KD]
    return (
        -kp * s * dx - kd * (wx - tbx),
        -kp * s * dy - kd * (wy - tby),
        -kp * s * dz - kd * (wz - tbz),
    )


@njit(cache=True)
def _rotate_t(qw, qx, qy, qz, x, y, z):
    """R(q)^T v for a unit q."""
    r00 = 1.0 - 2.0 * (qy * qy + qz * qz)
    r01 = 2.0 * (qx * qy - qw * qz)
    r02 = 2.0 * (qx * qz + qw * qy)
    r10 = 2.0 * (qx * qy + qw * qz)
    r11 = 1.0 - 2.0 * (qx * qx + qz * qz)
    r12 = 2.0 * (qy * qz - qw * qx)
    r20 = 2.0 * (qx * qz - qw * qy)
    r21 = 2.0 * (qy * qz + qw * qx)
    r22 = 1.0 - 2.0 * (qx * qx + qy * qy)
    return r00 * x + r10 * y + r20 * z, r01 * x + r11 * y + r21 * z, r02 * x + r12 * y + r22 * z

