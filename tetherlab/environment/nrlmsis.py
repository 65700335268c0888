"""NRLMSIS 2.1 total mass density through pymsis, tabulated before integration for the kernel.

Why a table: pymsis is a Fortran model called from Python (about 40 us a point in batches); the
right-hand side is compiled and must not call Python.  Before integration the density is tabulated
on a grid of (day slice, universal time, altitude, local solar time, latitude) over the run and the kernel
interpolates ln(rho) linearly in each of the five (32 table reads).  The lookup's error
against direct pymsis calls is measured by tests/test_environment.py and stated in
docs/environment.md, sec. 4.

Inputs: F10.7 (daily, sfu), its 81-day centred mean and the daily Ap, constant over the run and
always passed to pymsis (so it never looks for its space-weather file or downloads one).  The
seven-element Ap history NRLMSIS can use is filled with the daily Ap.

Coordinates in the kernel (t = TDB seconds since the epoch, r inertial GCRS):
* altitude: h = |r| - R_eq (1 - f sin^2 lat): the height above the WGS 84 ellipsoid along the
  radius (within ~0.1 km of the geodetic height at LEO);
* latitude: geocentric asin(z/|r|) (NRLMSIS takes geodetic: up to 0.19 deg apart);
* local solar time as NRLMSIS defines it, LST = UT (h) + longitude/15 (mean solar time), the
  longitude east of Greenwich = atan2(y, x) - (theta_0 + omega_E t), theta_0 the epoch's ERA.

Grid: altitude 100-1200 km every 20 km, LST every 2 h (periodic), latitude every 20 deg,
universal time of day every 4 h (periodic: at a fixed LST the density still depends on UT, i.e. on
longitude, through NRLMSIS's geomagnetic and longitude terms, by up to ~35 % at 500-1000 km),
and a day slice per ``refresh`` (drag's parameter, default 5 days: the seasonal and solar-
declination change) from the epoch to the end of the run plus one.  Outside the altitude range
ln(rho) is extrapolated linearly from the nearest band.

Block: [theta_0, UT of the epoch (s of day), slice step (s), n_slices, h0, dh, n_h, n_lst, lat0,
dlat, n_lat, n_ut, ln(rho) table (slice, ut, h, lst, lat)].
"""

from __future__ import annotations

import functools
import math

import numpy as np

from .._jit import njit
from .earth import EARTH_ROTATION_RATE_RAD_S

WGS84_A_M = 6378137.0
WGS84_F = 1.0 / 298.257223563
H0_M = 100e3
DH_M = 20e3
N_H = 56  # 100 .. 1200 km
N_LST = 12  # every 2 h
N_LAT = 10  # -90 .. 90 every 20 deg
N_UT = 6  # universal time of day every 4 h, periodic
HEADER = 12


def _utc_datetime64(epoch_tdb: str):
    from astropy.time import Time

    t = Time(epoch_tdb, scale="tdb")
    import erfa
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", erfa.ErfaWarning)
        utc = t.utc
        iso = utc.isot
    return np.datetime64(iso, "ns")


@functools.lru_cache(maxsize=4)
def table(epoch_tdb: str, duration_s: float, f107: float, f107a: float, ap: float, refresh_s: float) -> tuple:
    """(block list, build info).  Cached per process: the ladder's runs share one table."""
    import time

    import pymsis

    from . import earth_orientation

    import logging

    logging.getLogger("tetherlab").info(
        "building the NRLMSIS 2.1 density table over the run (%.4g d; pymsis, about 15 s)", duration_s / 86400.0
    )
    t0 = time.perf_counter()
    utc0 = _utc_datetime64(epoch_tdb)
    day0 = utc0.astype("datetime64[D]")
    ut0_s = float((utc0 - day0) / np.timedelta64(1, "ns")) * 1e-9
    theta0 = earth_orientation.earth_rotation_angle(epoch_tdb)["era_rad"]
    nslice = int(math.ceil(duration_s / refresh_s)) + 2
    hs = H0_M + DH_M * np.arange(N_H)
    lst = 24.0 * np.arange(N_LST) / N_LST
    lat = -90.0 + 180.0 * np.arange(N_LAT) / (N_LAT - 1)
    H, L, B = np.meshgrid(hs, lst, lat, indexing="ij")
    npt = H.size
    out = np.empty((nslice, N_UT, N_H, N_LST, N_LAT))
    for k in range(nslice):
        # the calendar day of slice k, then N_UT universal times on it
        day = (utc0 + np.timedelta64(int(round(k * refresh_s * 1e9)), "ns")).astype("datetime64[D]")
        for j in range(N_UT):
            ut_h = 24.0 * j / N_UT
            date = day.astype("datetime64[ns]") + np.timedelta64(int(round(ut_h * 3600e9)), "ns")
            lon = ((L.ravel() - ut_h) * 15.0 + 180.0) % 360.0 - 180.0
            rho = pymsis.calculate(
                np.full(npt, date), lon, B.ravel(), H.ravel() / 1e3,
                f107s=np.full(npt, f107), f107as=np.full(npt, f107a), aps=np.full((npt, 7), ap), version=2.1,
            )[:, 0]
            out[k, j] = np.log(rho).reshape(N_H, N_LST, N_LAT)
    block = [theta0, ut0_s, refresh_s, float(nslice), H0_M, DH_M, float(N_H), float(N_LST), -90.0,
             180.0 / (N_LAT - 1), float(N_LAT), float(N_UT)]
    info = {
        "model": "NRLMSIS 2.1 (pymsis, version=2.1), total mass density",
        "pymsis": _pymsis_version(),
        "f107_sfu": f107, "f107a_sfu": f107a, "ap": ap,
        "grid": (f"{nslice} day slices every {refresh_s:g} s x {N_UT} UT x {N_H} altitudes "
                 f"({H0_M/1e3:g}-{(H0_M + DH_M*(N_H-1))/1e3:g} km) x {N_LST} LST x {N_LAT} latitudes"),
        "build_s": time.perf_counter() - t0,
    }
    return block + out.ravel().tolist(), info


