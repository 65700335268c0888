"""Where the statics solve (tetherlab/statics.py) converges: rods x EA x hold angle.

The hanging chain of docs/hanging-chain.md (10 m, 1 kg, a 0.5 kg end mass, uniform gravity
9.80665 m/s^2) with the end mass held at the tether's unstretched length L from the nail, at an
angle from the downward vertical: 0, 0.1 % and 1 % (sin of the angle), 5, 30, 60 and 90 degrees.
For every (n, EA, angle) it records how the solve ended (its ``method``, or the error), its
iterations, its wall time (a loaded, shared machine: compare rows of one run only), the largest
rod force imbalance in newtons and the smallest rod axial force (negative: a strut).

Run:  PYTHONPATH=. python studies/statics_map.py OUT.csv [--rods 1,2,4] [--ea 1e3,1e5]
      PYTHONPATH=. python studies/statics_map.py OUT.csv --table   (the markdown table of docs/statics-map.md)
"""

from __future__ import annotations

import argparse
import csv
import math
import time

import numpy as np

from tetherlab.forces import uniform_gravity
from tetherlab.statics import NoTautEquilibrium, held_model, solve
from tetherlab.system import TetherSpec

L_M, MASS_KG, TIP_KG, G = 10.0, 1.0, 0.5, 9.80665
ANGLES = {
    "0": 0.0,
    "0.1%": math.asin(1e-3),
    "1%": math.asin(1e-2),
    "5deg": math.radians(5.0),
    "30deg": math.radians(30.0),
    "60deg": math.radians(60.0),
    "90deg": 0.5 * math.pi,
}
RODS = (1, 2, 4, 8, 16, 32, 64, 128, 256, 512)
EAS = (1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9)


def tip_at(angle_rad: float, reach_m: float = L_M) -> np.ndarray:
    return np.array([reach_m * math.sin(angle_rad), 0.0, -reach_m * math.cos(angle_rad)])


def held(n: int, ea_n: float):
    spec = TetherSpec("main", n, L_M, ea_n, MASS_KG, tip_mass_kg=TIP_KG, tip_name="tip")
    return held_model(spec, [(uniform_gravity.SPEC, {"g": G})])


def one(n: int, ea_n: float, angle: str) -> dict:
    model = held(n, ea_n)
    t0 = time.perf_counter()
    row = {"rods": n, "EA_N": ea_n, "angle": angle}
    try:
        eq = solve(model, np.zeros(3), tip_at(ANGLES[angle]))
    except NoTautEquilibrium as exc:
        row.update(method="REFUSED-PROVEN" if exc.proven else "REFUSED", iterations=-1, residual_N=math.nan,
                   min_axial_N=math.nan, error=str(exc)[-160:])
    except ValueError as exc:
        row.update(method="FAIL", iterations=-1, residual_N=math.nan, min_axial_N=math.nan, error=str(exc)[:160])
    else:
        row.update(method=eq.method, iterations=eq.iterations, residual_N=eq.residual_N,
                   min_axial_N=float(eq.axial_force_N.min()), error="")
    row["wall_s"] = time.perf_counter() - t0
    return row


CODES = {"newton": "N", "shooting": "S", "chord": "C", "trust-region": "T", "continuation": "K", "FAIL": "F",
         "REFUSED-PROVEN": "V", "REFUSED": "R"}


def table(path: str) -> str:
    """The CSV of a run as one markdown table: a row per (rods, EA), a column per angle; N newton,
    S shooting, C chord (one rod), K continuation, F failed (ValueError), V refused (no taut
    equilibrium exists: the vertical), R refused (none found: docs/catenary.md 3.2); lower case: the equilibrium returned has a
    rod in compression (a strut, not a hanging tether)."""
    rows = list(csv.DictReader(open(path)))
    angles = list(dict.fromkeys(r["angle"] for r in rows))
    cells = {}
    for r in rows:
        c = CODES.get(r["method"], "?")
        if c not in "FVR" and float(r["min_axial_N"]) < 0.0:
            c = c.lower()
        cells.setdefault((int(r["rods"]), float(r["EA_N"])), {})[r["angle"]] = c
    out = ["| rods | EA N | " + " | ".join(angles) + " |", "|---|---|" + "---|" * len(angles)]
    for (n, ea), by in sorted(cells.items()):
        out.append(f"| {n} | {ea:g} | " + " | ".join(by.get(a, " ") for a in angles) + " |")
    return "\n".join(out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out", help="CSV to write (or, with --table, to read)")
    ap.add_argument("--table", action="store_true", help="print the markdown table of an existing CSV")
    ap.add_argument("--rods", default=",".join(map(str, RODS)))
    ap.add_argument("--ea", default=",".join(f"{e:g}" for e in EAS))
    ap.add_argument("--angles", default=",".join(ANGLES))
    a = ap.parse_args()
    if a.table:
        print(table(a.out))
        return
    rods = [int(s) for s in a.rods.split(",")]
    eas = [float(s) for s in a.ea.split(",")]
    angles = a.angles.split(",")
    held(1, 1e7)  # compile outside the timings
    solve(held(1, 1e7), np.zeros(3), tip_at(0.1))
    fields = ["rods", "EA_N", "angle", "method", "iterations", "wall_s", "residual_N", "min_axial_N", "error"]
    with open(a.out, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=fields)
        w.writeheader()
        for n in rods:
            for ea in eas:
                for ang in angles:
                    row = one(n, ea, ang)
                    w.writerow(row)
                    fh.flush()
                    print(" ".join(f"{row[k]}" if not isinstance(row[k], float) else f"{row[k]:.3g}" for k in fields), flush=True)


if __name__ == "__main__":
    main()
