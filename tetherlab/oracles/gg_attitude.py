"""Gravity-gradient attitude libration of a rigid satellite on a circular orbit.

An oracle for tetherlab's rigid bodies in orbit.  numpy and scipy only.
Derivation: docs/rigid-oracles.md, section 2.

Orbit frame (LVLH, as docs/scenes.md; Hughes 1986 ch. 8-9; Wie 2008, gravity-gradient stabilization):
o3 = nadir (-r/|r|), o2 = minus the orbit normal (-h/|h|), o1 = o2 x o3 (along-track: the
velocity direction on a circular orbit).  Body principal axes x, y, z are aligned with o1, o2, o3
at the relative equilibrium; roll phi about x, pitch theta about y, yaw psi about z; moments
Ix (roll), Iy (pitch), Iz (yaw).  The orbit frame turns at n (orbit rate) about -o2.

Linearised about the equilibrium (docs/rigid-oracles.md 2.2, with the torque 3 n^2 c x (I c),
c the nadir direction in the body frame):

    Iy theta'' + 3 n^2 (Ix - Iz) theta = 0                            (pitch)
    Ix phi''  - n (Ix - Iy + Iz) psi' + 4 n^2 (Iy - Iz) phi = 0       (roll)
    Iz psi''  + n (Ix - Iy + Iz) phi' + n^2 (Iy - Ix) psi = 0         (yaw)

so w_pitch = n sqrt(3 (Ix - Iz)/Iy), and with k1 = (Iy - Iz)/Ix, k3 = (Iy - Ix)/Iz the roll-yaw
frequencies W = w/n solve the characteristic quartic

    W^4 - (1 + 3 k1 + k1 k3) W^2 + 4 k1 k3 = 0

(Hughes, Spacecraft Attitude Dynamics, 1986, ch. 9; Kaplan, Modern Spacecraft Dynamics and
Control, 1976; Wie, Space Vehicle Dynamics and Control, 2008: the same equations -- their
equation numbers could not be checked offline, so docs/rigid-oracles.md 2.2 derives them, and
that derivation, with its axis convention, is the source).  Linear stability: pitch Ix > Iz; roll-yaw
k1 k3 > 0, 1 + 3 k1 + k1 k3 > 0, (1 + 3 k1 + k1 k3)^2 > 16 k1 k3 (all three for two real positive
roots W^2).

:func:`integrate_nonlinear` integrates the full nonlinear rigid-body attitude on the circular
orbit (Euler's equations, quaternion kinematics, exact gravity-gradient torque of a body small
against its orbit radius) by scipy DOP853: the self-check of the linear frequencies, and a
reference time history.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .torque_free import integrate_reference, matrix_to_quat  # noqa: F401  (re-exported helper)


def k_ratios(Ix, Iy, Iz) -> tuple[float, float]:
    """(k1, k3) = ((Iy - Iz)/Ix, (Iy - Ix)/Iz)."""
    return (Iy - Iz) / Ix, (Iy - Ix) / Iz


def pitch_frequency(n_rad_s: float, Ix: float, Iy: float, Iz: float) -> float:
    """Linearised pitch libration frequency n sqrt(3 (Ix - Iz)/Iy) (rad/s); ValueError if Ix <= Iz
    (pitch unstable: the equilibrium is a saddle)."""
    if Ix <= Iz:
        raise ValueError(f"pitch is unstable for Ix <= Iz (got Ix = {Ix}, Iz = {Iz})")
    return n_rad_s * math.sqrt(3.0 * (Ix - Iz) / Iy)


@dataclass(frozen=True)
class Stability:
    pitch: bool  # Ix > Iz
    k1k3_positive: bool
    b_positive: bool  # 1 + 3 k1 + k1 k3 > 0
    discriminant_positive: bool  # (1 + 3 k1 + k1 k3)^2 > 16 k1 k3

    @property
    def roll_yaw(self) -> bool:
        return self.k1k3_positive and self.b_positive and self.discriminant_positive

    @property
    def all(self) -> bool:
        return self.pitch and self.roll_yaw


def stability(Ix, Iy, Iz) -> Stability:
    k1, k3 = k_ratios(Ix, Iy, Iz)
    b = 1.0 + 3.0 * k1 + k1 * k3
    return Stability(Ix > Iz, k1 * k3 > 0.0, b > 0.0, b * b > 16.0 * k1 * k3)


def roll_yaw_frequencies(n_rad_s: float, Ix: float, Iy: float, Iz: float) -> tuple[float, float]:
    """The two roll-yaw libration frequencies (low, high) in rad/s, from the quartic above."""
    st = stability(Ix, Iy, Iz)
    if not st.roll_yaw:
        raise ValueError(f"roll-yaw motion is not linearly stable for Ix, Iy, Iz = {Ix}, {Iy}, {Iz}: {st}")
    k1, k3 = k_ratios(Ix, Iy, Iz)
    b = 1.0 + 3.0 * k1 + k1 * k3
    c = 4.0 * k1 * k3
    disc = math.sqrt(b * b - 4.0 * c)
    hi2 = 0.5 * (b + disc)
    lo2 = c / hi2  # product of the roots: no cancellation for the small one
    return n_rad_s * math.sqrt(lo2), n_rad_s * math.sqrt(hi2)


def roll_yaw_matrix(n_rad_s, Ix, Iy, Iz) -> np.ndarray:
    """First-order system matrix of (phi, psi, phi', psi') (for eigenvalue cross-checks)."""
    g = n_rad_s * (Ix - Iy + Iz)
    A = np.zeros((4, 4))
    A[0, 2] = A[1, 3] = 1.0
    A[2, 0] = -4.0 * n_rad_s**2 * (Iy - Iz) / Ix
    A[2, 3] = g / Ix
    A[3, 1] = -(n_rad_s**2) * (Iy - Ix) / Iz
    A[3, 2] = -g / Iz
    return A


# -- orbit frame and angles -------------------------------------------------------------------------
def orbit_frame(r, v) -> np.ndarray:
    """Rows o1, o2, o3 (inertial components) of the LVLH frame: C_oi, inertial -> orbit."""
    r = np.asarray(r, float)
    v = np.asarray(v, float)
    o3 = -r / np.linalg.norm(r)
    h = np.cross(r, v)
    o2 = -h / np.linalg.norm(h)
    return np.array([np.cross(o2, o3), o2, o3])


def rpy_from_matrix(c_ob) -> np.ndarray:
    """(roll, pitch, yaw) of c_ob = Rz(yaw) Ry(pitch) Rx(roll) (body -> orbit, a 3-2-1 sequence).
    To first order the sequence does not matter: c_ob = 1 + [a x], a = (roll, pitch, yaw)."""
    c = np.asarray(c_ob, float)
    roll = math.atan2(c[2, 1], c[2, 2])
    pitch = -math.asin(max(-1.0, min(1.0, c[2, 0])))
    yaw = math.atan2(c[1, 0], c[0, 0])
    return np.array([roll, pitch, yaw])


def matrix_from_rpy(roll, pitch, yaw) -> np.ndarray:
    """Rz(yaw) Ry(pitch) Rx(roll): body -> orbit."""
    cr, sr = math.cos(roll), math.sin(roll)
    cp, sp = math.cos(pitch), math.sin(pitch)
    cy, sy = math.cos(yaw), math.sin(yaw)
    rz = np.array([[cy, -sy, 0.0], [sy, cy, 0.0], [0.0, 0.0, 1.0]])
    ry = np.array([[cp, 0.0, sp], [0.0, 1.0, 0.0], [-sp, 0.0, cp]])
    rx = np.array([[1.0, 0.0, 0.0], [0.0, cr, -sr], [0.0, sr, cr]])
    return rz @ ry @ rx


def circular_orbit(radius_m: float, mu_m3_s2: float):
    """(n, r(t), v(t)) of the circular equatorial orbit r = R (cos nt, sin nt, 0)."""
    n = math.sqrt(mu_m3_s2 / radius_m**3)

    def r(t):
        return radius_m * np.array([math.cos(n * t), math.sin(n * t), 0.0])

    def v(t):
        return radius_m * n * np.array([-math.sin(n * t), math.cos(n * t), 0.0])

    return n, r, v


def integrate_nonlinear(inertia_kg_m2, radius_m, mu_m3_s2, rpy0_rad, rpy_rate0_rad_s, t_s, rtol=1e-12, atol=1e-14):
    """Nonlinear attitude on the circular orbit r = R (cos nt, sin nt, 0): roll, pitch, yaw (n, 3).

    Initial attitude c_ob(0) from (roll, pitch, yaw); initial body rate = the orbit frame's rate
    seen in the body plus the body-frame rates ``rpy_rate0_rad_s`` relative to the orbit frame.
    Torque (body frame): 3 mu/R^3 c x (I c), c = the nadir direction in the body frame (the
    gravity-gradient torque of a body small against R: Hughes ch. 8)."""
    I = np.asarray(inertia_kg_m2, float)
    n, r, v = circular_orbit(radius_m, mu_m3_s2)
    c_oi0 = orbit_frame(r(0.0), v(0.0))
    c_ob0 = matrix_from_rpy(*rpy0_rad)
    c_ib0 = c_oi0.T @ c_ob0
    w_orbit_in = np.array([0.0, 0.0, n])  # LVLH rate (inertial components): n h/|h|
    w0 = c_ib0.T @ w_orbit_in + np.asarray(rpy_rate0_rad_s, float)

    def torque(t, c_ib, w):
        c = c_ib.T @ (-r(t) / radius_m)
        return 3.0 * n * n * np.cross(c, I * c)

    _, C = integrate_reference(I, w0, c_ib0, t_s, torque=torque, rtol=rtol, atol=atol)
    out = np.empty((len(t_s), 3))
    for k, tk in enumerate(np.asarray(t_s, float)):
        out[k] = rpy_from_matrix(orbit_frame(r(tk), v(tk)) @ C[k])
    return out
