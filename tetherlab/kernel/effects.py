"""Dispatch from the effect codes a scene names to the compiled effect kernels.

The kernel loops over the effect table of the parameter block, which holds *only* the effects the
scene names: an effect that is not named is never reached.  Each evaluation increments a counter
indexed by the effect code (``H_OFF_CNT``), which the tests use to prove it.

Two entry points, because a point mass and a stretch of tether feel effects differently:

* :func:`body_force` -- total force on a point mass (N); ``body`` is the body's index in the
  model (0 = the root body, 1 + k = the tip body of tether k), for effects with per-body
  parameters (drag area, ...);
* :func:`rod_force_density` -- force per unit of the rod coordinate xi in [-1, 1] on a rod element
  at position r, velocity v, with tangent dr/dxi and mass per unit xi (N); ``rod`` is the global
  rod index (RT_TETH of the rod table gives its tether); the half-rod totals R_1,
  R_2 and the moment M_G of paper eq. 9-13 are quadratures of it (docs/model.md, section 3).

Adding an effect = one module in tetherlab/forces/ + one branch in each function below.
"""

from __future__ import annotations

import math

from .._jit import njit
from ..forces import applied_force, central_gravity, uniform_gravity
from ..forces import stiefel_moon  # Stiefel-Scheifele analytic Moon, code 30
from ..forces import third_body, zonal  # gravity family, codes 10-13
from ..forces import drag, electrodynamic  # codes 20-29
from ..forces import oml  # code 22: OML bare-tether current (issue 13)
from .layout import ET_CODE, ET_OFF_PAR, ET_SIZE, H_FAIL_EFFECT, H_FAIL_EFFECT_T, H_NEFF, H_OFF_CNT, H_OFF_EFF


@njit(cache=True)
def _note_nonfinite(p, code, t, ax, ay, az):
    """Record which effect produced a non-finite force (the chain's failure header says where
    and when the acceleration broke; this says which named effect caused it).  Three compares
    per effect evaluation."""
    if not (math.isfinite(ax) and math.isfinite(ay) and math.isfinite(az)):
        p[H_FAIL_EFFECT] = code
        p[H_FAIL_EFFECT_T] = t


@njit(cache=True)
def body_force(p, t, body, x, y, z, vx, vy, vz, mass):
    """Total force (N) on point mass ``body`` from every effect the scene names."""
    return _body_force(p, t, body, x, y, z, vx, vy, vz, mass, True)


@njit(cache=True)
def perturbing_body_force(p, t, body, x, y, z, vx, vy, vz, mass):
    """As :func:`body_force` without central gravity: for formulations that integrate the Kepler
    motion analytically (DROMO), so it is neither computed nor subtracted again (which would
    also cancel about log10(mu/(r^2 a_p)) digits of the perturbation)."""
    return _body_force(p, t, body, x, y, z, vx, vy, vz, mass, False)


@njit(cache=True)
def _body_force(p, t, body, x, y, z, vx, vy, vz, mass, central):
    neff = int(p[H_NEFF])
    off = int(p[H_OFF_EFF])
    cnt = int(p[H_OFF_CNT])
    fx = 0.0
    fy = 0.0
    fz = 0.0
    for e in range(neff):
        code = int(p[off + e * ET_SIZE + ET_CODE])
        par = int(p[off + e * ET_SIZE + ET_OFF_PAR])
        if code == central_gravity.CODE:
            if not central:
                continue
            p[cnt + code] += 1.0
            ax, ay, az = central_gravity.accel(p[par], x, y, z)
        elif code == zonal.CODE_J2:
            # J2 and the Stiefel Moon are dispatched here, not in _other_body: on the DROMO
            # point-mass path that call cost ~12 ns each, as much as the two forces themselves
            p[cnt + code] += 1.0
            ax, ay, az = zonal.accel_j2(p[par], p[par + 1], p[par + 2], x, y, z)
        elif code == stiefel_moon.CODE:
            p[cnt + code] += 1.0
            ax, ay, az = stiefel_moon.accel(p[par], p[par + 1], p[par + 2], t, x, y, z, p[par + 3])
        else:
            p[cnt + code] += 1.0
            ax, ay, az = _other_body(p, code, par, t, body, x, y, z, vx, vy, vz, mass)
            _note_nonfinite(p, code, t, ax, ay, az)
            fx += ax
            fy += ay
            fz += az
            continue
        _note_nonfinite(p, code, t, ax, ay, az)
        fx += mass * ax
        fy += mass * ay
        fz += mass * az
    return fx, fy, fz


@njit(cache=True)
def _other_body(p, code, par, t, body, x, y, z, vx, vy, vz, mass):
    """Every effect on a point mass but central gravity, J2 and the Stiefel Moon (kept out of the
    hot loop so that loop stays small)."""
    fx = 0.0
    fy = 0.0
    fz = 0.0
    if code == uniform_gravity.CODE:
        fz += mass * uniform_gravity.accel(p[par], x, y, z)[2]
    elif code == applied_force.CODE:
        if body == int(p[par]):
            fx += p[par + 1]
            fy += p[par + 2]
            fz += p[par + 3]
    # -- gravity family (codes 10-13): zonal harmonics, DE421 third bodies
    elif code == zonal.CODE_ZONAL:  # (J2 alone: in _body_force)
        ax, ay, az = zonal.accel(p[par], p[par + 1], p[par + 2], p[par + 3], p[par + 4], x, y, z)
        fx += mass * ax
        fy += mass * ay
        fz += mass * az
    elif code == third_body.CODE_MOON or code == third_body.CODE_SUN:
        ax, ay, az = third_body.accel(p, par, t, x, y, z)
        fx += mass * ax
        fy += mass * ay
        fz += mass * az
    elif code == drag.CODE:  # (electrodynamic: no force on point masses)
        ax, ay, az = drag.body_force(p, par, t, body, x, y, z, vx, vy, vz)
        fx += ax
        fy += ay
        fz += az
    return fx, fy, fz


