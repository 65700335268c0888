"""Hub and spoke in free space: the steady state of N identical tethers spinning on a free hub.

An oracle for tetherlab's hub-and-spoke (paper section 2.4).  numpy and scipy
only.  Derivation: docs/rigid-oracles.md, section 3.

Each tether is a continuous elastic string of unstretched length L, mass rho per unstretched
length, axial stiffness EA (tension T = EA eps, eps the strain), attached at a point fixed on the
hub at distance r_h from the spin axis (r_h = 0: at the hub's centre), carrying a tip mass m_f.
No gravity (free space), so uniform rotation at Omega with every tether straight and radial is an
exact steady state; N >= 2 tethers spaced symmetrically keep the hub's centre fixed (the tethers'
pulls cancel).  With s in [0, L] the unstretched arc length from the hub and x(s) the distance
from the spin axis (the radial balance of an element in the rotating frame):

    x' = 1 + T/EA,    T' = -rho Omega^2 x,    x(0) = r_h,    T(L) = m_f Omega^2 x(L).

Eliminating T gives x'' = -kappa^2 x, kappa = Omega sqrt(rho/EA): a linear problem, so

    x(s) = r_h cos(kappa s) + B sin(kappa s),    T(s) = EA (x'(s) - 1),
    B = [EA + m_f Omega^2 r_h cos(kappa L) + EA kappa r_h sin(kappa L)]
        / [EA kappa cos(kappa L) - m_f Omega^2 sin(kappa L)]

(:func:`spoke_profile`; the denominator > 0 is the condition for the steady state to exist: past
it the spin stretches the tether without limit).  :func:`spoke_profile_bvp` solves the same
boundary-value problem with scipy's collocation solver as an independent check, and
:func:`spoke_profile_inextensible` is the EA -> infinity limit

    T(s) = Omega^2 [m_f (r_h + L) + rho (L - s) (r_h + (L + s)/2)],    x(s) = r_h + s.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_bvp
from scipy.optimize import brentq


@dataclass(frozen=True)
class Spoke:
    """The steady state of one spoke (build with :func:`spoke_profile`)."""

    omega_rad_s: float
    length_m: float
    EA_N: float
    rho_kg_m: float
    tip_mass_kg: float
    hub_radius_m: float
    kappa_1_m: float
    B_m: float

    def x(self, s_m):
        """Distance from the spin axis (m) at unstretched arc length s."""
        s = np.asarray(s_m, float)
        k = self.kappa_1_m
        return self.hub_radius_m * np.cos(k * s) + self.B_m * np.sin(k * s)

    def tension(self, s_m):
        """Tension (N) at unstretched arc length s."""
        s = np.asarray(s_m, float)
        k = self.kappa_1_m
        return self.EA_N * (-self.hub_radius_m * k * np.sin(k * s) + self.B_m * k * np.cos(k * s) - 1.0)

    @property
    def tip_radius_m(self) -> float:
        return float(self.x(self.length_m))

    @property
    def hub_tension_N(self) -> float:
        return float(self.tension(0.0))

    @property
    def tip_tension_N(self) -> float:
        return float(self.tension(self.length_m))

    def moment_of_inertia_kg_m2(self) -> float:
        """int rho x^2 ds + m_f x(L)^2 about the spin axis (closed form of the integral)."""
        k, L, r, B = self.kappa_1_m, self.length_m, self.hub_radius_m, self.B_m
        s2 = math.sin(2.0 * k * L) / (4.0 * k)
        ix2 = r * r * (0.5 * L + s2) + B * B * (0.5 * L - s2) + r * B * (1.0 - math.cos(2.0 * k * L)) / (2.0 * k)
        return self.rho_kg_m * ix2 + self.tip_mass_kg * self.tip_radius_m**2


def _check(omega, length, EA, rho, tip, r_h):
    for name, val, lo in (("omega_rad_s", omega, 0.0), ("length_m", length, 0.0), ("EA_N", EA, 0.0), ("rho_kg_m", rho, 0.0)):
        if not (math.isfinite(val) and val > lo):
            raise ValueError(f"{name}: expected a finite number > {lo}, got {val!r}")
    for name, val in (("tip_mass_kg", tip), ("hub_radius_m", r_h)):
        if not (math.isfinite(val) and val >= 0.0):
            raise ValueError(f"{name}: expected a finite number >= 0, got {val!r}")


def spoke_profile(omega_rad_s, length_m, EA_N, rho_kg_m, tip_mass_kg, hub_radius_m=0.0) -> Spoke:
    """The closed-form steady state of one extensible spoke (see the module docstring)."""
    _check(omega_rad_s, length_m, EA_N, rho_kg_m, tip_mass_kg, hub_radius_m)
    w2 = omega_rad_s**2
    k = omega_rad_s * math.sqrt(rho_kg_m / EA_N)
    c, s = math.cos(k * length_m), math.sin(k * length_m)
    den = EA_N * k * c - tip_mass_kg * w2 * s
    if not den > 0.0 or k * length_m >= 0.5 * math.pi:
        raise ValueError(f"omega_rad_s = {omega_rad_s}: beyond the spin at which a steady state exists "
                         f"(EA kappa cos kappa L <= m_f Omega^2 sin kappa L)")  # fmt: skip
    B = (EA_N + tip_mass_kg * w2 * hub_radius_m * c + EA_N * k * hub_radius_m * s) / den
    return Spoke(float(omega_rad_s), float(length_m), float(EA_N), float(rho_kg_m), float(tip_mass_kg),
                 float(hub_radius_m), k, B)  # fmt: skip


def spoke_profile_bvp(omega_rad_s, length_m, EA_N, rho_kg_m, tip_mass_kg, hub_radius_m=0.0, nodes=41, tol=1e-10):
    """The same steady state by scipy.integrate.solve_bvp (collocation): returns the solution
    object; ``sol.sol(s)`` gives (x(s), T(s)).  Independent of the closed form."""
    _check(omega_rad_s, length_m, EA_N, rho_kg_m, tip_mass_kg, hub_radius_m)
    w2 = omega_rad_s**2

    def f(s, y):
        return np.vstack([1.0 + y[1] / EA_N, -rho_kg_m * w2 * y[0]])

    def bc(ya, yb):
        return np.array([(ya[0] - hub_radius_m) / length_m, (yb[1] - tip_mass_kg * w2 * yb[0]) / EA_N])

    s = np.linspace(0.0, length_m, nodes)
    guess = spoke_profile_inextensible(omega_rad_s, length_m, rho_kg_m, tip_mass_kg, hub_radius_m)
    y0 = np.vstack([hub_radius_m + s, guess.tension(s)])
    sol = solve_bvp(f, bc, s, y0, tol=tol, bc_tol=1e-14, max_nodes=100000)
    if not sol.success:
        raise RuntimeError(f"solve_bvp: {sol.message}")
    return sol


@dataclass(frozen=True)
class InextensibleSpoke:
    omega_rad_s: float
    length_m: float
    rho_kg_m: float
    tip_mass_kg: float
    hub_radius_m: float

    def x(self, s_m):
        return self.hub_radius_m + np.asarray(s_m, float)

    def tension(self, s_m):
        s = np.asarray(s_m, float)
        L, r = self.length_m, self.hub_radius_m
        return self.omega_rad_s**2 * (self.tip_mass_kg * (r + L) + self.rho_kg_m * (L - s) * (r + 0.5 * (L + s)))


def spoke_profile_inextensible(omega_rad_s, length_m, rho_kg_m, tip_mass_kg, hub_radius_m=0.0) -> InextensibleSpoke:
    """The EA -> infinity limit (closed form, module docstring)."""
    return InextensibleSpoke(float(omega_rad_s), float(length_m), float(rho_kg_m), float(tip_mass_kg), float(hub_radius_m))


def angular_momentum(omega_rad_s, n_spokes, hub_axial_inertia_kg_m2, hub_mass_kg, length_m, EA_N, rho_kg_m,
                     tip_mass_kg, hub_radius_m=0.0) -> float:  # fmt: skip
    """Total angular momentum (N m s) about the spin axis of the steady state: the hub (a rigid
    body spinning with the tethers; its centre is on the axis, so its mass does not enter) plus N
    spokes.  ``hub_mass_kg`` is accepted for symmetry with the scene and unused."""
    del hub_mass_kg
    sp = spoke_profile(omega_rad_s, length_m, EA_N, rho_kg_m, tip_mass_kg, hub_radius_m)
    return omega_rad_s * (hub_axial_inertia_kg_m2 + n_spokes * sp.moment_of_inertia_kg_m2())


def spin_for_angular_momentum(h_N_m_s, n_spokes, hub_axial_inertia_kg_m2, length_m, EA_N, rho_kg_m, tip_mass_kg,
                              hub_radius_m=0.0) -> float:  # fmt: skip
    """The spin rate Omega (rad/s) of the steady state with total angular momentum h (brentq).

    A damped spinning system keeps its angular momentum while it relaxes (internal damping exerts
    no external torque), so this is the spin it settles at, whatever it started with."""
    # the steady state exists for kappa L < pi/2 (and the tip condition); search below that
    w_max = 0.5 * math.pi / (length_m * math.sqrt(rho_kg_m / EA_N))

    def h_of(w):
        try:
            return angular_momentum(w, n_spokes, hub_axial_inertia_kg_m2, 0.0, length_m, EA_N, rho_kg_m, tip_mass_kg,
                                    hub_radius_m) - h_N_m_s  # fmt: skip
        except ValueError:
            return math.inf

    hi = w_max
    while not math.isfinite(h_of(hi)):
        hi *= 0.999
    if h_of(hi) < 0.0:
        raise ValueError(f"h_N_m_s = {h_N_m_s}: more angular momentum than any steady state carries")
    return brentq(h_of, 1e-12 * hi, hi, xtol=1e-16, rtol=1e-15, maxiter=200)


def discretisation_bound_m(n_rods: int, spoke: Spoke) -> float:
    """Error budget for a chain of n uniform-strain rods against the continuum (docs/rigid-oracles.md
    3.4): each rod's strain is one number, while the continuum strain falls along the rod by
    (T(s_a) - T(s_b))/EA; if the rod's strain lies anywhere between its ends' continuum strains,
    every joint is within sum_j h (T(s_j) - T(s_j+1))/EA = h (T(0) - T(L))/EA of the continuum's
    point, h = L/n.  A first-order, worst-case bound (a consistent rod is second order)."""
    h = spoke.length_m / n_rods
    return h * (spoke.hub_tension_N - spoke.tip_tension_N) / spoke.EA_N
