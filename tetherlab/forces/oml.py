"""Bare electrodynamic tether in the orbital-motion-limited (OML) regime: the current is driven by
the motional field, not prescribed.

What it models (Sanmartin, Martinez-Sanchez & Ahedo 1993, J. Propulsion Power 9(3) 353; derivation,
normalisation and closed form in docs/effects-oml.md): a bare conductive tether of cross-section
A, perimeter p (round wire of diameter D: A = pi D^2/4, p = pi D) and conductivity sigma, with an
ideal hollow cathode (zero impedance) at one end.  The motional field relative to the co-rotating
ionosphere, E_m = (v - omega_E z^ x r) x B, projected on the unit vector u from the cathode end to
the other (anodic) end gives E_t = E_m . u.  With x measured from the anodic end, I(x) the current
and Delta V(x) the tether-to-plasma bias:

    dI/dx = e N_e (p/pi) sqrt(2 e Delta V / m_e)        (OML electron collection, Delta V > 0)
    dDeltaV/dx = I/(sigma A) - E_t                       (ohmic drop minus motional field)

with I(0) = 0 (free anodic end) and Delta V = 0 at the cathode (ideal contactor; ion collection
on a cathodic segment neglected: it is (m_e/m_i)^(1/2) smaller).  In i = I/(sigma A E_t),
phi = Delta V/(E_t L*), xi = x/L*:  di/dxi = (3/4) phi^(1/2), dphi/dxi = i - 1, with

    L* = [ (3 pi/4) sigma A sqrt(m_e E_t) / (sqrt(2) e^(3/2) N_e p) ]^(2/3).

The profile depends on l = L/L* only.  E_t <= 0 (the field pushes electrons the wrong way):
no current (the cathode cannot collect).

How it stays compiled: the dimensionless profile is solved once per process by shooting on phi_A
(RK4 + bisection, compiled) on a grid of l in (0, 4]; for l >= 4 it is closed form (phi_A = 1:
i = 1 - (1 - xi/4)^3 up to xi = 4, then 1).  The kernel needs, per rod, the average current
over the rod's stretch of tether, so it stores G(f, l)/l^(3/2) with G(f, l) = int_0^f i(f' l) df'
at the rod end fractions f (measured from the anodic end) and interpolates linearly in l.  Each
quadrature node of a rod uses its own E_t and N_e (the "locally uniform" approximation: the
closed form's assumption, applied node by node) and the rod's average current, so the total force
on a straight rod is exact for uniform E_t, N_e and the rod's share of the current; the
distribution of the force within one rod is uniform (n rods resolve it).

Force per unit xi: dF/dxi = nu I_rod (u . t-direction) (dr/dxi) x B, nu the sunlit fraction of the
``eclipse`` switch.  Joule dissipation (diagnostic, :func:`profile`): int I^2/(sigma A) dx.

Electron density (environment/ionosphere.py): a Chapman layer (default) or uniform.

| parameter | unit | required | default | meaning |
|-----------|------|----------|---------|---------|
| conductivity | S/m | yes | | tether conductivity (aluminium ~3.5e7) |
| tether_diameter | m | no | the tether's ``diameter`` | round bare wire |
| cathode | choice | no | "from" | end with the hollow cathode: the tether's ``from`` or ``to`` body |
| ionosphere | choice | no | "chapman" | "chapman" or "uniform" |
| electron_density | 1/m3 | no | 1e12 | uniform: N_e; chapman: the peak density N_max |
| peak_altitude | m | no | 350 km | Chapman peak height |
| scale_height | m | no | 100 km | Chapman scale height |
| field, dipole_strength, greenwich_angle, eclipse | | no | | as for ``electrodynamic`` |
"""

from __future__ import annotations

import functools
import math

import numpy as np

from ..environment import eclipse, ionosphere, magnetic
from ..errors import SceneError
from ..kernel.layout import H_OFF_ROD, RT_SIZE
from .electrodynamic import FIELD_PARAMS
from .registry import EffectSpec, ParamSpec, register

CODE = 22

