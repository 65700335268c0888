"""Zonal harmonics J2, J3, J4 of the central body (axially symmetric part of its gravity field).

What it models: the perturbation of the central body's point-mass gravity by its oblateness (J2)
and the next two zonal terms.  The point-mass term -mu/r itself is ``central_gravity``'s: a scene
names both.  Derivation of every formula below: ``docs/effects-gravity.md``.

Frame assumption: the body's rotation (symmetry) axis is the +z axis of the inertial frame the
scene is written in (for the Earth: the GCRS z axis, i.e. the celestial pole, neglecting
precession and nutation of the true pole, about 20 arcsec a year, 0.56 deg a century).

Two effects, so a scene pays only for what it names:

* ``j2``: J2 alone (a dedicated, cheaper kernel);
* ``zonal``: J2, J3 and J4 together.

| parameter | unit | required | default | meaning |
|-----------|------|----------|---------|---------|
| J2        |      | no       | 1.0826261738522e-3 | EGM2008 tide-free, -sqrt(5) C20bar |
| J3        |      | no (zonal) | -2.5324105185677e-6 | EGM2008, -sqrt(7) C30bar |
| J4        |      | no (zonal) | -1.6198975999170e-6 | EGM2008, -sqrt(9) C40bar |
| radius    | m    | no       | ``[central_body].radius`` | reference radius R of the J_n |

Constants: EGM2008 fully normalised Stokes coefficients (tide-free system), Pavlis, Holmes,
Kenyon & Factor (2012), "The development and evaluation of the Earth Gravitational Model 2008",
J. Geophys. Res. 117, B04406, coefficient file EGM2008_to2190_TideFree:
C20bar = -0.484165143790815e-3, C30bar = 0.957161207093473e-6, C40bar = 0.539965866638991e-6;
un-normalised J_n = -sqrt(2n + 1) C_n0bar.  EGM2008's own reference radius is 6378136.3 m and
GM 3.986004415e14 m^3/s^2; tetherlab uses the scene's central body (WGS 84 preset: 6378137 m,
3.986004418e14 m^3/s^2) unless ``radius`` is given: the relative change of J2 R^2 mu is 3e-7,
below any use tetherlab has.  (The often quoted 1.08262668e-3 is the WGS 84 / EGM96 value.)
"""

from __future__ import annotations

import math

from ..errors import SceneError
from .registry import EffectSpec, ParamSpec, register

CODE_J2 = 10
CODE_ZONAL = 11

# EGM2008 tide-free normalised zonal coefficients (Pavlis et al. 2012, see the module docstring)
EGM2008_C20 = -0.484165143790815e-3
EGM2008_C30 = 0.957161207093473e-6
EGM2008_C40 = 0.539965866638991e-6
EGM2008_J2 = -math.sqrt(5.0) * EGM2008_C20
EGM2008_J3 = -math.sqrt(7.0) * EGM2008_C30
EGM2008_J4 = -math.sqrt(9.0) * EGM2008_C40

_RADIUS = ParamSpec(
    "m", required=False, default=None,
    doc="reference radius R of the coefficients; default: the scene's [central_body] radius",
)


def _radius(params: dict, central: dict, name: str) -> float:
    r = params.get("radius", central["radius_m"])
    if not r > 0.0:
        key = f"effects.{name}.radius" if "radius" in params else "central_body.radius"
        raise SceneError(key, "a reference radius > 0 m for the zonal harmonics", f"{r!r} m")
    return float(r)


SPEC_J2 = register(
    EffectSpec(
        name="j2",
        code=CODE_J2,
        doc="Oblateness J2 of the central body (pole = inertial +z); EGM2008 default.",
        params={
            "J2": ParamSpec("", required=False, default=EGM2008_J2, doc="EGM2008 tide-free J2"),
            "radius": _RADIUS,
        },
        velocity_dependent=False,
        conservative=True,
        pack=lambda params, central, ctx: [central["mu_m3_s2"], _radius(params, central, "j2"), params["J2"]],
    )
)

