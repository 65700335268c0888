"""Electrodynamic (Lorentz) force of a constant current along each tether in the geomagnetic field.

Force per unit of the rod coordinate xi: dF/dxi = nu I (dr/dxi) x B(r); on a straight rod in a
uniform field the total is I L_a u x B.  No force on point masses.  The half-rod totals R_1, R_2
and the correction F_TP of paper eq. 13 follow from the Gauss-Legendre quadrature of this density
in tether/chain.py (docs/effects-electrodynamic.md, section 2).  nu is the sunlit fraction of the
``eclipse`` switch (1 when it is "none"): a current off in the Earth's shadow.

Sign convention: a positive current flows from end A_1 (the tether's ``from`` body) towards B_n
(its ``to`` body), i.e. along dr/dxi.  On a prograde orbit with the ``to`` body above the
``from`` body and the dipole of the Earth (field pointing north at the equator), I > 0 gives a
drag (de-orbit), I < 0 a thrust.

Reference: paper section 5 (constant current, dipole aligned with the rotation axis).

| parameter | unit | required | meaning |
|-----------|------|----------|---------|
| current | A | yes | current along every tether, > 0 from ``from`` to ``to`` |
| field | choice | no ("aligned") | "aligned": dipole along -z (rotation axis); "tilted": IGRF-13 2020 dipole axis, rotating with the Earth; "igrf14": IGRF-14 to degree 13 at the scene's epoch (environment/igrf.py) |
| dipole_strength | T m3 | no (IGRF-13 2020, 7.71e15 T m3) | |K| = mu_0 m / (4 pi) of the dipole (dipole fields only) |
| igrf_degree | 1 | no (13) | "igrf14" only: truncation degree 1..13 (1 = the IGRF dipole of the epoch) |
| greenwich_angle | rad | no | Earth-fixed fields: angle of the Greenwich meridian from the inertial x axis at t = 0; if given it wins over the epoch's Earth rotation angle (environment/earth_orientation.py); without it and without an epoch, 0 |
| eclipse | choice | no ("none") | "cylindrical" or "conical": the current times the sunlit fraction (needs the epoch: Sun from DE421) |
"""

from __future__ import annotations

from ..environment import eclipse, magnetic
from .registry import EffectSpec, ParamSpec, register

CODE = 20


def _pack(params, central, ctx):
    field = magnetic.pack_field_for(params, ctx, "electrodynamic")
    shadow = eclipse.pack(params.get("eclipse", "none"), ctx, central["radius_m"], "electrodynamic")
    # [current, offset of the eclipse block from par, field block..., eclipse block...]
    return [params["current"], float(2 + len(field)), *field, *shadow]


FIELD_PARAMS = {
    "field": ParamSpec("", required=False, default="aligned", choices=tuple(magnetic.FIELD_CODES),
                       doc="geomagnetic field model", dated=("igrf14",)),
    "dipole_strength": ParamSpec("T m3", required=False, default=magnetic.IGRF13_DIPOLE_T_M3,
                                 doc="|K| = mu_0 m / (4 pi); default IGRF-13 2020 (dipole fields)"),
    "igrf_degree": ParamSpec("", required=False, default=13.0,
                             doc="igrf14 only: truncation degree, an integer 1..13 (default 13)"),
    "greenwich_angle": ParamSpec("rad", required=False, default=None,
                                 doc="Earth rotation angle at t = 0 (override of the epoch's ERA)"),
    "eclipse": ParamSpec("", required=False, default="none", choices=tuple(eclipse.ECLIPSE_CODES),
                         doc="current switched by the sunlit fraction of this shadow model",
                         dated=tuple(c for c in eclipse.ECLIPSE_CODES if c != "none")),
}

SPEC = register(
    EffectSpec(
        name="electrodynamic",
        code=CODE,
        doc="Lorentz force I dr x B of a constant current along every tether (dipole or IGRF-14 field).",
        params={
            "current": ParamSpec("A", doc="current, > 0 flowing from the tether's `from` body to its `to` body"),
            **FIELD_PARAMS,
        },
        velocity_dependent=False,  # the current is prescribed, not driven by the motional EMF
        conservative=False,
        pack=_pack,
    )
)

# -- compiled kernels (SI floats only) -----------------------------------------------------------
from .._jit import njit  # noqa: E402


@njit(cache=True)
def rod_density(p, par, t, x, y, z, tx, ty, tz):
    """nu I (dr/dxi) x B(r): force per unit xi (N) on a rod element at r with tangent dr/dxi."""
    current = p[par] * eclipse.sunlit_fraction(p, par + int(p[par + 1]), t, x, y, z)
    if current == 0.0:
        return 0.0, 0.0, 0.0
    bx, by, bz = magnetic.field(p, par + 2, t, x, y, z)
    return (
        current * (ty * bz - tz * by),
        current * (tz * bx - tx * bz),
        current * (tx * by - ty * bx),
    )
