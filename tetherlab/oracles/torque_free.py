"""Torque-free asymmetric rigid body (Euler-Poinsot motion): closed-form rates and attitude.

An oracle for tetherlab's rigid bodies.  numpy and scipy only: no tetherlab
simulator code.  Derivation, sign choices and sources: docs/rigid-oracles.md, section 1.

Body axes are principal, with moments I1 < I2 < I3 (distinct; the axis-symmetric top is not
treated here).  With 2T = sum I_i w_i^2 and H^2 = sum I_i^2 w_i^2 the two invariants of Euler's
equations

    I1 w1' = (I2 - I3) w2 w3,   I2 w2' = (I3 - I1) w3 w1,   I3 w3' = (I1 - I2) w1 w2,

Landau & Lifshitz (Mechanics, 3rd ed. 1976, section 37, "The asymmetrical top") give the rates in
Jacobi elliptic functions of u = lam t + u0, parameter m = k^2:

* H^2 > 2T I2 (rotation about the major axis I3: energy below the separatrix, for given H):
    w1 = s a1 cn u,  w2 = a2 sn u,  w3 = s a3 dn u,
    a1^2 = (2T I3 - H^2)/(I1 (I3 - I1)),  a2^2 = (2T I3 - H^2)/(I2 (I3 - I2)),
    a3^2 = (H^2 - 2T I1)/(I3 (I3 - I1)),  lam^2 = (I3 - I2)(H^2 - 2T I1)/(I1 I2 I3),
    m = (I2 - I1)(2T I3 - H^2)/((I3 - I2)(H^2 - 2T I1));
* H^2 < 2T I2 (rotation about the minor axis I1: energy above the separatrix):
    w1 = s a1 dn u,  w2 = a2 sn u,  w3 = s a3 cn u,
    a1^2 = (2T I3 - H^2)/(I1 (I3 - I1)),  a2^2 = (H^2 - 2T I1)/(I2 (I2 - I1)),
    a3^2 = (H^2 - 2T I1)/(I3 (I3 - I1)),  lam^2 = (I2 - I1)(2T I3 - H^2)/(I1 I2 I3),
    m = (I3 - I2)(H^2 - 2T I1)/((I2 - I1)(2T I3 - H^2))
  (L&L: "interchange the suffixes 1 and 3"; the sign of w2 is fixed by substituting into
  Euler's equations, docs/rigid-oracles.md 1.2).

s = +-1 is the sign of the component that never changes sign (w3 resp. w1); u0 follows from the
initial rates through the amplitude phi0 (sn u0 = sin phi0, cn u0 = cos phi0), u0 = F(phi0 | m).
The rates are periodic with period P = 4 K(m) / lam.

Attitude: with the inertial frame's z axis along the fixed angular momentum H and the body
attitude written as C = N Rz(psi) Rx(theta) Rz(phi) (body -> inertial, a 3-1-3 sequence),

    I1 w1 = H sin theta sin phi,  I2 w2 = H sin theta cos phi,  I3 w3 = H cos theta,
    psi' = H (I1 w1^2 + I2 w2^2) / (I1^2 w1^2 + I2^2 w2^2)

(L&L section 37).  theta and phi are algebraic in the rates; psi in closed form with the
incomplete elliptic integral of the third kind (:func:`psi_closed_form`, Carlson's R_F and R_J
from scipy.special), or by adaptive Gauss-Kronrod quadrature of psi' (scipy.integrate.quad, one
period stored); the two agree to ~1e-13 rad.  :func:`integrate_reference` is a second,
independent method (Euler's equations and the quaternion kinematics by scipy's DOP853 at rtol
1e-13).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.integrate import quad, solve_ivp
from scipy.special import elliprf, elliprj, ellipj, ellipk, ellipkinc

MAJOR = "major"  # rotation about the axis of largest moment (H^2 > 2T I2)
MINOR = "minor"  # rotation about the axis of smallest moment (H^2 < 2T I2)


@dataclass(frozen=True)
class EulerTop:
    """The closed-form torque-free motion of one rigid body (build with :func:`euler_top`)."""

    inertia_kg_m2: tuple[float, float, float]  # principal moments I1 < I2 < I3
    w0_rad_s: tuple[float, float, float]  # body rates at t = 0
    regime: str  # MAJOR or MINOR
    amplitudes: tuple[float, float, float]  # a1, a2, a3 (rad/s)
    sign: float  # s: the sign of the component that never changes sign
    lam_rad_s: float  # d u / d t
    m: float  # parameter k^2 of the elliptic functions
    u0: float
    quarter_period_u: float  # K(m)
    period_s: float  # period of the body rates, 4 K / lam
    energy2_J: float  # 2 T
    h_N_m_s: float  # |H|
    c0: np.ndarray = field(repr=False)  # initial attitude, body -> inertial
    frame_h: np.ndarray = field(repr=False)  # N: columns e1, e2, e3 = H/|H| (inertial)
    psi0: float = 0.0
    dpsi_half_period: float = 0.0  # increase of psi over P/2

    @property
    def h_inertial(self) -> np.ndarray:
        """The fixed angular momentum vector in the inertial frame (N m s)."""
        return self.frame_h[:, 2] * self.h_N_m_s


def euler_top(inertia_kg_m2, w0_rad_s, c0=None) -> EulerTop:
    """The torque-free motion from principal moments I1 < I2 < I3 (kg m^2), initial body rates
    (rad/s) and optional initial attitude c0 (3x3 body -> inertial rotation; identity default)."""
    I1, I2, I3 = (float(x) for x in inertia_kg_m2)
    if not (0.0 < I1 < I2 < I3):
        raise ValueError(f"inertia_kg_m2: expected principal moments 0 < I1 < I2 < I3, got {inertia_kg_m2!r}")
    if I1 + I2 < I3:
        raise ValueError(f"inertia_kg_m2: expected I1 + I2 >= I3 (a physical body), got {inertia_kg_m2!r}")
    w = np.asarray(w0_rad_s, float)
    if w.shape != (3,) or not np.all(np.isfinite(w)):
        raise ValueError(f"w0_rad_s: expected 3 finite rates, got {w0_rad_s!r}")
    w1, w2, w3 = w
    E2 = I1 * w1 * w1 + I2 * w2 * w2 + I3 * w3 * w3
    H2 = (I1 * w1) ** 2 + (I2 * w2) ** 2 + (I3 * w3) ** 2
    # 2T I3 - H^2 and H^2 - 2T I1 as sums of non-negative terms (no cancellation)
    p3 = I1 * w1 * w1 * (I3 - I1) + I2 * w2 * w2 * (I3 - I2)
    p1 = I2 * w2 * w2 * (I2 - I1) + I3 * w3 * w3 * (I3 - I1)
    # H^2 - 2T I2 = I1 w1^2 (I1 - I2) + I3 w3^2 (I3 - I2): its sign picks the regime
    d2 = I3 * w3 * w3 * (I3 - I2) - I1 * w1 * w1 * (I2 - I1)
    if p3 <= 0.0 or p1 <= 0.0:
        raise ValueError("w0_rad_s: a pure spin about a principal axis is steady; the oracle needs a tumbling body")
    if abs(d2) <= 1e-12 * (I3 * w3 * w3 * (I3 - I2) + I1 * w1 * w1 * (I2 - I1)):
        raise ValueError("w0_rad_s: on the separatrix (H^2 = 2T I2); the elliptic solution degenerates")
    if d2 > 0.0:
        regime = MAJOR
        a = (math.sqrt(p3 / (I1 * (I3 - I1))), math.sqrt(p3 / (I2 * (I3 - I2))), math.sqrt(p1 / (I3 * (I3 - I1))))
        lam = math.sqrt((I3 - I2) * p1 / (I1 * I2 * I3))
        m = (I2 - I1) * p3 / ((I3 - I2) * p1)
        s = 1.0 if w3 >= 0.0 else -1.0
        phi0 = math.atan2(w2 / a[1], s * w1 / a[0])
    else:
        regime = MINOR
        a = (math.sqrt(p3 / (I1 * (I3 - I1))), math.sqrt(p1 / (I2 * (I2 - I1))), math.sqrt(p1 / (I3 * (I3 - I1))))
        lam = math.sqrt((I2 - I1) * p3 / (I1 * I2 * I3))
        m = (I3 - I2) * p1 / ((I2 - I1) * p3)
        s = 1.0 if w1 >= 0.0 else -1.0
        phi0 = math.atan2(w2 / a[1], s * w3 / a[2])
    K = float(ellipk(m))
    u0 = float(ellipkinc(phi0, m))
    c0 = np.eye(3) if c0 is None else np.asarray(c0, float)
    if c0.shape != (3, 3) or np.max(np.abs(c0.T @ c0 - np.eye(3))) > 1e-12 or np.linalg.det(c0) < 0:
        raise ValueError("c0: expected a proper rotation matrix (body -> inertial)")
    h_in = c0 @ (np.array([I1, I2, I3]) * w)
    h = float(np.linalg.norm(h_in))
    e3 = h_in / h
    # any e1 perpendicular to e3: Gram-Schmidt on the inertial axis least aligned with it
    g = np.eye(3)[int(np.argmin(np.abs(e3)))]
    e1 = g - (g @ e3) * e3
    e1 /= np.linalg.norm(e1)
    frame = np.column_stack([e1, np.cross(e3, e1), e3])
    r313 = frame.T @ c0  # = Rz(psi0) Rx(theta0) Rz(phi0); third column (s psi s th, -c psi s th, c th)
    psi0 = math.atan2(r313[0, 2], -r313[1, 2])
    top = EulerTop((I1, I2, I3), (float(w1), float(w2), float(w3)), regime, a, s, lam, m, u0, K,
                   4.0 * K / lam, E2, h, c0, frame, psi0)  # fmt: skip
    half = 0.5 * top.period_s
    dpsi = _quad_psi_rate(top, 0.0, half)
    object.__setattr__(top, "dpsi_half_period", dpsi)
    return top


def rates(top: EulerTop, t_s) -> np.ndarray:
    """Body rates (n, 3) in rad/s at times t_s (closed form)."""
    t = np.atleast_1d(np.asarray(t_s, float))
    # reduce u modulo the period 4K first: ellipj is most accurate for small arguments
    u = np.mod(top.lam_rad_s * t + top.u0, 4.0 * top.quarter_period_u)
    sn, cn, dn, _ = ellipj(u, top.m)
    a1, a2, a3 = top.amplitudes
    s = top.sign
    if top.regime == MAJOR:
        return np.column_stack([s * a1 * cn, a2 * sn, s * a3 * dn])
    return np.column_stack([s * a1 * dn, a2 * sn, s * a3 * cn])


def rate_derivatives(top: EulerTop, t_s) -> np.ndarray:
    """d w / d t (n, 3) of the closed form, from sn' = cn dn, cn' = -sn dn, dn' = -m sn cn
    (for the self-check that the closed form satisfies Euler's equations)."""
    t = np.atleast_1d(np.asarray(t_s, float))
    u = np.mod(top.lam_rad_s * t + top.u0, 4.0 * top.quarter_period_u)
    sn, cn, dn, _ = ellipj(u, top.m)
    a1, a2, a3 = top.amplitudes
    s, lam, m = top.sign, top.lam_rad_s, top.m
    if top.regime == MAJOR:
        return lam * np.column_stack([-s * a1 * sn * dn, a2 * cn * dn, -s * a3 * m * sn * cn])
    return lam * np.column_stack([-s * a1 * m * sn * cn, a2 * cn * dn, -s * a3 * sn * dn])


def euler_residual(top: EulerTop, t_s) -> np.ndarray:
    """I w' + w x (I w) of the closed form (N m): zero by Euler's equations."""
    w = rates(top, t_s)
    dw = rate_derivatives(top, t_s)
    I = np.array(top.inertia_kg_m2)
    return I * dw + np.cross(w, I * w)


def _psi_rate(top: EulerTop, t):
    w = rates(top, t)[0]
    I1, I2, _ = top.inertia_kg_m2
    return top.h_N_m_s * (I1 * w[0] ** 2 + I2 * w[1] ** 2) / ((I1 * w[0]) ** 2 + (I2 * w[1]) ** 2)


def _quad_psi_rate(top: EulerTop, a: float, b: float) -> float:
    if b <= a:
        return 0.0
    val, _ = quad(lambda t: _psi_rate(top, t), a, b, epsabs=1e-14, epsrel=1e-13, limit=400)
    return float(val)


def euler_angles_313(top: EulerTop, t_s, psi_method: str = "closed") -> np.ndarray:
    """(psi, theta, phi) (n, 3) in rad of C = N Rz(psi) Rx(theta) Rz(phi); psi unwrapped.

    ``psi_method``: "closed" (elliptic integral of the third kind, :func:`psi_closed_form`) or
    "quad" (Gauss-Kronrod quadrature of psi'); they agree to ~1e-13 rad (tested)."""
    t = np.atleast_1d(np.asarray(t_s, float))
    w = rates(top, t)
    I = np.array(top.inertia_kg_m2)
    hb = I * w  # body-frame angular momentum
    theta = np.arctan2(np.hypot(hb[:, 0], hb[:, 1]), hb[:, 2])
    phi = np.arctan2(hb[:, 0], hb[:, 1])
    if psi_method == "closed":
        psi = psi_closed_form(top, t)
    elif psi_method == "quad":
        half = 0.5 * top.period_s
        psi = np.empty_like(t)
        for i, ti in enumerate(t):
            k = math.floor(ti / half)
            psi[i] = top.psi0 + k * top.dpsi_half_period + _quad_psi_rate(top, 0.0, ti - k * half)
    else:
        raise ValueError(f"psi_method: expected 'closed' or 'quad', got {psi_method!r}")
    return np.column_stack([psi, theta, phi])


def _pi_incomplete(n: float, phi, m: float):
    """Incomplete elliptic integral of the third kind Pi(n; phi | m) = int_0^phi dth /
    ((1 - n sin^2 th) sqrt(1 - m sin^2 th)) for |phi| <= pi/2, by Carlson's symmetric forms
    (DLMF 19.25.14): s R_F(c^2, 1 - m s^2, 1) + (n/3) s^3 R_J(c^2, 1 - m s^2, 1, 1 - n s^2)."""
    sphi = np.sin(phi)
    c2 = np.cos(phi) ** 2
    d2 = 1.0 - m * sphi * sphi
    return sphi * elliprf(c2, d2, 1.0) + (n / 3.0) * sphi**3 * elliprj(c2, d2, 1.0, 1.0 - n * sphi * sphi)


def psi_closed_form(top: EulerTop, t_s) -> np.ndarray:
    """psi(t) in closed form with the elliptic integral of the third kind (L&L section 37),
    a second method for the quadrature of :func:`euler_angles_313` (docs/rigid-oracles.md 1.3).

    psi' = H (2T - I3 w3^2)/(H^2 - I3^2 w3^2) = H/I3 + (H/I3)(2T I3 - H^2)/(A + B sn^2 u), with
    I3^2 w3^2 = I3^2 a3^2 dn^2 u (major) or I3^2 a3^2 cn^2 u (minor), so A = H^2 - I3^2 a3^2 and
    B = m I3^2 a3^2 (major) or I3^2 a3^2 (minor); int du/(A + B sn^2 u) = Pi(-B/A; am u | m)/A."""
    t = np.atleast_1d(np.asarray(t_s, float))
    I1, I2, I3 = top.inertia_kg_m2
    h = top.h_N_m_s
    a3 = top.amplitudes[2]
    A = h * h - (I3 * a3) ** 2
    B = (I3 * a3) ** 2 * (top.m if top.regime == MAJOR else 1.0)
    nchar = -B / A
    K, m = top.quarter_period_u, top.m
    pic = elliprf(0.0, 1.0 - m, 1.0) + (nchar / 3.0) * elliprj(0.0, 1.0 - m, 1.0, 1.0 - nchar)

    def big_pi(u):
        # am(u + 2K) = am(u) + pi: reduce u to [-K, K), where |am| <= pi/2
        k = np.floor((u + K) / (2.0 * K))
        ur = u - 2.0 * k * K
        phi = ellipj(ur, m)[3]
        return 2.0 * k * pic + _pi_incomplete(nchar, phi, m)

    u = top.lam_rad_s * t + top.u0
    c = (h / I3) * (top.energy2_J * I3 - h * h) / (top.lam_rad_s * A)
    return top.psi0 + (h / I3) * t + c * (big_pi(u) - big_pi(np.array([top.u0]))[0])


def _rz(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _rx(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def attitude(top: EulerTop, t_s, psi_method: str = "closed") -> np.ndarray:
    """Attitude matrices (n, 3, 3), body -> inertial, at times t_s."""
    ang = euler_angles_313(top, t_s, psi_method)
    return np.array([top.frame_h @ _rz(p) @ _rx(th) @ _rz(ph) for p, th, ph in ang])


# -- the second, independent method ---------------------------------------------------------------
def quat_to_matrix(q) -> np.ndarray:
    """Rotation matrix (body -> inertial) of a unit quaternion q = (q0, q1, q2, q3), scalar first."""
    q0, q1, q2, q3 = np.asarray(q, float) / np.linalg.norm(q)
    return np.array([
        [1 - 2 * (q2 * q2 + q3 * q3), 2 * (q1 * q2 - q0 * q3), 2 * (q1 * q3 + q0 * q2)],
        [2 * (q1 * q2 + q0 * q3), 1 - 2 * (q1 * q1 + q3 * q3), 2 * (q2 * q3 - q0 * q1)],
        [2 * (q1 * q3 - q0 * q2), 2 * (q2 * q3 + q0 * q1), 1 - 2 * (q1 * q1 + q2 * q2)],
    ])  # fmt: skip


def matrix_to_quat(c) -> np.ndarray:
    """Unit quaternion (scalar first, q0 >= 0) of a rotation matrix (Shepperd's method)."""
    c = np.asarray(c, float)
    tr = np.trace(c)
    cand = [1 + tr, 1 + 2 * c[0, 0] - tr, 1 + 2 * c[1, 1] - tr, 1 + 2 * c[2, 2] - tr]
    i = int(np.argmax(cand))
    q = np.empty(4)
    q[i] = 0.5 * math.sqrt(cand[i])
    f = 0.25 / q[i]
    if i == 0:
        q[1:] = f * np.array([c[2, 1] - c[1, 2], c[0, 2] - c[2, 0], c[1, 0] - c[0, 1]])
    elif i == 1:
        q[0], q[2], q[3] = f * (c[2, 1] - c[1, 2]), f * (c[0, 1] + c[1, 0]), f * (c[0, 2] + c[2, 0])
    elif i == 2:
        q[0], q[1], q[3] = f * (c[0, 2] - c[2, 0]), f * (c[0, 1] + c[1, 0]), f * (c[1, 2] + c[2, 1])
    else:
        q[0], q[1], q[2] = f * (c[1, 0] - c[0, 1]), f * (c[0, 2] + c[2, 0]), f * (c[1, 2] + c[2, 1])
    return q if q[0] >= 0 else -q


def integrate_reference(inertia_kg_m2, w0_rad_s, c0, t_s, torque=None, rtol=1e-13, atol=1e-15):
    """Euler's equations + quaternion kinematics q' = q (x) (0, w)/2 by scipy DOP853.

    Returns (w (n, 3), C (n, 3, 3)).  ``torque(t, C, w)`` (body frame, N m) is optional (the
    gravity-gradient oracle uses it).  Independent of the closed form above."""
    I = np.asarray(inertia_kg_m2, float)

    def f(t, y):
        q = y[:4]
        w = y[4:]
        q0, q1, q2, q3 = q
        dq = 0.5 * np.array([
            -q1 * w[0] - q2 * w[1] - q3 * w[2],
            q0 * w[0] + q2 * w[2] - q3 * w[1],
            q0 * w[1] + q3 * w[0] - q1 * w[2],
            q0 * w[2] + q1 * w[1] - q2 * w[0],
        ])  # fmt: skip
        M = np.zeros(3) if torque is None else torque(t, quat_to_matrix(q), w)
        dw = (M - np.cross(w, I * w)) / I
        return np.concatenate([dq, dw])

    t = np.asarray(t_s, float)
    y0 = np.concatenate([matrix_to_quat(c0), np.asarray(w0_rad_s, float)])
    sol = solve_ivp(f, (0.0, float(t[-1])), y0, method="DOP853", rtol=rtol, atol=atol, t_eval=t)
    if not sol.success:
        raise RuntimeError(sol.message)
    return sol.y[4:].T, np.array([quat_to_matrix(q) for q in sol.y[:4].T])


def rotation_angle(a, b) -> np.ndarray:
    """Angle (rad) of the rotation a^T b between matching attitude matrices (n, 3, 3)."""
    a = np.asarray(a, float)
    b = np.asarray(b, float)
    r = np.einsum("nji,njk->nik", a, b)
    # robust small angles: |skew part| = sin(angle)
    sk = 0.5 * np.stack([r[:, 2, 1] - r[:, 1, 2], r[:, 0, 2] - r[:, 2, 0], r[:, 1, 0] - r[:, 0, 1]], axis=1)
    return np.arctan2(np.linalg.norm(sk, axis=1), 0.5 * (np.trace(r, axis1=1, axis2=2) - 1.0))
