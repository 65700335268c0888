"""Exponential atmosphere, piecewise by altitude band, co-rotating with the Earth.

rho(h) = rho0_k exp(-(h - h0_k) / H_k) for h0_k <= h < h0_{k+1}, from Vallado, Fundamentals of
Astrodynamics and Applications (4th ed., 2013), Table 8-4 (0 to 1000 km; the same nominal values
as Wertz 1978, p. 820).  Above 1000 km the last band is extended; below 0 km the density is that
of sea level.  Altitude h = |r| - R (spherical Earth, R = the central body's radius), as the table
is meant for.  Derivation and discussion: docs/effects-electrodynamic.md, section 3.
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import njit
from .earth import EARTH_ROTATION_RATE_RAD_S  # the atmosphere co-rotates

# (base altitude h0 km, nominal density rho0 kg/m^3, scale height H km): Vallado Table 8-4.
VALLADO_TABLE_8_4 = (
    (0.0, 1.225, 7.249),
    (25.0, 3.899e-2, 6.349),
    (30.0, 1.774e-2, 6.682),
    (40.0, 3.972e-3, 7.554),
    (50.0, 1.057e-3, 8.382),
    (60.0, 3.206e-4, 7.714),
    (70.0, 8.770e-5, 6.549),
    (80.0, 1.905e-5, 5.799),
    (90.0, 3.396e-6, 5.382),
    (100.0, 5.297e-7, 5.877),
    (110.0, 9.661e-8, 7.263),
    (120.0, 2.438e-8, 9.473),
    (130.0, 8.484e-9, 12.636),
    (140.0, 3.845e-9, 16.149),
    (150.0, 2.070e-9, 22.523),
    (180.0, 5.464e-10, 29.740),
    (200.0, 2.789e-10, 37.105),
    (250.0, 7.248e-11, 45.546),
    (300.0, 2.418e-11, 53.628),
    (350.0, 9.518e-12, 53.298),
    (400.0, 3.725e-12, 58.515),
    (450.0, 1.585e-12, 60.828),
    (500.0, 6.967e-13, 63.822),
    (600.0, 1.454e-13, 71.835),
    (700.0, 3.614e-14, 88.667),
    (800.0, 1.170e-14, 124.64),
    (900.0, 5.245e-15, 181.05),
    (1000.0, 3.019e-15, 268.00),
)

#: The table in SI, as a constant array the compiled kernel closes over (frozen at compile time).
TABLE_SI = np.array([(h * 1e3, rho, hs * 1e3) for h, rho, hs in VALLADO_TABLE_8_4])



@njit(cache=True)
def density(h_m):
    """Density (kg/m^3) at altitude h (m) from Vallado Table 8-4."""
    tab = TABLE_SI
    n = tab.shape[0]
    if h_m <= 0.0:
        return tab[0, 1]
    k = n - 1
    while k > 0 and tab[k, 0] > h_m:
        k -= 1
    return tab[k, 1] * math.exp(-(h_m - tab[k, 0]) / tab[k, 2])


@njit(cache=True)
def relative_velocity(x, y, z, vx, vy, vz):
    """Velocity relative to the co-rotating atmosphere, v - omega_E z^ x r (m/s)."""
    w = EARTH_ROTATION_RATE_RAD_S
    return vx + w * y, vy - w * x, vz
