"""Build the extended-precision reference for Stiefel & Scheifele's Example 1 (J2 only).

Problem: E. Stiefel & G. Scheifele, *Linear and Regular Celestial Mechanics*, Springer 1971,
sect. 23, Example 1 -- the Earth's central field and its J2 term, no Moon; the initial state of
Example 2 (/work/shared/references/stiefel-scheifele.md: perigee of an e = 0.95 orbit inclined
30 deg) and t_f = 286.79660900 d.  The book's published final position of Example 1
is not available to this project, so none is compared here.

The same two independent computations as ``build_reference.py`` (whose functions are reused with
the Moon's mass set to zero, so the equations are the same transcriptions, minus the Moon):

1. heyoka's Taylor method in IEEE binary128, tolerance = binary128 epsilon;
2. the decimal-arithmetic Taylor integrator of ``build_reference.py`` (60 digits, order 50),
   plus its 40-digit self-check.

Then heyoka in double precision at tolerances 1e-4 ... 1e-13 (work-precision points).

Rebuild:  .venv/bin/python references/stiefel/build_example1.py   (about a minute)
Writes references/stiefel/example1.json; tests/test_stiefel_example1.py reads it.
"""

from __future__ import annotations

import datetime as _dt
import decimal
import json
import os
import platform
import sys
import time
from decimal import Decimal
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import build_reference as br  # noqa: E402  (the Example 2 builder: equations and methods)

OUT_JSON = HERE / "example1.json"
TF_DAYS = "286.79660900"  # Stiefel & Scheifele (1971) sect. 23, Example 1
#: Example 1 is Example 2 without the Moon: its mass set to zero switches the Moon terms off in
#: both methods (heyoka: the parameter par[3]; decimal: the constant mum).
CONST = dict(br.CONST, mu_moon_km3_s2="0")


def main() -> int:
    t_start = time.perf_counter()
    br.CONST = CONST
    br.TF_DAYS = TF_DAYS
    import heyoka as hy

    print("heyoka", hy.__version__, "| numpy", np.__version__, flush=True)
    sys_ = br._heyoka_system(hy)
    print("[1] heyoka real128 ...", flush=True)
    h128 = br.heyoka_real128(hy, sys_)
    ref_pos, ref_vel = h128["state"][:3], h128["state"][3:]
    print("    r_f =", ref_pos, f"steps={h128['n_steps']} wall={h128['wall_s']:.1f}s", flush=True)
    h128_dbl = br.heyoka_real128(hy, sys_, round_inputs_to_double=True)
    d_dblin = br._dist(h128_dbl["state"][:3], ref_pos)

    res2 = {}
    for name, cfg in (("main", {"prec_digits": 60, "order": 50, "tol_exp": -52}),
                      ("check", {"prec_digits": 40, "order": 32, "tol_exp": -33})):  # fmt: skip
        print(f"[2] decimal Taylor ({name}: {cfg}) ...", flush=True)
        t0 = time.perf_counter()
        r = br.decimal_taylor(cfg["prec_digits"], cfg["order"], cfg["tol_exp"])
        r["wall_s"] = time.perf_counter() - t0
        r["config"] = cfg
        res2[name] = r
    d_methods = br._dist(res2["main"]["position_km"], ref_pos)
    d_methods_vel = br._dist(res2["main"]["velocity_km_s"], ref_vel)
    d_self = br._dist(res2["check"]["position_km"], res2["main"]["position_km"])
    print(f"    |heyoka128 - decimal| = {float(d_methods) * 1e3:.3e} m; self-check "
          f"{float(d_self) * 1e3:.3e} m", flush=True)  # fmt: skip

    print("[3] heyoka double precision table ...", flush=True)
    table = br.heyoka_double_table(hy, sys_, ref_pos)
    doc = {
        "problem": "Stiefel-Scheifele (1971) sect. 23 Example 1: Earth point mass + J2 (no Moon), "
                   "initial state of Example 2 (e=0.95, i=30 deg, perigee), t_f = 286.79660900 d",
        "units": {"length": "km", "time": "s", "velocity": "km/s"},
        "t_final_days": TF_DAYS,
        "t_final_s": br.tf_seconds_str(),
        "initial_state": {"position_km": br.X0, "velocity_km_s": br.V0},
        "final_state": {
            "method": "heyoka Taylor, binary128 (heyoka.real128), tol = 2^-112",
            "position_km": ref_pos,
            "velocity_km_s": ref_vel,
            "position_km_float": [float(s) for s in ref_pos],
            "velocity_km_s_float": [float(s) for s in ref_vel],
            "n_steps": h128["n_steps"],
            "taylor_order": h128["order"],
            "propagation_wall_s": h128["wall_s"],
        },
        "second_method": {
            "method": "build_reference.decimal_taylor (own Taylor series by AD recurrences, "
                      "Python decimal), Moon mass 0",
            "position_km": res2["main"]["position_km"],
            "velocity_km_s": res2["main"]["velocity_km_s"],
            "config": res2["main"]["config"],
            "n_steps": res2["main"]["n_steps"],
            "self_check": {"config": res2["check"]["config"],
                           "position_km": res2["check"]["position_km"],
                           "distance_to_main_m": float(d_self * 1000)},  # fmt: skip
            "distance_to_reference_m": float(d_methods * 1000),
            "velocity_difference_m_s": float(d_methods_vel * 1000),
        },
        "published": None,
        "sensitivity": {"distance_if_inputs_rounded_to_double_m": float(d_dblin * 1000)},
        "heyoka_double": {
            "description": "heyoka taylor_adaptive, fp double; error = |r_f - reference| in m; "
                           "wall time of propagate_until alone, median of "
                           f"{br.N_TIMING_REPEATS}",
            "rows": table,
        },
        "provenance": {
            "oracle": "heyoka.py",
            "oracle_version": hy.__version__,
            "second_method_engine": "Python decimal (libmpdec)",
            "libmpdec_version": decimal.__libmpdec_version__,
            "numpy_version": np.__version__,
            "python_version": platform.python_version(),
            "command": "python references/stiefel/build_example1.py",
            "precision": "heyoka: IEEE binary128; second method: 60 significant decimal digits",
            "tolerance": str(h128["tol"]),
            "date_utc": _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
            "machine": platform.platform(),
            "cpu_count": os.cpu_count(),
            "constants": CONST,
            "constants_rounding": "decimal strings converted directly to binary128",
            "builder_wall_s": time.perf_counter() - t_start,
        },
    }
    assert Decimal(doc["t_final_s"]) == Decimal(TF_DAYS) * 86400  # builder self-check, not input
    OUT_JSON.write_text(json.dumps(doc, indent=2) + "\n")
    print(f"wrote {OUT_JSON}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
