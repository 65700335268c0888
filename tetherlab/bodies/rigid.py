"""Rigid-body kinematics and the terms of Euler's equations (compiled, SI floats).

Conventions (docs/model.md section 12): the attitude is the unit quaternion q = (w, x, y, z),
scalar first, of the rotation taking body axes to inertial axes, v_inertial = R(q) v_body.  The
angular velocity omega is kept in body axes; its kinematics is q' = 1/2 q (x) (0, omega_b)
(Hamilton product).  The quaternion is not renormalised by the right-hand side: R(q) below is the
rotation matrix of q/|q| (exactly orthogonal for any q != 0), so a drift of |q| changes nothing in
the dynamics and is reported as a diagnostic (1 - |q|).
"""

from __future__ import annotations

import math

from .._jit import njit
from ..kernel.vec3 import cross, mat_vec


@njit(cache=True)
def rotation(p, off, qw, qx, qy, qz):
    """Write R(q/|q|) (body -> inertial, row-major 9) to p[off:off+9]; returns |q|."""
    n2 = qw * qw + qx * qx + qy * qy + qz * qz
    s = 2.0 / n2
    p[off] = 1.0 - s * (qy * qy + qz * qz)
    p[off + 1] = s * (qx * qy - qw * qz)
    p[off + 2] = s * (qx * qz + qw * qy)
    p[off + 3] = s * (qx * qy + qw * qz)
    p[off + 4] = 1.0 - s * (qx * qx + qz * qz)
    p[off + 5] = s * (qy * qz - qw * qx)
    p[off + 6] = s * (qx * qz - qw * qy)
    p[off + 7] = s * (qy * qz + qw * qx)
    p[off + 8] = 1.0 - s * (qx * qx + qy * qy)
    return math.sqrt(n2)


@njit(cache=True)
def quat_rate(qw, qx, qy, qz, wx, wy, wz):
    """q' = 1/2 q (x) (0, omega_b)."""
    return (
        0.5 * (-qx * wx - qy * wy - qz * wz),
        0.5 * (qw * wx + qy * wz - qz * wy),
        0.5 * (qw * wy + qz * wx - qx * wz),
        0.5 * (qw * wz + qx * wy - qy * wx),
    )


@njit(cache=True)
def gravity_gradient_torque(p, jb, mu, rbx, rby, rbz):
    """3 mu / r^5 (r_b x J_B r_b), body axes, with r_b the centre of mass's position from the
    attracting centre in body axes and J_B = p[jb:jb+9] (Hughes 1986, ch. 8, eq. 8.1.17; the
    first term of the expansion of the point-mass field over the body, MacCullagh)."""
    r2 = rbx * rbx + rby * rby + rbz * rbz
    k = 3.0 * mu / (r2 * r2 * math.sqrt(r2))
    jx, jy, jz = mat_vec(p, jb, rbx, rby, rbz)
    cx, cy, cz = cross(rbx, rby, rbz, jx, jy, jz)
    return k * cx, k * cy, k * cz


@njit(cache=True)
def gravity_gradient_potential(p, jb, mu, rbx, rby, rbz):
    """MacCullagh's term of the potential energy (J): -mu/(2 r^3) (tr J - 3 r^T J r / r^2);
    its gradient with respect to the attitude is the torque above."""
    r2 = rbx * rbx + rby * rby + rbz * rbz
    r = math.sqrt(r2)
    jx, jy, jz = mat_vec(p, jb, rbx, rby, rbz)
    tr = p[jb] + p[jb + 4] + p[jb + 8]
    return -mu / (2.0 * r2 * r) * (tr - 3.0 * (rbx * jx + rby * jy + rbz * jz) / r2)


@njit(cache=True)
def quat_from_matrix(p, off):
    """Unit quaternion (w, x, y, z) of the rotation matrix p[off:off+9] (Shepperd's method)."""
    m00 = p[off]
    m11 = p[off + 4]
    m22 = p[off + 8]
    tr = m00 + m11 + m22
    if tr >= m00 and tr >= m11 and tr >= m22:
        w = 0.5 * math.sqrt(1.0 + tr)
        f = 0.25 / w
        return w, (p[off + 7] - p[off + 5]) * f, (p[off + 2] - p[off + 6]) * f, (p[off + 3] - p[off + 1]) * f
    if m00 >= m11 and m00 >= m22:
        x = 0.5 * math.sqrt(1.0 + 2.0 * m00 - tr)
        f = 0.25 / x
        return (p[off + 7] - p[off + 5]) * f, x, (p[off + 1] + p[off + 3]) * f, (p[off + 2] + p[off + 6]) * f
    if m11 >= m22:
        y = 0.5 * math.sqrt(1.0 + 2.0 * m11 - tr)
        f = 0.25 / y
        return (p[off + 2] - p[off + 6]) * f, (p[off + 1] + p[off + 3]) * f, y, (p[off + 5] + p[off + 7]) * f
    z = 0.5 * math.sqrt(1.0 + 2.0 * m22 - tr)
    f = 0.25 / z
    return (p[off + 3] - p[off + 1]) * f, (p[off + 2] + p[off + 6]) * f, (p[off + 5] + p[off + 7]) * f, z


@njit(cache=True)
def orbit_frame(p, off, rx, ry, rz, vx, vy, vz):
    """The orbit (LVLH) frame of (r, v) as the matrix whose columns are o1, o2, o3 (a body aligned
    with it has R = this), docs/scenes.md: o3 = -r/|r|, o2 = -(r x v)/|r x v|, o1 = o2 x o3.
    Returns its angular velocity (r x v)/r^2 (inertial axes; exact for the in-plane rotation)."""
    r = math.sqrt(rx * rx + ry * ry + rz * rz)
    hx, hy, hz = cross(rx, ry, rz, vx, vy, vz)
    h = math.sqrt(hx * hx + hy * hy + hz * hz)
    o3x, o3y, o3z = -rx / r, -ry / r, -rz / r
    o2x, o2y, o2z = -hx / h, -hy / h, -hz / h
    o1x, o1y, o1z = cross(o2x, o2y, o2z, o3x, o3y, o3z)
    p[off] = o1x
    p[off + 1] = o2x
    p[off + 2] = o3x
    p[off + 3] = o1y
    p[off + 4] = o2y
    p[off + 5] = o3y
    p[off + 6] = o1z
    p[off + 7] = o2z
    p[off + 8] = o3z
    r2 = r * r
    return hx / r2, hy / r2, hz / r2
