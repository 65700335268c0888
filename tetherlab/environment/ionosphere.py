"""Electron density of the ionosphere for the OML current (forces/oml.py): a Chapman layer or a
uniform density.  Derivation and choice of defaults: docs/effects-oml.md, sec. 4.

Chapman alpha layer (Chapman 1931; Davies 1990, Ionospheric Radio, sec. 2.4):

    N_e(h) = N_max exp( (1 - z - exp(-z)) / 2 ),   z = (h - h_max)/H,

with h = |r| - R (spherical Earth).  Defaults: N_max = 1e12 m^-3, h_max = 350 km, H = 100 km,
the order of a daytime mid-latitude F2 layer at moderate solar activity (IRI climatology,
Bilitza et al. 2017) with a topside scale height chosen so that N_e(1000 km) ~ 6e10 m^-3.
No local-time, latitude or solar-cycle dependence: a documented stand-in, not an ionosphere
model.  (PyIRI 0.1.7 installs offline with its coefficients; it is not wired in yet.)
"""

from __future__ import annotations

import math

from .._jit import njit
from .earth import EARTH_ROTATION_RATE_RAD_S  # noqa: F401  (the plasma co-rotates with the Earth)

IONO_CHAPMAN = 0
IONO_UNIFORM = 1
IONO_CODES = {"chapman": IONO_CHAPMAN, "uniform": IONO_UNIFORM}

def pack(params: dict, effect: str) -> list[float]:
    from ..errors import SceneError

    ne = params["electron_density"]
    if not (ne >= 0.0 and math.isfinite(ne)):
        raise SceneError(f"effects.{effect}.electron_density", "an electron density >= 0 m-3", repr(ne))
    hmax = params["peak_altitude"]
    hs = params["scale_height"]
    if not (hs > 0.0 and math.isfinite(hs)):
        raise SceneError(f"effects.{effect}.scale_height", "a scale height > 0 m", repr(hs))
    if not math.isfinite(hmax):
        raise SceneError(f"effects.{effect}.peak_altitude", "a finite altitude", repr(hmax))
    return [float(IONO_CODES[params["ionosphere"]]), ne, hmax, hs]


@njit(cache=True)
def density(p, off, h_m):
    """N_e (m^-3) at altitude h (m)."""
    if int(p[off]) == IONO_UNIFORM:
        return p[off + 1]
    z = (h_m - p[off + 2]) / p[off + 3]
    if z < -30.0:
        return 0.0
    return p[off + 1] * math.exp(0.5 * (1.0 - z - math.exp(-z)))
