"""Cost of the statics solve (tetherlab/statics.py) against the rod count.

The hanging chain of docs/hanging-chain.md (10 m, 1 kg, a 0.5 kg end mass, EA = 1e7 N, uniform
gravity) with the end mass held at the tether's length 30 deg off the vertical (plain Newton
converges there over 8-512 rods) and 1 % off the vertical (a near-vertical hold; the shooting takes over
at some n): wall time of one solve (compilation excluded by a warm-up), its Newton iterations and
the path that found it; last rows: the exponent of log(wall) against log(n) fitted by least squares
over 64-512 rods.  The Jacobian is dense, by forward differences (3n + 3 columns, each an O(n)
kernel call) and factorised by dense LU: expect an exponent between 2 and 3.

Command line: ``python -m tetherlab.benchmarks.statics [--rods 8 16 ... 512]``.
"""

from __future__ import annotations

import argparse
import math
import sys
import time

import numpy as np

from . import print_markdown
from .cost_vs_n import fit_exponent

RODS = (8, 16, 32, 64, 128, 256, 512)
HOLDS = {"30deg": math.radians(30.0), "1%": math.asin(0.01)}
FIT_FROM = 64


def _held(n):
    from ..forces import uniform_gravity
    from ..statics import held_model
    from ..system import TetherSpec

    spec = TetherSpec("main", n, 10.0, 1e7, 1.0, tip_mass_kg=0.5, tip_name="tip")
    return held_model(spec, [(uniform_gravity.SPEC, {"g": 9.80665})])


def run_one(n, angle):
    from ..statics import solve

    model = _held(n)
    tip = np.array([10.0 * math.sin(angle), 0.0, -10.0 * math.cos(angle)])
    t0 = time.perf_counter()
    eq = solve(model, np.zeros(3), tip)
    return time.perf_counter() - t0, eq


def table(rods=RODS):
    run_one(2, HOLDS["30deg"])  # compile / load
    rows, fits = [], []
    for hold, angle in HOLDS.items():
        ns, walls = [], []
        for n in rods:
            wall, eq = run_one(n, angle)
            rows.append({"hold": hold, "rods": n, "wall_s": wall, "iterations": eq.iterations, "method": eq.method,
                         "residual_N": eq.residual_N})  # fmt: skip
            if n >= FIT_FROM:
                ns.append(n)
                walls.append(wall)
        fits.append({"hold": hold, "rods": f"{ns[0]}-{ns[-1]}" if ns else "", "exponent": fit_exponent(ns, walls)})
    return rows, fits


def bench_rows():
    rows, fits = table()
    return rows + [{"hold": f["hold"], "rods": f["rods"], "wall_s": f["exponent"], "iterations": "<- fitted exponent of wall_s",
                    "method": "", "residual_N": ""} for f in fits]  # fmt: skip


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--rods", type=int, nargs="*", default=list(RODS))
    args = ap.parse_args(argv)
    rows, fits = table(tuple(args.rods))
    print_markdown(rows)
    print("\n| hold | rods | exponent of wall time vs n |\n|---|---|---|")
    for f in fits:
        print(f"| {f['hold']} | {f['rods']} | {f['exponent']:.2f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
