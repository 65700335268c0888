"""The in-plane libration of a tether of varying length on a circular orbit, as a rigid rod in the
Hill frame (docs/deployment.md 7, 14.2): an independent reference for a retrieval.

A station and a subsatellite (reduced mass m*) joined by a straight line of length l(t) and
density rho, at the in-plane angle theta from the local vertical.  Its angular momentum about the
centre of mass is I (theta' + Omega) with I = (m* + rho l/3) l^2, and the gravity gradient's torque
is -3 Omega^2 I sin theta cos theta, so

    theta'' = -(I'/I) (theta' + Omega) - 3 Omega^2 sin theta cos theta,
    I'/I = 2 l'/l + (rho l'/3) l^2 / I        (the material leaving the line takes its share).

For a massless line I'/I = 2 l'/l, the classic variable-length pendulum.  Nothing here imports
the TMED tether code; the length is the law's l(t), not the simulator's.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp


def libration(t_s: np.ndarray, length, rate, *, omega_rad_s: float, mstar_kg: float, rho_kg_m: float = 0.0,
              theta0_rad: float = 0.0, dtheta0_rad_s: float = 0.0, rtol: float = 1e-11) -> np.ndarray:
    """theta(t) at the times t_s (from t_s[0]) for the length l = length(t) and rate l' = rate(t)
    (callables, SI), from theta0 and theta'0; DOP853 at rtol (atol rtol x 1e-3 rad)."""

    def rhs(t, y):
        th, w = y
        l = length(t)
        ld = rate(t)
        inertia = (mstar_kg + rho_kg_m * l / 3.0) * l * l
        growth = 2.0 * ld / l + rho_kg_m * ld * l * l / (3.0 * inertia)
        return [w, -growth * (w + omega_rad_s) - 3.0 * omega_rad_s**2 * math.sin(th) * math.cos(th)]

    t_s = np.asarray(t_s, float)
    sol = solve_ivp(rhs, (t_s[0], t_s[-1]), [theta0_rad, dtheta0_rad_s], method="DOP853", t_eval=t_s, rtol=rtol,
                    atol=rtol * 1e-3)  # fmt: skip
    if not sol.success:
        raise RuntimeError(f"reeled pendulum: {sol.message}")
    return sol.y[0]


def libration_sensitivity(t_s: np.ndarray, length, rate, *, omega_rad_s: float, mstar_kg: float,
                          rho_kg_m: float = 0.0, rtol: float = 1e-11) -> dict:
    """The reeled pendulum from rest at the vertical with its variational equation: theta, theta',
    theta'' and the state transition matrix Phi(t) of (dtheta, dtheta') at the times t_s.

    Linearised about the solution, a perturbation f(t) of theta'' moves theta by
    int_0^t G(t, tau) f(tau) dtau, G(t, tau) = [Phi(t) Phi(tau)^-1]_(0,1) (docs/deployment.md 14.1)."""

    def parts(t, th, w):
        l = length(t)
        ld = rate(t)
        inertia = (mstar_kg + rho_kg_m * l / 3.0) * l * l
        growth = 2.0 * ld / l + rho_kg_m * ld * l * l / (3.0 * inertia)
        acc = -growth * (w + omega_rad_s) - 3.0 * omega_rad_s**2 * math.sin(th) * math.cos(th)
        return growth, acc

    def rhs(t, y):
        th, w = y[0], y[1]
        growth, acc = parts(t, th, w)
        a = np.array([[0.0, 1.0], [-3.0 * omega_rad_s**2 * math.cos(2.0 * th), -growth]])
        phi = y[2:].reshape(2, 2)
        return np.concatenate(([w, acc], (a @ phi).ravel()))

    t_s = np.asarray(t_s, float)
    y0 = np.array([0.0, 0.0, 1.0, 0.0, 0.0, 1.0])
    sol = solve_ivp(rhs, (t_s[0], t_s[-1]), y0, method="DOP853", t_eval=t_s, rtol=rtol, atol=rtol * 1e-3)
    if not sol.success:
        raise RuntimeError(f"reeled pendulum: {sol.message}")
    th, w = sol.y[0], sol.y[1]
    growth, acc = np.array([parts(t, a, b) for t, a, b in zip(t_s, th, w)]).T
    return {"theta": th, "dtheta": w, "ddtheta": acc, "growth": growth,
            "phi": sol.y[2:].T.reshape(-1, 2, 2)}  # fmt: skip