ELECTRON_MASS_KG = 9.1093837015e-31  # CODATA 2018
ELEMENTARY_CHARGE_C = 1.602176634e-19  # SI 2019, exact
L_TABLE_MAX = 4.0  # above: closed form (the anodic segment is 4 L* long, docs/effects-oml.md)
N_L = 201  # grid of l in [0, 4] (linear interpolation: error measured in tests/test_oml.py)
N_RK4 = 1680  # RK4 steps across the tether in the shooting (a multiple of n = 1..8, 10, 12, 14, 15, 16)


# -- the dimensionless solution (compiled; one shooting per l) ------------------------------------
from .._jit import njit  # noqa: E402


@njit(cache=True)
def _integrate(ell, phi_a, nsteps):
    """RK4 of (i, phi, C = int i) from xi = 0 (i = 0, phi = phi_A) to xi = ell; returns phi(ell)."""
    h = ell / nsteps
    i = 0.0
    phi = phi_a
    for _ in range(nsteps):
        k1i = 0.75 * math.sqrt(max(phi, 0.0))
        k1p = i - 1.0
        k2i = 0.75 * math.sqrt(max(phi + 0.5 * h * k1p, 0.0))
        k2p = i + 0.5 * h * k1i - 1.0
        k3i = 0.75 * math.sqrt(max(phi + 0.5 * h * k2p, 0.0))
        k3p = i + 0.5 * h * k2i - 1.0
        k4i = 0.75 * math.sqrt(max(phi + h * k3p, 0.0))
        k4p = i + h * k3i - 1.0
        i += h * (k1i + 2.0 * k2i + 2.0 * k3i + k4i) / 6.0
        phi += h * (k1p + 2.0 * k2p + 2.0 * k3p + k4p) / 6.0
    return phi


@njit(cache=True)
def anodic_bias(ell, nsteps):
    """phi_A such that phi(ell) = 0 (ideal cathode), by bisection on [0, 1]; ell < 4."""
    lo = 0.0
    hi = 1.0
    for _ in range(52):
        mid = 0.5 * (lo + hi)
        if _integrate(ell, mid, nsteps) > 0.0:
            hi = mid
        else:
            lo = mid
    return 0.5 * (lo + hi)


@njit(cache=True)
def profile_numeric(ell, phi_a, nsteps):
    """(xi, i, phi, C) at nsteps + 1 points, RK4 from the anodic end with phi(0) = phi_A."""
    h = ell / nsteps
    out = np.empty((nsteps + 1, 4))
    i = 0.0
    phi = phi_a
    c = 0.0
    out[0, 0] = 0.0
    out[0, 1] = i
    out[0, 2] = phi
    out[0, 3] = c
    for k in range(nsteps):
        k1i = 0.75 * math.sqrt(max(phi, 0.0))
        k1p = i - 1.0
        k1c = i
        k2i = 0.75 * math.sqrt(max(phi + 0.5 * h * k1p, 0.0))
        k2p = i + 0.5 * h * k1i - 1.0
        k2c = i + 0.5 * h * k1i
        k3i = 0.75 * math.sqrt(max(phi + 0.5 * h * k2p, 0.0))
        k3p = i + 0.5 * h * k2i - 1.0
        k3c = i + 0.5 * h * k2i
        k4i = 0.75 * math.sqrt(max(phi + h * k3p, 0.0))
        k4p = i + h * k3i - 1.0
        k4c = i + h * k3i
        i += h * (k1i + 2.0 * k2i + 2.0 * k3i + k4i) / 6.0
        phi += h * (k1p + 2.0 * k2p + 2.0 * k3p + k4p) / 6.0
        c += h * (k1c + 2.0 * k2c + 2.0 * k3c + k4c) / 6.0
        out[k + 1, 0] = (k + 1) * h
        out[k + 1, 1] = i
        out[k + 1, 2] = phi
        out[k + 1, 3] = c
    return out


