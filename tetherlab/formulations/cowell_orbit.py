"""Cowell's equations in a frame turning uniformly with the reference orbit ("cowell-orbit").

Why: RADAU5's simplified Newton iteration uses one Jacobian for the three stages of a step.  The
stiff axial force of a rod acts along the rod, and in the inertial frame a tether on a circular
orbit turns at the orbital rate Omega, so the stiff direction turns by Omega h within a step.  The
iteration's contraction then grows like h^4 (the rotated axial stiffness couples into the soft
lateral directions; docs/integrators.md section 11) and limits the step to a few seconds on a
many-rod tether, far below what the error allows.  In a frame turning with the orbit the tether is
nearly at rest: only its libration and the drift of the orbit's rate turn it, and the same
Jacobian serves the whole step.

Frame: R(t) rotates about the fixed unit axis k by the angle w (t - t_a) (omega = w k, set at the
anchor time t_a from the root body's r x v / |r|^2: at the start, for the relative equilibria of
``orbit.motion``, exactly the rigid rotation).  An orbit that decays speeds up (the de-orbit ends
19 % faster than it starts), so the driver (tetherlab.pipeline) re-anchors the frame every few
orbits: the state is turned back to inertial components at t_a and the run restarts there.  Every 3-vector of q_trans (root positions and rod vectors d_i) is stored
in the frame's components, q_in = R q, and its rate as the frame-relative rate v = q' with
q_in' = R (v + omega x q).  Then (a the inertial acceleration of the same vector, in the frame's
components)

    q'' = R^T a(R q, R (v + omega x q)) - 2 omega x v - omega x (omega x q),

with a the unchanged Cowell right-hand side (tether/chain.py, every effect): the forces are
computed on the inertial state and only the kinematics change.  The elastic and damping forces of
a rod depend on |d| and d . d', both invariant (d . (omega x d) = 0), so the structured Newton
matrix (tether/newton.py) and the event functions (kernel/events.py: |r0| and the rod tensions)
apply to the frame's state unchanged.  The Coriolis and centrifugal terms (order Omega, Omega^2)
are not stiff and are left out of the Newton matrix.

Rigid bodies (docs/integrators.md section 11): each quaternion is stored body -> frame,
q_f = q_R^* (x) q (q_R = (cos phi/2, k sin phi/2), phi = w (t - t_a), the frame's rotation), and
the body rate omega_b (body axes, relative to inertial space) and the wheels' momenta are kept as
they are.  With q = q_R (x) q_f and q_R' = 1/2 (0, omega) (x) q_R,

    q_f' = q_R^* (x) q' - 1/2 (0, omega) (x) q_f,

q' the unchanged Cowell kinematics 1/2 q (x) (0, omega_b); Euler's equations and the wheels are
untouched.  Why the frame for the quaternion: every position, rod vector and attitude of the frame
state is then the inertial one turned by the same R^T, so an orbit-pointing body is nearly at rest
in the frame as the tether is (the point of the frame), and the state reads as a rigidly turned
inertial configuration, which is what tether/newton.py assumes of the rod blocks (an inertial
quaternion beside the frame's rod vectors puts each attachment point off by the frame angle, up
to 10 pi in a segment).  Why not omega_b too: the body rate relative to the frame, omega_b -
R_f^T omega, would add a term to Euler's equations and to the wheels' for no gain.

Parameter block (appended to the model's p, header H_OFF_FORM): OP_W (3) omega in rad/s, OP_T0 the
anchor time t_a, then scratch for the inertial state and its derivative (2 x H_NSTATE).
"""

from __future__ import annotations

import math

import numpy as np
from numba import carray

from .._jit import njit, rhs_cfunc
from ..kernel.layout import FORM_COWELL_ORBIT, H_FORM, H_LEN, H_NQT, H_NRIGID, H_NSTATE, H_OFF_ATT, H_OFF_FORM
from ..tether.solve import system_accelerations

OP_W = 0
OP_T0 = 3
OP_SCR = 4


def attach(p: np.ndarray, omega_rad_s: np.ndarray, t_anchor_s: float = 0.0) -> np.ndarray:
    """A copy of the model's parameter block with the frame block appended (header H_OFF_FORM)."""
    n = int(p[H_NSTATE])
    off = p.size
    out = np.concatenate([p, np.zeros(OP_SCR + 2 * n)])
    out[H_LEN] = out.size
    out[H_OFF_FORM] = off
    out[H_FORM] = FORM_COWELL_ORBIT
    set_frame(out, omega_rad_s, t_anchor_s)
    return out


