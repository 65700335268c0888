"""``make bench``: speed targets, printed as tables (never asserted in tests).

1. Right-hand-side cost per call for n = 1, 2, 4, ... 256 rods (target: linear in n and
   <= 0.5 us per rod for n >= 16), measured by a compiled loop calling the cfunc.
2. The benchmark scene studies/scenes/bench-libration.toml with every integrator, and the same
   run through scipy's solve_ivp on the same compiled right-hand side (target: >= 30x faster).
3. Start-up of a second ``tetherlab run`` (target: integrating within 3 s, no recompilation).
"""

from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from ._jit import njit, ptr

ROOT = Path(__file__).resolve().parent.parent
METHODS = ("dop853", "vern9", "radau5", "scipy:DOP853")
BENCH_SCENE = ROOT / "studies" / "scenes" / "bench-libration.toml"


@njit(cache=True)
def _time_rhs(rhs, y, dy, p, ncalls):
    s = 0
    for _ in range(ncalls):
        s += rhs(0.0, ptr(y), ptr(dy), ptr(p))  # as the integrators call it (no refcounting)
    return s


def rhs_cost_table(max_rods: int = 256) -> list[dict]:
    from .forces import EFFECTS
    from .formulations.cowell import cowell_rhs
    from .system import TetherSpec, build_model, chain_state

    mu = 3.986004418e14
    rows = []
    n = 1
    while n <= max_rods:
        tet = TetherSpec("t", n, 5000.0, 5e4, 10.0, 0.0, "paper", 100.0, "mf")
        model = build_model(
            root_mass_kg=1000.0, tethers=[tet], effects=[(EFFECTS["central_gravity"], {})],
            central={"mu_m3_s2": mu},
        )
        r = 7.4e6
        w = np.sqrt(mu / r**3)
        th = np.pi / 6
        u = np.array([np.cos(th), np.sin(th), 0.0])
        y = chain_state(model, np.array([r, 0, 0.0]), np.array([0, r * w, 0.0]), [np.tile(u, (n, 1))], [1e-5], np.array([0, 0, w]))
        dy = np.empty_like(y)
        p = model.fresh_params()
        _time_rhs(cowell_rhs, y, dy, p, 10)
        ncalls = max(2000, int(2e6 / n))
        best = np.inf
        for _ in range(5):
            t0 = time.perf_counter()
            _time_rhs(cowell_rhs, y, dy, p, ncalls)
            best = min(best, (time.perf_counter() - t0) / ncalls)
        rows.append({"rods": n, "us_per_call": best * 1e6, "us_per_rod": best * 1e6 / n})
        n *= 2
    return rows


def scene_table(scene_path=BENCH_SCENE) -> list[dict]:
    from .scene import load_scene
    from .pipeline import prepare, simulate

    scene = load_scene(scene_path)
    rows = []
    ref = None
    for method in METHODS:
        sc = scene.replace(**{"integrator.method": method})
        simulate(sc, progress=False)  # warm-up: compilation excluded from the timing
        best = None
        for _ in range(3 if not method.startswith("scipy") else 1):
            res = simulate(sc, progress=False)
            if best is None or res.stats["wall_s"] < best.stats["wall_s"]:
                best = res
        prep = prepare(sc)
        tip = best.timeseries[["mf.x_m", "mf.y_m", "mf.z_m"]].to_numpy()
        if ref is None:
            ref = tip
        rows.append(
            {
                "method": method,
                "wall_s": best.stats["wall_s"],
                "steps": best.stats["n_accepted"],
                "rejected": best.stats["n_rejected"],
                "rhs": best.stats["n_rhs"],
                "jac": best.stats.get("n_jac", 0),
                "max_tip_diff_m": float(np.max(np.linalg.norm(tip - ref, axis=1))),
                "rtol": prep.rtol,
            }
        )
    return rows


def startup_table(scene_path=BENCH_SCENE) -> list[dict]:
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for attempt in ("first", "second"):
            t0 = time.perf_counter()
            out = subprocess.run(
                [sys.executable, "-m", "tetherlab", "run", str(scene_path), "--out", tmp, "--quiet"],
                capture_output=True, text=True, env=dict(os.environ),
            )
            total = time.perf_counter() - t0
            import json

            stats = json.loads((Path(tmp) / "run.json").read_text())["stats"] if out.returncode == 0 else {}
            rows.append(
                {
                    "run": attempt,
                    "total_s": total,
                    "integrate_s": stats.get("wall_s", float("nan")),
                    "compile_s": stats.get("compile_s", float("nan")),
                    "before_integration_s": total - stats.get("total_wall_s", float("nan")),
                }
            )
    return rows


def _print_table(title, rows):
    print(f"\n## {title}\n")
    if not rows:
        print("(none)")
        return
    keys = list(rows[0])
    print("| " + " | ".join(keys) + " |")
    print("|" + "---|" * len(keys))
    for r in rows:
        print("| " + " | ".join(f"{v:.4g}" if isinstance(v, float) else str(v) for v in r.values()) + " |")


