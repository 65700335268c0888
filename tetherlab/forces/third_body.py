"""Third-body gravity of the Moon and the Sun from the DE421 ephemeris, in a central-body frame.

What it models: the pull of body b (gravitational parameter mu_b, position s relative to the
central body) on a point at r, minus its pull on the central body (the frame's origin accelerates
with the central body, so the non-inertial frame adds that "indirect" term):

    a = mu_b [ (s - r)/|s - r|^3 - s/|s|^3 ]                      (docs/effects-gravity.md, sec. 3)

Positions: DE421 through skyfield with the kernel file shipped by ``skyfield_data`` (offline),
fitted piecewise by Chebyshev polynomials over the run before integration
(:mod:`tetherlab.ephemeris`); the fit error against skyfield is reported in the result's
``meta["effect_meta"]``.  Needs the scene's ``epoch`` (TDB); t in the kernel is TDB seconds since
that epoch.  Axes: ICRF = GCRS axes, so the scene's inertial frame must be the Earth's GCRS
(the same frame assumption as ``zonal``: its +z is the celestial pole).

Not ``conservative``: the potential depends on time, so kinetic + potential energy is not an
invariant.  Its (tidal) potential U = -mu_b [1/|s - r| - 1/|s| - s.r/|s|^3] is still provided
(:func:`potential`, a = -grad_r U) for the gradient test, but the energy diagnostics leave it out.

| effect       | parameter | unit    | required | default | source |
|--------------|-----------|---------|----------|---------|--------|
| ``moon_de421`` | mu      | m3 / s2 | no | 4.902800222e12 | GM_E (3.986004418e14) x M_Moon/M_E (1.23000371e-2), IAU 2009 system (Luzum et al. 2011, Celest. Mech. Dyn. Astr. 110, 293), the ratio from DE421 |
| ``sun_de421``  | mu      | m3 / s2 | no | 1.32712440041e20 | IAU 2009 system, TDB-compatible GM_Sun (from DE421: 2.959122082855911e-4 au^3/d^2, Folkner et al. 2008, IPN PR 42-178) |
"""

from __future__ import annotations

import math

from .. import ephemeris
from ..errors import SceneError
from .registry import EffectSpec, ParamSpec, register

CODE_MOON = 12
CODE_SUN = 13

MU_MOON_M3_S2 = 3.986004418e14 * 1.23000371e-2  # IAU 2009: GM_E x Moon/Earth mass ratio
MU_SUN_M3_S2 = 1.32712440041e20  # IAU 2009, TDB-compatible (DE421)


def _pack(body: str):
    def pack(params: dict, central: dict, ctx: dict) -> list[float]:
        name = f"{body}_de421"
        epoch = ctx.get("epoch")
        if epoch is None:
            raise SceneError("epoch", f"an ISO date (TDB), e.g. '2026-01-01T00:00:00', for effect {name!r}", "nothing")
        duration = ctx.get("duration_s")
        if duration is None or not (duration > 0 and math.isfinite(duration)):
            raise SceneError("duration", f"a finite run length for effect {name!r} (the ephemeris fit covers it)", repr(duration))
        position = ephemeris.de421_position_function(body, epoch)
        try:
            block, err = ephemeris.fit_block(position, duration)
        finally:
            position.close()
        if "meta" in ctx:
            ctx["meta"][name] = {
                "ephemeris": "DE421 (skyfield-data), geometric, ICRF axes, Earth-centred",
                "time_scale": "TDB",
                "epoch": epoch,
                "segment_s": ephemeris.SEGMENT_S,
                "degree": ephemeris.DEGREE,
                "fit_error_m": err,
            }
        return [params["mu"]] + block

    return pack


SPEC_MOON = register(
    EffectSpec(
        name="moon_de421",
        code=CODE_MOON,
        doc="Moon's direct + indirect gravity, DE421 positions (needs the scene's epoch, TDB).",
        params={"mu": ParamSpec("m3 / s2", required=False, default=MU_MOON_M3_S2, doc="GM of the Moon")},
        velocity_dependent=False,
        conservative=False,
        dated=True,
        pack=_pack("moon"),
    )
)

SPEC_SUN = register(
    EffectSpec(
        name="sun_de421",
        code=CODE_SUN,
        doc="Sun's direct + indirect gravity, DE421 positions (needs the scene's epoch, TDB).",
        params={"mu": ParamSpec("m3 / s2", required=False, default=MU_SUN_M3_S2, doc="GM of the Sun")},
        velocity_dependent=False,
        conservative=False,
        dated=True,
        pack=_pack("sun"),
    )
)

# -- compiled kernels (SI floats only) -----------------------------------------------------------
# Parameter block: [mu_b, ephemeris block of tetherlab.ephemeris]
from .._jit import njit  # noqa: E402


@njit(cache=True)
def accel_at(mu, sx, sy, sz, x, y, z):
    """mu [(s - r)/|s - r|^3 - s/|s|^3] (m/s^2) for a body at s."""
    dx = sx - x
    dy = sy - y
    dz = sz - z
    d2 = dx * dx + dy * dy + dz * dz
    s2 = sx * sx + sy * sy + sz * sz
    kd = mu / (d2 * math.sqrt(d2))
    ks = mu / (s2 * math.sqrt(s2))
    return kd * dx - ks * sx, kd * dy - ks * sy, kd * dz - ks * sz


@njit(cache=True)
def potential_at(mu, sx, sy, sz, x, y, z):
    """Tidal potential per unit mass (J/kg), zero at the central body; accel_at = -grad_r.

    -mu [1/d - 1/S - q/S^3] (d = |s - r|, S = |s|, q = s.r) is evaluated as one fraction whose
    numerator has no first-order cancellation (docs/effects-gravity.md, sec. 3): the naive form
    loses the digits of S/|r| (8 of them for the Sun at LEO).
    """
    dx = sx - x
    dy = sy - y
    dz = sz - z
    d = math.sqrt(dx * dx + dy * dy + dz * dz)
    S2 = sx * sx + sy * sy + sz * sz
    S = math.sqrt(S2)
    q = sx * x + sy * y + sz * z
    r2 = x * x + y * y + z * z
    num = q * S * (2.0 * q - r2) / (S + d) - r2 * S2 + 2.0 * q * q - q * r2
    return -mu * num / (S2 * S * d * (S + d))


@njit(cache=True)
def accel(p, par, t, x, y, z):
    sx, sy, sz = ephemeris.position(p, par + 1, t)
    return accel_at(p[par], sx, sy, sz, x, y, z)


@njit(cache=True)
def potential(p, par, t, x, y, z):
    sx, sy, sz = ephemeris.position(p, par + 1, t)
    return potential_at(p[par], sx, sy, sz, x, y, z)
