"""Momentum exchange between a rigid body and its momentum wheels.

An oracle for tetherlab's wheels.  numpy and scipy only.
Derivation: docs/rigid-oracles.md, section 4.

Quantities are physical and convention-free: J_s the inertia of the whole body with its wheels
*locked* (the paper's "inertia tensor including the contribution of the wheels"), wheel i with
spin axis a_i (unit, body frame), axial moment Iw_i, speed Omega_i *relative to the body*, motor
torque M_i (on the wheel about a_i; -M_i a_i on the body).  Then

    H_b = J_s w + sum_i Iw_i Omega_i a_i                  (total angular momentum, body frame)
    dH_b/dt + w x H_b = 0                                 (no external torque)
    Iw_i (a_i . w' + Omega_i') = M_i                      (axial balance of wheel i)
    E = w.J_s w / 2 + sum_i Iw_i Omega_i (a_i . w) + sum_i Iw_i Omega_i^2 / 2
    dE/dt = sum_i M_i Omega_i                             (the motors' work)

Single axis (closed form, :class:`SingleAxis`): body spinning at w about a principal axis of J_s
(moment J) with one wheel on that axis and a piecewise-constant motor torque M(t):

    w(t) = w0 - int M dt / (J - Iw),     Omega(t) = Omega0 + J int M dt / (Iw (J - Iw)),
    J w + Iw Omega = const,              (J - Iw) dw = -d[Iw (w + Omega)]  (the wheel's gain),
    E(t) - E(0) = int M Omega dt.

Note on the paper's eqs. 45-46: with J_B including the wheels and h_w = Iw Omega a (relative),
eq. 45 is exact but eq. 46 (h_w' = M_w) is not: h_w' = M_w - Iw (a . w') a.  Eq. 46 holds for the
wheel's *absolute* axial momentum Iw (a.w + Omega), with J_B then excluding the wheels' axial
moments (docs/rigid-oracles.md 4.1).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

from .torque_free import matrix_to_quat, quat_to_matrix


@dataclass(frozen=True)
class SingleAxis:
    """Body of axial moment J (wheel locked) spinning at w0 about a principal axis, one wheel of
    axial moment Iw at relative speed Omega0 on that axis; motor torque ``torques_N_m[k]`` from
    ``switch_times_s[k]`` on (the first switch at 0)."""

    J_kg_m2: float
    Iw_kg_m2: float
    w0_rad_s: float
    Omega0_rad_s: float
    switch_times_s: tuple
    torques_N_m: tuple

    def __post_init__(self):
        if not (0.0 < self.Iw_kg_m2 < self.J_kg_m2):
            raise ValueError(f"Iw_kg_m2: expected 0 < Iw < J = {self.J_kg_m2}, got {self.Iw_kg_m2}")
        if len(self.switch_times_s) != len(self.torques_N_m) or self.switch_times_s[0] != 0.0:
            raise ValueError("switch_times_s: expected one time per torque, the first 0")
        if any(b <= a for a, b in zip(self.switch_times_s, self.switch_times_s[1:])):
            raise ValueError("switch_times_s: expected increasing times")

    def impulse(self, t_s):
        """int_0^t M dt (N m s) and int_0^t M t' dt' (N m s^2), exact for piecewise constants."""
        t = np.asarray(t_s, float)
        edges = np.append(np.asarray(self.switch_times_s, float), np.inf)
        imp = np.zeros_like(t)
        mom = np.zeros_like(t)
        for M, a, b in zip(self.torques_N_m, edges[:-1], edges[1:]):
            hi = np.clip(t, a, b)
            imp += M * (hi - a)
            mom += 0.5 * M * (hi * hi - a * a)
        return imp, mom

    def state(self, t_s):
        """(w, Omega) at t (rad/s)."""
        imp, _ = self.impulse(t_s)
        J, Iw = self.J_kg_m2, self.Iw_kg_m2
        return self.w0_rad_s - imp / (J - Iw), self.Omega0_rad_s + J * imp / (Iw * (J - Iw))

    def angular_momentum(self, t_s):
        w, Om = self.state(t_s)
        return self.J_kg_m2 * w + self.Iw_kg_m2 * Om

    def wheel_absolute_momentum(self, t_s):
        w, Om = self.state(t_s)
        return self.Iw_kg_m2 * (w + Om)

    def energy(self, t_s):
        w, Om = self.state(t_s)
        J, Iw = self.J_kg_m2, self.Iw_kg_m2
        return 0.5 * (J - Iw) * w * w + 0.5 * Iw * (w + Om) ** 2

    def motor_work(self, t_s):
        """int_0^t M Omega dt (J): Omega is linear in t on each piece, so exact in closed form."""
        t = np.asarray(t_s, float)
        J, Iw = self.J_kg_m2, self.Iw_kg_m2
        c = J / (Iw * (J - Iw))
        edges = np.append(np.asarray(self.switch_times_s, float), np.inf)
        work = np.zeros_like(t)
        for M, a, b in zip(self.torques_N_m, edges[:-1], edges[1:]):
            hi = np.clip(t, a, b)
            _, Om_a = self.state(np.full_like(t, a))
            # Omega(t') = Omega(a) + c M (t' - a) on [a, b]
            work += M * (Om_a * (hi - a) + 0.5 * c * M * (hi - a) ** 2)
        return work


def integrate_gyrostat(J_s, axes, Iw, w0, Omega0, c0, t_s, motor_torque=None, rtol=1e-13, atol=1e-15):
    """A free rigid body with wheels (the equations of the module docstring) plus the quaternion
    kinematics, by scipy DOP853.  ``motor_torque(t, w, Omega) -> (k,)`` (N m), zero if None.

    Returns dict of t, w (n, 3), Omega (n, k), C (n, 3, 3) body -> inertial, H_inertial (n, 3),
    energy (n,), work (n,) = int sum M_i Omega_i dt (integrated alongside)."""
    J_s = np.asarray(J_s, float)
    A = np.atleast_2d(np.asarray(axes, float))  # (k, 3) unit axes, body frame
    A = A / np.linalg.norm(A, axis=1)[:, None]
    Iw = np.atleast_1d(np.asarray(Iw, float))
    k = len(Iw)
    # mass matrix of (w', Omega'): [[J_s, A^T diag(Iw)], [diag(Iw) A, diag(Iw)]]
    Mm = np.zeros((3 + k, 3 + k))
    Mm[:3, :3] = J_s
    Mm[:3, 3:] = A.T * Iw
    Mm[3:, :3] = Iw[:, None] * A
    Mm[3:, 3:] = np.diag(Iw)

    def f(t, y):
        q, w, Om = y[:4], y[4:7], y[7 : 7 + k]
        M = np.zeros(k) if motor_torque is None else np.asarray(motor_torque(t, w, Om), float)
        H = J_s @ w + A.T @ (Iw * Om)
        rhs = np.concatenate([-np.cross(w, H), M])
        acc = np.linalg.solve(Mm, rhs)
        q0, q1, q2, q3 = q
        dq = 0.5 * np.array([
            -q1 * w[0] - q2 * w[1] - q3 * w[2],
            q0 * w[0] + q2 * w[2] - q3 * w[1],
            q0 * w[1] + q3 * w[0] - q1 * w[2],
            q0 * w[2] + q1 * w[1] - q2 * w[0],
        ])  # fmt: skip
        return np.concatenate([dq, acc, [float(M @ Om)]])

    t = np.asarray(t_s, float)
    tu, back = np.unique(t, return_inverse=True)  # solve_ivp wants strictly increasing t_eval
    y0 = np.concatenate([matrix_to_quat(c0), np.asarray(w0, float), np.asarray(Omega0, float), [0.0]])
    sol = solve_ivp(f, (0.0, float(t[-1])), y0, method="DOP853", rtol=rtol, atol=atol, t_eval=tu)
    if not sol.success:
        raise RuntimeError(sol.message)
    Y = sol.y[:, back]
    C = np.array([quat_to_matrix(q) for q in Y[:4].T])
    w = Y[4:7].T
    Om = Y[7 : 7 + k].T
    Hb = w @ J_s.T + (Om * Iw) @ A
    E = 0.5 * np.einsum("ni,ij,nj->n", w, J_s, w) + np.sum(Iw * Om * (w @ A.T), axis=1) + 0.5 * np.sum(Iw * Om * Om, axis=1)
    return {"t": t, "w": w, "Omega": Om, "C": C, "H_inertial": np.einsum("nij,nj->ni", C, Hb), "energy": E,
            "work": Y[-1]}  # fmt: skip
