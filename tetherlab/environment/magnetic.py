"""The geomagnetic field as a centred dipole: aligned with the rotation axis, or tilted and rotating
with the Earth.  Derivation: docs/effects-electrodynamic.md, section 1.

A centred dipole of strength vector K (T m^3; K = mu_0 m / (4 pi) for a magnetic moment m in
A m^2) has the field

    B(r) = (3 (K . r) r - |r|^2 K) / |r|^5,

the negative gradient of the scalar potential V = K . r / |r|^3.  The degree-1 Gauss coefficients
of a spherical-harmonic model with reference radius a give, in Earth-fixed axes,
K = a^3 (g11, h11, g10) (Langel 1987, Geomagnetism vol. 1, ch. 4; docs section 1.1).

Constants (SI):

| name | value | source |
|------|-------|--------|
| IGRF13_G10_T, IGRF13_G11_T, IGRF13_H11_T | -29404.8, -1450.9, 4652.5 nT | IGRF-13, epoch 2020.0 (Alken et al. 2021, Earth Planets Space 73:49, table of coefficients) |
| IGRF_REFERENCE_RADIUS_M | 6371.2 km | IGRF reference radius (same source) |
| EARTH_ROTATION_RATE_RAD_S | 7.292115e-5 rad/s | WGS 84 (NIMA TR8350.2, table 3.1) |

All kernels take SI floats only; the Earth's rotation enters through the angle
theta(t) = theta_0 + omega_E t of the Earth-fixed x axis from the inertial x axis; theta_0 is the
explicit greenwich_angle or the ERA of the scene's epoch (earth_orientation.py).  Field "igrf14":
IGRF-14 to degree 13 (igrf.py) in the same rotating axes.
"""

from __future__ import annotations

import math

from .._jit import njit
from . import igrf
from .earth import EARTH_ROTATION_RATE_RAD_S

IGRF13_G10_T = -29404.8e-9
IGRF13_G11_T = -1450.9e-9
IGRF13_H11_T = 4652.5e-9
IGRF_REFERENCE_RADIUS_M = 6371.2e3

#: Dipole strength |K| = a^3 sqrt(g10^2 + g11^2 + h11^2) of IGRF-13 at 2020.0 (T m^3): about
#: 7.71e15 T m^3, i.e. a moment of 7.71e22 A m^2 and 29.8 uT at the equator of the 6371.2 km sphere.
IGRF13_DIPOLE_T_M3 = IGRF_REFERENCE_RADIUS_M**3 * math.sqrt(
    IGRF13_G10_T**2 + IGRF13_G11_T**2 + IGRF13_H11_T**2
)

#: Unit vector of K in Earth-fixed axes (x to Greenwich on the equator, z to the north pole).
#: K points to the southern hemisphere (g10 < 0): the field lines leave the Earth in the south.
IGRF13_AXIS_ECEF = tuple(
    c * IGRF_REFERENCE_RADIUS_M**3 / IGRF13_DIPOLE_T_M3 for c in (IGRF13_G11_T, IGRF13_H11_T, IGRF13_G10_T)
)

#: Field model codes stored in the parameter block.
FIELD_ALIGNED = 0
FIELD_TILTED = 1
FIELD_IGRF = 2  # IGRF-14 to degree 13 (environment/igrf.py), Earth-fixed, rotating with the Earth
FIELD_CODES = {"aligned": FIELD_ALIGNED, "tilted": FIELD_TILTED, "igrf14": FIELD_IGRF}


def pack_field(model: str, strength_t_m3: float, greenwich_angle_rad: float, igrf_block=None) -> list[float]:
    """The floats the kernel :func:`field` reads: code, |K|, unit axis in Earth-fixed axes, angle
    (6 floats), followed for "igrf14" by the IGRF block of environment/igrf.py (``igrf_block``)."""
    if model == "aligned":
        axis = (0.0, 0.0, -1.0)  # along -z: the sign of g10 (the field points north at the equator)
    else:
        axis = IGRF13_AXIS_ECEF
    out = [float(FIELD_CODES[model]), strength_t_m3, *axis, greenwich_angle_rad]
    if model == "igrf14":
        if igrf_block is None:
            raise ValueError("field 'igrf14' needs its coefficient block (environment/igrf.py pack)")
        out += list(igrf_block)
    return out


FIELD_NPAR = 6  # floats before the IGRF block


