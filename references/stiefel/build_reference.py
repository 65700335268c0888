"""Build the extended-precision reference for the Stiefel-Scheifele test problem.

Problem definition: /work/shared/references/stiefel-scheifele.md (E. Stiefel & G. Scheifele,
*Linear and Regular Celestial Mechanics*, Springer 1971, sect. 23, Example 2; quoted in the
tetherlab paper, section 4.1, eqs. 50-52).

Two independent computations of the final state at t_f = 288.12768941 d:

1. heyoka's Taylor method in IEEE binary128 (``heyoka.real128``), tolerance = binary128 epsilon.
2. A Taylor-series integrator written here from scratch (automatic differentiation by the
   classical recurrences, own step-size rule) in base-10 arithmetic with Python's ``decimal``
   module (libmpdec), at 48 significant digits. It shares no code, no arithmetic and no
   step-size control with heyoka; it is run at two settings to show its own convergence.

Then heyoka in double precision at tolerances 1e-4 ... 1e-13 (the points for the
work-precision tables), with errors measured against the binary128 reference.

Only this builder imports heyoka (an oracle); the tests read reference.json.

Rebuild:  /tmp/tv/bin/python references/stiefel/build_reference.py   (project: .venv/bin/python)
"""

from __future__ import annotations

import datetime as _dt
import decimal
import json
import math
import os
import platform
import statistics
import sys
import time
from decimal import Decimal, localcontext
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
OUT_JSON = HERE / "reference.json"
DEFINITION = "/work/shared/references/stiefel-scheifele.md"

# --- printed constants (book units: km, s), kept as decimal strings -------------------------
CONST = {
    "mu_earth_km3_s2": "398601",  # K^2
    "J2": "1.08265e-3",
    "R_earth_km": "6371.22",
    "mu_moon_km3_s2": "4902.66",  # k^2 M'
    "rho_moon_km": "384400",
    "sigma_moon_rad_s": "2.665315780887e-6",  # printed value (used); see sigma_computed below
    "moon_inclination_deg": "30",
}
X0 = ["0.0", "-5888.9727", "-3400.0"]  # km, eq. 50
V0 = ["10.691338", "0.0", "0.0"]  # km/s, eq. 51
TF_DAYS = "288.12768941"
DAY_S = "86400"
N_ORBITS = 50
# Published final position: book Table 2b, quoted as eq. (52) of the paper (km).
PUBLISHED_EQ52_KM = ["-24219.0503", "227962.1064", "129753.4424"]

DOUBLE_TOLS = [10.0**-k for k in range(4, 14)]  # 1e-4 ... 1e-13
N_TIMING_REPEATS = 3


def tf_seconds_str() -> str:
    with localcontext() as c:
        c.prec = 60
        return str(Decimal(TF_DAYS) * Decimal(DAY_S))  # exact: 24894232.365024


# =============================================================================================
# 1. heyoka (binary128 reference, double-precision work-precision points)
# =============================================================================================
def _heyoka_system(hy):
    """Cartesian equations of motion; constants enter as runtime parameters so that they carry
    the full precision of the integrator's floating-point type.

    par[0] mu, par[1] J2, par[2] R, par[3] mu', par[4] rho, par[5] sigma, par[6] sqrt(3)/2.
    """
    x, y, z, vx, vy, vz = hy.make_vars("x", "y", "z", "vx", "vy", "vz")
    mu, j2, re, mum, rho, sig, c32 = (hy.par[i] for i in range(7))
    r2 = x * x + y * y + z * z
    ir3 = 1.0 / (r2 * hy.sqrt(r2))
    ir5 = ir3 / r2
    q = z * z / r2
    kj = -1.5 * j2 * mu * re * re * ir5
    th = sig * hy.time
    mx, my, mz = rho * hy.sin(th), -rho * c32 * hy.cos(th), -0.5 * rho * hy.cos(th)
    dx, dy, dz = x - mx, y - my, z - mz
    d2 = dx * dx + dy * dy + dz * dz
    id3 = 1.0 / (d2 * hy.sqrt(d2))
    irho3 = 1.0 / (rho * rho * rho)
    ax = -mu * x * ir3 + kj * x * (1.0 - 5.0 * q) - mum * (dx * id3 + mx * irho3)
    ay = -mu * y * ir3 + kj * y * (1.0 - 5.0 * q) - mum * (dy * id3 + my * irho3)
    az = -mu * z * ir3 + kj * z * (3.0 - 5.0 * q) - mum * (dz * id3 + mz * irho3)
    return [(x, vx), (y, vy), (z, vz), (vx, ax), (vy, ay), (vz, az)]


