"""Build tether-free orbit references for the gravity effects with heyoka (an oracle sharing no code with tetherlab).

Three point-mass problems, each integrated by heyoka's Taylor method in IEEE binary128
(``heyoka.real128``, tolerance 2^-112) and, as a cross-check, in double at tolerance 1e-15:

* ``leo_j2``: LEO, Earth point mass + J2, 1 day;
* ``leo_zonal``: the same orbit with J2 + J3 + J4, 1 day;
* ``geo_moon_circular``: an eccentric near-geostationary orbit, Earth point mass + a Moon on a
  circular inclined orbit given in closed form (direct + indirect term), 5 days.

The equations are written here from the textbook forms (Vallado, *Fundamentals of
Astrodynamics and Applications*, 4th ed., sect. 8.6.1 for the zonal terms; Battin 1999 sect. 8.4
for the third body), not from tetherlab's kernels, so the two share no code.  Every constant is
the repr() of the IEEE double tetherlab uses (so both sides integrate the same problem), widened
exactly to binary128.  Units: m, s.

Only this builder imports heyoka; tests/test_gravity_effects.py reads references.json.

Rebuild:  /tmp/tv/bin/python references/heyoka_orbits/build_references.py   (project: .venv/bin/python)
"""

from __future__ import annotations

import datetime as _dt
import json
import math
import platform
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
OUT_JSON = HERE / "references.json"

# -- constants (double values, repr strings; sources as in tetherlab/forces/*.py) ---------------
MU_EARTH = 3.986004418e14  # WGS 84 GM (m^3/s^2), tetherlab's "earth" preset
R_EARTH = 6378137.0  # WGS 84 equatorial radius (m), the preset's radius = the zonal reference radius
# EGM2008 tide-free: J_n = -sqrt(2n+1) C_n0bar, C20bar = -0.484165143790815e-3,
# C30bar = 0.957161207093473e-6, C40bar = 0.539965866638991e-6 (Pavlis et al. 2012)
J2 = -math.sqrt(5.0) * -0.484165143790815e-3
J3 = -math.sqrt(7.0) * 0.957161207093473e-6
J4 = -3.0 * 0.539965866638991e-6
MU_MOON = 3.986004418e14 * 1.23000371e-2  # IAU 2009 GM_E x Moon/Earth mass ratio
RHO_MOON = 384400.0e3  # mean Earth-Moon distance (m), circular orbit radius of the model Moon
INC_MOON = math.radians(5.145)  # inclination of the model Moon's orbit to the x-y plane (about x)

LEO_R0 = [6778137.0, 0.0, 0.0]  # 400 km altitude on the x axis
LEO_V0 = [0.0, 4850.0, 6100.0]  # 7793 m/s, inclination 51.5 deg, perigee at t = 0 (e ~ 0.03)
GEO_R0 = [42164e3, 0.0, 0.0]
GEO_V0 = [0.0, 3200.0, 300.0]  # faster than circular (3075 m/s): e ~ 0.09, i ~ 5.4 deg

CASES = {
    "leo_j2": {"terms": ["central", "J2"], "r0": LEO_R0, "v0": LEO_V0, "days": 1.0, "n_out": 9},
    "leo_zonal": {"terms": ["central", "J2", "J3", "J4"], "r0": LEO_R0, "v0": LEO_V0, "days": 1.0, "n_out": 9},
    "geo_moon_circular": {"terms": ["central", "moon_circular"], "r0": GEO_R0, "v0": GEO_V0, "days": 5.0, "n_out": 11},
}


def moon_rate() -> float:
    """Mean motion of the model Moon (rad/s), Kepler's third law for the Earth-Moon pair."""
    return math.sqrt((MU_EARTH + MU_MOON) / RHO_MOON**3)


def moon_position(t: np.ndarray) -> np.ndarray:
    """(3, n) position of the model Moon (m); the same closed form as the heyoka expressions."""
    th = moon_rate() * np.asarray(t, float)
    return RHO_MOON * np.array([np.cos(th), np.sin(th) * math.cos(INC_MOON), np.sin(th) * math.sin(INC_MOON)])


def _system(hy, terms):
    """Cartesian equations of motion.  par: [mu, R, J2, J3, J4, mu_moon, rho, n_moon, cos i, sin i]."""
    x, y, z, vx, vy, vz = hy.make_vars("x", "y", "z", "vx", "vy", "vz")
    mu, re, j2, j3, j4, mum, rho, nm, ci, si = (hy.par[k] for k in range(10))
    r2 = x * x + y * y + z * z
    r = hy.sqrt(r2)
    ir3 = 1.0 / (r2 * r)
    ax, ay, az = -mu * x * ir3, -mu * y * ir3, -mu * z * ir3
    zr2 = z * z / r2
    if "J2" in terms:  # Vallado eq. 8-30 (J2)
        k = -1.5 * j2 * mu * re * re * ir3 / r2
        ax, ay, az = ax + k * x * (1.0 - 5.0 * zr2), ay + k * y * (1.0 - 5.0 * zr2), az + k * z * (3.0 - 5.0 * zr2)
    if "J3" in terms:  # Vallado sect. 8.6.1 (J3)
        k = -2.5 * j3 * mu * re * re * re * ir3 / (r2 * r2)
        ax = ax + k * x * (3.0 * z - 7.0 * z * zr2)
        ay = ay + k * y * (3.0 * z - 7.0 * z * zr2)
        az = az + k * (6.0 * z * z - 7.0 * z * z * zr2 - 0.6 * r2)
    if "J4" in terms:  # Vallado sect. 8.6.1 (J4)
        k = 1.875 * j4 * mu * re * re * re * re * ir3 / (r2 * r2)
        w = 1.0 - 14.0 * zr2 + 21.0 * zr2 * zr2
        ax, ay = ax + k * x * w, ay + k * y * w
        az = az + k * z * (5.0 - (70.0 / 3.0) * zr2 + 21.0 * zr2 * zr2)
    if "moon_circular" in terms:  # Battin 1999 eq. 8.58: direct minus indirect (Earth's) pull
        th = nm * hy.time
        mx, my, mz = rho * hy.cos(th), rho * hy.sin(th) * ci, rho * hy.sin(th) * si
        dx, dy, dz = mx - x, my - y, mz - z
        d2 = dx * dx + dy * dy + dz * dz
        id3 = 1.0 / (d2 * hy.sqrt(d2))
        irho3 = 1.0 / (rho * rho * rho)
        ax, ay, az = ax + mum * (dx * id3 - mx * irho3), ay + mum * (dy * id3 - my * irho3), az + mum * (dz * id3 - mz * irho3)
    return [(x, vx), (y, vy), (z, vz), (vx, ax), (vy, ay), (vz, az)]