def solution(ell: float, nsteps: int = N_RK4) -> dict:
    """Dimensionless profile for l = L/L*: xi, i, phi, cumulative C; phi_A, i at the cathode end,
    i_av, and the zero-bias point xi_B (= l for l <= 4: the whole tether is anodic)."""
    if not ell > 0.0:
        raise ValueError(f"l = L/L* must be > 0, got {ell!r}")
    if ell >= L_TABLE_MAX:
        xi = np.linspace(0.0, ell, nsteps + 1)
        s = np.clip(1.0 - xi / 4.0, 0.0, None)
        i = 1.0 - s**3
        phi = s**4
        c = np.where(xi <= 4.0, xi - 1.0 + s**4, xi - 1.0)
        return {"xi": xi, "i": i, "phi": phi, "C": c, "phi_A": 1.0, "i_C": 1.0, "i_av": 1.0 - 1.0 / ell, "xi_B": 4.0}
    phi_a = anodic_bias(ell, nsteps)
    prof = profile_numeric(ell, phi_a, nsteps)
    return {"xi": prof[:, 0], "i": prof[:, 1], "phi": prof[:, 2], "C": prof[:, 3], "phi_A": phi_a,
            "i_C": prof[-1, 1], "i_av": prof[-1, 3] / ell, "xi_B": ell}


@njit(cache=True)
def _table(fracs, ells, nsteps):
    out = np.zeros((fracs.size, ells.size))
    for k in range(ells.size):
        ell = ells[k]
        if ell == 0.0:
            for j in range(fracs.size):  # l -> 0 limit: i = (l^1.5 - (l - xi)^1.5)/2 (docs)
                f = fracs[j]
                out[j, k] = 0.5 * (f - 0.4 * (1.0 - (1.0 - f) ** 2.5))
            continue
        phi_a = anodic_bias(ell, nsteps)
        prof = profile_numeric(ell, phi_a, nsteps)
        for j in range(fracs.size):
            pos = fracs[j] * nsteps
            m = min(int(pos), nsteps - 1)
            w = pos - m
            c = (1.0 - w) * prof[m, 3] + w * prof[m + 1, 3]
            out[j, k] = c / ell / ell**1.5
    return out


@functools.lru_cache(maxsize=8)
def table(fracs: tuple[float, ...]) -> np.ndarray:
    """G(f, l)/l^(3/2) at the fractions ``fracs`` (rows) on the l grid of N_L points in [0, 4].

    The fractions are multiples of 1/n (rod ends); N_RK4 is a multiple of every n <= 16 used, so
    the cumulative integral is read at an RK4 node when it can be."""
    ells = np.linspace(0.0, L_TABLE_MAX, N_L)
    return _table(np.array(fracs, float), ells, N_RK4)


@njit(cache=True)
def cumulative(p, tab, ntab, row, f, ell):
    """G(f, l) = int_0^f i df' (fraction units) from the table row ``row`` (l < 4) or closed form."""
    if ell >= L_TABLE_MAX:
        xi = f * ell
        if xi <= 4.0:
            s = 1.0 - 0.25 * xi
            return (xi - 1.0 + s * s * s * s) / ell
        return (xi - 1.0) / ell
    pos = ell / L_TABLE_MAX * (ntab - 1)
    k = min(int(pos), ntab - 2)
    w = pos - k
    base = tab + row * ntab
    return ((1.0 - w) * p[base + k] + w * p[base + k + 1]) * ell**1.5


# -- scene boundary -------------------------------------------------------------------------------
#: block: [sigma A, perimeter, L* prefactor, iono block (4), R_E, off field, off eclipse, off table,
#:         n_l, per rod (global order): L_tether, cathode sign, row1, row2, f1, f2, ...]
B_SIGA, B_PERIM, B_PREF, B_IONO, B_RE, B_OFF_FIELD, B_OFF_ECL, B_OFF_TAB, B_NTAB, B_RODS = 0, 1, 2, 3, 7, 8, 9, 10, 11, 12
ROD_SIZE = 6