def _pars(fp, conv, sigma: str, double_c32: bool = False):
    vals = [conv(CONST[k]) for k in ("mu_earth_km3_s2", "J2", "R_earth_km", "mu_moon_km3_s2",
                                     "rho_moon_km")]
    vals.append(conv(sigma))
    if double_c32:
        vals.append(fp(float(np.sqrt(3.0) / 2.0)))
    else:
        vals.append(np.sqrt(np.array([conv("3")], dtype=fp))[0] / conv("2"))
    return np.array(vals, dtype=fp)


def sigma_computed_str() -> str:
    with localcontext() as c:
        c.prec = 40
        mu, mum, rho = (Decimal(CONST[k]) for k in ("mu_earth_km3_s2", "mu_moon_km3_s2",
                                                    "rho_moon_km"))
        return str(((mu + mum) / rho**3).sqrt())


def heyoka_real128(hy, sys_, sigma: str | None = None, round_inputs_to_double: bool = False):
    R = hy.real128
    # round_inputs_to_double: every decimal input (constants, sqrt(3)/2, initial state, t_f) is
    # first rounded to IEEE double, as a double-precision run sees it, then widened exactly.
    conv = (lambda s: R(float(s))) if round_inputs_to_double else R
    sigma = CONST["sigma_moon_rad_s"] if sigma is None else sigma
    tol = R(2) ** -112  # binary128 machine epsilon
    ta = hy.taylor_adaptive(sys_, np.array([conv(s) for s in X0 + V0], dtype=R),
                            pars=_pars(R, conv, sigma, double_c32=round_inputs_to_double),
                            tol=tol, fp_type=R, compact_mode=True)
    t0 = time.perf_counter()
    out = ta.propagate_until(conv(tf_seconds_str()))
    wall = time.perf_counter() - t0
    if str(out[0]) != "taylor_outcome.time_limit":
        raise RuntimeError(f"heyoka real128 did not reach t_f: {out[0]}")
    return {"state": [str(v) for v in ta.state], "n_steps": int(out[3]), "order": int(ta.order),
            "tol": str(tol), "wall_s": wall, "time": str(ta.time)}


def heyoka_double_table(hy, sys_, ref_pos):
    rows = []
    x0 = np.array([float(s) for s in X0 + V0])
    pars = _pars(float, float, CONST["sigma_moon_rad_s"])
    tf = float(tf_seconds_str())
    for tol in DOUBLE_TOLS:
        ta = hy.taylor_adaptive(sys_, x0.copy(), pars=pars, tol=tol)  # creation not timed
        walls = []
        for _ in range(N_TIMING_REPEATS):
            ta.time = 0.0
            ta.state[:] = x0
            t0 = time.perf_counter()
            out = ta.propagate_until(tf)
            walls.append(time.perf_counter() - t0)
            if str(out[0]) != "taylor_outcome.time_limit":
                raise RuntimeError(f"heyoka double tol={tol} did not reach t_f: {out[0]}")
        err_km = _dist([Decimal(repr(float(v))) for v in ta.state[:3]], ref_pos)
        rows.append({
            "tol": tol,
            "order": int(ta.order),
            "final_position_error_m": float(err_km * 1000),
            "n_steps": int(out[3]),
            "mean_steps_per_orbit": int(out[3]) / N_ORBITS,
            "wall_time_s_median": statistics.median(walls),
            "wall_time_s_all": walls,
        })
        print(f"  double tol={tol:.0e} order={ta.order:2d} err={float(err_km) * 1e3:.3e} m "
              f"steps={out[3]} wall={statistics.median(walls) * 1e3:.2f} ms", flush=True)
    return rows