#: benchmark modules in tetherlab/benchmarks/ with a ``bench_rows()`` (name, table title)
EXTRA_SECTIONS = (
    ("stiefel", "Stiefel-Scheifele, Examples 2 (ex2: J2 + Moon) and 1 (ex1: J2 only): tetherlab's best method "
                "against heyoka at 1 m and 1 mm final error (target ratios 0.5, 0.8); cost exponent x: wall ~ error^-x"),
    ("stiefel_costs", "Stiefel-Scheifele cost breakdown of tetherlab's pick (ex2: DROMO sigma Vern9; ex1: DROMO "
                      "sigma with the linear time element, ABM) against heyoka: rhs latency, the "
                      "method's step overhead, glue, heyoka per step and per Taylor order; last rows: fitted trends"),
    ("deorbit", "Electrodynamic de-orbit, n = 1, whole mission, every integrator (paper section 5: about 35 d)"),
    ("uncertainty", "Uncertainty studies: per-sample overhead (the full path, replace + prepare, and the parameter-only re-pack) against a de-orbit's integration (target < 5 %), machinery cost against N, de-orbit throughput against workers"),
    ("deorbit_rods", "Electrodynamic de-orbit against the rod count: RADAU5, formulation cowell-orbit, "
                     "quasi-static start, rtol 1e-8 (targets: n = 16 <= 60 s, n = 64 <= 5 min)"),
    ("cost_vs_n", "Cost per simulated orbit against the rod count, bench-libration rtol 1e-8, "
                  "damped and undamped; last rows: fitted exponents (target: radau5 <= 1.2; docs/integrators.md 10)"),
    ("rigid_newton", "RADAU5 with a rigid body: dense against the bordered structured Newton matrix, per simulated "
                     "second against the rod count; last rows: fitted exponents (docs/integrators.md 13)"),
    ("forest_newton", "RADAU5 on a forest (two bench-libration-like systems, D = 2e4 N s): dense against the "
                      "structured Newton matrix, per simulated second against the rods per tether; last rows: "
                      "fitted exponents (docs/integrators.md 13)"),
    ("hanging_chain", "Hanging chain with a tip mass, 35 s, elastic and inextensible models, RADAU5, DOP853 and Vern9: wall "
                      "time (set-up included) to reach 1e-4 and "
                      "1e-5 in the first lateral frequency from the mode start, the angle release and the held start "
                      "(docs/hanging-chain.md 4); last rows: fitted exponents in n"),
    ("hanging_chain_inextensible", "Hanging chain with a tip mass, 35 s, model inextensible, RADAU5, DOP853 and Vern9: wall "
                                   "time (set-up included) to reach 1e-4 and 1e-5 in the first lateral frequency from "
                                   "the mode start (docs/inextensible.md 7; target <= 0.10 s at 32 rods); last rows: "
                                   "fitted exponents in n (target <= 1.2)"),
    ("statics", "Statics solve (hanging chain, EA = 1e7 N, held at its length 30 deg and 1 % off the vertical): "
                "wall time and Newton iterations against n = 8 ... 512; last rows: fitted exponents over 64-512"),
    ("environment", "Environment effects: rhs cost per body and per rod, beside central gravity"),
    ("igrf", "IGRF-14 field: cost of one evaluation against the degree (target: degree 13 in a few us)"),
    ("rigid", "Right-hand-side cost: rigid root + 3 wheels + 4 tethers against the point-mass hub"),
    ("deployment", "Deployment from a reel, 500 m to 20 km at constant speed in one orbit, or exponentially at "
                   "L'/(Omega L) = 0.5 (rods of 1000/500/250 m; straight and quasi-static "
                   "births), against the same system at 20 km over the same time: wall "
                   "time, cost per birth, exponent in the final rod count (targets: ratio <= 2 at 500 m rods, ~1)"),
)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--max-rods", type=int, default=256)
    ap.add_argument("--skip-startup", action="store_true")
    ap.add_argument("--only", nargs="*", default=None,
                    help="sections to run: rhs scene effects startup (others come from tetherlab/benchmarks/)")
    args = ap.parse_args(argv)
    want = (lambda name: args.only is None or name in args.only)
    if want("rhs"):
        rows = rhs_cost_table(args.max_rods)
        _print_table("Right-hand-side cost per call (target: linear in n, <= 0.5 us/rod for n >= 16)", rows)
    if want("scene"):
        srows = scene_table()
        _print_table("bench-libration.toml, 10 orbits (target: >= 30x faster than scipy on the same rhs)", srows)
        by = {r["method"]: r for r in srows}
        if "scipy:DOP853" in by:
            for m in ("dop853", "vern9", "radau5"):
                if m in by:
                    print(f"speed-up {m} vs scipy:DOP853: {by['scipy:DOP853']['wall_s'] / by[m]['wall_s']:.1f}x")
    if want("effects"):
        from .benchmarks.effects import rhs_cost_rows

        _print_table("Right-hand-side cost per call against the effects named", rhs_cost_rows())
    for name, title in EXTRA_SECTIONS:
        if want(name):
            import importlib

            try:
                rows = importlib.import_module(f".benchmarks.{name}", __package__).bench_rows()
            except ModuleNotFoundError:
                continue
            _print_table(title, rows)
    if not args.skip_startup and want("startup"):
        _print_table("Start-up of `tetherlab run` (target: second run integrating within 3 s)", startup_table())
    print(f"\npeak RSS of this process: {resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024:.0f} MiB")
    return 0


if __name__ == "__main__":
    sys.exit(main())
