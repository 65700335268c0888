"""Classical orbital elements <-> Cartesian state for the two-body problem, elliptic and hyperbolic.

Plain floats and numpy arrays, SI throughout (m, m/s, m^3/s^2, rad); no astropy here, so the
builder and tests can call these in tight loops.

Elements: semi-major axis ``a`` (m; > 0 elliptic, < 0 hyperbolic), eccentricity ``e`` (0 <= e,
e != 1), inclination ``i`` (rad, [0, pi]), right ascension of the ascending node ``raan``, argument
of periapsis ``argp`` and true anomaly ``nu`` (rad).  Parabolic orbits (e = 1) have no finite
``a`` and are refused: give such a state as position and velocity.

Conventions where an angle is undefined (the same on both directions, so round trips hold):

* circular (e = 0): no periapsis; ``argp = 0`` and ``nu`` is the argument of latitude (angle from
  the ascending node to the position);
* equatorial (i = 0 or pi): no node; ``raan = 0`` and the node line is taken along +x, so ``argp``
  is the longitude of periapsis measured from +x (in the direction of motion);
* circular equatorial: ``raan = argp = 0`` and ``nu`` is the true longitude from +x.

Returned angles: ``raan`` and ``argp`` in [0, 2 pi); ``nu`` in [0, 2 pi) for elliptic orbits and in
(-pi, pi] for hyperbolic ones (where it lies between the asymptotes).

Formulas: Vallado, *Fundamentals of Astrodynamics and Applications*, 4th ed., algorithms 9
(RV2COE) and 10 (COE2RV); Curtis, *Orbital Mechanics for Engineering Students*, algorithm 4.2 and
section 4.6.  Angles are taken with ``atan2`` rather than ``arccos`` so they keep full precision
near 0 and pi and need no quadrant fix-ups.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

TWO_PI = 2.0 * math.pi

# Below this eccentricity, or this ratio |node| / |h| (= sin i), the periapsis or the node is
# taken as undefined.  Rounding in a Cartesian state of a truly circular or equatorial orbit
# leaves e and sin i around 1e-16; 1e-11 sits well above that yet far below any orbit a user means
# as eccentric or inclined.  Above the threshold the individual angles of a nearly circular orbit
# are ill-conditioned, but their sum (which fixes the position) is not, so states still round-trip.
SMALL = 1e-11


class KeplerElements(NamedTuple):
    a: float  # semi-major axis, m (< 0 for hyperbolic orbits)
    e: float  # eccentricity
    i: float  # inclination, rad
    raan: float  # right ascension of the ascending node, rad
    argp: float  # argument of periapsis, rad
    nu: float  # true anomaly, rad


def _check_mu(mu: float) -> None:
    if not (math.isfinite(mu) and mu > 0.0):
        raise ValueError(f"mu must be a positive finite gravitational parameter (m^3/s^2), got {mu!r}")


def check_elements(a: float, e: float, nu: float) -> None:
    """Raise ValueError unless (a, e, nu) describe a real elliptic or hyperbolic state."""
    for name, value in (("a", a), ("e", e), ("nu", nu)):
        if not math.isfinite(value):
            raise ValueError(f"{name} must be finite, got {value!r}")
    if e < 0.0:
        raise ValueError(f"eccentricity must be >= 0, got {e!r}")
    if e == 1.0:
        raise ValueError("parabolic orbit (e = 1) has no finite semi-major axis; give position and velocity")
    if e < 1.0 and not a > 0.0:
        raise ValueError(f"an elliptic orbit (e = {e!r} < 1) needs a > 0, got a = {a!r} m")
    if e > 1.0 and not a < 0.0:
        raise ValueError(f"a hyperbolic orbit (e = {e!r} > 1) needs a < 0, got a = {a!r} m")
    if e > 1.0 and not 1.0 + e * math.cos(nu) > 0.0:
        limit = math.degrees(math.acos(-1.0 / e))
        raise ValueError(
            f"true anomaly {math.degrees(nu)!r} deg lies beyond the asymptotes of a hyperbola with "
            f"e = {e!r} (|nu| must be < {limit:.6g} deg)"
        )


def elements_to_cartesian(
    mu: float, a: float, e: float, i: float, raan: float, argp: float, nu: float
) -> tuple[np.ndarray, np.ndarray]:
    """Position (m) and velocity (m/s) in the inertial frame of the central body."""
    _check_mu(mu)
    check_elements(a, e, nu)
    for name, value in (("i", i), ("raan", raan), ("argp", argp)):
        if not math.isfinite(value):
            raise ValueError(f"{name} must be finite, got {value!r}")
    p = a * (1.0 - e * e)  # semi-latus rectum, > 0 for both conics given the checks above
    cos_nu, sin_nu = math.cos(nu), math.sin(nu)
    radius = p / (1.0 + e * cos_nu)
    r_pf = np.array([radius * cos_nu, radius * sin_nu, 0.0])
    speed_scale = math.sqrt(mu / p)
    v_pf = np.array([-speed_scale * sin_nu, speed_scale * (e + cos_nu), 0.0])
    q = _perifocal_to_inertial(i, raan, argp)
    return q @ r_pf, q @ v_pf


def _perifocal_to_inertial(i: float, raan: float, argp: float) -> np.ndarray:
    # R3(-raan) R1(-i) R3(-argp), written out.
    ci, si = math.cos(i), math.sin(i)
    cO, sO = math.cos(raan), math.sin(raan)
    cw, sw = math.cos(argp), math.sin(argp)
    return np.array(
        [
            [cO * cw - sO * sw * ci, -cO * sw - sO * cw * ci, sO * si],
            [sO * cw + cO * sw * ci, -sO * sw + cO * cw * ci, -cO * si],
            [sw * si, cw * si, ci],
        ]
    )


def _angle(from_vec: np.ndarray, to_vec: np.ndarray, normal: np.ndarray) -> float:
    """Angle from ``from_vec`` to ``to_vec`` about ``normal`` (right-handed), in (-pi, pi]."""
    return math.atan2(float(np.dot(np.cross(from_vec, to_vec), normal)), float(np.dot(from_vec, to_vec)))


def cartesian_to_elements(mu: float, r, v) -> KeplerElements:
    """Classical elements of the osculating orbit through position ``r`` (m), velocity ``v`` (m/s).

    Raises ValueError for a rectilinear state (r parallel to v: no orbital plane) and for an
    exactly parabolic one (zero energy: no finite semi-major axis).
    """
    _check_mu(mu)
    r = np.asarray(r, dtype=float).reshape(3)
    v = np.asarray(v, dtype=float).reshape(3)
    if not (np.all(np.isfinite(r)) and np.all(np.isfinite(v))):
        raise ValueError("position and velocity must be finite")
    r_norm = float(np.linalg.norm(r))
    if r_norm == 0.0:
        raise ValueError("position is at the centre of the central body")
    v2 = float(np.dot(v, v))
    h = np.cross(r, v)
    h_norm = float(np.linalg.norm(h))
    if h_norm <= SMALL * r_norm * math.sqrt(v2) or h_norm == 0.0:
        raise ValueError("rectilinear state (velocity along the radius): the orbital plane is undefined")
    energy = 0.5 * v2 - mu / r_norm
    if energy == 0.0:
        raise ValueError("parabolic state (zero orbital energy) has no finite semi-major axis")
    a = -mu / (2.0 * energy)
    e_vec = ((v2 - mu / r_norm) * r - float(np.dot(r, v)) * v) / mu
    e = float(np.linalg.norm(e_vec))
    h_hat = h / h_norm
    i = math.atan2(math.hypot(h[0], h[1]), h[2])

    node = np.array([-h[1], h[0], 0.0])  # z x h
    node_norm = float(np.linalg.norm(node))
    if node_norm <= SMALL * h_norm:
        raan = 0.0
        node_hat = np.array([1.0, 0.0, 0.0])
    else:
        node_hat = node / node_norm
        raan = math.atan2(node[1], node[0]) % TWO_PI

    if e <= SMALL:
        argp = 0.0
        peri_hat = node_hat
    else:
        peri_hat = e_vec / e
        argp = _angle(node_hat, peri_hat, h_hat) % TWO_PI
    nu = _angle(peri_hat, r, h_hat)
    if e < 1.0:
        nu %= TWO_PI
    # Clean-ups of the modulo: x % 2pi can return 2pi itself for tiny negative x.
    raan = 0.0 if raan >= TWO_PI else raan
    argp = 0.0 if argp >= TWO_PI else argp
    nu = 0.0 if nu >= TWO_PI else nu
    return KeplerElements(a, e, i, raan, argp, nu)


def period(mu: float, a: float) -> float:
    """Keplerian period (s) of an elliptic orbit with semi-major axis ``a`` (m)."""
    _check_mu(mu)
    if not (math.isfinite(a) and a > 0.0):
        raise ValueError(f"only elliptic orbits (a > 0) have a period, got a = {a!r} m")
    return TWO_PI * math.sqrt(a**3 / mu)