# =============================================================================================
# 2. Independent method: Taylor series by automatic differentiation in decimal arithmetic
# =============================================================================================
def _dec_pi() -> Decimal:
    """pi by Machin's formula, in the current decimal context (with guard digits)."""
    def atan_inv(n: int) -> Decimal:
        x = Decimal(1) / n
        x2 = x * x
        term, total, k, sign = x, x, 1, 1
        eps = Decimal(10) ** (-(decimal.getcontext().prec + 2))
        while abs(term) > eps:
            term *= x2
            k += 2
            sign = -sign
            total += sign * term / k
        return total
    return 16 * atan_inv(5) - 4 * atan_inv(239)


def _dec_sincos(theta: Decimal, two_pi: Decimal) -> tuple[Decimal, Decimal]:
    th = theta % two_pi
    if th > two_pi / 2:
        th -= two_pi
    th2 = th * th
    eps = Decimal(10) ** (-(decimal.getcontext().prec + 2))
    s, c = th, Decimal(1)
    ts, tc, k = th, Decimal(1), 1
    while True:
        ts = -ts * th2 / ((2 * k) * (2 * k + 1))
        tc = -tc * th2 / ((2 * k - 1) * (2 * k))
        s += ts
        c += tc
        if abs(ts) < eps and abs(tc) < eps:
            return s, c
        k += 1


def _log10(d: Decimal) -> float:
    """log10 of a positive Decimal without float over/underflow."""
    e = d.adjusted()
    return e + math.log10(float(d.scaleb(-e)))


