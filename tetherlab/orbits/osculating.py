"""The orbital outputs of a run, row by row: altitude, osculating elements, and over the Earth the
geodetic latitude, longitude and height.

Vectorised forms of :func:`tetherlab.orbits.kepler.cartesian_to_elements` (same conventions: the
node line from z x h, an equatorial orbit's node at +x, a circular orbit's periapsis on the node
line, angles in [0, 2 pi)); rows whose orbital plane is undefined (r parallel to v) are NaN.

The Earth-fixed frame turns about z at the WGS 84 rate from the angle ``theta0_rad`` at t = 0,
the Earth rotation angle the Earth-fixed effects use (environment/earth_orientation.py: the ERA
of the scene's epoch, 0 without one), precession, nutation and polar motion left out as they are
there. Geodetic coordinates on the WGS 84 ellipsoid (NIMA TR8350.2, table 3.1: a = 6378137 m,
1/f = 298.257223563) by Bowring's iteration (Bowring 1976, Survey Review 23(181)): two iterations
converge; three agree with ERFA's closed form (astropy ``EarthLocation.to_geodetic``) within
3e-11 rad and 2e-8 m from the surface to 40 000 km (tests/test_first_use.py).
"""

from __future__ import annotations

import numpy as np

from ..environment.earth import EARTH_ROTATION_RATE_RAD_S

TWO_PI = 2.0 * np.pi
WGS84_A_M = 6378137.0
WGS84_F = 1.0 / 298.257223563


def elements(mu_m3_s2: float, r: np.ndarray, v: np.ndarray) -> dict[str, np.ndarray]:
    """Osculating a (m), e, i, RAAN, argument of periapsis (rad) of each row of r (m), v (m/s)."""
    r = np.atleast_2d(np.asarray(r, float))
    v = np.atleast_2d(np.asarray(v, float))
    rn = np.linalg.norm(r, axis=1)
    v2 = np.einsum("ij,ij->i", v, v)
    h = np.cross(r, v)
    hn = np.linalg.norm(h, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        undefined = ~(hn > 1e-12 * rn * np.sqrt(v2))
        energy = 0.5 * v2 - mu_m3_s2 / rn
        a = -mu_m3_s2 / (2.0 * energy)
        rv = np.einsum("ij,ij->i", r, v)
        e_vec = ((v2 - mu_m3_s2 / rn)[:, None] * r - rv[:, None] * v) / mu_m3_s2
        e = np.linalg.norm(e_vec, axis=1)
        h_hat = h / hn[:, None]
        inc = np.arctan2(np.hypot(h[:, 0], h[:, 1]), h[:, 2])
        node = np.stack([-h[:, 1], h[:, 0], np.zeros(len(h))], axis=1)
        nn = np.linalg.norm(node, axis=1)
        equatorial = ~(nn > 1e-12 * hn)
        node_hat = np.where(equatorial[:, None], np.array([1.0, 0.0, 0.0]), node / np.where(equatorial, 1.0, nn)[:, None])
        raan = np.where(equatorial, 0.0, np.arctan2(node[:, 1], node[:, 0]) % TWO_PI)
        circular = ~(e > 1e-12)
        peri_hat = np.where(circular[:, None], node_hat, e_vec / np.where(circular, 1.0, e)[:, None])
        sin_w = np.einsum("ij,ij->i", np.cross(node_hat, peri_hat), h_hat)
        argp = np.where(circular, 0.0, np.arctan2(sin_w, np.einsum("ij,ij->i", node_hat, peri_hat)) % TWO_PI)
    out = {"a_m": a, "eccentricity": e, "inclination_rad": inc, "raan_rad": raan, "argp_rad": argp}
    for k in out:
        out[k] = np.where(undefined, np.nan, out[k])
    return out


def earth_fixed(t_s: np.ndarray, r: np.ndarray, theta0_rad: float) -> np.ndarray:
    """Rows of r (inertial, m) in the Earth-fixed frame at times t_s (rotation about z)."""
    ang = theta0_rad + EARTH_ROTATION_RATE_RAD_S * np.asarray(t_s, float)
    c, s = np.cos(ang), np.sin(ang)
    r = np.atleast_2d(np.asarray(r, float))
    return np.stack([c * r[:, 0] + s * r[:, 1], -s * r[:, 0] + c * r[:, 1], r[:, 2]], axis=1)


def geodetic(r_ecef: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """WGS 84 geodetic latitude (rad), longitude (rad, in (-pi, pi]) and height (m) of
    Earth-fixed rows r_ecef (m)."""
    x, y, z = (np.asarray(r_ecef, float)[:, k] for k in range(3))
    a, f = WGS84_A_M, WGS84_F
    b = a * (1.0 - f)
    e2 = f * (2.0 - f)
    ep2 = e2 / (1.0 - e2)
    p = np.hypot(x, y)
    lon = np.arctan2(y, x)
    beta = np.arctan2(z, (1.0 - f) * p)  # reduced latitude, first guess
    for _ in range(3):
        lat = np.arctan2(z + ep2 * b * np.sin(beta) ** 3, p - e2 * a * np.cos(beta) ** 3)
        beta = np.arctan2((1.0 - f) * np.sin(lat), np.cos(lat))
    sin_lat = np.sin(lat)
    n = a / np.sqrt(1.0 - e2 * sin_lat**2)
    # the height from the form that stays accurate at every latitude (poles included)
    height = p * np.cos(lat) + (z + e2 * n * sin_lat) * sin_lat - n
    return lat, lon, height
