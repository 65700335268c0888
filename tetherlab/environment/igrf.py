"""IGRF-14 main field to degree 13, evaluated in the compiled kernel.

What it models: the internal geomagnetic field B = -grad V,

    V(r, theta, phi, t) = a sum_{n=1}^{N} (a/r)^(n+1) sum_{m=0}^{n}
                          (g_n^m(t) cos m phi + h_n^m(t) sin m phi) P_n^m(cos theta),

geocentric spherical coordinates in the Earth-fixed frame (theta colatitude, phi east longitude),
P_n^m Schmidt semi-normalised without the Condon-Shortley phase, a = 6371.2 km.  Components
(docs/environment.md, sec. 2):

    B_r     =  sum (n+1) (a/r)^(n+2) sum (g c_m + h s_m) P_n^m
    B_theta = -sum       (a/r)^(n+2) sum (g c_m + h s_m) dP_n^m/dtheta
    B_phi   =  sum       (a/r)^(n+2) sum m (g s_m - h c_m) P_n^m / sin theta

with c_m = cos m phi, s_m = sin m phi.  P_n^m and dP_n^m/dtheta by the recursions (column by
column in m, so no array is needed and nothing is allocated):

    P_0^0 = 1, P_1^1 = sin theta, P_m^m = sqrt((2m-1)/(2m)) sin theta P_{m-1}^{m-1}  (m >= 2)
    P_n^m = [(2n-1) cos theta P_{n-1}^m - sqrt((n-1)^2 - m^2) P_{n-2}^m] / sqrt(n^2 - m^2),

and their theta-derivatives.

Coefficients: read at scene load from the IGRF-14 coefficient file shipped inside the ``ppigrf``
package (``ppigrf/IGRF14.shc``: 5-year main-field epochs 1900-2025 and the 2025-2030 secular
variation as the 2030 column), never typed in here.  Time: IGRF is linear in time between its
epochs; the block holds g(t0) at the scene epoch and the slope of the 5-year interval that
contains t0, so g(t) = g(t0) + gdot t is IGRF exactly while the run stays in that interval (and a
linear extrapolation of it across an epoch boundary: an error of the order of the change of the
secular variation, a few nT/yr^2).  Validity: 1900.0 to 2030.0 (the file's range); outside, a
SceneError.

Block (``pack``): ``[nmax, a_m, 6 floats per (n, m)]`` in the order n = 1..nmax, m = 0..n:
``g, h, gdot, hdot`` (T, T/s) and the two recursion constants (no square root in the kernel).
"""

from __future__ import annotations

import datetime as _dt
import functools
import math
from pathlib import Path

import numpy as np

from .._jit import njit

IGRF_REFERENCE_RADIUS_M = 6371.2e3  # IGRF reference radius (Alken et al. 2021, 2025)
NMAX = 13
GENERATION = "IGRF-14"
NCOEF = 6  # floats per (n, m) in the block


def coefficient_file() -> Path:
    import ppigrf.ppigrf as pp

    return Path(pp.shc_fn_igrf14)


@functools.lru_cache(maxsize=1)
def _tables():
    """(epochs as datetimes, g[n, m, k], h[n, m, k]) in nT from ppigrf's IGRF-14 file."""
    import ppigrf.ppigrf as pp

    g, h = pp.read_shc(str(coefficient_file()))
    times = [t.to_pydatetime() for t in g.index]
    nt = len(times)
    G = np.zeros((NMAX + 1, NMAX + 1, nt))
    H = np.zeros((NMAX + 1, NMAX + 1, nt))
    for (n, m) in g.columns:
        G[n, m] = np.asarray(g[(n, m)], float)
        H[n, m] = np.asarray(h[(n, m)], float)
    return times, G, H


def validity() -> tuple[_dt.datetime, _dt.datetime]:
    times, _, _ = _tables()
    return times[0], times[-1]


def coefficients_at(date: _dt.datetime, nmax: int = NMAX):
    """(g, h, gdot, hdot) arrays [n, m] in T and T/s at ``date`` (linear between the epochs, as
    ppigrf's own interpolation in time)."""
    times, G, H = _tables()
    if not (times[0] <= date <= times[-1]):
        raise ValueError(f"date {date.isoformat()} outside {GENERATION} ({times[0].date()} to {times[-1].date()})")
    k = 0
    while k < len(times) - 2 and date >= times[k + 1]:
        k += 1
    span = (times[k + 1] - times[k]).total_seconds()
    frac = (date - times[k]).total_seconds() / span
    g = (G[:, :, k] + frac * (G[:, :, k + 1] - G[:, :, k])) * 1e-9
    h = (H[:, :, k] + frac * (H[:, :, k + 1] - H[:, :, k])) * 1e-9
    gdot = (G[:, :, k + 1] - G[:, :, k]) * 1e-9 / span
    hdot = (H[:, :, k + 1] - H[:, :, k]) * 1e-9 / span
    return g[: nmax + 1, : nmax + 1], h[: nmax + 1, : nmax + 1], gdot[: nmax + 1, : nmax + 1], hdot[: nmax + 1, : nmax + 1]


