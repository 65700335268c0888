"""RADAU5 on a forest (two root bodies): the dense Newton matrix against the structured one
(docs/integrators.md section 13, "Forests").

The scene: two bench-libration-like systems on neighbouring circular orbits (7400 and 7410 km),
each a 1000 kg root with a 5 km, 10 kg tether (EA = 5e4 N, damping 2e4 N s) to a 100 kg end mass,
``rods = n`` per tether (2n in all); central gravity; rtol = atol = 1e-8; 300 s simulated.  Wall
time of the integration alone (compilation excluded by a warm-up run), per simulated second; the
fitted exponent is the slope of log(cost) against log(n) by least squares over one Newton
matrix's rows.

Command line: ``python -m tetherlab.benchmarks.forest_newton [--rods 4 16 64] [--dense-max-rods 64]``.
"""

from __future__ import annotations

import argparse
import sys

from . import print_markdown
from .cost_vs_n import fit_exponent

DURATION_S = 300.0


def forest_scene(n, duration_s=DURATION_S):
    from ..scene import Scene

    def teth(frm, to):
        return {"from": frm, "to": to, "rods": int(n), "length": "5 km", "EA": "5e4 N", "mass": "10 kg",
                "damping": "2e4 N s", "model": "paper", "initial": {"shape": "straight", "theta": "30 deg"}}  # fmt: skip

    return Scene.from_dict({
        "duration": f"{duration_s} s",
        "effects": {"central_gravity": {}},
        "bodies": {
            "m0": {"mass": "1000 kg"}, "mf": {"mass": "100 kg"},
            "n0": {"mass": "1000 kg", "elements": {"a": "7410 km", "e": 0.0, "i": "0 deg", "nu": "1 deg"}},
            "nf": {"mass": "100 kg"},
        },
        "tethers": {"a": teth("m0", "mf"), "b": teth("n0", "nf")},
        "orbit": {"reference": "m0", "elements": {"a": "7400 km", "e": 0.0, "i": "0 deg", "nu": "0 deg"},
                  "motion": "corotating"},
        "integrator": {"method": "radau5", "rtol": 1e-8, "atol": 1e-8},
        "output": {"count": 11},
    })  # fmt: skip


def run_one(n, newton, duration_s=DURATION_S):
    from ..formulations.cowell import cowell_rhs
    from ..integrators.driver import integrate
    from ..pipeline import _event_args, prepare

    from ..tether.newton_solver import choose

    prep = prepare(forest_scene(n, duration_s))
    p = prep.model.fresh_params()
    return integrate("radau5", cowell_rhs, 0.0, prep.y0, prep.t_out, p, prep.rtol, prep.atol, h_max=prep.h_max,
                     max_steps=prep.max_steps, second_order=True, newton=choose(p, prep.y0.size, True, newton),
                     **_event_args(prep))  # fmt: skip


def table(rods=(4, 16, 64), dense_max_rods=64):
    rows, fits = [], []
    for newton in ("dense", "structured"):
        run_one(2, newton, 1.0)  # compile / load
        ns, costs = [], []
        for n in rods:
            if newton == "dense" and n > dense_max_rods:
                continue
            res = run_one(n, newton)
            st = res.stats
            cost = st["wall_s"] / DURATION_S if res.success else float("nan")
            ns.append(n)
            costs.append(cost)
            rows.append({
                "newton": newton, "rods_per_tether": n, "s_per_sim_s": cost, "steps": st["n_accepted"],
                "rejected": st["n_rejected"], "newton_fail": st["n_newton_fail"], "rhs": st["n_rhs"],
                "jac": st["n_jac"], "matrix": st["newton_matrix"],
            })  # fmt: skip
        fits.append({"newton": newton, "rods": f"{ns[0]}-{ns[-1]}", "exponent": fit_exponent(ns, costs)})
    return rows, fits


def bench_rows():
    rows, fits = table()
    return rows + [{"newton": f["newton"], "rods_per_tether": f["rods"], "s_per_sim_s": f["exponent"],
                    "steps": "<- fitted exponent of s/sim_s", "rejected": "", "newton_fail": "", "rhs": "",
                    "jac": "", "matrix": ""} for f in fits]  # fmt: skip


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--rods", type=int, nargs="*", default=[4, 16, 64])
    ap.add_argument("--dense-max-rods", type=int, default=64)
    args = ap.parse_args(argv)
    rows, fits = table(tuple(args.rods), args.dense_max_rods)
    print_markdown(rows)
    print("\n| newton | rods per tether | exponent of s per simulated s vs n |\n|---|---|---|")
    for f in fits:
        print(f"| {f['newton']} | {f['rods']} | {f['exponent']:.2f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