def _pack(params, central, ctx):
    sigma = params["conductivity"]
    if not (sigma > 0.0 and math.isfinite(sigma)):
        raise SceneError("effects.oml.conductivity", "a conductivity > 0 (aluminium: '3.5e7 S/m')", repr(sigma))
    tethers = ctx["tethers"]
    diam = []
    for t in tethers:
        d = params.get("tether_diameter", t.diameter_m)
        if d is None:
            raise SceneError(f"tethers.{t.name}.diameter",
                             "a tether diameter (OML collection and the resistance need the wire's cross-section), "
                             "or effects.oml.tether_diameter", "none")
        if not (d > 0.0 and math.isfinite(d)):
            raise SceneError("effects.oml.tether_diameter", "a diameter > 0", repr(d))
        diam.append(d)
    if len(set(diam)) > 1:
        raise SceneError("effects.oml.tether_diameter", "one diameter shared by every tether", repr(diam))
    d = diam[0]
    area = math.pi * d * d / 4.0
    perim = math.pi * d
    iono = ionosphere.pack(params, "oml")
    # L* = [pref sqrt(E_t) / N_e]^(2/3), pref = (3 pi/4) sigma A sqrt(m_e) / (sqrt(2) e^1.5 p)
    pref = 0.75 * math.pi * sigma * area * math.sqrt(ELECTRON_MASS_KG) / (math.sqrt(2.0) * ELEMENTARY_CHARGE_C**1.5 * perim)
    # rods: fractions of the tether from its anodic end
    sign = 1.0 if params["cathode"] == "from" else -1.0
    rods = []
    fr = set()
    for t in tethers:
        n = t.rods
        for j in range(n):
            # rod j spans [j/n, (j+1)/n] of the tether from its `from` end
            a, b = j / n, (j + 1) / n
            f1, f2 = (1.0 - b, 1.0 - a) if sign > 0 else (a, b)
            f1, f2 = round(f1, 15), round(f2, 15)
            fr.update((f1, f2))
            rods.append((t.length_m, f1, f2))
    fracs = tuple(sorted(fr))
    tab = table(fracs)
    row = {f: k for k, f in enumerate(fracs)}
    rod_block = []
    for length, f1, f2 in rods:
        rod_block += [length, sign, float(row[f1]), float(row[f2]), f1, f2]
    field = magnetic.pack_field_for(params, ctx, "oml")
    shadow = eclipse.pack(params.get("eclipse", "none"), ctx, central["radius_m"], "oml")
    head = B_RODS + len(rod_block)
    off_field = head
    off_ecl = off_field + len(field)
    off_tab = off_ecl + len(shadow)
    ctx.setdefault("meta", {}).setdefault("oml", {}).update(
        {"model": "OML bare tether, ideal cathode, ion collection neglected (Sanmartin et al. 1993)",
         "table": f"G(f, l) at {len(fracs)} fractions x {N_L} l in [0, 4], RK4 {N_RK4} steps"})
    return [sigma * area, perim, pref, *iono, central["radius_m"], float(off_field), float(off_ecl), float(off_tab),
            float(N_L), *rod_block, *field, *shadow, *tab.ravel().tolist()]


SPEC = register(
    EffectSpec(
        name="oml",
        code=CODE,
        doc="Bare-tether current collected in the OML regime from the motional field (Sanmartin et al. 1993), its Lorentz force.",
        params={
            "conductivity": ParamSpec("S / m", doc="tether conductivity"),
            "tether_diameter": ParamSpec("m", required=False, doc="wire diameter (default: the tether's own)"),
            "cathode": ParamSpec("", required=False, default="from", choices=("from", "to"),
                                 doc="end of the tether with the hollow cathode"),
            "ionosphere": ParamSpec("", required=False, default="chapman", choices=tuple(ionosphere.IONO_CODES),
                                    doc="electron density model: Chapman layer or uniform"),
            "electron_density": ParamSpec("1 / m3", required=False, default=1e12,
                                          doc="uniform: N_e; chapman: the peak N_max"),
            "peak_altitude": ParamSpec("m", required=False, default=350e3, doc="Chapman peak altitude"),
            "scale_height": ParamSpec("m", required=False, default=100e3, doc="Chapman scale height"),
            **FIELD_PARAMS,
        },
        velocity_dependent=True,  # the current follows the motional field (v - w x r) x B
        conservative=False,
        pack=_pack,
    )
)


