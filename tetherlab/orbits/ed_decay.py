"""Closed-form decay of a rigid, local-vertical electrodynamic tether with a constant current in a
dipole field aligned with the rotation axis, on slowly shrinking circular orbits.

Derivation: docs/effects-electrodynamic.md, section 5.  For a vertical tether of length L carrying
I upwards, the Lorentz force along the track is F_t = -I L K cos(i) / r^3 at every point of the
orbit (no orbit average needed), and the energy balance of a circular orbit gives

    da/dt = 2 F_t / (M n) = -2 I L K cos(i) / (M sqrt(mu) a^(3/2)),

so with the inclination held fixed

    T(a0 -> a1) = M sqrt(mu) (a0^(5/2) - a1^(5/2)) / (5 I L K cos i).

The out-of-plane part of the force, F_h = I L K sin(i) cos(u) / r^3, raises the inclination
secularly: di/da = -tan(i) / (4 a), i.e. sin i = sin i0 (a0 / a)^(1/4);
:func:`decay_time_with_inclination_s` integrates da/dt with that law (one quadrature).
"""

from __future__ import annotations

import math

from scipy.integrate import quad


def decay_time_s(mass_kg, current_a, length_m, dipole_t_m3, inclination_rad, mu_m3_s2, a0_m, a1_m) -> float:
    """Time (s) for a to fall from a0 to a1 at constant inclination."""
    if not (a0_m > a1_m > 0.0):
        raise ValueError(f"a0_m must exceed a1_m > 0, got a0_m={a0_m!r}, a1_m={a1_m!r}")
    c = current_a * length_m * dipole_t_m3 * math.cos(inclination_rad)
    if not c > 0.0:
        raise ValueError(f"I L K cos(i) must be > 0 for a decay, got {c!r}")
    return mass_kg * math.sqrt(mu_m3_s2) * (a0_m**2.5 - a1_m**2.5) / (5.0 * c)


def decay_rate_m_s(mass_kg, current_a, length_m, dipole_t_m3, inclination_rad, mu_m3_s2, a_m) -> float:
    """da/dt (m/s, negative for a decay) at semi-major axis a."""
    return -2.0 * current_a * length_m * dipole_t_m3 * math.cos(inclination_rad) / (
        mass_kg * math.sqrt(mu_m3_s2) * a_m**1.5
    )


def inclination_at(inclination0_rad, a0_m, a_m) -> float:
    """Inclination (rad) after decaying from a0 to a: sin i = sin i0 (a0/a)^(1/4)."""
    return math.asin(min(1.0, math.sin(inclination0_rad) * (a0_m / a_m) ** 0.25))


def decay_time_with_inclination_s(mass_kg, current_a, length_m, dipole_t_m3, inclination0_rad, mu_m3_s2, a0_m, a1_m) -> float:
    """Time (s) from a0 to a1 with the secular inclination drift of the out-of-plane force."""

    def dt_da(a):
        i = inclination_at(inclination0_rad, a0_m, a)
        return -1.0 / decay_rate_m_s(mass_kg, current_a, length_m, dipole_t_m3, i, mu_m3_s2, a)

    value, _ = quad(dt_da, a1_m, a0_m, epsabs=0.0, epsrel=1e-12, limit=200)
    return value
