"""Build the continuum limit of part G's deployment (docs/deployment.md 8h): the deploying damped
string of tetherlab/oracles/deploying_string.py (numpy and scipy only; none of the simulator's
tether code) on grids of N segments doubled level by level, each to the end of the run, and a run at
a tenth of the tolerance on one grid for the time integration's error.  Writes limit.json next to
this file after every grid (so an interrupted build keeps what it finished).

The case is part G's scene (studies/deployment.py convergence_scene; tests/test_deploying_string.py
checks that the numbers below are the scene's): a 1000 kg station with 10 km of stored line on a
7000 km circular orbit pays out 500 m -> 4.5 km of a 5 g/m line (EA 1e5 N, damping 1e4 N s) at
constant speed in half an orbit to a 25 kg end mass.

    PYTHONPATH=. python references/deploying_string/build_limit.py [N ...]
"""

from __future__ import annotations

import datetime
import json
import math
import platform
import sys
import time
from pathlib import Path

import numpy as np
import scipy

ROOT = Path(__file__).resolve().parents[2]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from tetherlab.oracles.deploying_string import DeployingString, solve  # noqa: E402

MU_M3_S2 = 3.986004418e14  # the scene preset "earth" (tetherlab/scene/data.py)
RADIUS_M = 7000e3
DURATION_S = math.pi * math.sqrt(RADIUS_M**3 / MU_M3_S2)  # half an orbit
CASE = DeployingString(station_kg=1000.0, end_kg=25.0, rho_kg_m=5e-3, ea_n=1e5, damping_n_s=1e4, length0_m=500.0,
                       speed_m_s=4000.0 / DURATION_S, stored0_m=10000.0, mu_m3_s2=MU_M3_S2, radius_m=RADIUS_M,
                       duration_s=DURATION_S)  # fmt: skip
GRIDS = (8, 16, 32, 64, 128)
RTOL = 1e-8
ATOL = 1e-7  # m and m/s
CHECK_GRID = 16  # the grid run again at RTOL/10 for the time integration's error
METHOD = "BDF"


def main(argv=None) -> int:
    grids = tuple(int(a) for a in (argv if argv is not None else sys.argv[1:])) or GRIDS
    path = Path(__file__).with_name("limit.json")
    levels, check = [], None
    t_all = time.perf_counter()
    for n in (CHECK_GRID,) + grids:
        is_check = check is None
        t0 = time.perf_counter()
        s = solve(CASE, n, rtol=RTOL / 10 if is_check else RTOL, atol_m=ATOL / 10 if is_check else ATOL,
                  method=METHOD)
        row = {"grid": n, "theta_rad": float(s.theta_rad[-1]), "offset_m": float(s.offset_m[-1]),
               "steps": s.n_steps, "nfev": s.nfev, "njev": s.njev, "nlu": s.nlu,
               "wall_s": round(time.perf_counter() - t0, 2)}  # fmt: skip
        print(json.dumps(row), flush=True)
        if is_check:
            check = dict(row, rtol=RTOL / 10, atol=ATOL / 10)
            continue
        levels.append(row)
        out = {
            "case": {k: getattr(CASE, k) for k in CASE.__dataclass_fields__},
            "method": METHOD, "rtol": RTOL, "atol": ATOL,
            "levels": levels, "tolerance_check": check,
            "provenance": {
                "oracle": "tetherlab/oracles/deploying_string.py",
                "builder": "references/deploying_string/build_limit.py",
                "command": "PYTHONPATH=. python references/deploying_string/build_limit.py " + " ".join(map(str, grids)),
                "python": sys.version.split()[0], "numpy": np.__version__, "scipy": scipy.__version__,
                "machine": f"{platform.system()} {platform.machine()}",
                "date_utc": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M"),
                "build_s": round(time.perf_counter() - t_all, 1),
            },
        }  # fmt: skip
        path.write_text(json.dumps(out, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
