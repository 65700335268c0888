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

Rod count as an axis (docs/verification.md 7): the damped libration scene (studies/scenes/bench-libration.toml,
D = 2e4 N s, theta0 = 30 deg, one orbit) at n = 4, 8, ..., 128 rods, radau5 with its structured
O(n) Newton matrix at rtol = atol = 1e-5 ... 1e-10, each against a radau5 reference at 1e-11 of
the same n (the error of the discretisation in n is not in these numbers: each n is its own
problem).  The reference's own error, measured once against radau5 at 1e-12 (loaded machine):
2.6e-7 ... 1.3e-6 m for n = 4 ... 128, against 3.2e-6 ... 8.4e-6 m for the 1e-10 points, so the
tightest points' errors are known to ~10 ... 40 %, the looser ones far better.  A 1e-12 reference
cost 95 s at n = 128 (1e-11: 12 s), which the verify budget does not have.  Its own
figure (work_precision_rods.png: error against wall time, one series per n) and tables: the error
and wall time at every (n, tol), and the wall time's fitted exponent in n at each tolerance.

heyoka on the same axes (Stiefel only).  heyoka's double-precision Taylor integrator
(tetherlab.benchmarks.stiefel.heyoka_rows, through the summary
tetherlab.summaries.stiefel_heyoka_final_state) runs the Stiefel problem at tolerances 1e-4 ...
1e-15 and the double epsilon (its accuracy floor), with the same error measure against the same
oracle.  Its wall time is measured like tetherlab's and under the same conditions: a second sweep
through the same tetherlab.sweep machinery (same scheduler, same number of worker processes, so
each point is timed in a worker with the same number of other runs beside it, as tetherlab's
are), one timed integration per point with compilation excluded on both sides (tetherlab: the
numba kernels are compiled or loaded before the clock starts; heyoka: the taylor_adaptive
construction, where it JIT-compiles, and a warm-up propagation come before the clock).  A Taylor
method makes no right-hand-side evaluations, so heyoka has no point on the rhs axis; its Taylor
steps are drawn against tetherlab's accepted steps in a separate, labelled panel
(work_precision_stiefel.png).  heyoka does not apply to the libration and de-orbit cases: they
have a tether, whose TMED equations (an O(n) reaction solve per evaluation) exist only in
tetherlab's kernels.  heyoka is an oracle: it is imported inside the summary's call only; without
it the study runs and its report says why heyoka's points are absent.
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
#: heyoka on the Stiefel axes: tetherlab's tolerances and tighter, to its double-precision floor
#: (heyoka clamps a tolerance below the epsilon to it: 1e-16 gives the epsilon's run, 7.3e-4 m)
HEYOKA_TOLS = TOLERANCES + [1e-14, 1e-15, float(np.finfo(float).eps)]
HEYOKA_CASE = "Stiefel heyoka"
#: the rod-count axis: damped libration, radau5 (structured Newton), reference of the same n
ROD_AXIS_RODS = (4, 8, 16, 32, 64, 128)
ROD_AXIS_TOLS = [10.0**-k for k in range(5, 11)]
ROD_AXIS_REFERENCE = ("radau5", 1e-11)
ROD_AXIS_DAMPING = "2e4 N s"  # as tetherlab/benchmarks/cost_vs_n.py's damped rows
ROD_AXIS_PREFIX = "damped libration n="
HEYOKA_METHOD = "heyoka taylor (double)"


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