SPEC_ZONAL = register(
    EffectSpec(
        name="zonal",
        code=CODE_ZONAL,
        doc="Zonal harmonics J2, J3, J4 of the central body (pole = inertial +z); EGM2008 defaults.",
        params={
            "J2": ParamSpec("", required=False, default=EGM2008_J2, doc="EGM2008 tide-free J2"),
            "J3": ParamSpec("", required=False, default=EGM2008_J3, doc="EGM2008 J3"),
            "J4": ParamSpec("", required=False, default=EGM2008_J4, doc="EGM2008 tide-free J4"),
            "radius": _RADIUS,
        },
        velocity_dependent=False,
        conservative=True,
        pack=lambda params, central, ctx: [
            central["mu_m3_s2"], _radius(params, central, "zonal"), params["J2"], params["J3"], params["J4"],
        ],
    )
)

# -- compiled kernels (SI floats only) -----------------------------------------------------------
# Parameter block of j2: [mu, R, J2]; of zonal: [mu, R, J2, J3, J4].
# a_n = mu J_n R^n / r^(n+2) [P'_{n+1}(s) r_hat - P'_n(s) z_hat], s = z/r (docs/effects-gravity.md)
from .._jit import njit  # noqa: E402


@njit(cache=True)
def accel_j2(mu, R, J2, x, y, z):
    """J2 acceleration (m/s^2): -(3/2) J2 mu R^2/r^5 [x(1-5s^2), y(1-5s^2), z(3-5s^2)]."""
    r2 = x * x + y * y + z * z
    s2 = z * z / r2
    k = -1.5 * J2 * mu * R * R / (r2 * r2 * math.sqrt(r2))
    kxy = k * (1.0 - 5.0 * s2)
    return kxy * x, kxy * y, k * (3.0 - 5.0 * s2) * z


@njit(cache=True)
def potential_j2(mu, R, J2, x, y, z):
    """J2 potential per unit mass (J/kg), U = mu J2 R^2 / r^3 P2(s); accel_j2 = -grad U."""
    r2 = x * x + y * y + z * z
    r = math.sqrt(r2)
    s2 = z * z / r2
    return mu * J2 * R * R / (r2 * r) * 0.5 * (3.0 * s2 - 1.0)


@njit(cache=True)
def accel(mu, R, J2, J3, J4, x, y, z):
    """J2 + J3 + J4 acceleration (m/s^2), the sum of a_n above."""
    r2 = x * x + y * y + z * z
    r = math.sqrt(r2)
    s = z / r
    s2 = s * s
    q = R / r
    # Legendre derivatives P'_2 .. P'_5 at s
    dp2 = 3.0 * s
    dp3 = 1.5 * (5.0 * s2 - 1.0)
    dp4 = 2.5 * s * (7.0 * s2 - 3.0)
    dp5 = (315.0 * s2 * s2 - 210.0 * s2 + 15.0) / 8.0
    k = mu / r2  # mu / r^2; each term adds (R/r)^n
    q2 = q * q
    c2 = k * J2 * q2
    c3 = k * J3 * q2 * q
    c4 = k * J4 * q2 * q2
    radial = c2 * dp3 + c3 * dp4 + c4 * dp5  # along r_hat
    polar = c2 * dp2 + c3 * dp3 + c4 * dp4  # along -z_hat
    return radial * x / r, radial * y / r, radial * s - polar


@njit(cache=True)
def potential(mu, R, J2, J3, J4, x, y, z):
    """J2 + J3 + J4 potential per unit mass (J/kg), U = sum mu J_n R^n / r^(n+1) P_n(s)."""
    r2 = x * x + y * y + z * z
    r = math.sqrt(r2)
    s = z / r
    s2 = s * s
    q = R / r
    p2 = 0.5 * (3.0 * s2 - 1.0)
    p3 = 0.5 * s * (5.0 * s2 - 3.0)
    p4 = (35.0 * s2 * s2 - 30.0 * s2 + 3.0) / 8.0
    return mu / r * q * q * (J2 * p2 + q * (J3 * p3 + q * J4 * p4))
