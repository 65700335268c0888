"""Work-precision study: error against wall time and against right-hand-side evaluations.

    PYTHONPATH=. python studies/workprecision.py OUTDIR [--scheduler tcp://...] [--workers N] [--quick]

The error of a run is the largest distance (m) between any body's final position and that of a
tight-tolerance reference run of the same scene (tetherlab.summaries.final_state).  The study is
a function of a list of cases, :func:`work_precision(cases, ...)`, each case a ``Case(label,
scene, reference)`` (reference: a scene whose run is the truth, or a dict of final positions
``{"<body>.x_m": ...}`` from an oracle), so other modules add points to the same axes: the
Stiefel problem (Cowell and DROMO, reference from references/stiefel), a day of the de-orbit
scene.  Every run goes through tetherlab.sweep (parallel, cached under OUTDIR/cache, resumable).

Default cases: the in-plane libration scene (studies/scenes/libration-inplane.toml, theta0 = 30
deg) over one orbit, n = 1, 2, 4 rods; integrators dop853 and radau5 at rtol = atol = 1e-4 ...
1e-13, scipy:DOP853 at 1e-6, 1e-8, 1e-10 (slow: a Python step loop); reference dop853 at 1e-14.
Also the Stiefel-Scheifele problem with Cowell and DROMO against the stored oracle, and one day of
the de-orbit scene (n = 1) against dop853 at 1e-14.
"""

from __future__ import annotations

import argparse
import math
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

HERE = Path(__file__).resolve().parent
TOLERANCES = [10.0**-k for k in range(4, 14)]
METHODS = {"dop853": TOLERANCES, "radau5": TOLERANCES, "scipy:DOP853": [1e-6, 1e-8, 1e-10]}
REFERENCE = ("dop853", 1e-14)


@dataclass
class Case:
    label: str  # e.g. "libration n=2"; also the figure's series prefix
    scene: Any  # tetherlab.scene.Scene; its integrator block is replaced for every point
    reference: Any  # a Scene run as the truth, or {"<body>.x_m": float, ...} final positions
    methods: dict | None = None  # method -> tolerances for this case (default: METHODS)


def with_integrator(scene, method: str, tol: float):
    return scene.replace(**{"integrator.method": method, "integrator.rtol": tol, "integrator.atol": tol})


def position_error_m(summary: dict, reference: dict) -> float:
    """Largest distance (m) between a body's final position in ``summary`` and in ``reference``."""
    bodies = sorted({k.rsplit(".", 1)[0] for k in reference if k.endswith(("x_m", "y_m", "z_m"))})
    if not bodies:
        raise ValueError("reference: expected final positions '<body>.x_m', '<body>.y_m', '<body>.z_m'")
    err = 0.0
    for b in bodies:
        d = [summary[f"{b}.{a}_m"] - reference[f"{b}.{a}_m"] for a in "xyz"]
        err = max(err, math.sqrt(sum(x * x for x in d)))
    return err


def work_precision(cases, out_dir, methods=None, *, scheduler=None, workers=None, progress=True):
    """Run every case x method x tolerance; return table rows (also written to work_precision.csv)."""
    from tetherlab.summaries import final_state
    from tetherlab.sweep import run_sweep

    methods = METHODS if methods is None else methods
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    # references first (they may be reused by several cases)
    ref_scenes = [c.reference for c in cases if not isinstance(c.reference, dict)]
    refs = {}
    if ref_scenes:
        rr = run_sweep(ref_scenes, final_state, cache_dir=out / "cache", scheduler=scheduler, workers=workers,
                       labels=[f"reference {c.label}" for c in cases if not isinstance(c.reference, dict)],
                       progress=progress, description="work-precision references")
        k = 0
        for c in cases:
            if not isinstance(c.reference, dict):
                rec = rr.records[k]
                k += 1
                if not rec.ok:
                    raise RuntimeError(f"reference run of {c.label!r} failed: {rec.error}")
                refs[c.label] = rec.summary
    for c in cases:
        if isinstance(c.reference, dict):
            refs[c.label] = c.reference
    scenes, params, labels = [], [], []
    for c in cases:
        for m, tols in (c.methods or methods).items():
            for tol in tols:
                scenes.append(with_integrator(c.scene, m, tol))
                params.append({"case": c.label, "method": m, "tol": tol})
                labels.append(f"{c.label} {m} {tol:.0e}")
    res = run_sweep(scenes, final_state, cache_dir=out / "cache", scheduler=scheduler, workers=workers,
                    labels=labels, params=params, progress=progress, description="work-precision")
    rows = []
    for r in res.records:
        row = {**r.params, "ok": r.ok, "error": r.error or ""}
        if r.ok:
            row.update(error_m=position_error_m(r.summary, refs[r.params["case"]]), wall_s=r.summary["wall_s"],
                       n_rhs=r.summary["n_rhs"], n_steps=r.summary["n_steps"])
        rows.append(row)
    import pandas as pd

    pd.DataFrame(rows).to_csv(out / "work_precision.csv", index=False, float_format="%.6g")
    figures(rows, out)
    return rows