def work_precision(cases, out_dir, methods=None, *, heyoka=False, scheduler=None, workers=None, progress=True):
    """Run every case x method x tolerance; return table rows (also written to work_precision.csv).

    ``heyoka=True`` adds heyoka's Stiefel points (:func:`heyoka_stiefel_rows`) when heyoka can
    be imported (:func:`heyoka_missing` says why not otherwise).
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    rows = tetherlab_rows(cases, out, methods, scheduler=scheduler, workers=workers, progress=progress)
    if heyoka and heyoka_missing(scheduler) is None:
        rows += heyoka_stiefel_rows(out, scheduler=scheduler, workers=workers, progress=progress)
    import pandas as pd

    pd.DataFrame(rows).to_csv(out / "work_precision.csv", index=False, float_format="%.6g")
    figures(rows, out)
    return rows


def tetherlab_rows(cases, out_dir, methods=None, *, scheduler=None, workers=None, progress=True):
    """Every case x method x tolerance through tetherlab.sweep (cached under OUTDIR/cache)."""
    from tetherlab.summaries import final_state
    from tetherlab.sweep import run_sweep

    methods = METHODS if methods is None else methods
    out = Path(out_dir)
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
        row = {**r.params, "ok": r.ok, "error": r.error or "", "cached": r.cached}
        if r.ok:
            row.update(error_m=position_error_m(r.summary, refs[r.params["case"]]), wall_s=r.summary["wall_s"],
                       n_rhs=r.summary["n_rhs"], n_steps=r.summary["n_steps"])
        rows.append(row)
    return rows


def heyoka_missing(scheduler=None) -> str | None:
    """Why heyoka's points cannot be made here (None: they can).  On a Dask cluster the workers'
    environment decides: a worker without heyoka records its ImportError in the run's row."""
    if scheduler is not None:
        return None
    import importlib.util

    if importlib.util.find_spec("heyoka") is None:
        return ("heyoka is not installed in this environment, so its Stiefel points are absent "
                "(install the oracle extra: pip install -e '.[oracle]'); tetherlab's points are unaffected.")
    return None


def stiefel_truth() -> dict:
    """Final position of the Stiefel-Scheifele satellite (m) from references/stiefel/reference.json
    (heyoka binary128 and a decimal Taylor integrator, agreeing to 2e-22 m)."""
    import json

    ref = json.loads((HERE.parent / "references" / "stiefel" / "reference.json").read_text())
    pos = [float(x) * 1e3 for x in ref["final_state"]["position_km"]]
    return {"sat.x_m": pos[0], "sat.y_m": pos[1], "sat.z_m": pos[2]}


def heyoka_stiefel_rows(out_dir, tols=HEYOKA_TOLS, *, scheduler=None, workers=None, progress=True):
    """heyoka's Stiefel points, as rows of the same table (``n_rhs`` NaN: a Taylor method has none).

    Run by the same machinery as tetherlab's points (tetherlab.sweep, same scheduler and number of
    workers, cache under OUTDIR/cache), so the wall times are taken under the same conditions;
    the summary is tetherlab.summaries.stiefel_heyoka_final_state, which reuses
    tetherlab.benchmarks.stiefel.heyoka_rows (construction, i.e. JIT, not timed).
    """
    from tetherlab.scene import load_scene
    from tetherlab.summaries import stiefel_heyoka_final_state
    from tetherlab.sweep import run_sweep

    out = Path(out_dir)
    base = load_scene(HERE / "scenes" / "stiefel-scheifele.toml").replace(**{"output.count": 2})
    scenes = [with_integrator(base, "dop853", tol) for tol in tols]  # the method key is unused by heyoka
    params = [{"case": HEYOKA_CASE, "method": HEYOKA_METHOD, "tol": tol} for tol in tols]
    res = run_sweep(scenes, stiefel_heyoka_final_state, cache_dir=out / "cache", scheduler=scheduler,
                    workers=workers, labels=[f"heyoka {_tol_str(tol)}" for tol in tols], params=params,
                    progress=progress, description="work-precision, heyoka")  # fmt: skip
    truth = stiefel_truth()
    rows = []
    for r in res.records:
        row = {**r.params, "ok": r.ok, "error": r.error or "", "cached": r.cached}
        if r.ok:
            row.update(error_m=position_error_m(r.summary, truth), wall_s=r.summary["wall_s"],
                       n_rhs=math.nan, n_steps=r.summary["n_steps"])
        rows.append(row)
    return rows


def _finite_pos(v) -> bool:
    return v is not None and isinstance(v, (int, float)) and math.isfinite(v) and v > 0


