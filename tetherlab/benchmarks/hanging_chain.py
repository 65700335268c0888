"""The hanging chain with a tip mass (docs/hanging-chain.md): wall time to reach 1e-4 and 1e-5
relative error in the first lateral frequency, against the rod count, from three starts.

Starts (studies/scenes/hanging-chain.toml, 35 s, RADAU5):

* ``mode``: the free hang released in its first lateral mode, end mass 1 cm aside (the
  equilibrium start);
* ``angle``: the free hang turned by asin(0.01) (1 % off the vertical), every rod at its release
  tension (``initial.release``, the released start);
* ``held``: hanging-chain-placed.toml, the static shape with the end mass held at the unstretched
  length 1 % off the vertical, let go (n <= 16 only, its reference at rtol 1e-10: it costs 13 s
  at 32 rods and rtol 1e-8, about two minutes at 1e-10).

The frequency is fitted to the end mass's sideways motion (``oracles.continuum.fit_frequencies``,
the first three lateral frequencies as starting guesses); its error at a tolerance is taken against
the same start and rod count at rtol = atol = 1e-11, so it is the integrator's error, not the
rods' (which docs/hanging-chain.md section 4 measures against Bessel).  For each rtol of a ladder
1e-5 ... 1e-10 the run's ``total_wall_s`` (set-up included, kernels compiled by a warm-up run) is
recorded; the cost to reach an error is that of the loosest rtol that reaches it.  Last rows:
the fitted exponent of that cost in n.

Command line: ``python -m tetherlab.benchmarks.hanging_chain [--rods 16 32 64 128]``.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

from . import print_markdown
from .cost_vs_n import fit_exponent

ROOT = Path(__file__).resolve().parents[2]
SCENES = ROOT / "studies" / "scenes"
LADDER = (1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10)
REFERENCE_RTOL = 1e-11
TARGETS = (1e-4, 1e-5)
HELD_MAX_RODS = 16
HELD_REFERENCE_RTOL = 1e-10  # 54 s at 16 rods (measured); 1e-11 would be minutes


def _scene(start, n, rtol):
    from ..scene import load_scene

    if start == "held":
        sc = load_scene(SCENES / "hanging-chain-placed.toml")
    else:
        sc = load_scene(SCENES / "hanging-chain.toml")
        release = {"mode": 1, "amplitude": "1 cm"} if start == "mode" else {"angle": f"{math.asin(0.01)} rad"}
        sc = sc.replace(**{"tethers.main.initial": {"shape": "equilibrium", "release": release}})
    return sc.replace(**{"tethers.main.rods": int(n), "integrator.rtol": rtol, "integrator.atol": rtol})


def run_one(start, n, rtol):
    """(omega_1, total wall s, integration wall s, steps) of one run."""
    from ..oracles.continuum import fit_frequencies
    from ..oracles.hanging_chain import continuum_frequencies
    from ..pipeline import simulate

    res = simulate(_scene(start, n, rtol), progress=False)
    ts = res.timeseries
    guesses = continuum_frequencies(10.0, 1.0, 0.5, 9.80665, count=3)
    w, _, _ = fit_frequencies(ts["t_s"].to_numpy(), ts["tip.x_m"].to_numpy(), guesses)
    st = res.stats
    return float(w[0]), float(st["total_wall_s"]), float(st["wall_s"]), int(st["n_accepted"])


def bench_rows(rods=(16, 32, 64, 128), starts=("mode", "angle", "held")) -> list[dict]:
    run_one("mode", 4, 1e-6)  # warm-up: compile the kernels outside the timings
    rows = []
    reach = {}
    for start in starts:
        for n in rods:
            if start == "held" and n > HELD_MAX_RODS:
                continue
            w_ref = run_one(start, n, HELD_REFERENCE_RTOL if start == "held" else REFERENCE_RTOL)[0]
            best = {x: (float("nan"), float("nan"), None) for x in TARGETS}
            for rtol in LADDER:
                w, wall, integ, steps = run_one(start, n, rtol)
                err = abs(w / w_ref - 1.0)
                for x in TARGETS:
                    if err <= x and best[x][2] is None:
                        best[x] = (wall, integ, rtol)
                if all(best[x][2] is not None for x in TARGETS):
                    break
            reach[(start, n)] = best
            row = {"start": start, "rods": n}
            for x in TARGETS:
                row[f"wall_s@{x:g}"] = best[x][0]
                row[f"integration_s@{x:g}"] = best[x][1]
                row[f"rtol@{x:g}"] = best[x][2] if best[x][2] is not None else "not reached"
            rows.append(row)
    for start in starts:
        ns = [n for n in rods if (start, n) in reach]
        row = {"start": f"{start}: exponent in n", "rods": f"{ns[0]}-{ns[-1]}" if ns else ""}
        for x in TARGETS:
            row[f"wall_s@{x:g}"] = fit_exponent(ns, [reach[(start, n)][x][0] for n in ns])
            row[f"integration_s@{x:g}"] = fit_exponent(ns, [reach[(start, n)][x][1] for n in ns])
            row[f"rtol@{x:g}"] = ""
        rows.append(row)
    return rows


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rods", nargs="*", type=int, default=[16, 32, 64, 128])
    ap.add_argument("--starts", nargs="*", default=["mode", "angle", "held"])
    args = ap.parse_args(argv)
    print_markdown(bench_rows(tuple(args.rods), tuple(args.starts)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