def _pars_double(terms):
    allp = [MU_EARTH, R_EARTH, J2, J3, J4, MU_MOON, RHO_MOON, moon_rate(), math.cos(INC_MOON), math.sin(INC_MOON)]
    # heyoka wants exactly as many values as the highest par index used + 1
    used = max({"central": 1, "J2": 3, "J3": 4, "J4": 5, "moon_circular": 10}[t] for t in terms)
    return allp[:used]


def _run(hy, case, fp):
    sys_ = _system(hy, case["terms"])
    x0 = case["r0"] + case["v0"]
    t_out = np.linspace(0.0, case["days"] * 86400.0, case["n_out"])
    if fp == "real128":
        R = hy.real128
        tol = R(2) ** -112
        ta = hy.taylor_adaptive(sys_, np.array([R(v) for v in x0], dtype=R), pars=np.array([R(v) for v in _pars_double(case['terms'])], dtype=R),
                                tol=tol, fp_type=R, compact_mode=True)
        conv = R
    else:
        tol = 1e-15
        ta = hy.taylor_adaptive(sys_, np.array(x0, float), pars=np.array(_pars_double(case['terms'])), tol=tol)
        conv = float
    states = [[str(v) for v in x0]]
    steps = 0
    t0 = time.perf_counter()
    for t in t_out[1:]:
        out = ta.propagate_until(conv(float(t)))
        if str(out[0]) != "taylor_outcome.time_limit":
            raise RuntimeError(f"heyoka {fp} stopped at {ta.time}: {out[0]}")
        steps += int(out[3])
        states.append([str(v) for v in ta.state])
    wall = time.perf_counter() - t0
    return {"t_s": t_out.tolist(), "states": states, "tol": str(tol), "order": int(ta.order),
            "n_steps": steps, "wall_s": wall}


def main() -> int:
    import heyoka as hy

    started = time.perf_counter()
    out = {
        "what": "tether-free point-mass orbits with the gravity effects (tetherlab, heyoka oracle)",
        "units": {"length": "m", "time": "s", "velocity": "m/s"},
        "state_layout": "x, y, z, vx, vy, vz",
        "constants": {
            "mu_earth_m3_s2": MU_EARTH, "R_m": R_EARTH, "J2": J2, "J3": J3, "J4": J4,
            "mu_moon_m3_s2": MU_MOON, "rho_moon_m": RHO_MOON, "inc_moon_rad": INC_MOON,
            "n_moon_rad_s": moon_rate(),
            "moon_position": "rho [cos(n t), sin(n t) cos(inc), sin(n t) sin(inc)]",
        },
        "cases": {},
    }
    for name, case in CASES.items():
        ref = _run(hy, case, "real128")
        dbl = _run(hy, case, "double")
        ref_f = np.array([[float(v) for v in s] for s in ref["states"]])
        dbl_f = np.array([[float(v) for v in s] for s in dbl["states"]])
        diff_m = float(np.max(np.linalg.norm(ref_f[:, :3] - dbl_f[:, :3], axis=1)))
        out["cases"][name] = {
            "terms": case["terms"],
            "duration_days": case["days"],
            "t_s": ref["t_s"],
            "states": ref["states"],  # binary128 decimal strings, row 0 = initial state
            "states_float": ref_f.tolist(),
            "real128": {k: ref[k] for k in ("tol", "order", "n_steps", "wall_s")},
            "double_tol_1e-15": {k: dbl[k] for k in ("tol", "order", "n_steps", "wall_s")},
            "max_position_difference_double_vs_real128_m": diff_m,
        }
        print(f"{name}: real128 {ref['n_steps']} steps {ref['wall_s']:.1f} s; double tol 1e-15 differs by {diff_m:.3e} m", flush=True)
    out["provenance"] = {
        "oracle": "heyoka.py Taylor integrator",
        "heyoka": hy.__version__,
        "numpy": np.__version__,
        "python": sys.version.split()[0],
        "precision": "IEEE binary128 (heyoka.real128), tol 2^-112; cross-check in double, tol 1e-15",
        "command": "python references/heyoka_orbits/build_references.py",
        "date_utc": _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M"),
        "machine": f"{platform.system()} {platform.machine()}",
        "builder_wall_s": round(time.perf_counter() - started, 1),
    }
    OUT_JSON.write_text(json.dumps(out, indent=1) + "\n")
    print(f"wrote {OUT_JSON}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
