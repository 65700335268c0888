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
from ..forces import oml  # code 22: OML bare-tether current (docs/effects-oml.md)
from .layout import (
    ET_CODE,
    ET_OFF_PAR,
    ET_SIZE,
    H_FAIL_EFFECT,
    H_FAIL_EFFECT_T,
    H_NEFF,
    H_NREST,
    H_OFF_CNT,
    H_OFF_EFF,
    H_OFF_REST,
    H_PAR_CG,
    H_PAR_J2,
    H_PAR_SMOON,
)


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
    """The scene's effects on point mass ``body`` (central gravity only with ``central``).

    Central gravity, J2 and the Stiefel Moon are reached through their header slots (layout
    H_PAR_CG, H_PAR_J2, H_PAR_SMOON: their parameter offsets, -1 when the scene does not name
    them), every other effect through the (code, offset) list H_OFF_REST.  Walking the whole
    effect table instead (a code and an offset read and converted per entry, a compare chain)
    cost ~9 % of a whole DROMO Stiefel-Scheifele run (docs/integrators.md section 8).  An effect
    the scene does not name is still never evaluated."""
    cnt = int(p[H_OFF_CNT])
    fx = 0.0
    fy = 0.0
    fz = 0.0
    if central:
        pc = int(p[H_PAR_CG])
        if pc >= 0:
            p[cnt + central_gravity.CODE] += 1.0
            ax, ay, az = central_gravity.accel(p[pc], x, y, z)
            _note_nonfinite(p, central_gravity.CODE, t, ax, ay, az)
            fx += mass * ax
            fy += mass * ay
            fz += mass * az
    pj = int(p[H_PAR_J2])
    if pj >= 0:
        p[cnt + zonal.CODE_J2] += 1.0
        ax, ay, az = zonal.accel_j2(p[pj], p[pj + 1], p[pj + 2], x, y, z)
        _note_nonfinite(p, zonal.CODE_J2, t, ax, ay, az)
        fx += mass * ax
        fy += mass * ay
        fz += mass * az
    pm = int(p[H_PAR_SMOON])
    if pm >= 0:
        p[cnt + stiefel_moon.CODE] += 1.0
        ax, ay, az = stiefel_moon.accel(p[pm], p[pm + 1], p[pm + 2], t, x, y, z, p[pm + 3])
        _note_nonfinite(p, stiefel_moon.CODE, t, ax, ay, az)
        fx += mass * ax
        fy += mass * ay
        fz += mass * az
    off = int(p[H_OFF_REST])
    for e in range(int(p[H_NREST])):
        code = int(p[off + 2 * e])
        par = int(p[off + 2 * e + 1])
        p[cnt + code] += 1.0
        ax, ay, az = _other_body(p, code, par, t, body, x, y, z, vx, vy, vz, mass)
        _note_nonfinite(p, code, t, ax, ay, az)
        fx += ax
        fy += ay
        fz += az
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


@njit(cache=True, inline="always")
def rod_central_gravity_only(p):
    """The parameter offset of central gravity when it is the only effect the scene names (the
    common case: the rods' quadrature then runs without the effect dispatch), else -1."""
    off = int(p[H_OFF_EFF])
    if int(p[H_NEFF]) == 1 and int(p[off + ET_CODE]) == central_gravity.CODE:
        return int(p[off + ET_OFF_PAR])
    return -1


@njit(cache=True, inline="always")
def rod_central_gravity_density(p, mu, t, x, y, z, mass_per_xi):
    """:func:`rod_force_density` when central gravity (parameter ``mu``) is the only effect, the
    same operations in the same order, without counting: the caller counts its nodes at once
    (:func:`count_rod_nodes`)."""
    ax, ay, az = central_gravity.accel(mu, x, y, z)
    _note_nonfinite(p, central_gravity.CODE, t, ax, ay, az)
    return 0.0 + mass_per_xi * ax, 0.0 + mass_per_xi * ay, 0.0 + mass_per_xi * az


@njit(cache=True, inline="always")
def count_rod_nodes(p, nodes):
    """Count ``nodes`` evaluations of every effect the scene names (what ``nodes`` calls of
    :func:`rod_force_density` count)."""
    off = int(p[H_OFF_EFF])
    cnt = int(p[H_OFF_CNT])
    for e in range(int(p[H_NEFF])):
        p[cnt + int(p[off + e * ET_SIZE + ET_CODE])] += nodes


@njit(cache=True, inline="always")
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
