"""Reference values for a continuous tether in circular orbit, and a frequency estimator.

Derivations and sources: docs/bead.md, section 5.  Everything here is independent of both
discrete models (TMED and beads): plain closed forms, or scipy ODE solves of the continuous
equations with tolerances far below the discretisation errors being measured.

* :func:`hill_vertical_tension`: closed-form tension at the two attachments of an inextensible
  tether on the local vertical in the Hill (linear gravity-gradient) approximation.
* :func:`exact_vertical_tension`: the same for an extensible tether in exact 1/r^2 gravity
  (shooting on the root radius and the spin rate).
* :func:`out_of_plane_modes`: out-of-plane lateral modes of the continuous tether with its end
  masses, tension varying along it (Sturm-Liouville problem, shooting on the eigenvalue).
* :func:`uniform_string_frequency`: f_k = k/(2L) sqrt(T/rho), the textbook string.
* :func:`dumbbell_inplane_frequency`: rigid in-plane libration at finite amplitude (elliptic K).
* :func:`fit_frequencies`: angular frequencies of a sampled sum of sinusoids (variable projection
  least squares started from Hann-windowed FFT peaks).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq, least_squares
from scipy.special import ellipk

_ODE = dict(method="DOP853", rtol=1e-13, atol=1e-14)


def com_offset_m(m0_kg: float, mf_kg: float, tether_mass_kg: float, length_m: float) -> float:
    """Distance a from the root to the centre of mass of a straight uniform tether with end masses."""
    return (mf_kg + 0.5 * tether_mass_kg) * length_m / (m0_kg + mf_kg + tether_mass_kg)


def hill_tension_profile(s_m, m0_kg, mf_kg, tether_mass_kg, length_m, omega_rad_s):
    """Tension T(s) (N) along an inextensible tether on the local vertical, Hill approximation:
    T(s) = 3 omega^2 [m0 a - rho ((s - a)^2 - a^2)/2] (docs/bead.md, eq. B3)."""
    a = com_offset_m(m0_kg, mf_kg, tether_mass_kg, length_m)
    rho = tether_mass_kg / length_m
    s = np.asarray(s_m, float)
    return 3.0 * omega_rad_s**2 * (m0_kg * a - 0.5 * rho * ((s - a) ** 2 - a * a))


def hill_vertical_tension(m0_kg, mf_kg, tether_mass_kg, length_m, omega_rad_s) -> tuple[float, float]:
    """(T_root, T_tip) in N: 3 omega^2 m0 a and 3 omega^2 mf (L - a) (docs/bead.md, eq. B4)."""
    a = com_offset_m(m0_kg, mf_kg, tether_mass_kg, length_m)
    w2 = omega_rad_s**2
    return 3.0 * w2 * m0_kg * a, 3.0 * w2 * mf_kg * (length_m - a)


@dataclass(frozen=True)
class HangingTether:
    """Exact relative equilibrium of a continuous extensible tether on the local vertical."""

    tension_root_N: float
    tension_tip_N: float
    spin_rad_s: float
    root_offset_m: float  # radial offset of the root from the centre of mass (negative: below)
    elongation: float  # stretched/unstretched length - 1


def exact_vertical_tension(m0_kg, mf_kg, tether_mass_kg, length_m, EA_N, mu_m3_s2, r_com_m, side=1.0) -> HangingTether:
    """Extensible tether in exact 1/r^2 gravity rotating rigidly at Omega, centre of mass at r_com.

    With s the unstretched arc length from the root and xi(s) the radial offset from r_com:
    xi' = side (1 + T/EA), T' = -side rho g(xi), g = Omega^2 r - mu/r^2 (outward, per unit mass);
    T(0) = -side m0 g(xi_0), tip balance mf g(xi_L) = side T(L), centre of mass
    m0 xi_0 + int rho xi ds + mf xi_L = 0.  Unknowns xi_0 and Omega^2/omega_c^2 - 1 (Newton with a
    finite-difference Jacobian); the ODE by DOP853 at rtol 1e-13 (docs/bead.md, eq. B5).
    """
    rho = tether_mass_kg / length_m
    w2 = mu_m3_s2 / r_com_m**3
    M = m0_kg + mf_kg + tether_mass_kg

    def g(xi, delta):  # Omega^2 r - mu/r^2 without cancellation (docs/bead.md, section 3)
        r = r_com_m + xi
        return w2 * (delta * r + xi) + mu_m3_s2 * xi * (2 * r_com_m + xi) / (r_com_m**2 * r**2)

    def shoot(x):
        xi0, delta = x[0] * length_m, x[1]
        T0 = -side * m0_kg * g(xi0, delta)

        def f(s, y):
            xi, T, _ = y
            return [side * (1.0 + T / EA_N), -side * rho * g(xi, delta), rho * xi]

        sol = solve_ivp(f, (0.0, length_m), [xi0, T0, 0.0], **_ODE)
        xiL, TL, mom = sol.y[:, -1]
        res = np.array([(mf_kg * g(xiL, delta) - side * TL) / (mf_kg * w2 * length_m),
                        (m0_kg * xi0 + mom + mf_kg * xiL) / (M * length_m)])  # fmt: skip
        return res, T0, TL, xiL

    a = com_offset_m(m0_kg, mf_kg, tether_mass_kg, length_m)
    x = np.array([-side * a / length_m, 0.0])
    for _ in range(30):
        res, *_ = shoot(x)
        J = np.empty((2, 2))
        for j, dx in enumerate((1e-7, 1e-7)):
            xp = x.copy()
            xp[j] += dx
            J[:, j] = (shoot(xp)[0] - res) / dx
        step = np.linalg.solve(J, res)
        x = x - step
        if np.max(np.abs(step)) < 1e-14:
            break
    res, T0, TL, xiL = shoot(x)
    if np.max(np.abs(res)) > 1e-10:
        raise RuntimeError(f"exact_vertical_tension: shooting did not converge (residual {np.max(np.abs(res)):.3g})")
    return HangingTether(T0, TL, math.sqrt(w2 * (1.0 + x[1])), x[0] * length_m, side * (xiL - x[0] * length_m) / length_m - 1.0)


@dataclass(frozen=True)
class LateralMode:
    omega_rad_s: float  # angular frequency of the mode (inertial time)
    lam: float  # eigenvalue lambda = Omega^2 - omega^2 of (T Z')' + lambda rho Z = 0

    shape: object  # callable Z(s), normalised to max |Z| = 1 over [0, L]


def _oop_shoot(lam, m0, mf, rho, L, tension, dense=False):
    def f(s, y):
        return [y[1] / tension(s), -lam * rho * y[0]]

    sol = solve_ivp(f, (0.0, L), [1.0, -lam * m0], dense_output=dense, **_ODE)
    Z, w = sol.y[:, -1]
    return w - lam * mf * Z, sol


def out_of_plane_modes(m0_kg, mf_kg, tether_mass_kg, length_m, omega_rad_s, count: int) -> list[LateralMode]:
    """The first ``count`` out-of-plane lateral (string) modes of a tether on the local vertical.

    Hill frame, inextensible tether, tension T(s) of :func:`hill_tension_profile`.  Out-of-plane
    displacement z(s, t): rho z_tt = (T z_s)_s - rho omega^2 z, with the end masses
    m0 z_tt = T z_s - m0 omega^2 z at s = 0 and mf z_tt = -T z_s - mf omega^2 z at s = L.  Modes
    z = Z(s) cos(Omega t) give (T Z')' + lambda rho Z = 0, T Z'(0) = -lambda m0 Z(0),
    T Z'(L) = lambda mf Z(L), with Omega^2 = omega^2 + lambda (docs/bead.md, eqs. C1-C3).
    lambda = 0 (translation) and lambda = 3 omega^2 (rigid libration at 2 omega) are roots too;
    the lateral modes are the roots above 3 omega^2, found by bracketing and brentq.
    """
    rho = tether_mass_kg / length_m

    def tension(s):
        return float(hill_tension_profile(s, m0_kg, mf_kg, tether_mass_kg, length_m, omega_rad_s))

    t_mean = float(np.mean(hill_tension_profile(np.linspace(0, length_m, 201), m0_kg, mf_kg, tether_mass_kg, length_m, omega_rad_s)))
    spacing = math.pi / length_m * math.sqrt(t_mean / rho)  # string mode spacing in sqrt(lambda)
    lo = math.sqrt(3.0) * omega_rad_s * 1.05
    grid = np.arange(lo, (count + 1.5) * spacing, spacing / 16.0)
    vals = [_oop_shoot(k * k, m0_kg, mf_kg, rho, length_m, tension)[0] for k in grid]
    modes = []
    for i in range(len(grid) - 1):
        if vals[i] * vals[i + 1] < 0:
            k = brentq(lambda k: _oop_shoot(k * k, m0_kg, mf_kg, rho, length_m, tension)[0], grid[i], grid[i + 1], xtol=1e-15, rtol=1e-14)
            sol = _oop_shoot(k * k, m0_kg, mf_kg, rho, length_m, tension, dense=True)[1]
            peak = float(np.max(np.abs(sol.sol(np.linspace(0.0, length_m, 2001))[0])))
            modes.append(LateralMode(math.sqrt(omega_rad_s**2 + k * k), k * k, lambda s, sol=sol, c=peak: sol.sol(s)[0] / c))
            if len(modes) == count:
                break
    if len(modes) < count:
        raise RuntimeError(f"out_of_plane_modes: found {len(modes)} of {count} modes")
    return modes


def uniform_string_frequency(k: int, length_m: float, tension_N: float, rho_kg_m: float) -> float:
    """Angular frequency 2 pi f_k, f_k = k/(2L) sqrt(T/rho) of a string with fixed ends."""
    return math.pi * k / length_m * math.sqrt(tension_N / rho_kg_m)


def dumbbell_inplane_frequency(omega_rad_s: float, theta0_rad: float) -> float:
    """In-plane libration frequency at amplitude theta0 of a rigid tether on a circular orbit.

    theta'' = -(3/2) omega^2 sin(2 theta) is a pendulum in 2 theta with small-amplitude frequency
    sqrt(3) omega; at amplitude 2 theta0 its period is 4 K(k)/(sqrt3 omega), k = sin(theta0)
    (docs/bead.md, eq. A2).  scipy's ellipk takes the parameter m = k^2.
    """
    return math.sqrt(3.0) * omega_rad_s * math.pi / (2.0 * ellipk(math.sin(theta0_rad) ** 2))


def spectral_peak(t: np.ndarray, q: np.ndarray, lo_rad_s: float, hi_rad_s: float) -> float:
    """Angular frequency of the largest Hann-windowed, 16x zero-padded FFT peak in [lo, hi]."""
    t = np.asarray(t, float)
    q = np.asarray(q, float) - np.mean(q)
    dt = t[1] - t[0]
    n = 16 * len(q)
    spec = np.abs(np.fft.rfft(q * np.hanning(len(q)), n))
    w = 2 * math.pi * np.fft.rfftfreq(n, dt)
    band = (w >= lo_rad_s) & (w <= hi_rad_s)
    if not band.any():
        raise ValueError(f"spectral_peak: no frequency in [{lo_rad_s}, {hi_rad_s}] rad/s at this sampling")
    return float(w[band][np.argmax(spec[band])])


def fit_frequencies(t: np.ndarray, q: np.ndarray, guesses_rad_s) -> tuple[np.ndarray, np.ndarray, float]:
    """Least-squares fit q(t) ~ c + sum_i (a_i cos W_i t + b_i sin W_i t).

    The amplitudes are linear (solved by lstsq for given frequencies: variable projection), the
    frequencies W_i nonlinear, started at ``guesses_rad_s``.  Returns (W, amplitudes, rms residual
    relative to the rms of q).  For noise-free data the frequency error is far below the FFT bin.
    """
    t = np.asarray(t, float)
    q = np.asarray(q, float)
    g = np.asarray(guesses_rad_s, float)
    tc = t - t.mean()  # centred time: better conditioned

    def design(w):
        cols = [np.ones_like(tc)]
        for wi in w:
            cols += [np.cos(wi * tc), np.sin(wi * tc)]
        return np.stack(cols, axis=1)

    scale = np.std(q) or 1.0

    def resid(x):
        A = design(x * g)
        coef, *_ = np.linalg.lstsq(A, q, rcond=None)
        return (q - A @ coef) / scale

    sol = least_squares(resid, np.ones_like(g), xtol=1e-15, ftol=1e-15, gtol=1e-15)
    w = sol.x * g
    coef, *_ = np.linalg.lstsq(design(w), q, rcond=None)
    amps = np.hypot(coef[1::2], coef[2::2])
    return w, amps, float(np.sqrt(np.mean(sol.fun**2)))