def _pymsis_version() -> str:
    from importlib.metadata import version

    return version("pymsis")


def density_direct(epoch_tdb: str, t_s, r_m, f107: float, f107a: float, ap: float) -> np.ndarray:
    """pymsis at inertial positions r_m (n, 3) and times t_s, with the kernel's coordinate
    conventions (for the lookup-error test)."""
    import pymsis

    from . import earth_orientation

    utc0 = _utc_datetime64(epoch_tdb)
    theta0 = earth_orientation.earth_rotation_angle(epoch_tdb)["era_rad"]
    t_s = np.asarray(t_s, float)
    r_m = np.asarray(r_m, float)
    rn = np.linalg.norm(r_m, axis=1)
    lat = np.arcsin(r_m[:, 2] / rn)
    lon = np.arctan2(r_m[:, 1], r_m[:, 0]) - theta0 - EARTH_ROTATION_RATE_RAD_S * t_s
    lon = (np.degrees(lon) + 180.0) % 360.0 - 180.0
    h = rn - WGS84_A_M * (1.0 - WGS84_F * np.sin(lat) ** 2)
    dates = utc0 + (t_s * 1e9).round().astype("timedelta64[ns]")
    n = t_s.size
    return pymsis.calculate(dates, lon, np.degrees(lat), h / 1e3, f107s=np.full(n, f107), f107as=np.full(n, f107a),
                            aps=np.full((n, 7), ap), version=2.1)[:, 0]


@njit(cache=True)
def density(p, off, t, x, y, z):
    """rho (kg/m^3) at inertial r (m), time t (s) from the table at p[off]."""
    theta0 = p[off]
    ut0 = p[off + 1]
    step = p[off + 2]
    ns = int(p[off + 3])
    h0 = p[off + 4]
    dh = p[off + 5]
    nh = int(p[off + 6])
    nl = int(p[off + 7])
    lat0 = p[off + 8]
    dlat = p[off + 9]
    na = int(p[off + 10])
    r = math.sqrt(x * x + y * y + z * z)
    s = z / r
    lat = math.degrees(math.asin(s))
    h = r - WGS84_A_M * (1.0 - WGS84_F * s * s)
    lon = math.atan2(y, x) - theta0 - EARTH_ROTATION_RATE_RAD_S * t
    lst = ((ut0 + t) / 3600.0 + lon * 12.0 / math.pi) % 24.0
    # indices and weights: day slice, UT of day (periodic), altitude, LST (periodic), latitude
    nu = int(p[off + 11])
    ts = t / step
    k = int(math.floor(ts))
    if k < 0:
        k = 0
    elif k > ns - 2:
        k = ns - 2
    wt = ts - k
    if wt < 0.0:
        wt = 0.0
    elif wt > 1.0:
        wt = 1.0
    uu = ((ut0 + t) % 86400.0) * nu / 86400.0
    ju = int(math.floor(uu))
    wu = uu - ju
    ju = ju % nu
    ju2 = (ju + 1) % nu
    hh = (h - h0) / dh
    i = int(math.floor(hh))
    if i < 0:
        i = 0
    elif i > nh - 2:
        i = nh - 2
    wh = hh - i  # may lie outside [0, 1]: linear extrapolation of ln rho
    ll = lst * nl / 24.0
    j = int(math.floor(ll))
    wl = ll - j
    j = j % nl
    j2 = (j + 1) % nl
    aa = (lat - lat0) / dlat
    m = int(math.floor(aa))
    if m < 0:
        m = 0
    elif m > na - 2:
        m = na - 2
    wa = aa - m
    base = off + HEADER
    acc = 0.0
    for dk in range(2):
        fk = wt if dk == 1 else 1.0 - wt
        for du in range(2):
            fu = fk * (wu if du == 1 else 1.0 - wu)
            uj = ju2 if du == 1 else ju
            for di in range(2):
                fi = fu * (wh if di == 1 else 1.0 - wh)
                for dj in range(2):
                    fj = fi * (wl if dj == 1 else 1.0 - wl)
                    jj = j2 if dj == 1 else j
                    row = ((((k + dk) * nu + uj) * nh + (i + di)) * nl + jj) * na + m
                    acc += fj * ((1.0 - wa) * p[base + row] + wa * p[base + row + 1])
    return math.exp(acc)
