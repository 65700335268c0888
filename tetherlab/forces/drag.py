"""Atmospheric drag on bodies and tether rods, exponential atmosphere co-rotating with the Earth.

Body:  F = -1/2 rho Cd A |v_r| v_r,  v_r = v - omega_E z^ x r (velocity relative to the air).
Rod (a cylinder of diameter D):  force per unit length -1/2 rho Cd_t D |v_n| v_n with v_n the part
of v_r normal to the tether; per unit of the rod coordinate xi it is multiplied by |dr/dxi|.
rho from Vallado Table 8-4 (tetherlab/environment/atmosphere.py).  The half-rod totals and the
F_TP correction of paper eq. 13 follow from the quadrature in tether/chain.py.
Derivation: docs/effects-electrodynamic.md, section 3.

| parameter | unit | required | meaning |
|-----------|------|----------|---------|
| area | m2 | yes | cross-section of each body: one value for all, or a table {body = area} naming every body |
| cd | 1 | no (2.2) | drag coefficient of each body: one value, or a table per body |
| tether_cd | 1 | no (2.2) | drag coefficient of the tether cylinder (on D L) |
| tether_diameter | m | no | diameter of every tether; default: each tether's own `diameter` |

Cd = 2.2 is the usual value for a compact satellite in free-molecular flow (Vallado 2013,
section 8.6.2; Montenbruck & Gill 2000, section 3.5); a thin cylinder is of the same order.
"""

from __future__ import annotations

import math

from ..environment import atmosphere
from ..errors import SceneError
from ..kernel.layout import H_OFF_ROD, RT_SIZE, RT_TETH
from .registry import EffectSpec, ParamSpec, register

CODE = 21


def _pack(params, central, ctx):
    """[R, nb, cd*A per body (kernel order), Cd_t*D per tether]."""
    bodies = ctx["bodies"]
    cda = []
    for name in bodies:
        area = params["area"][name]
        cd = params["cd"][name]
        if not (area >= 0.0 and cd >= 0.0):
            raise SceneError(f"effects.drag.area.{name}", "an area >= 0 and a cd >= 0", f"area {area!r} m2, cd {cd!r}")
        cda.append(area * cd)
    cdd = []
    for t in ctx["tethers"]:
        diameter = params.get("tether_diameter", t.diameter_m)
        if diameter is None:
            raise SceneError(
                f"tethers.{t.name}.diameter",
                "a tether diameter (drag on the tether needs its cross-section), or effects.drag.tether_diameter",
                "none",
            )
        if not (diameter > 0.0 and params["tether_cd"] >= 0.0):
            raise SceneError("effects.drag.tether_diameter", "a diameter > 0 and tether_cd >= 0",
                             f"{diameter!r} m, tether_cd {params['tether_cd']!r}")
        cdd.append(params["tether_cd"] * diameter)
    return [central["radius_m"], float(len(bodies)), *cda, *cdd]


SPEC = register(
    EffectSpec(
        name="drag",
        code=CODE,
        doc="Atmospheric drag (exponential atmosphere, Vallado Table 8-4) on bodies and tether rods.",
        params={
            "area": ParamSpec("m2", per_body=True, doc="cross-section area of each body"),
            "cd": ParamSpec("", required=False, default=2.2, per_body=True, doc="drag coefficient of each body"),
            "tether_cd": ParamSpec("", required=False, default=2.2, doc="drag coefficient of the tether cylinder"),
            "tether_diameter": ParamSpec("m", required=False, doc="tether diameter (default: the tether's own)"),
        },
        velocity_dependent=True,
        conservative=False,
        pack=_pack,
    )
)

# -- compiled kernels (SI floats only) -----------------------------------------------------------
from .._jit import njit  # noqa: E402


@njit(cache=True)
def body_force(p, par, body, x, y, z, vx, vy, vz):
    """-1/2 rho Cd A |v_r| v_r (N) on body ``body`` (kernel order)."""
    h = math.sqrt(x * x + y * y + z * z) - p[par]
    k = -0.5 * atmosphere.density(h) * p[par + 2 + body]
    wx, wy, wz = atmosphere.relative_velocity(x, y, z, vx, vy, vz)
    s = k * math.sqrt(wx * wx + wy * wy + wz * wz)
    return s * wx, s * wy, s * wz


@njit(cache=True)
def rod_density(p, par, rod, x, y, z, vx, vy, vz, tx, ty, tz):
    """-1/2 rho Cd_t D |dr/dxi| |v_n| v_n: force per unit xi (N) on a rod element."""
    nb = int(p[par + 1])
    teth = int(p[int(p[H_OFF_ROD]) + rod * RT_SIZE + RT_TETH])
    cdd = p[par + 2 + nb + teth]
    h = math.sqrt(x * x + y * y + z * z) - p[par]
    wx, wy, wz = atmosphere.relative_velocity(x, y, z, vx, vy, vz)
    t2 = tx * tx + ty * ty + tz * tz
    c = (wx * tx + wy * ty + wz * tz) / t2
    nx = wx - c * tx
    ny = wy - c * ty
    nz = wz - c * tz
    s = -0.5 * atmosphere.density(h) * cdd * math.sqrt(t2) * math.sqrt(nx * nx + ny * ny + nz * nz)
    return s * nx, s * ny, s * nz
