"""The analytic Moon of the Stiefel-Scheifele test problem (tetherlab paper section 4.1).

What it models: a third body of gravitational parameter mu' on a circular orbit of radius rho,
inclined 30 deg to the equator, at angular rate w, exactly as E. Stiefel & G. Scheifele define it
(*Linear and Regular Celestial Mechanics*, Springer 1971, section 23, Example 2; the definition
sheet ``shared/references/stiefel-scheifele.md``).  Earth-centred inertial frame, t in seconds
since the scene epoch (the problem is epoch-free: t = 0 is the book's initial instant):

    a(t)   = rho [sin wt, -(sqrt 3/2) cos wt, -(1/2) cos wt]            (Moon position)
    a_Moon = -mu' [(r - a)/|r - a|^3 + a/rho^3]                          (direct + indirect)

The indirect term a/rho^3 is the Moon's pull on the Earth (|a| = rho), so the Earth-centred frame
stays the frame of the equations.  Potential per unit mass (its gradient at fixed t is minus the
acceleration): U = -mu' [1/|r - a| - r.a/rho^3]; it depends on t, so energy is not conserved and
the effect is declared non-conservative (its potential stays out of the energy diagnostics).
Derivation and checks: ``docs/dromo.md`` section 6.

| parameter    | unit    | required | default              | meaning                         |
|--------------|---------|----------|----------------------|---------------------------------|
| mu           | m3 / s2 | no       | 4902.66 km^3/s^2     | Moon's gravitational parameter  |
| orbit_radius | m       | no       | 384400 km            | radius rho of the circular orbit|
| rate         | rad / s | no       | 2.665315780887e-6    | angular rate w (printed value)  |

Defaults: the printed constants of Stiefel & Scheifele (1971), section 23 (definition sheet
table); the rate is the printed value, not sqrt((mu + mu')/rho^3) (the sheet's "traps").
"""

from __future__ import annotations

from .registry import EffectSpec, ParamSpec, register

CODE = 30

# Stiefel & Scheifele (1971), section 23, printed constants (SI)
MU_MOON_M3_S2 = 4902.66e9
RHO_MOON_M = 384400e3
RATE_MOON_RAD_S = 2.665315780887e-6

SPEC = register(
    EffectSpec(
        name="stiefel_moon",
        code=CODE,
        doc="Analytic circular Moon of the Stiefel-Scheifele problem (direct + indirect terms).",
        params={
            "mu": ParamSpec("m3 / s2", required=False, default=MU_MOON_M3_S2,
                            doc="Moon's mu; Stiefel & Scheifele 1971: 4902.66 km^3/s^2"),
            "orbit_radius": ParamSpec("m", required=False, default=RHO_MOON_M,
                                      doc="Moon orbit radius; Stiefel & Scheifele 1971: 384400 km"),
            "rate": ParamSpec("rad / s", required=False, default=RATE_MOON_RAD_S,
                              doc="Moon angular rate; Stiefel & Scheifele 1971: 2.665315780887e-6 rad/s"),
        },
        velocity_dependent=False,
        # the potential below depends on t, so energy is not an invariant: kept out of the energy
        # diagnostics (as forces/third_body.py does for the DE421 bodies); used by the tests
        conservative=False,
        # the fourth value multiplies the indirect term: always 1 here (no scene key reaches it);
        # tetherlab.mutants sets it to 0 for the verification's negative control only
        pack=lambda params, central, ctx: [params["mu"], params["orbit_radius"], params["rate"], 1.0],
    )
)

# -- compiled kernels (SI floats only) -----------------------------------------------------------
# Parameter block: [mu', rho, w, 1.0] (the last: the indirect term's factor, see pack).
from .._jit import njit  # noqa: E402

import math  # noqa: E402

_HALF_SQRT3 = 0.8660254037844386  # cos 30 deg: the Moon's orbit is inclined 30 deg


@njit(cache=True)
def moon_position(rho, w, t):
    """Moon position a(t) (m): rho [sin wt, -(sqrt 3/2) cos wt, -(1/2) cos wt]."""
    c = math.cos(w * t)
    return rho * math.sin(w * t), -rho * _HALF_SQRT3 * c, -0.5 * rho * c


@njit(cache=True)
def accel(mu, rho, w, t, x, y, z, indirect=1.0):
    """Direct + indirect acceleration -mu' [(r - a)/|r - a|^3 + a/rho^3] (m/s^2).

    ``indirect`` multiplies the indirect term: 1 in every run (pack); 0 only as the deliberate
    defect of tetherlab.mutants."""
    ax, ay, az = moon_position(rho, w, t)
    dx = x - ax
    dy = y - ay
    dz = z - az
    d2 = dx * dx + dy * dy + dz * dz
    kd = mu / (d2 * math.sqrt(d2))
    ki = indirect * mu / (rho * rho * rho)
    return -(kd * dx + ki * ax), -(kd * dy + ki * ay), -(kd * dz + ki * az)


@njit(cache=True)
def potential(mu, rho, w, t, x, y, z):
    """U = -mu' [1/|r - a| - r.a/rho^3] (J/kg); minus its gradient is :func:`accel`."""
    ax, ay, az = moon_position(rho, w, t)
    dx = x - ax
    dy = y - ay
    dz = z - az
    return -mu * (1.0 / math.sqrt(dx * dx + dy * dy + dz * dz) - (x * ax + y * ay + z * az) / (rho * rho * rho))