def set_frame(pe: np.ndarray, omega_rad_s, t_anchor_s: float) -> None:
    """Re-anchor the frame of a block made by :func:`attach` (in place)."""
    omega = np.asarray(omega_rad_s, dtype=float).reshape(3)
    if not (np.all(np.isfinite(omega)) and float(omega @ omega) > 0.0):
        raise ValueError(f"omega_rad_s: expected a finite non-zero angular velocity; got {omega.tolist()}")
    off = int(pe[H_OFF_FORM])
    pe[off + OP_W : off + OP_W + 3] = omega
    pe[off + OP_T0] = t_anchor_s


@njit(cache=True)
def _rot(kx, ky, kz, c, s, v0, v1, v2):
    """Rodrigues: v rotated by the angle (cos c, sin s) about the unit axis k."""
    kv = kx * v0 + ky * v1 + kz * v2
    cx = ky * v2 - kz * v1
    cy = kz * v0 - kx * v2
    cz = kx * v1 - ky * v0
    return (v0 * c + cx * s + kx * kv * (1.0 - c),
            v1 * c + cy * s + ky * kv * (1.0 - c),
            v2 * c + cz * s + kz * kv * (1.0 - c))  # fmt: skip


@njit(cache=True)
def _qmul(aw, ax, ay, az, bw, bx, by, bz):
    """Hamilton product a (x) b of quaternions (w, x, y, z)."""
    return (aw * bw - ax * bx - ay * by - az * bz,
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw)  # fmt: skip