def figures(rows, out: Path):
    """work_precision_wall.png (every case; heyoka's Stiefel points too), work_precision_rhs.png
    (tetherlab only: heyoka makes no rhs evaluations), and, when heyoka's points are present,
    work_precision_stiefel.png: the Stiefel problem alone, error against wall time (a) and
    against accepted steps (b; heyoka's are Taylor steps, labelled as such)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rod_axis_figure(rows, out)
    series = {}
    for r in rows:
        if r["ok"] and not str(r["case"]).startswith(ROD_AXIS_PREFIX):  # the rod axis has its own figure
            series.setdefault((r["case"], r["method"]), []).append(r)
    # colour = integrator, marker = case: every series stays identifiable past 10 of them
    methods = sorted({m for _, m in series})
    cases = sorted({c for c, _ in series})
    colours = {m: f"C{k}" for k, m in enumerate(m for m in methods if m != HEYOKA_METHOD)}
    colours[HEYOKA_METHOD] = "k"  # the oracle in black
    markers = {c: "osD^v<>px*h+"[k % 12] for k, c in enumerate(cases)}
    has_heyoka = any(m == HEYOKA_METHOD for _, m in series)

    def draw(ax, xkey, keep):
        for (case, method), pts in sorted(series.items()):
            if not keep(case, method):
                continue
            pts = sorted(pts, key=lambda r: r["tol"])
            # an error of exactly 0 (identical to the reference), or a cost that does not exist
            # (heyoka's rhs count), cannot be drawn on log axes
            good = [r for r in pts if _finite_pos(r["error_m"]) and _finite_pos(r[xkey])]
            if not good:
                continue
            ax.loglog([r[xkey] for r in good], [r["error_m"] for r in good], "-", marker=markers[case],
                      color=colours[method], ms=4, lw=1.4 if method == HEYOKA_METHOD else 0.8,
                      label=f"{case}, {method}")  # fmt: skip
        ax.set_ylabel("final position error (m)")
        ax.grid(True, which="both", alpha=0.3)

    for xkey, xlabel, name in (("wall_s", "integrator wall time (s)", "wall"), ("n_rhs", "rhs evaluations", "rhs")):
        fig, ax = plt.subplots(figsize=(8, 5.5))
        draw(ax, xkey, lambda c, m: True)
        ax.set_xlabel(xlabel)
        if xkey == "n_rhs" and has_heyoka:
            ax.set_title("heyoka absent: a Taylor method makes no rhs evaluations "
                         "(its Taylor steps: work_precision_stiefel.png)", fontsize=8)  # fmt: skip
        ax.legend(fontsize=6, ncol=2)
        from tetherlab.provenance import stamp_figure
        stamp_figure(fig, "studies/workprecision.py; truth: dop853 at 1e-14 runs, references/stiefel/reference.json")
        fig.savefig(out / f"work_precision_{name}.png", dpi=110)
        plt.close(fig)

    if not has_heyoka:
        return
    stiefel = lambda c, m: c.startswith("Stiefel")  # noqa: E731
    fig, (a, b) = plt.subplots(1, 2, figsize=(12, 5.2))
    draw(a, "wall_s", stiefel)
    a.set_xlabel("integrator wall time (s); compilation excluded on both sides")
    a.set_title("(a) Stiefel-Scheifele, 50 revolutions: error against wall time", fontsize=9)
    draw(b, "n_steps", stiefel)
    b.set_xlabel("accepted steps (tetherlab: Runge-Kutta steps; heyoka: Taylor steps, whose\n"
                 "order grows as the tolerance tightens; not the same work per step)")  # fmt: skip
    b.set_title("(b) against steps: heyoka has no rhs evaluations to count", fontsize=9)
    a.legend(fontsize=6)
    from tetherlab.provenance import stamp_figure
    stamp_figure(fig, "studies/workprecision.py; references/stiefel/reference.json; heyoka taylor_adaptive (oracle)")
    fig.savefig(out / "work_precision_stiefel.png", dpi=110)
    plt.close(fig)


def libration_cases(rods=(1, 2, 4), duration="1 orbits"):
    from tetherlab.scene import load_scene

    base = load_scene(HERE / "scenes" / "libration-inplane.toml").replace(**{"duration": duration, "output.count": 11})
    cases = []
    for n in rods:
        sc = base.replace(**{"tethers.main.rods": n})
        cases.append(Case(f"libration n={n}", sc, with_integrator(sc, *REFERENCE)))
    return cases


def rod_axis_cases(rods=ROD_AXIS_RODS, duration="1 orbits", tols=None):
    """The rod-count axis: the damped libration scene at each n, radau5 (``newton = "auto"``:
    the structured Newton matrix from 4 rods on) against a radau5 reference at 1e-11 of the same n."""
    from tetherlab.scene import load_scene

    base = load_scene(HERE / "scenes" / "bench-libration.toml").replace(
        **{"duration": duration, "output.count": 2, "tethers.main.damping": ROD_AXIS_DAMPING})
    cases = []
    for n in rods:
        sc = base.replace(**{"tethers.main.rods": int(n)})
        cases.append(Case(f"{ROD_AXIS_PREFIX}{int(n)}", sc, with_integrator(sc, *ROD_AXIS_REFERENCE),
                          {"radau5": list(ROD_AXIS_TOLS if tols is None else tols)}))
    return cases


def _rods_of(case_label: str) -> int:
    return int(case_label[len(ROD_AXIS_PREFIX):])


def fit_exponent(ns, costs) -> float:
    """Least-squares slope of log(cost) on log(n) (NaN with fewer than two positive points)."""
    ns = np.asarray(ns, float)
    c = np.asarray(costs, float)
    ok = np.isfinite(c) & (c > 0)
    if ok.sum() < 2:
        return math.nan
    return float(np.polyfit(np.log(ns[ok]), np.log(c[ok]), 1)[0])


def rod_axis_tables(rows) -> list[str]:
    """Markdown: error and wall time at every (n, tol) of the rod axis, and per tolerance the
    fitted exponent of wall time (and of steps) against n: the speed table's trend over size."""
    pts = [r for r in rows if str(r["case"]).startswith(ROD_AXIS_PREFIX)]
    if not pts:
        return []
    ns = sorted({_rods_of(r["case"]) for r in pts})
    tols = sorted({r["tol"] for r in pts}, reverse=True)
    cell = {(_rods_of(r["case"]), r["tol"]): r for r in pts}
    md = ["### Rod count as an axis: damped libration, radau5 (structured Newton), one orbit", "",
          f"Each n against a radau5 run at {ROD_AXIS_REFERENCE[1]:g} of the same n (final body positions, m); D = "
          f"{ROD_AXIS_DAMPING}. Wall time = integration only. Error (m) / wall (s) at each rod count and tolerance; "
          "last columns: least-squares exponent of wall time and of accepted steps against n over the rods shown.", "",
          "| tol | " + " | ".join(f"n = {n}" for n in ns) + " | wall ~ n^p | steps ~ n^p |",
          "|---|" + "---|" * (len(ns) + 2)]
    for tol in tols:
        cells, walls, steps = [], [], []
        for n in ns:
            r = cell.get((n, tol))
            if r is None or not r["ok"]:
                cells.append("FAILED" if r is not None else "")
                walls.append(math.nan)
                steps.append(math.nan)
                continue
            cells.append(f"{r['error_m']:.2g} / {r['wall_s']:.3g}")
            walls.append(r["wall_s"])
            steps.append(r["n_steps"])
        md.append(f"| {_tol_str(tol)} | " + " | ".join(cells) +
                  f" | {fit_exponent(ns, walls):.2f} | {fit_exponent(ns, steps):.2f} |")
    return md + [""]


