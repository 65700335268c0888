"""RADAU5 on scenes with a rigid body: the dense Newton matrix against the bordered structured one
(docs/integrators.md section 13).

The scenes are studies/scenes/deorbit-ed-rigid.toml (a 1063 kg rigid satellite, no wheels, the
tether attached 1 m off its centre; 7 border unknowns) and studies/scenes/rigid-example.toml (a
500 kg rigid body with three wheels under PD control; 10 border unknowns), each with ``rods = n``
and a short duration, at the scene's own tolerances.  Wall time of the integration alone
(compilation excluded by a warm-up run), per simulated second; the fitted exponent is the slope of
log(cost) against log(n) by least squares over the rows of one scene and Newton matrix.

Command line: ``python -m tetherlab.benchmarks.rigid_newton [--rods 4 16 64 128] [--dense-max-rods 64]``.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from . import print_markdown
from .cost_vs_n import fit_exponent

ROOT = Path(__file__).resolve().parents[2]
#: scene -> simulated seconds per run
SCENES = {"deorbit-ed-rigid": 100.0, "rigid-example": 20.0}


def run_one(scene, n, newton, duration_s):
    from ..formulations.cowell import cowell_rhs
    from ..integrators.driver import integrate
    from ..pipeline import _event_args, prepare
    from ..scene import load_scene

    sc = load_scene(ROOT / "studies" / "scenes" / f"{scene}.toml").replace(**{
        "tethers.main.rods": int(n), "duration": f"{duration_s} s", "integrator.method": "radau5",
    })  # fmt: skip
    from ..tether.newton_solver import choose

    prep = prepare(sc)
    p = prep.model.fresh_params()
    m1 = prep.model.n_qt
    return integrate("radau5", cowell_rhs, 0.0, prep.y0, prep.t_out, p, prep.rtol, prep.atol, h_max=prep.h_max,
                     max_steps=prep.max_steps, second_order=m1, newton=choose(p, prep.y0.size, m1, newton),
                     **_event_args(prep))  # fmt: skip


def table(rods=(4, 16, 64, 128), scenes=tuple(SCENES), dense_max_rods=128):
    rows, fits = [], []
    for scene in scenes:
        dur = SCENES[scene]
        for newton in ("dense", "structured"):
            run_one(scene, 2, newton, 1.0)  # compile / load
            ns, costs = [], []
            for n in rods:
                if newton == "dense" and n > dense_max_rods:
                    continue
                res = run_one(scene, n, newton, dur)
                st = res.stats
                cost = st["wall_s"] / dur if res.success else float("nan")
                ns.append(n)
                costs.append(cost)
                rows.append({
                    "scene": scene, "newton": newton, "rods": n, "s_per_sim_s": cost,
                    "steps": st["n_accepted"], "rejected": st["n_rejected"], "newton_fail": st["n_newton_fail"],
                    "rhs": st["n_rhs"], "jac": st["n_jac"], "sim_s": dur,
                })  # fmt: skip
            fits.append({"scene": scene, "newton": newton, "rods": f"{ns[0]}-{ns[-1]}",
                         "exponent": fit_exponent(ns, costs)})  # fmt: skip
    return rows, fits


def bench_rows():
    rows, fits = table(dense_max_rods=64)
    return rows + [{"scene": f["scene"], "newton": f["newton"], "rods": f["rods"], "s_per_sim_s": f["exponent"],
                    "steps": "<- fitted exponent of s/sim_s", "rejected": "", "newton_fail": "", "rhs": "",
                    "jac": "", "sim_s": ""} for f in fits]  # fmt: skip


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--rods", type=int, nargs="*", default=[4, 16, 64, 128])
    ap.add_argument("--scenes", nargs="*", default=list(SCENES))
    ap.add_argument("--dense-max-rods", type=int, default=128)
    args = ap.parse_args(argv)
    rows, fits = table(tuple(args.rods), tuple(args.scenes), args.dense_max_rods)
    print_markdown(rows)
    print("\n| scene | newton | rods | exponent of s per simulated s vs n |\n|---|---|---|---|")
    for f in fits:
        print(f"| {f['scene']} | {f['newton']} | {f['rods']} | {f['exponent']:.2f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