@njit(cache=True)
def dipole(kx, ky, kz, x, y, z):
    """Field (T) of a centred dipole of strength vector K (T m^3) at r (m)."""
    r2 = x * x + y * y + z * z
    r = math.sqrt(r2)
    kr = kx * x + ky * y + kz * z
    inv5 = 1.0 / (r2 * r2 * r)
    return (
        (3.0 * kr * x - r2 * kx) * inv5,
        (3.0 * kr * y - r2 * ky) * inv5,
        (3.0 * kr * z - r2 * kz) * inv5,
    )


@njit(cache=True)
def field(p, par, t, x, y, z):
    """Field (T) at inertial r (m), time t (s since the scene epoch), for the packed model at p[par:].

    aligned: K = |K| (0, 0, -1), fixed in inertial axes.  tilted: the Earth-fixed axis rotated
    about z by theta(t) = theta_0 + omega_E t.  igrf14: IGRF-14 in Earth-fixed axes, same rotation
    (theta_0: the ERA of the epoch or the explicit greenwich_angle, earth_orientation.py).
    """
    code = int(p[par])
    if code == FIELD_IGRF:
        # inertial -> Earth-fixed (rotation by -theta about z), IGRF there, and back
        th = p[par + 5] + EARTH_ROTATION_RATE_RAD_S * t
        c = math.cos(th)
        sn = math.sin(th)
        bx, by, bz = igrf.field_ecef(p, par + FIELD_NPAR, t, c * x + sn * y, -sn * x + c * y, z)
        return c * bx - sn * by, sn * bx + c * by, bz
    s = p[par + 1]
    ax = p[par + 2]
    ay = p[par + 3]
    az = p[par + 4]
    if code == FIELD_TILTED:
        th = p[par + 5] + EARTH_ROTATION_RATE_RAD_S * t
        c = math.cos(th)
        sn = math.sin(th)
        ax, ay = c * ax - sn * ay, sn * ax + c * ay
    return dipole(s * ax, s * ay, s * az, x, y, z)


def pack_field_for(params: dict, ctx: dict, effect: str) -> list[float]:
    """The field block of an effect with ``field``, ``dipole_strength`` and ``greenwich_angle``:
    validates the epoch against the model's range (IGRF: its coefficient file's) and picks the
    Earth rotation angle (earth_orientation.rotation_angle_at_start: an explicit greenwich_angle
    wins over the epoch's ERA).  Reports the choice in ``ctx["meta"][effect]``."""
    from ..errors import SceneError
    from . import earth_orientation

    model = params["field"]
    strength = params["dipole_strength"]
    if not strength > 0.0:
        raise SceneError(f"effects.{effect}.dipole_strength", "a dipole strength > 0 (e.g. '8e15 T m3')", repr(strength))
    meta = ctx.setdefault("meta", {}).setdefault(effect, {})
    if model == "aligned":
        meta["field"] = "aligned dipole"
        return pack_field(model, strength, 0.0)
    blk = None
    if model == "igrf14":
        epoch = ctx.get("epoch")
        if epoch is None:
            raise SceneError("epoch", f"an ISO date (TDB) for effects.{effect}.field = 'igrf14' (IGRF is dated)", "nothing")
        first, last = igrf.validity()
        date = igrf.epoch_datetime(epoch)
        duration = ctx.get("duration_s") or 0.0
        import datetime as _dt

        end = date + _dt.timedelta(seconds=float(duration))
        if date < first or end > last:
            raise SceneError(
                "epoch",
                f"a run inside {igrf.GENERATION}'s coefficients ({first.date()} to {last.date()}) for effects.{effect}.field",
                f"{epoch!r} to {end.isoformat(timespec='seconds')}",
            )
        degree = params.get("igrf_degree", float(igrf.NMAX))
        if not (degree == int(degree) and 1 <= degree <= igrf.NMAX):
            raise SceneError(f"effects.{effect}.igrf_degree", f"an integer from 1 to {igrf.NMAX}", repr(degree))
        blk = igrf.pack(date, nmax=int(degree))
        meta["field"] = f"{igrf.GENERATION} degree {int(degree)} ({igrf.coefficient_file()} via ppigrf), coefficients at {date.isoformat()}"
    else:
        meta["field"] = "tilted dipole (IGRF-13 2020 axis)"
    angle, how = earth_orientation.rotation_angle_at_start(params, ctx, effect)
    meta["earth_rotation_angle_rad"] = angle
    meta["earth_rotation_angle_source"] = how
    return pack_field(model, strength, angle, blk)


def field_block_size(p, par) -> int:
    """Length of the field block at p[par] (6, or 6 + the IGRF block)."""
    if int(p[par]) == FIELD_IGRF:
        return FIELD_NPAR + igrf.block_size(int(p[par + FIELD_NPAR]))
    return FIELD_NPAR