def rod_axis_figure(rows, out: Path) -> None:
    pts = [r for r in rows if str(r["case"]).startswith(ROD_AXIS_PREFIX) and r["ok"]]
    if not pts:
        return
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 5))
    ns = sorted({_rods_of(r["case"]) for r in pts})
    cmap = plt.get_cmap("viridis")
    for k, n in enumerate(ns):
        # joined in tolerance order (as the other figures): the wall time need not fall with it
        good = sorted((r for r in pts if _rods_of(r["case"]) == n and _finite_pos(r["error_m"])
                       and _finite_pos(r["wall_s"])), key=lambda r: -r["tol"])  # fmt: skip
        if good:
            ax.loglog([r["wall_s"] for r in good], [r["error_m"] for r in good], "o-", ms=4,
                      color=cmap(k / max(1, len(ns) - 1)), label=f"n = {n}")
    ax.set_xlabel("integrator wall time (s)")
    ax.set_ylabel(f"final position error (m) against radau5 {ROD_AXIS_REFERENCE[1]:g}, same n")
    ax.set_title("damped libration, radau5 (structured Newton), one orbit: rods as an axis", fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    from tetherlab.provenance import stamp_figure
    stamp_figure(fig, "studies/workprecision.py rod_axis_cases; studies/scenes/bench-libration.toml, D = 2e4 N s")
    fig.savefig(out / "work_precision_rods.png", dpi=110)
    plt.close(fig)


def stiefel_cases():
    """The Stiefel-Scheifele problem (paper 4.1), Cowell and DROMO, against the stored oracle
    (references/stiefel: heyoka binary128 and a decimal Taylor integrator agreeing to 2e-22 m).
    heyoka's own double-precision points are added by :func:`heyoka_stiefel_rows`."""
    from tetherlab.scene import load_scene

    truth = stiefel_truth()
    base = load_scene(HERE / "scenes" / "stiefel-scheifele.toml").replace(**{"output.count": 2})
    # Vern9 only here: its gain is at tight tolerances on smooth orbits (docs/integrators.md)
    native = {"dop853": TOLERANCES, "vern9": TOLERANCES, "radau5": TOLERANCES}
    return [
        Case("Stiefel cowell", base.replace(**{"integrator.formulation": "cowell"}), truth,
             {**native, "scipy:DOP853": [1e-6, 1e-8, 1e-10]}),
        # abm: constant-step Adams-Bashforth-Moulton, DROMO sigma form only (docs/integrators.md s8)
        Case("Stiefel dromo", base.replace(**{"integrator.formulation": "dromo"}), truth,
             {**native, "abm": TOLERANCES}),
        # the linear time element (docs/dromo.md section 11): pays on Example 1, not on this case;
        # on the axes so that a user sees both
        Case("Stiefel dromo+te", base.replace(**{"integrator.formulation": "dromo", "integrator.time_element": "linear"}),
             truth, {"vern9": TOLERANCES, "abm": TOLERANCES}),
    ]


def deorbit_day_cases():
    """One day of the electrodynamic de-orbit (n = 1), against a dop853 run at 1e-14.  The
    scene has a [stop] event, so only the native (event-locating) integrators run it."""
    from tetherlab.scene import load_scene

    sc = load_scene(HERE / "scenes" / "deorbit-ed.toml").replace(**{"duration": "1 d", "output.step": None, "output.count": 2})
    return [Case("de-orbit 1 d", sc, with_integrator(sc, *REFERENCE), {"dop853": TOLERANCES, "radau5": TOLERANCES})]


def _tol_str(tol: float) -> str:
    """'1e-10' for a power of ten, '2.22e-16' (the double epsilon) otherwise."""
    return f"{tol:.0e}" if abs(math.log10(tol) - round(math.log10(tol))) < 1e-9 else f"{tol:.3g}"


def report_md(rows, heyoka_note: str | None, quick: bool = False) -> str:
    """The study's Markdown section: how the points were made, the figures, every row."""
    h = [r for r in rows if r["method"] == HEYOKA_METHOD]
    title = ("## Work-precision (quick: libration n = 1, 2, a quarter orbit)" if quick else
             "## Work-precision: libration (n = 1, 2, 4), Stiefel-Scheifele (Cowell, DROMO, heyoka), one day of the de-orbit, "
             "damped libration at n = 4 ... 128 (rods as an axis)")
    md = [title, "",
          "Error = largest final position distance (m) to the reference: a run with "
          f"{REFERENCE[0]} at rtol = atol = {REFERENCE[1]:g} (libration, de-orbit day), or the "
          "extended-precision oracle of references/stiefel (Stiefel-Scheifele: heyoka binary128 and a decimal "
          "Taylor integrator, agreeing to 2e-22 m). Wall time = the integration alone, compilation excluded. "
          "Failed runs are listed with their error.", ""]
    if h:
        md += ["heyoka (oracle, double-precision taylor_adaptive, tolerances 1e-4 ... 1e-15 and the double "
               "epsilon, its accuracy floor) is on the Stiefel axes as case 'Stiefel heyoka'. Same error measure, "
               "same reference; its wall times were measured in this study like tetherlab's: through the same "
               "sweep machinery with the same number of worker processes (so with as many other runs beside it), "
               "one timed propagate_until after the integrator's construction (its JIT compilation) and a warm-up "
               "propagation, as tetherlab's time starts after its kernels are compiled or loaded. A Taylor method "
               "makes no right-hand-side evaluations: heyoka is absent from the rhs figure and its rhs cell reads "
               "n/a; its Taylor steps are drawn against tetherlab's accepted steps in the separate panel (b) of "
               "the Stiefel figure. heyoka does not apply to the libration and de-orbit cases: they carry a "
               "tether, whose TMED equations exist only in tetherlab's kernels. Rows read from the sweep cache "
               "(column cached of the CSV) keep the wall time of the run that made them.", "",
               "What the two clocks cover (measured once on this machine, Stiefel at 1e-13): tetherlab's first run in a "
               "process takes 1-10 % longer than its repeats, heyoka's timed run follows a warm-up one. tetherlab's "
               "wall time for DROMO with dop853 covers the whole compiled loop, output-time search included "
               "(tetherlab/propagation/dromo.py, _clock_run); the Python set-up and output conversion around it "
               "(about 0.1 ms) is outside. With radau5 it covers the sigma pass only: the Newton search for the "
               "final time and its Python glue add a few dozen steps and about 15-20 % of wall time, so those "
               "points are that much optimistic against heyoka's whole propagate_until.", ""]
    elif heyoka_note:
        md += [f"**heyoka's points are absent:** {heyoka_note}", ""]
    md += ["![wall](work_precision_wall.png)", "", "![rhs](work_precision_rhs.png)", ""]
    rod_md = rod_axis_tables(rows)
    if rod_md:
        md += rod_md + ["![rods](work_precision_rods.png)", ""]
    if h:
        md += ["![stiefel](work_precision_stiefel.png)", ""]
    md += ["| case | method | tol | error (m) | wall (s) | rhs | steps |", "|---|---|---|---|---|---|---|"]
    for r in rows:
        if r["ok"]:
            rhs = "n/a (Taylor)" if r["method"] == HEYOKA_METHOD else f"{r['n_rhs']:.0f}"
            md.append(f"| {r['case']} | {r['method']} | {_tol_str(r['tol'])} | {r['error_m']:.3g} | {r['wall_s']:.3g} | "
                      f"{rhs} | {r['n_steps']:.0f} |")  # fmt: skip
        else:
            md.append(f"| {r['case']} | {r['method']} | {_tol_str(r['tol'])} | FAILED: {r['error']} | | | |")
    return "\n".join(md) + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out")
    ap.add_argument("--scheduler")
    ap.add_argument("--workers", type=int)
    ap.add_argument("--quick", action="store_true", help="n = 1, 2 only and 0.25 orbit (a smoke run; no heyoka)")
    ap.add_argument("--no-heyoka", action="store_true", help="leave out heyoka's Stiefel points")
    ap.add_argument("--quiet", action="store_true")
    ap.add_argument("--rods", type=int, nargs="*", default=list(ROD_AXIS_RODS),
                    help="rod counts of the rod axis (damped libration; none: leave the axis out)")
    args = ap.parse_args(argv)
    cases = (libration_cases((1, 2), "0.25 orbits") if args.quick else
             libration_cases() + stiefel_cases() + deorbit_day_cases() + rod_axis_cases(tuple(args.rods)))
    want_heyoka = not (args.quick or args.no_heyoka)
    note = heyoka_missing(args.scheduler) if want_heyoka else None
    rows = work_precision(cases, args.out, heyoka=want_heyoka, scheduler=args.scheduler, workers=args.workers,
                          progress=not args.quiet)  # fmt: skip
    md = report_md(rows, note, quick=args.quick)
    (Path(args.out) / "work_precision.md").write_text(md)
    print(md)
    # heyoka's rows are the oracle's: a failed one is reported, it does not fail tetherlab's study
    return 0 if all(r["ok"] for r in rows if r["method"] != HEYOKA_METHOD) else 1


if __name__ == "__main__":
    sys.exit(main())