@rhs_cfunc
def cowell_orbit_rhs(t, y_ptr, dy_ptr, p_ptr):
    p = carray(p_ptr, (int(p_ptr[H_LEN]),))
    n = int(p[H_NSTATE])
    y = carray(y_ptr, (n,))
    dy = carray(dy_ptr, (n,))
    h = int(p[H_NQT])
    off = int(p[H_OFF_FORM])
    wx = p[off + OP_W]
    wy = p[off + OP_W + 1]
    wz = p[off + OP_W + 2]
    w = math.sqrt(wx * wx + wy * wy + wz * wz)
    kx = wx / w
    ky = wy / w
    kz = wz / w
    c = math.cos(w * (t - p[off + OP_T0]))
    s = math.sin(w * (t - p[off + OP_T0]))
    yi = p[off + OP_SCR : off + OP_SCR + n]
    ai = p[off + OP_SCR + n : off + OP_SCR + 2 * n]
    for j in range(h // 3):
        o = 3 * j
        q0 = y[o]
        q1 = y[o + 1]
        q2 = y[o + 2]
        v0 = y[h + o] + wy * q2 - wz * q1
        v1 = y[h + o + 1] + wz * q0 - wx * q2
        v2 = y[h + o + 2] + wx * q1 - wy * q0
        yi[o], yi[o + 1], yi[o + 2] = _rot(kx, ky, kz, c, s, q0, q1, q2)
        yi[h + o], yi[h + o + 1], yi[h + o + 2] = _rot(kx, ky, kz, c, s, v0, v1, v2)
    for i in range(2 * h, n):  # attitude and wheel blocks: omega_b and the wheels as they are
        yi[i] = y[i]
    nrig = int(p[H_NRIGID])
    c2 = 1.0
    s2 = 0.0
    if nrig > 0:  # quaternions body -> frame to body -> inertial: q = q_R (x) q_f
        c2 = math.cos(0.5 * w * (t - p[off + OP_T0]))
        s2 = math.sin(0.5 * w * (t - p[off + OP_T0]))
        att = int(p[H_OFF_ATT])
        for j in range(nrig):
            o = att + 7 * j
            yi[o], yi[o + 1], yi[o + 2], yi[o + 3] = _qmul(c2, kx * s2, ky * s2, kz * s2,
                                                           y[o], y[o + 1], y[o + 2], y[o + 3])  # fmt: skip
    st = system_accelerations(t, yi[:h], yi[h : 2 * h], yi[2 * h :], p, ai[h : 2 * h], ai[2 * h :])
    for j in range(h // 3):
        o = 3 * j
        a0, a1, a2 = _rot(kx, ky, kz, c, -s, ai[h + o], ai[h + o + 1], ai[h + o + 2])
        q0 = y[o]
        q1 = y[o + 1]
        q2 = y[o + 2]
        v0 = y[h + o]
        v1 = y[h + o + 1]
        v2 = y[h + o + 2]
        # omega x q, then omega x (omega x q), and omega x v
        e0 = wy * q2 - wz * q1
        e1 = wz * q0 - wx * q2
        e2 = wx * q1 - wy * q0
        dy[h + o] = a0 - 2.0 * (wy * v2 - wz * v1) - (wy * e2 - wz * e1)
        dy[h + o + 1] = a1 - 2.0 * (wz * v0 - wx * v2) - (wz * e0 - wx * e2)
        dy[h + o + 2] = a2 - 2.0 * (wx * v1 - wy * v0) - (wx * e1 - wy * e0)
    for i in range(2 * h, n):
        dy[i] = ai[i]
    if nrig > 0:  # q_f' = q_R^* (x) q' - 1/2 (0, omega) (x) q_f
        att = int(p[H_OFF_ATT])
        for j in range(nrig):
            o = att + 7 * j
            d0, d1, d2, d3 = _qmul(c2, -kx * s2, -ky * s2, -kz * s2, ai[o], ai[o + 1], ai[o + 2], ai[o + 3])
            e0, e1, e2, e3 = _qmul(0.0, wx, wy, wz, y[o], y[o + 1], y[o + 2], y[o + 3])
            dy[o] = d0 - 0.5 * e0
            dy[o + 1] = d1 - 0.5 * e1
            dy[o + 2] = d2 - 0.5 * e2
            dy[o + 3] = d3 - 0.5 * e3
    for i in range(h):
        dy[i] = y[h + i]
    return st


def _rotation_matrices(t: np.ndarray, omega: np.ndarray) -> np.ndarray:
    """R(t) for every time since the anchor (shape (m, 3, 3)): the frame's components to inertial
    ones."""
    w = float(np.linalg.norm(omega))
    k = omega / w
    K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    ang = w * np.atleast_1d(np.asarray(t, dtype=float))
    s = np.sin(ang)[:, None, None]
    c = np.cos(ang)[:, None, None]
    return np.eye(3) + s * K + (1.0 - c) * (K @ K)


def _turn_quaternions(t, Y, omega: np.ndarray, quaternions, sign: float) -> None:
    """In place: each quaternion block (offsets ``quaternions``) of the rows Y turned by the
    frame's rotation q_R(t) (sign +1: body -> frame to body -> inertial, q_R (x) q_f; -1: back)."""
    if not len(quaternions):
        return
    w = float(np.linalg.norm(omega))
    k = omega / w
    half = 0.5 * w * np.atleast_1d(np.asarray(t, dtype=float))
    c, s = np.cos(half), sign * np.sin(half)
    for o in quaternions:
        b = Y[:, o : o + 4].copy()
        Y[:, o] = c * b[:, 0] - s * (k[0] * b[:, 1] + k[1] * b[:, 2] + k[2] * b[:, 3])
        Y[:, o + 1] = c * b[:, 1] + s * (k[0] * b[:, 0] + k[1] * b[:, 3] - k[2] * b[:, 2])
        Y[:, o + 2] = c * b[:, 2] + s * (k[1] * b[:, 0] - k[0] * b[:, 3] + k[2] * b[:, 1])
        Y[:, o + 3] = c * b[:, 3] + s * (k[2] * b[:, 0] + k[0] * b[:, 2] - k[1] * b[:, 1])


def to_inertial(t, Y, omega_rad_s, state, quaternions=()) -> np.ndarray:
    """Cowell states [q, q_in', attitude, wheels] (rows) from frame states [q, v, attitude_f,
    wheels] at the times ``t`` since the anchor; ``state``: the model's StateLayout;
    ``quaternions``: the offsets of the rigid bodies' quaternions (StateLayout.quaternion_of),
    stored body -> frame in the frame state."""
    omega = np.asarray(omega_rad_s, dtype=float)
    Y = np.atleast_2d(np.asarray(Y, dtype=float))
    R = _rotation_matrices(t, omega)
    m = Y.shape[0]
    q = Y[:, state.q].reshape(m, -1, 3)
    v = Y[:, state.qd].reshape(m, -1, 3) + np.cross(omega, q)
    out = Y.copy()
    out[:, state.q] = np.einsum("mij,mkj->mki", R, q).reshape(m, -1)
    out[:, state.qd] = np.einsum("mij,mkj->mki", R, v).reshape(m, -1)
    _turn_quaternions(t, out, omega, quaternions, 1.0)
    return out


def to_frame(t: float, y, omega_rad_s, state, quaternions=()) -> np.ndarray:
    """The frame state of one Cowell state y at the time t since the anchor (:func:`to_inertial`)."""
    omega = np.asarray(omega_rad_s, dtype=float)
    y = np.asarray(y, dtype=float)
    R = _rotation_matrices(t, omega)[0]
    q_in = y[state.q].reshape(-1, 3)
    q = q_in @ R  # R^T q_in for every row
    v = y[state.qd].reshape(-1, 3) @ R - np.cross(omega, q)
    out = y.copy()
    out[state.q] = q.ravel()
    out[state.qd] = v.ravel()
    _turn_quaternions([t], out[None, :], omega, quaternions, -1.0)
    return out


def frame_rate(y0: np.ndarray, state) -> np.ndarray:
    """omega of the frame: the root body's r x v / |r|^2 at the start (``state``: the StateLayout)."""
    r = y0[state.root_r]
    v = y0[state.root_v]
    rr = float(r @ r)
    if not rr > 0.0:
        raise ValueError("the root body is at the centre of the central body: no orbit to turn with")
    return np.cross(r, v) / rr