def epoch_datetime(epoch_tdb: str) -> _dt.datetime:
    """The scene epoch as a naive datetime (TDB; the 69 s to UTC change IGRF by < 0.001 nT)."""
    from astropy.time import Time

    return Time(epoch_tdb, scale="tdb").to_datetime()


def pack(date: _dt.datetime, nmax: int = NMAX) -> list[float]:
    """[nmax, a, then per (n, m), n = 1..nmax, m = 0..n: g, h, gdot, hdot, alpha, beta].

    alpha, beta are the recursion constants, computed here so the kernel takes no square root:
    n > m: alpha = (2n - 1)/sqrt(n^2 - m^2), beta = sqrt((n-1)^2 - m^2)/sqrt(n^2 - m^2);
    n = m >= 2: alpha = sqrt((2m - 1)/(2m)) (the sectoral step), beta = 0; n = m = 1: 1, 0.
    """
    g, h, gd, hd = coefficients_at(date, nmax)
    out = [float(nmax), IGRF_REFERENCE_RADIUS_M]
    for n in range(1, nmax + 1):
        for m in range(n + 1):
            if n == m:
                alpha = 1.0 if m == 1 else math.sqrt((2.0 * m - 1.0) / (2.0 * m))
                beta = 0.0
            else:
                k3 = 1.0 / math.sqrt(n * n - m * m)
                alpha = (2.0 * n - 1.0) * k3
                beta = math.sqrt((n - 1.0) ** 2 - m * m) * k3
            out += [g[n, m], h[n, m], gd[n, m], hd[n, m], alpha, beta]
    return out


def block_size(nmax: int = NMAX) -> int:
    return 2 + NCOEF * (nmax * (nmax + 3) // 2)


@njit(cache=True)
def field_ecef(p, off, t, x, y, z):
    """IGRF field (T) in Earth-fixed Cartesian axes at Earth-fixed r (m), t s after the epoch."""
    nmax = int(p[off])
    a = p[off + 1]
    rho2 = x * x + y * y
    r2 = rho2 + z * z
    r = math.sqrt(r2)
    rho = math.sqrt(rho2)
    ct = z / r
    st = rho / r
    if st < 1e-15:  # on the axis: any longitude; P_n^m / sin(theta) keeps its finite limit
        st = 1e-15
        cp = 1.0
        sp = 0.0
    else:
        cp = x / rho
        sp = y / rho
    q = a / r
    br = 0.0
    bt = 0.0
    bp = 0.0
    # sectoral P_m^m, dP_m^m carried from m - 1 to m
    pmm = 1.0
    dpmm = 0.0
    cm = 1.0  # cos(m phi), sin(m phi) by the angle-addition recursion
    sm = 0.0
    qm = q * q  # (a/r)^(n+2) at n = m = 0
    for m in range(nmax + 1):
        if m == 1:
            pmm, dpmm = st, ct
        elif m >= 2:
            f = p[off + 2 + NCOEF * ((m * (m + 1)) // 2 - 1 + m) + 4]  # sqrt((2m-1)/(2m))
            pmm, dpmm = f * st * pmm, f * (st * dpmm + ct * pmm)
        if m >= 1:
            cm, sm = cm * cp - sm * sp, sm * cp + cm * sp
            qm *= q
        # column m: n = m, m + 1, ... by the three-term recursion (seeded with P_{m-1}^m = 0)
        p2 = 0.0
        dp2 = 0.0
        p1 = pmm
        dp1 = dpmm
        qn = qm  # (a/r)^(n+2) at n = m
        for n in range(m, nmax + 1):
            j = off + 2 + NCOEF * ((n * (n + 1)) // 2 - 1 + m)
            if n == m:
                pn = pmm
                dpn = dpmm
            else:
                alpha = p[j + 4]  # (2n-1)/sqrt(n^2-m^2)
                beta = p[j + 5]  # sqrt((n-1)^2-m^2)/sqrt(n^2-m^2)
                pn = alpha * ct * p1 - beta * p2
                dpn = alpha * (ct * dp1 - st * p1) - beta * dp2
                p2, dp2 = p1, dp1
                p1, dp1 = pn, dpn
                qn *= q
            if n == 0:
                continue  # no monopole
            gg = p[j] + p[j + 2] * t
            hh = p[j + 1] + p[j + 3] * t
            gc = gg * cm + hh * sm
            br += (n + 1.0) * qn * gc * pn
            bt -= qn * gc * dpn
            bp += qn * m * (gg * sm - hh * cm) * pn
    bp /= st
    # spherical -> Cartesian (Earth-fixed)
    bx = (br * st + bt * ct) * cp - bp * sp
    by = (br * st + bt * ct) * sp + bp * cp
    bz = br * ct - bt * st
    return bx, by, bz