def figures(rows, out: Path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    series = {}
    for r in rows:
        if r["ok"]:
            series.setdefault((r["case"], r["method"]), []).append(r)
    for xkey, xlabel, name in (("wall_s", "integrator wall time (s)", "wall"), ("n_rhs", "rhs evaluations", "rhs")):
        fig, ax = plt.subplots(figsize=(8, 5.5))
        # colour = integrator, marker = case: every series stays identifiable past 10 of them
        methods = sorted({m for _, m in series})
        cases = sorted({c for c, _ in series})
        colours = {m: f"C{k}" for k, m in enumerate(methods)}
        markers = {c: "osD^v<>px*h+"[k % 12] for k, c in enumerate(cases)}
        for (case, method), pts in sorted(series.items()):
            pts = sorted(pts, key=lambda r: r["tol"])
            # an error of exactly 0 (identical to the reference) cannot be drawn on log axes
            xs = [r[xkey] for r in pts if r["error_m"] > 0]
            ys = [r["error_m"] for r in pts if r["error_m"] > 0]
            ax.loglog(xs, ys, "-", marker=markers[case], color=colours[method], ms=4, lw=0.8,
                      label=f"{case}, {method}")
        ax.set_xlabel(xlabel)
        ax.set_ylabel("final position error (m)")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=6, ncol=2)
        fig.tight_layout()
        fig.savefig(out / f"work_precision_{name}.png", dpi=110)
        plt.close(fig)


def libration_cases(rods=(1, 2, 4), duration="1 orbits"):
    from tetherlab.scene import load_scene

    base = load_scene(HERE / "scenes" / "libration-inplane.toml").replace(**{"duration": duration, "output.count": 11})
    cases = []
    for n in rods:
        sc = base.replace(**{"tethers.main.rods": n})
        cases.append(Case(f"libration n={n}", sc, with_integrator(sc, *REFERENCE)))
    return cases


def stiefel_cases():
    """The Stiefel-Scheifele problem (paper 4.1), Cowell and DROMO, against the stored oracle
    (references/stiefel: heyoka binary128 and a decimal Taylor integrator agreeing to 2e-22 m).
    heyoka's own double-precision points are in the Stiefel table study beside these."""
    import json

    from tetherlab.scene import load_scene

    ref = json.loads((HERE.parent / "references" / "stiefel" / "reference.json").read_text())
    pos = [float(x) * 1e3 for x in ref["final_state"]["position_km"]]
    truth = {"sat.x_m": pos[0], "sat.y_m": pos[1], "sat.z_m": pos[2]}
    base = load_scene(HERE / "scenes" / "stiefel-scheifele.toml").replace(**{"output.count": 2})
    native = {"dop853": TOLERANCES, "radau5": TOLERANCES}
    return [
        Case("Stiefel cowell", base.replace(**{"integrator.formulation": "cowell"}), truth,
             {**native, "scipy:DOP853": [1e-6, 1e-8, 1e-10]}),
        Case("Stiefel dromo", base.replace(**{"integrator.formulation": "dromo"}), truth, native),
    ]


def deorbit_day_cases():
    """One day of the electrodynamic de-orbit (n = 1), against a dop853 run at 1e-14.  The
    scene has a [stop] event, so only the native (event-locating) integrators run it."""
    from tetherlab.scene import load_scene

    sc = load_scene(HERE / "scenes" / "deorbit-ed.toml").replace(**{"duration": "1 d", "output.step": None, "output.count": 2})
    return [Case("de-orbit 1 d", sc, with_integrator(sc, *REFERENCE), {"dop853": TOLERANCES, "radau5": TOLERANCES})]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out")
    ap.add_argument("--scheduler")
    ap.add_argument("--workers", type=int)
    ap.add_argument("--quick", action="store_true", help="n = 1, 2 only and 0.25 orbit (a smoke run)")
    ap.add_argument("--quiet", action="store_true")
    args = ap.parse_args(argv)
    cases = libration_cases((1, 2), "0.25 orbits") if args.quick else libration_cases() + stiefel_cases() + deorbit_day_cases()
    rows = work_precision(cases, args.out, scheduler=args.scheduler, workers=args.workers, progress=not args.quiet)
    md = ["## Work-precision: libration (n = 1, 2, 4), Stiefel-Scheifele (Cowell, DROMO), one day of the de-orbit", "",
          "Error = largest final position distance (m) to the reference: a run with "
          f"{REFERENCE[0]} at rtol = atol = {REFERENCE[1]:g} (libration, de-orbit day), or the "
          "extended-precision oracle of references/stiefel (Stiefel-Scheifele; heyoka's double-"
          "precision points are in the Stiefel table section). Failed runs are listed with their error.", "",
          "![wall](work_precision_wall.png)", "", "![rhs](work_precision_rhs.png)", "",
          "| case | method | tol | error (m) | wall (s) | rhs |", "|---|---|---|---|---|---|"]
    for r in rows:
        if r["ok"]:
            md.append(f"| {r['case']} | {r['method']} | {r['tol']:.0e} | {r['error_m']:.3g} | {r['wall_s']:.3g} | {r['n_rhs']:.0f} |")
        else:
            md.append(f"| {r['case']} | {r['method']} | {r['tol']:.0e} | FAILED: {r['error']} | | |")
    (Path(args.out) / "work_precision.md").write_text("\n".join(md) + "\n")
    print("\n".join(md))
    return 0 if all(r["ok"] for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
