"""Cost per simulated orbit against the rod count, every native method, damped and undamped
(target: radau5 exponent <= 1.2; docs/integrators.md section 10).

The scene is studies/scenes/bench-libration.toml with ``rods = n`` and axial damping D = 0 or
2e4 N s, rtol = atol = 1e-8.  Each run covers a fraction of an orbit (``orbit_fraction``, smaller
for the explicit methods whose cost grows as n^2) and the wall time of the integration alone
(compilation excluded by a warm-up run) is scaled to one orbit.  The fitted exponent is the slope
of log(cost) against log(n) by least squares over the rows of one method and damping.

Command line: ``python -m tetherlab.benchmarks.cost_vs_n [--rods 4 8 ... 256] [--methods ...]``.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from . import print_markdown

ROOT = Path(__file__).resolve().parents[2]
SCENE = ROOT / "studies" / "scenes" / "bench-libration.toml"
ORBIT_S = 6335.174182413265  # 2 pi sqrt(a^3/mu) at a = 7400 km (the scene's orbit)

#: method -> fraction of an orbit simulated (explicit methods pay n^2; their runs are shorter)
FRACTION = {"radau5": 0.25, "radau5-eq": 0.25, "radau5-dense": 0.05, "dop853": 0.02, "vern9": 0.02}
#: "radau5-eq": RADAU5 from ``orbit.motion = "equilibrium"`` (rods at their static strain, the
#: libration kept) instead of the scene's unstrained corotating start, whose undamped axial
#: transient rings for the whole run and makes the error control resolve modes whose frequency
#: grows like n (docs/integrators.md section 9)


def run_one(method, n, damping, orbit_fraction, rtol=1e-8, newton="auto", motion="corotating"):
    from ..formulations.cowell import cowell_rhs
    from ..integrators.driver import integrate
    from ..pipeline import _event_args, prepare
    from ..scene import load_scene

    sc = load_scene(SCENE).replace(**{
        "tethers.main.rods": int(n), "tethers.main.damping": f"{damping} N s",
        "duration": f"{orbit_fraction * ORBIT_S} s", "integrator.method": method,
        "integrator.rtol": rtol, "integrator.atol": rtol, "output.count": 11, "orbit.motion": motion,
    })  # fmt: skip
    from ..tether.newton_solver import choose

    prep = prepare(sc)
    p = prep.model.fresh_params()
    res = integrate(prep.method, cowell_rhs, 0.0, prep.y0, prep.t_out, p,
                    prep.rtol, prep.atol, h_max=prep.h_max, max_steps=prep.max_steps,
                    second_order=True, newton=choose(p, prep.y0.size, True, newton),
                    **_event_args(prep))  # fmt: skip
    return res


def fit_exponent(ns, costs):
    ns = np.asarray(ns, float)
    c = np.asarray(costs, float)
    ok = np.isfinite(c) & (c > 0)
    if ok.sum() < 2:
        return float("nan")
    return float(np.polyfit(np.log(ns[ok]), np.log(c[ok]), 1)[0])


def table(rods=(4, 8, 16, 32, 64, 128, 256), methods=("radau5", "radau5-eq", "dop853", "vern9"),
          dampings=(0.0, 2e4), explicit_max_rods=64, dense_max_rods=32):  # fmt: skip
    rows = []
    fits = []
    for method in methods:
        kernel, newton = ("radau5", "dense") if method == "radau5-dense" else (method, "auto")
        motion = "equilibrium" if method == "radau5-eq" else "corotating"
        kernel = "radau5" if method == "radau5-eq" else kernel
        run_one(kernel, 2, 0.0, 0.001, newton=newton)  # compile / load
        for damping in dampings:
            ns, costs, per_step = [], [], []
            for n in rods:
                if kernel != "radau5" and n > explicit_max_rods:
                    continue
                if method == "radau5-dense" and n > dense_max_rods:
                    continue
                frac = FRACTION[method]
                res = run_one(kernel, n, damping, frac, newton=newton, motion=motion)
                st = res.stats
                per_orbit = st["wall_s"] / frac if res.success else float("nan")
                ns.append(n)
                costs.append(per_orbit)
                per_step.append(st["wall_s"] / max(st["n_accepted"] + st["n_rejected"], 1))
                rows.append({
                    "method": method, "damping_N_s": damping, "rods": n,
                    "s_per_orbit": per_orbit, "steps_per_orbit": st["n_accepted"] / frac,
                    "ms_per_trial_step": 1e3 * per_step[-1],
                    "rejected": st["n_rejected"], "newton_fail": st["n_newton_fail"],
                    "rhs": st["n_rhs"], "orbit_fraction": frac,
                })  # fmt: skip
            fits.append({"method": method, "damping_N_s": damping, "rods": f"{ns[0]}-{ns[-1]}",
                         "fitted_exponent": fit_exponent(ns, costs),
                         "per_step_exponent": fit_exponent(ns, per_step)})  # fmt: skip
    return rows, fits


def bench_rows():
    rows, fits = table()
    return rows + [{"method": f["method"], "damping_N_s": f["damping_N_s"], "rods": f["rods"],
                    "s_per_orbit": f["fitted_exponent"], "steps_per_orbit": "<- exponent of s/orbit",
                    "ms_per_trial_step": f["per_step_exponent"], "rejected": "<- of ms/step",
                    "newton_fail": "", "rhs": "", "orbit_fraction": ""}
                   for f in fits]  # fmt: skip


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--rods", type=int, nargs="*", default=[4, 8, 16, 32, 64, 128, 256])
    ap.add_argument("--methods", nargs="*", default=["radau5", "radau5-eq", "dop853", "vern9"])
    ap.add_argument("--dampings", type=float, nargs="*", default=[0.0, 2e4])
    ap.add_argument("--explicit-max-rods", type=int, default=64)
    args = ap.parse_args(argv)
    rows, fits = table(tuple(args.rods), tuple(args.methods), tuple(args.dampings),
                       args.explicit_max_rods)  # fmt: skip
    print_markdown(rows)
    print("\n| method | damping_N_s | rods | exponent of s/orbit vs n | exponent of ms/step |")
    print("|---|---|---|---|---|")
    for f in fits:
        print(f"| {f['method']} | {f['damping_N_s']:g} | {f['rods']} | {f['fitted_exponent']:.2f} "
              f"| {f['per_step_exponent']:.2f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
