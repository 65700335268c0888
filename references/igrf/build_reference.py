"""Build the IGRF oracle data: ppigrf's own evaluation of IGRF-14 at random points and dates.

    PYTHONPATH=. python references/igrf/build_reference.py

Writes references/igrf/reference.json: 1200 points (geocentric radius 6371.2-8371.2 km, colatitude
uniform in cos, longitude uniform, dates uniform in 1900-01-01 .. 2029-12-31) with ppigrf.igrf_gc's
B_r, B_theta, B_phi (nT), and the provenance (package, version, coefficient file and its sha256,
command, tolerance, date).  The test (tests/test_environment.py) evaluates tetherlab's compiled
kernel (tetherlab/environment/igrf.py) at the same points and requires agreement to 0.1 nT.

Half of the points are evaluated by the kernel at t = 0 from coefficients packed at their own
date; the other half from coefficients packed at an earlier date of the same 5-year interval,
advanced by the kernel's secular-variation term (``t_offset_s`` > 0), so the linear time
dependence in the kernel is checked too.
"""

from __future__ import annotations

import datetime as dt
import hashlib
import json
import platform
import sys
from importlib.metadata import version
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
N_POINTS = 1200
SEED = 20261201
TOLERANCE_NT = 0.1


def main() -> int:
    import ppigrf
    import ppigrf.ppigrf as pp

    rng = np.random.default_rng(SEED)
    shc = Path(pp.shc_fn_igrf14)
    g, _ = pp.read_shc(str(shc))
    first, last = g.index[0].to_pydatetime(), g.index[-1].to_pydatetime()
    span = (last - first).total_seconds()
    rows = []
    for k in range(N_POINTS):
        r_km = 6371.2 + rng.uniform(0.0, 2000.0)
        theta = float(np.degrees(np.arccos(rng.uniform(-1.0, 1.0))))
        phi = float(rng.uniform(-180.0, 180.0))
        date = first + dt.timedelta(seconds=float(rng.uniform(0.0, span - 86400.0)))
        date = date.replace(microsecond=0)
        # second half: the kernel starts from the beginning of the date's 5-year interval
        offset = 0.0
        if k >= N_POINTS // 2:
            epoch0 = dt.datetime(first.year + 5 * ((date.year - first.year) // 5), 1, 1)
            offset = (date - epoch0).total_seconds()
        br, bt, bp = (float(np.ravel(v)[0]) for v in ppigrf.igrf_gc(r_km, theta, phi, date, coeff_fn=str(shc)))
        rows.append({"r_km": r_km, "theta_deg": theta, "phi_deg": phi, "date": date.isoformat(),
                     "t_offset_s": offset, "Br_nT": br, "Btheta_nT": bt, "Bphi_nT": bp})
    out = {
        "provenance": {
            "oracle": "ppigrf.igrf_gc (geocentric), IGRF-14 coefficient file shipped in the ppigrf wheel",
            "package": f"ppigrf {version('ppigrf')}",
            "coefficient_file": shc.name,
            "coefficient_sha256": hashlib.sha256(shc.read_bytes()).hexdigest(),
            "generation": "IGRF-14 (1900.0-2030.0; 2025-2030 from the secular variation)",
            "max_degree": 13,
            "command": "PYTHONPATH=. python references/igrf/build_reference.py",
            "seed": SEED,
            "tolerance_nT": TOLERANCE_NT,
            "date": dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds"),
            "python": sys.version.split()[0],
            "numpy": np.__version__,
            "pandas": version("pandas"),
            "machine": platform.platform(),
        },
        "points": rows,
    }
    (HERE / "reference.json").write_text(json.dumps(out, indent=1))
    print(f"wrote {len(rows)} points to {HERE / 'reference.json'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
