"""The hanging chain with a tip mass, inextensible model (docs/inextensible.md 7): wall time to
reach 1e-4 and 1e-5 relative error in the first lateral frequency, against the rod count.

The start is the elastic bench's ``mode`` start (tetherlab/benchmarks/hanging_chain.py: the free
hang released in its first lateral mode, end mass 1 cm aside, 35 s), with
``model = "inextensible"``, RADAU5 (its structured Newton matrix, docs/inextensible.md 8) and the
explicit methods (DOP853, Vern9: without axial modes the equations are not stiff, but the chain's
fastest lateral mode holds their step).  The error at a tolerance is taken against the same rod count and
method at rtol = atol = 1e-12 (the integrator's error, not the rods': docs/inextensible.md 6.2
has those); the cost to reach an error is the wall time around ``simulate`` (the start's set-up,
the integration and the result's diagnostics; kernels compiled by a warm-up run) at the loosest
rtol of the ladder that reaches it, beside the integration's own (``stats["wall_s"]``) and the
counts, which do not depend on the machine's load: steps, rhs calls, RADAU5's Jacobians,
factorisations and Newton failures.  (The run's ``total_wall_s`` leaves out the start and the
diagnostics: it is not the user's cost.)  Last rows: the fitted exponents in n.  Target
(docs/hanging-chain.md, the rigid-link chain's cost): <= 0.10 s at 32 rods for 35 s, overhead
included; exponent <= 1.2.

Command line: ``python -m tetherlab.benchmarks.hanging_chain_inextensible [--rods 16 32 64 128]``.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from . import print_markdown
from .cost_vs_n import fit_exponent

ROOT = Path(__file__).resolve().parents[2]
SCENES = ROOT / "studies" / "scenes"
LADDER = (1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10)
REFERENCE_RTOL = 1e-12
TARGETS = (1e-4, 1e-5)
METHODS = ("radau5", "dop853", "vern9")  # RADAU5 with the structured matrix (docs/inextensible.md 8)


def _scene(n, rtol, method):
    from ..scene import load_scene

    return load_scene(SCENES / "hanging-chain.toml").replace(**{
        "tethers.main.model": "inextensible", "integrator.method": method,
        "tethers.main.initial": {"shape": "equilibrium", "release": {"mode": 1, "amplitude": "1 cm"}},
        "tethers.main.rods": int(n), "integrator.rtol": rtol, "integrator.atol": rtol})  # fmt: skip


def run_one(n, rtol, method):
    """(omega_1, wall s around simulate, integration wall s, counts) of one run."""
    from ..oracles.continuum import fit_frequencies
    from ..oracles.hanging_chain import continuum_frequencies
    from ..pipeline import simulate

    sc = _scene(n, rtol, method)
    t0 = time.perf_counter()
    res = simulate(sc, progress=False)
    wall = time.perf_counter() - t0
    ts = res.timeseries
    guesses = continuum_frequencies(10.0, 1.0, 0.5, 9.80665, count=3)
    w, _, _ = fit_frequencies(ts["t_s"].to_numpy(), ts["tip.x_m"].to_numpy(), guesses)
    st = res.stats
    counts = {k: int(st[k]) for k in ("n_accepted", "n_rhs", "n_jac", "n_lu", "n_newton_fail")}
    return float(w[0]), wall, float(st["wall_s"]), counts


def bench_rows(rods=(16, 32, 64, 128), methods=METHODS) -> list[dict]:
    for method in methods:
        run_one(4, 1e-6, method)  # warm-up: compile the kernels outside the timings
    rows = []
    reach = {}
    for method in methods:
        for n in rods:
            w_ref = run_one(n, REFERENCE_RTOL, method)[0]
            best = {x: (float("nan"), float("nan"), None, {}) for x in TARGETS}
            for rtol in LADDER:
                w, wall, integ, counts = run_one(n, rtol, method)
                err = abs(w / w_ref - 1.0)
                for x in TARGETS:
                    if err <= x and best[x][2] is None:
                        best[x] = (wall, integ, rtol, counts)
                if all(best[x][2] is not None for x in TARGETS):
                    break
            reach[(method, n)] = best
            row = {"model": "inextensible", "method": method, "rods": n}
            for x in TARGETS:
                row[f"wall_s@{x:g}"] = best[x][0]
                row[f"integration_s@{x:g}"] = best[x][1]
                row[f"rtol@{x:g}"] = best[x][2] if best[x][2] is not None else "not reached"
            for k, v in best[TARGETS[-1]][3].items():  # the counts of the run reaching the last target
                row[k] = v
            rows.append(row)
    for method in methods:
        ns = [n for n in rods if (method, n) in reach]
        row = {"model": "inextensible", "method": f"{method}: exponent in n", "rods": f"{ns[0]}-{ns[-1]}" if ns else ""}
        for x in TARGETS:
            row[f"wall_s@{x:g}"] = fit_exponent(ns, [reach[(method, n)][x][0] for n in ns])
            row[f"integration_s@{x:g}"] = fit_exponent(ns, [reach[(method, n)][x][1] for n in ns])
            row[f"rtol@{x:g}"] = ""
        for k in ("n_accepted", "n_rhs"):
            row[k] = fit_exponent(ns, [reach[(method, n)][TARGETS[-1]][3].get(k, float("nan")) for n in ns])
        rows.append(row)
    return rows


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rods", nargs="*", type=int, default=[16, 32, 64, 128])
    ap.add_argument("--methods", nargs="*", default=list(METHODS))
    args = ap.parse_args(argv)
    print_markdown(bench_rows(tuple(args.rods), tuple(args.methods)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
