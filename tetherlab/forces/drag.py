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
| atmosphere | choice | no ("exponential") | "exponential" (Vallado Table 8-4) or "nrlmsis21" (NRLMSIS 2.1 via pymsis, tabulated: environment/nrlmsis.py; needs the epoch) |
| f107, f107a, ap | sfu, sfu, 1 | nrlmsis21: yes | daily F10.7, its 81-day mean, daily Ap (constant over the run; never downloaded) |
| refresh | s | no (5 d) | nrlmsis21: time step of the table's day slices (each with 8 universal times) |

Cd = 2.2 is the usual value for a compact satellite in free-molecular flow (Vallado 2013,
section 8.6.2; Montenbruck & Gill 2000, section 3.5); a thin cylinder is of the same order.
"""

from __future__ import annotations

import math

from ..environment import atmosphere, nrlmsis
from ..errors import SceneError
from ..kernel.layout import H_OFF_ROD, RT_SIZE, RT_TETH
from .registry import EffectSpec, ParamSpec, register

CODE = 21
ATM_EXPONENTIAL = 0
ATM_NRLMSIS = 1


def _atmosphere_block(params, ctx) -> list[float]:
    """[0] for the exponential atmosphere; [1, NRLMSIS table block] for nrlmsis21."""
    if params.get("atmosphere", "exponential") == "exponential":
        return [float(ATM_EXPONENTIAL)]
    from ..environment import nrlmsis

    idx = {}
    for key, what in (("f107", "F10.7 in sfu, e.g. 150"), ("f107a", "the 81-day mean F10.7 in sfu, e.g. 150"),
                      ("ap", "the daily Ap index, e.g. 15")):
        v = params.get(key)
        if v is None:
            raise SceneError(f"effects.drag.{key}", f"{what} (atmosphere = 'nrlmsis21' needs the space-weather indices; "
                             "tetherlab never downloads them)", "nothing")
        if not (v >= 0.0 and math.isfinite(v)):
            raise SceneError(f"effects.drag.{key}", f"{what}, >= 0", repr(v))
        idx[key] = float(v)
    epoch = ctx.get("epoch")
    if epoch is None:
        raise SceneError("epoch", "an ISO date (TDB) for effects.drag.atmosphere = 'nrlmsis21' (NRLMSIS is dated)", "nothing")
    duration = ctx.get("duration_s")
    if duration is None or not (duration > 0 and math.isfinite(duration)):
        raise SceneError("duration", "a finite run length for effects.drag.atmosphere = 'nrlmsis21'", repr(duration))
    refresh = params.get("refresh", 5 * 86400.0)
    if not (refresh > 0.0 and math.isfinite(refresh)):
        raise SceneError("effects.drag.refresh", "a time step > 0 (e.g. '1 d')", repr(refresh))
    block, info = nrlmsis.table(epoch, float(duration), idx["f107"], idx["f107a"], idx["ap"], float(refresh))
    ctx.setdefault("meta", {}).setdefault("drag", {})["atmosphere"] = info
    return [float(ATM_NRLMSIS)] + list(block)


def _pack(params, central, ctx):
    """[R, nb, offset of the atmosphere block, cd*A per body (kernel order), Cd_t*D per tether,
    atmosphere block]."""
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
    atm = _atmosphere_block(params, ctx)
    return [central["radius_m"], float(len(bodies)), float(3 + len(cda) + len(cdd)), *cda, *cdd, *atm]


SPEC = register(
    EffectSpec(
        name="drag",
        code=CODE,
        doc="Atmospheric drag (exponential atmosphere, Vallado Table 8-4, or NRLMSIS 2.1) on bodies and tether rods.",
        params={
            "area": ParamSpec("m2", per_body=True, doc="cross-section area of each body"),
            "cd": ParamSpec("", required=False, default=2.2, per_body=True, doc="drag coefficient of each body"),
            "tether_cd": ParamSpec("", required=False, default=2.2, doc="drag coefficient of the tether cylinder"),
            "tether_diameter": ParamSpec("m", required=False, doc="tether diameter (default: the tether's own)"),
            "atmosphere": ParamSpec("", required=False, default="exponential", choices=("exponential", "nrlmsis21"),
                                    doc="density model", dated=("nrlmsis21",)),
            "f107": ParamSpec("", required=False, doc="nrlmsis21: daily F10.7 (sfu)"),
            "f107a": ParamSpec("", required=False, doc="nrlmsis21: 81-day mean F10.7 (sfu)"),
            "ap": ParamSpec("", required=False, doc="nrlmsis21: daily Ap"),
            "refresh": ParamSpec("s", required=False, doc="nrlmsis21: table day-slice step (default 5 d)"),
        },
        velocity_dependent=True,
        conservative=False,
        pack=_pack,
    )
)

# -- compiled kernels (SI floats only) -----------------------------------------------------------
from .._jit import njit  # noqa: E402


@njit(cache=True)
def density(p, par, t, x, y, z):
    """rho (kg/m^3) of the drag effect's atmosphere at inertial r, time t."""
    off = par + int(p[par + 2])
    if int(p[off]) == ATM_NRLMSIS:
        return nrlmsis.density(p, off + 1, t, x, y, z)
    return atmosphere.density(math.sqrt(x * x + y * y + z * z) - p[par])


@njit(cache=True)
def body_force(p, par, t, body, x, y, z, vx, vy, vz):
    """-1/2 rho Cd A |v_r| v_r (N) on body ``body`` (kernel order)."""
    k = -0.5 * density(p, par, t, x, y, z) * p[par + 3 + body]
    wx, wy, wz = atmosphere.relative_velocity(x, y, z, vx, vy, vz)
    s = k * math.sqrt(wx * wx + wy * wy + wz * wz)
    return s * wx, s * wy, s * wz


@njit(cache=True)
def rod_density(p, par, t, rod, x, y, z, vx, vy, vz, tx, ty, tz):
    """-1/2 rho Cd_t D |dr/dxi| |v_n| v_n: force per unit xi (N) on a rod element."""
    nb = int(p[par + 1])
    teth = int(p[int(p[H_OFF_ROD]) + rod * RT_SIZE + RT_TETH])
    cdd = p[par + 3 + nb + teth]
    wx, wy, wz = atmosphere.relative_velocity(x, y, z, vx, vy, vz)
    t2 = tx * tx + ty * ty + tz * tz
    c = (wx * tx + wy * ty + wz * tz) / t2
    nx = wx - c * tx
    ny = wy - c * ty
    nz = wz - c * tz
    s = -0.5 * density(p, par, t, x, y, z) * cdd * math.sqrt(t2) * math.sqrt(nx * nx + ny * ny + nz * nz)
    return s * nx, s * ny, s * nz