def decimal_taylor(prec: int, order: int, tol_exp: int, guard: int = 10):
    """Integrate the problem with a fixed-order Taylor method in `prec`-digit decimal arithmetic.

    Series of the solution are generated by the standard AD recurrences (products, real powers
    s**alpha via s u' = alpha s' u). Step size: for each of the two groups (position, velocity)
    h_g = min over k in {p-1, p} of (eps_g / ||c_k||_inf)**(1/k), eps_g = 10**tol_exp *
    max(1, ||group||_inf); h = 0.9 * min_g h_g. Last step lands exactly on t_f.
    """
    with localcontext() as ctx:
        ctx.prec = prec + guard
        pi = _dec_pi()
        two_pi = 2 * pi
        ctx.prec = prec
        D = Decimal
        mu, j2, re, mum, rho, sig = (D(CONST[k]) for k in (
            "mu_earth_km3_s2", "J2", "R_earth_km", "mu_moon_km3_s2", "rho_moon_km",
            "sigma_moon_rad_s"))
        c32 = D(3).sqrt() / 2
        kj = D("-1.5") * j2 * mu * re * re
        two_kj = 2 * kj
        irho3 = 1 / (rho * rho * rho)
        tf = D(TF_DAYS) * D(DAY_S)
        p = order
        # sigma^k / k!
        fk = [D(1)]
        for k in range(1, p + 1):
            fk.append(fk[-1] * sig / k)
        eps = D(10) ** tol_exp
        lg_eps = float(tol_exp)

        pos = [D(s) for s in X0]
        vel = [D(s) for s in V0]
        t = D(0)
        n_steps = 0
        from operator import mul

        def conv(a, b, k):
            return sum(map(mul, a[:k + 1], b[k::-1]))

        def sq(a, k):
            # sum_{j=0}^{k} a_j a_{k-j}, using symmetry
            h = (k + 1) // 2
            s = sum(map(mul, a[:h], a[k:k - h:-1])) if h else D(0)
            s += s
            if k % 2 == 0:
                s += a[k // 2] * a[k // 2]
            return s

        def pw(u, s, k, two_alpha):
            # u = s**(two_alpha/2): u_k = 1/(2 k s_0) sum_{j<k} (two_alpha (k-j) - 2 j) s_{k-j} u_j
            acc = sum((two_alpha * (k - j) - 2 * j) * s[k - j] * u[j] for j in range(k))
            return acc / (2 * k * s[0])

        while t < tf:
            s0, c0 = _dec_sincos(sig * t, two_pi)
            sin_c = (s0, c0, -s0, -c0)
            cos_c = (c0, -s0, -c0, s0)
            X = [[pos[i]] for i in range(3)]
            V = [[vel[i]] for i in range(3)]
            S, W3, W5, W7, Z2, ZW7, H, H2 = ([] for _ in range(8))
            Dd = [[], [], []]
            M = [[], [], []]
            SD, WD = [], []
            for k in range(p):
                x, y, z = X
                S.append(sq(x, k) + sq(y, k) + sq(z, k))
                if k == 0:
                    r = S[0].sqrt()
                    W3.append(1 / (S[0] * r))
                    W5.append(W3[0] / S[0])
                    W7.append(W5[0] / S[0])
                else:
                    W3.append(pw(W3, S, k, -3))
                    W5.append(pw(W5, S, k, -5))
                    W7.append(pw(W7, S, k, -7))
                Z2.append(sq(z, k))
                ZW7.append(conv(Z2, W7, k))
                g = W5[k] - 5 * ZW7[k]
                H.append(kj * g - mu * W3[k])
                H2.append(H[k] + two_kj * W5[k])
                sk = fk[k] * sin_c[k % 4]
                ck = fk[k] * cos_c[k % 4]
                mk = (rho * sk, -rho * c32 * ck, -rho * ck / 2)
                for i in range(3):
                    M[i].append(mk[i])
                    Dd[i].append(X[i][k] - mk[i])
                SD.append(sq(Dd[0], k) + sq(Dd[1], k) + sq(Dd[2], k))
                if k == 0:
                    WD.append(1 / (SD[0] * SD[0].sqrt()))
                else:
                    WD.append(pw(WD, SD, k, -3))
                acc = (conv(x, H, k) - mum * (conv(Dd[0], WD, k) + mk[0] * irho3),
                       conv(y, H, k) - mum * (conv(Dd[1], WD, k) + mk[1] * irho3),
                       conv(z, H2, k) - mum * (conv(Dd[2], WD, k) + mk[2] * irho3))
                for i in range(3):
                    X[i].append(V[i][k] / (k + 1))
                    V[i].append(acc[i] / (k + 1))
            # step size
            hmin = None
            for grp, base in ((X, pos), (V, vel)):
                scale = max(D(1), max(abs(b) for b in base))
                lg_e = lg_eps + _log10(scale)
                for k in (p - 1, p):
                    nk = max(abs(grp[i][k]) for i in range(3))
                    if nk == 0:
                        continue
                    lg_h = (lg_e - _log10(nk)) / k
                    hmin = lg_h if hmin is None else min(hmin, lg_h)
            h = D(repr(0.9 * 10.0**hmin))
            if t + h >= tf:
                h = tf - t
            # Horner
            pos = [_horner(X[i], h) for i in range(3)]
            vel = [_horner(V[i], h) for i in range(3)]
            t = tf if h == tf - t else t + h
            n_steps += 1
        return {"position_km": [str(v) for v in pos], "velocity_km_s": [str(v) for v in vel],
                "n_steps": n_steps, "time": str(t)}


def _horner(c, h):
    acc = c[-1]
    for a in reversed(c[:-1]):
        acc = acc * h + a
    return acc


# =============================================================================================
# helpers
# =============================================================================================
def _dist(a, b) -> Decimal:
    with localcontext() as c:
        c.prec = 60
        return sum(((Decimal(str(p)) - Decimal(str(q))) ** 2 for p, q in zip(a, b)),
                   Decimal(0)).sqrt()


def _round_str(s: str, decimals: int) -> str:
    with localcontext() as c:
        c.prec = 80
        return str(Decimal(s).quantize(Decimal(1).scaleb(-decimals)))


def _sci(d: Decimal) -> str:
    return f"{float(d):.3e}"


def main() -> int:
    t_start = time.perf_counter()
    import heyoka as hy

    print("heyoka", hy.__version__, "| numpy", np.__version__, "| decimal/libmpdec",
          decimal.__libmpdec_version__, flush=True)
    sys_ = _heyoka_system(hy)

    # ---- 1. heyoka binary128 -----------------------------------------------------------------
    print("[1] heyoka real128, tol = 2^-112 ...", flush=True)
    h128 = heyoka_real128(hy, sys_)
    ref_pos, ref_vel = h128["state"][:3], h128["state"][3:]
    print("    r_f =", ref_pos, f"steps={h128['n_steps']} order={h128['order']} "
          f"wall={h128['wall_s']:.1f}s", flush=True)
    # sensitivity diagnostics (same oracle): computed sigma; inputs rounded to IEEE double
    sig_c = sigma_computed_str()
    h128_sig = heyoka_real128(hy, sys_, sigma=sig_c)
    d_sigma = _dist(h128_sig["state"][:3], ref_pos)
    h128_dbl = heyoka_real128(hy, sys_, round_inputs_to_double=True)
    d_dblin = _dist(h128_dbl["state"][:3], ref_pos)
    print(f"    effect of computed sigma ({sig_c}): {_sci(d_sigma * 1000)} m; "
          f"of rounding inputs to double: {_sci(d_dblin * 1000)} m", flush=True)

    # ---- 2. independent decimal Taylor method -------------------------------------------------
    cfg_main = {"prec_digits": 60, "order": 50, "tol_exp": -52}
    cfg_check = {"prec_digits": 40, "order": 32, "tol_exp": -33}
    res2 = {}
    for name, cfg in (("main", cfg_main), ("check", cfg_check)):
        print(f"[2] decimal Taylor ({name}: {cfg}) ...", flush=True)
        t0 = time.perf_counter()
        r = decimal_taylor(cfg["prec_digits"], cfg["order"], cfg["tol_exp"])
        r["wall_s"] = time.perf_counter() - t0
        r["config"] = cfg
        res2[name] = r
        print(f"    r_f = {r['position_km']} steps={r['n_steps']} wall={r['wall_s']:.1f}s",
              flush=True)
    d_methods = _dist(res2["main"]["position_km"], ref_pos)
    d_methods_vel = _dist(res2["main"]["velocity_km_s"], ref_vel)
    d_self = _dist(res2["check"]["position_km"], res2["main"]["position_km"])
    print(f"    |heyoka128 - decimal| = {_sci(d_methods * 1000)} m (pos), "
          f"{_sci(d_methods_vel * 1000)} m/s (vel); decimal self-check {_sci(d_self * 1000)} m",
          flush=True)

    # resolved decimals (km): digits at which the two independent methods agree
    agree = max(d_methods, Decimal("1e-30"))
    decimals = max(0, int(math.floor(-math.log10(float(agree)))) - 1)
    agree_v = max(d_methods_vel, Decimal("1e-30"))
    decimals_v = max(0, int(math.floor(-math.log10(float(agree_v)))) - 1)

    d_pub = _dist(ref_pos, PUBLISHED_EQ52_KM)
    d_pub_components_m = [float((Decimal(a) - Decimal(b)) * 1000)
                          for a, b in zip(ref_pos, PUBLISHED_EQ52_KM)]
    print(f"    distance to published eq. 52: {float(d_pub) * 1000:.4f} m", flush=True)

    # ---- 3. heyoka double work-precision points -----------------------------------------------
    print("[3] heyoka double precision table ...", flush=True)
    table = heyoka_double_table(hy, sys_, ref_pos)

    wall_total = time.perf_counter() - t_start
    doc = {
        "problem": "Stiefel-Scheifele (1971) sect. 23 Example 2: Earth J2 + analytic circular "
                   "Moon inclined 30 deg, e=0.95 orbit, 50 revolutions; tetherlab paper sect. 4.1",
        "units": {"length": "km", "time": "s", "velocity": "km/s"},
        "t_final_days": TF_DAYS,
        "t_final_s": tf_seconds_str(),
        "n_orbits": N_ORBITS,
        "initial_state": {"position_km": X0, "velocity_km_s": V0},
        "final_state": {
            "method": "heyoka Taylor, binary128 (heyoka.real128), tol = 2^-112",
            "position_km": [_round_str(s, decimals) for s in ref_pos],
            "velocity_km_s": [_round_str(s, decimals_v) for s in ref_vel],
            "position_km_float": [float(s) for s in ref_pos],
            "velocity_km_s_float": [float(s) for s in ref_vel],
            "position_km_full_binary128": ref_pos,
            "velocity_km_s_full_binary128": ref_vel,
            "resolved_decimals_km": decimals,
            "resolved_decimals_km_s": decimals_v,
            "n_steps": h128["n_steps"],
            "taylor_order": h128["order"],
            "propagation_wall_s": h128["wall_s"],
        },
        "second_method": {
            "method": "own fixed-order Taylor series integrator (AD recurrences), Python decimal "
                      "(libmpdec) base-10 arithmetic; no code shared with heyoka",
            "position_km": res2["main"]["position_km"],
            "velocity_km_s": res2["main"]["velocity_km_s"],
            "position_km_float": [float(s) for s in res2["main"]["position_km"]],
            "velocity_km_s_float": [float(s) for s in res2["main"]["velocity_km_s"]],
            "config": res2["main"]["config"],
            "n_steps": res2["main"]["n_steps"],
            "wall_s": res2["main"]["wall_s"],
            "self_check": {
                "config": res2["check"]["config"],
                "position_km": res2["check"]["position_km"],
                "n_steps": res2["check"]["n_steps"],
                "wall_s": res2["check"]["wall_s"],
                "distance_to_main_m": float(d_self * 1000),
            },
            "distance_to_reference_m": float(d_methods * 1000),
            "velocity_difference_m_s": float(d_methods_vel * 1000),
        },
        "published": {
            "source": "Stiefel & Scheifele 1971, Table 2b (498 steps/revolution); "
                      "tetherlab paper sect. 4.1, eq. (52)",
            "position_km": PUBLISHED_EQ52_KM,
            "distance_to_reference_m": float(d_pub * 1000),
            "component_differences_m": d_pub_components_m,
        },
        "sensitivity": {
            "sigma_computed_rad_s": sig_c,
            "distance_if_sigma_computed_m": float(d_sigma * 1000),
            "distance_if_inputs_rounded_to_double_m": float(d_dblin * 1000),
            "note": "binary128 heyoka runs; the double table below uses double-rounded inputs, "
                    "so its errors have a floor of about distance_if_inputs_rounded_to_double_m",
        },
        "heyoka_double": {
            "description": "heyoka taylor_adaptive, fp double, default order for tol, "
                           "non-compact mode; error = |r_f - reference| in m; wall time of "
                           "propagate_until alone (integrator creation/compilation excluded), "
                           f"median of {N_TIMING_REPEATS}",
            "rows": table,
        },
        "provenance": {
            "oracle": "heyoka.py",
            "oracle_version": hy.__version__,
            "second_method_engine": "Python decimal (libmpdec)",
            "libmpdec_version": decimal.__libmpdec_version__,
            "mpmath_version": None,
            "mpmath_note": "mpmath not used (the second method uses the standard-library decimal "
                           "module)",
            "numpy_version": np.__version__,
            "python_version": platform.python_version(),
            "command": "python references/stiefel/build_reference.py",
            "argv": sys.argv,
            "precision": "heyoka: IEEE binary128 (heyoka.real128, 113-bit significand); "
                         "second method: 60 significant decimal digits",
            "fp_type": "real128",
            "tolerance": str(h128["tol"]),
            "date_utc": _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
            "machine": platform.platform(),
            "processor": platform.machine(),
            "cpu_count": os.cpu_count(),
            "constants": CONST,
            "sigma_choice": "printed value 2.665315780887e-6 rad/s (not computed from "
                            "sqrt((mu+mu')/rho^3))",
            "constants_rounding": "all constants and initial conditions converted from their "
                                  "decimal strings directly to binary128 (never via double)",
            "definition_file": DEFINITION,
            "builder_wall_s": wall_total,
        },
    }
    OUT_JSON.write_text(json.dumps(doc, indent=2) + "\n")
    print(f"wrote {OUT_JSON}  (builder wall time {wall_total:.1f} s)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
