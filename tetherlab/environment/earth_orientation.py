"""Earth orientation from the scene's epoch: the Earth rotation angle (ERA) through ERFA.

What it gives: the angle theta_0 of the Earth-fixed x axis (Greenwich meridian on the equator)
from the inertial x axis at t = 0, for every Earth-fixed model (tilted dipole, IGRF); in the
kernel theta(t) = theta_0 + omega_E t.  Derivation and error budget: docs/environment.md, sec. 1.

Why the ERA and not GMST: tetherlab's inertial frame is the GCRS with the pole on +z and no
precession-nutation (forces/zonal.py).  The ERA (IAU 2000, ``erfa.era00``) is the angle between the
Celestial Intermediate Origin and the Terrestrial Intermediate Origin: measured from an origin
that stays within milliarcseconds of the GCRS x axis over centuries (the CIO is "non-rotating").
GMST adds the accumulated precession in right ascension (about 0.36 deg by 2026), which belongs
to a frame of date, not to the GCRS.  What remains neglected is the tilt of the true pole from
the GCRS pole (precession-nutation, X ~ 0.14 deg, Y ~ 0.002 deg in 2026) and polar motion (~0.3").

Time scales: the scene's epoch is TDB.  UT1 = UTC + (UT1 - UTC); TDB -> TT (erfa.tdbtt, the
periodic term, < 1.7 ms) -> TAI (-32.184 s) -> UTC (ERFA's own leap-second table, erfa.dat) ->
UT1 with UT1 - UTC from astropy's bundled IERS-B table when the epoch is inside it (never
downloaded), else 0 (|UT1 - UTC| < 0.9 s by definition of UTC: 6.6e-5 rad, 0.0038 deg).

The rotation rate in the kernel is WGS 84's omega_E = 7.292115e-5 rad/s; the ERA's own rate,
2 pi 1.00273781191135448 / 86400 s = 7.2921151467e-5 rad/s, differs by 1.5e-13 rad/s: 6e-7 rad
over a 45-day run.
"""

from __future__ import annotations

import math
import warnings

#: Rate of the ERA (rad/s): 2 pi x 1.00273781191135448 per UT1 day (IERS Conventions 2010, eq. 5.15).
ERA_RATE_RAD_S = 2.0 * math.pi * 1.00273781191135448 / 86400.0


def _jd_tdb(epoch_tdb: str) -> tuple[float, float]:
    from astropy.time import Time

    t = Time(epoch_tdb, scale="tdb")
    return float(t.jd1), float(t.jd2)


def ut1_minus_utc_s(jd_utc1: float, jd_utc2: float) -> tuple[float, str]:
    """UT1 - UTC (s) from astropy's bundled IERS-B table (offline), and where it came from."""
    try:
        from astropy.utils import iers

        table = iers.IERS_B.open()  # the file bundled with astropy-iers-data: no download
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            dut1, status = table.ut1_utc(jd_utc1, jd_utc2, return_status=True)
        if int(status) == iers.FROM_IERS_B:
            return float(getattr(dut1, "value", dut1)), "IERS-B (astropy bundled)"
    except Exception:  # noqa: BLE001 - any failure: fall back to the documented bound
        pass
    return 0.0, "UT1 = UTC (epoch outside the bundled IERS-B table; |UT1-UTC| < 0.9 s)"


def earth_rotation_angle(epoch_tdb: str) -> dict:
    """ERA (rad, in [0, 2 pi)) at the TDB epoch, with the time-scale chain used.

    Returns {"era_rad", "ut1_minus_utc_s", "dut1_source", "jd_ut1"}.
    """
    import erfa

    tdb1, tdb2 = _jd_tdb(epoch_tdb)
    # TDB -> TT: the periodic TDB - TT term (erfa.dtdb at the geocentre, < 1.7 ms)
    dtr = erfa.dtdb(tdb1, tdb2, 0.0, 0.0, 0.0, 0.0)
    tt1, tt2 = erfa.tdbtt(tdb1, tdb2, dtr)
    tai1, tai2 = erfa.tttai(tt1, tt2)
    with warnings.catch_warnings():
        # "dubious year": past ERFA's leap-second horizon UTC is extrapolated with no new leap
        # second (an error of at most a second or so in UT1: 7e-5 rad)
        warnings.simplefilter("ignore", erfa.ErfaWarning)
        utc1, utc2 = erfa.taiutc(tai1, tai2)
    dut1, source = ut1_minus_utc_s(utc1, utc2)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", erfa.ErfaWarning)
        ut11, ut12 = erfa.utcut1(utc1, utc2, dut1)
    era = float(erfa.era00(ut11, ut12))
    return {"era_rad": era, "ut1_minus_utc_s": dut1, "dut1_source": source, "jd_ut1": ut11 + ut12}


def rotation_angle_at_start(params: dict, ctx: dict, effect: str) -> tuple[float, str]:
    """theta_0 for an Earth-fixed model: an explicit ``greenwich_angle`` wins over the epoch.

    Order: (1) the effect's ``greenwich_angle`` if the scene gives it (an override: the user
    says which angle); (2) the ERA of the scene's ``epoch``; (3) 0 with no epoch (the angle of
    the older scenes, kept so they run unchanged).  Returns (angle, how it was chosen).
    """
    if params.get("greenwich_angle") is not None:
        return float(params["greenwich_angle"]), f"effects.{effect}.greenwich_angle (explicit override)"
    epoch = ctx.get("epoch")
    if epoch is not None:
        era = earth_rotation_angle(epoch)
        return era["era_rad"], f"ERA of epoch {epoch} TDB via ERFA era00; UT1-UTC {era['ut1_minus_utc_s']:+.4f} s ({era['dut1_source']})"
    return 0.0, "0 (no epoch and no greenwich_angle)"