@njit(cache=True)
def rod_force_density(p, t, rod, x, y, z, vx, vy, vz, tx, ty, tz, mass_per_xi):
    neff = int(p[H_NEFF])
    off = int(p[H_OFF_EFF])
    cnt = int(p[H_OFF_CNT])
    fx = 0.0
    fy = 0.0
    fz = 0.0
    for e in range(neff):
        code = int(p[off + e * ET_SIZE + ET_CODE])
        par = int(p[off + e * ET_SIZE + ET_OFF_PAR])
        p[cnt + code] += 1.0
        if code == central_gravity.CODE:
            ax, ay, az = central_gravity.accel(p[par], x, y, z)
            _note_nonfinite(p, code, t, ax, ay, az)
            fx += mass_per_xi * ax
            fy += mass_per_xi * ay
            fz += mass_per_xi * az
        else:
            ax, ay, az = _other_rod(p, code, par, t, rod, x, y, z, vx, vy, vz, tx, ty, tz, mass_per_xi)
            _note_nonfinite(p, code, t, ax, ay, az)
            fx += ax
            fy += ay
            fz += az
    return fx, fy, fz


@njit(cache=True)
def _other_rod(p, code, par, t, rod, x, y, z, vx, vy, vz, tx, ty, tz, mass_per_xi):
    """Every effect but central gravity (kept out of the hot loop so that loop stays small)."""
    fx = 0.0
    fy = 0.0
    fz = 0.0
    if code == uniform_gravity.CODE:
        fz += mass_per_xi * uniform_gravity.accel(p[par], x, y, z)[2]
    # -- gravity family (codes 10-13): zonal harmonics, DE421 third bodies
    elif code == zonal.CODE_J2:
        ax, ay, az = zonal.accel_j2(p[par], p[par + 1], p[par + 2], x, y, z)
        fx += mass_per_xi * ax
        fy += mass_per_xi * ay
        fz += mass_per_xi * az
    elif code == zonal.CODE_ZONAL:
        ax, ay, az = zonal.accel(p[par], p[par + 1], p[par + 2], p[par + 3], p[par + 4], x, y, z)
        fx += mass_per_xi * ax
        fy += mass_per_xi * ay
        fz += mass_per_xi * az
    elif code == third_body.CODE_MOON or code == third_body.CODE_SUN:
        ax, ay, az = third_body.accel(p, par, t, x, y, z)
        fx += mass_per_xi * ax
        fy += mass_per_xi * ay
        fz += mass_per_xi * az
    elif code == electrodynamic.CODE:
        ax, ay, az = electrodynamic.rod_density(p, par, t, x, y, z, tx, ty, tz)
        fx += ax
        fy += ay
        fz += az
    elif code == drag.CODE:
        ax, ay, az = drag.rod_density(p, par, t, rod, x, y, z, vx, vy, vz, tx, ty, tz)
        fx += ax
        fy += ay
        fz += az
    elif code == stiefel_moon.CODE:
        ax, ay, az = stiefel_moon.accel(p[par], p[par + 1], p[par + 2], t, x, y, z, p[par + 3])
        fx += mass_per_xi * ax
        fy += mass_per_xi * ay
        fz += mass_per_xi * az
    elif code == oml.CODE:
        ax, ay, az = oml.rod_density(p, par, rod, t, x, y, z, vx, vy, vz, tx, ty, tz)
        fx += ax
        fy += ay
        fz += az
    return fx, fy, fz


@njit(cache=True)
def potential_per_mass(p, t, x, y, z):
    """Sum of the potentials (J/kg) of the conservative effects named (for energy diagnostics)."""
    neff = int(p[H_NEFF])
    off = int(p[H_OFF_EFF])
    u = 0.0
    for e in range(neff):
        code = int(p[off + e * ET_SIZE + ET_CODE])
        par = int(p[off + e * ET_SIZE + ET_OFF_PAR])
        if code == central_gravity.CODE:
            u += central_gravity.potential(p[par], x, y, z)
        elif code == uniform_gravity.CODE:
            u += uniform_gravity.potential(p[par], x, y, z)
        # -- gravity family: zonal harmonics (the DE421 third bodies are time-dependent, not
        # conservative, so their potential stays out of the energy: forces/third_body.py)
        elif code == zonal.CODE_J2:
            u += zonal.potential_j2(p[par], p[par + 1], p[par + 2], x, y, z)
        elif code == zonal.CODE_ZONAL:
            u += zonal.potential(p[par], p[par + 1], p[par + 2], p[par + 3], p[par + 4], x, y, z)
    return u