@njit(cache=True)
def rod_current(p, par, rod, t, x, y, z, vx, vy, vz, tx, ty, tz):
    """(I_rod >= 0 from the cathode end to the anodic end (A), E_t (V/m), sign of u along dr/dxi,
    B) at one node: the rod's average OML current for the local E_t and N_e."""
    rb = par + B_RODS + ROD_SIZE * rod
    sgn = p[rb + 1]
    bx, by, bz = magnetic.field(p, par + int(p[par + B_OFF_FIELD]), t, x, y, z)
    nu = eclipse.sunlit_fraction(p, par + int(p[par + B_OFF_ECL]), t, x, y, z)
    if nu == 0.0:
        return 0.0, 0.0, sgn, bx, by, bz
    w = ionosphere.EARTH_ROTATION_RATE_RAD_S
    wx = vx + w * y
    wy = vy - w * x
    wz = vz
    ex = wy * bz - wz * by
    ey = wz * bx - wx * bz
    ez = wx * by - wy * bx
    tl = math.sqrt(tx * tx + ty * ty + tz * tz)
    et = sgn * (ex * tx + ey * ty + ez * tz) / tl
    if et <= 0.0:
        return 0.0, et, sgn, bx, by, bz
    h = math.sqrt(x * x + y * y + z * z) - p[par + B_RE]
    ne = ionosphere.density(p, par + B_IONO, h)
    if ne <= 0.0:
        return 0.0, et, sgn, bx, by, bz
    lstar = (p[par + B_PREF] * math.sqrt(et) / ne) ** (2.0 / 3.0)
    ell = p[rb] / lstar
    tab = par + int(p[par + B_OFF_TAB])
    ntab = int(p[par + B_NTAB])
    f1 = p[rb + 4]
    f2 = p[rb + 5]
    g1 = cumulative(p, tab, ntab, int(p[rb + 2]), f1, ell)
    g2 = cumulative(p, tab, ntab, int(p[rb + 3]), f2, ell)
    i_rod = (g2 - g1) / (f2 - f1)
    return nu * p[par + B_SIGA] * et * i_rod, et, sgn, bx, by, bz


@njit(cache=True)
def rod_density(p, par, rod, t, x, y, z, vx, vy, vz, tx, ty, tz):
    """Force per unit xi (N): I_rod u x B |dr/dxi| = sgn I_rod (dr/dxi) x B."""
    cur, _, sgn, bx, by, bz = rod_current(p, par, rod, t, x, y, z, vx, vy, vz, tx, ty, tz)
    c = sgn * cur
    return c * (ty * bz - tz * by), c * (tz * bx - tx * bz), c * (tx * by - ty * bx)


def profile(sigma_s_m: float, diameter_m: float, length_m: float, et_v_m: float, ne_m3: float) -> dict:
    """Dimensional profile for uniform E_t and N_e: x from the anodic end (m), I (A), bias (V),
    average current, Joule power int I^2/(sigma A) dx (W) and the power drawn from the orbit
    E_t int I dx (W).  For the docs, the tests and the fidelity study."""
    area = math.pi * diameter_m**2 / 4.0
    perim = math.pi * diameter_m
    pref = 0.75 * math.pi * sigma_s_m * area * math.sqrt(ELECTRON_MASS_KG) / (math.sqrt(2.0) * ELEMENTARY_CHARGE_C**1.5 * perim)
    lstar = (pref * math.sqrt(et_v_m) / ne_m3) ** (2.0 / 3.0)
    sol = solution(length_m / lstar)
    x = sol["xi"] * lstar
    current = sol["i"] * sigma_s_m * area * et_v_m
    bias = sol["phi"] * et_v_m * lstar
    joule = float(np.trapezoid(current**2, x) / (sigma_s_m * area))
    return {"x_m": x, "current_a": current, "bias_v": bias, "l_star_m": lstar, "ell": length_m / lstar,
            "average_current_a": sol["i_av"] * sigma_s_m * area * et_v_m, "joule_w": joule,
            "motional_power_w": float(et_v_m * np.trapezoid(current, x)), "solution": sol}


_ = H_OFF_ROD, RT_SIZE  # rod indices are global (kernel order), as the rod table's
