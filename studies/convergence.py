"""Rod-count convergence study: runs studies/convergence.toml as sweeps, writes OUTDIR/.

    PYTHONPATH=. python studies/convergence.py OUTDIR [--max-rods N] [--scheduler tcp://...] [--workers N]

For each case and quantity: the values against n, the Richardson estimate of the converged
value and the observed order from the three finest successful points (tetherlab.richardson),
the order from every three consecutive counts, |a_n - estimate| on a log-log figure, a CSV per
case (every run, with its cost and any error), OUTDIR/convergence.csv (every value) and a
Markdown section (OUTDIR/convergence.md).  All cases go through one pool of workers, largest rod
counts first.  Runs are cached in OUTDIR/cache: an interrupted study resumes.  Failed runs are
listed with their message, never dropped silently.  The run settings of each case, and the
measurements that justify them, are in studies/convergence.toml.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROD_KEY = "tethers.main.rods"


def first_lateral_shape(base, point):
    """Lay the rods on the first lateral mode of a string: rod i (of n) at angle
    a cos(pi (i - 1/2) / n) from the local vertical, a = 0.1 rad.

    The slope of w(s) = A sin(pi s / L) is proportional to cos(pi s / L); sampled at the rod
    midpoints s_i = (i - 1/2) L / n it sums to zero over the rods, so the tip starts on the
    vertical through the root and only the lateral mode (not the libration) is excited at
    first order.
    """
    n = int(point[ROD_KEY])
    a = 0.1
    theta = [f"{a * math.cos(math.pi * (i + 0.5) / n)!r} rad" for i in range(n)]
    return {"tethers.main.initial.theta": theta, "tethers.main.initial.phi": ["0 rad"] * n}


def analyse(case, res):
    """Rows of the convergence table for every quantity of one case."""
    from tetherlab.richardson import observed_order, richardson

    ok = sorted((r for r in res.records if r.ok), key=lambda r: r.params[ROD_KEY])
    out = []
    for q in case.quantities:
        ns = [r.params[ROD_KEY] for r in ok]
        vals = [r.summary[q] for r in ok]
        est = richardson(ns, vals) if len(ns) >= 3 else {"order": math.nan, "limit": math.nan,
                                                          "error_estimate": math.nan}
        # the order from every three consecutive counts (NaN for the first two): shows where the
        # sequence enters its asymptotic range, and where it leaves it for round-off
        local = [math.nan, math.nan][: len(ns)] + [
            observed_order(vals[i - 2], vals[i - 1], vals[i], ns[i] / ns[i - 1]) for i in range(2, len(ns))
        ]
        out.append({"quantity": q, "ns": ns, "values": vals, "local_orders": local, **est,
                    "wall_s": [r.wall_s for r in ok]})  # the whole run in its worker: set-up, integration, summary
    return out


def quantity_table(case, a) -> list[str]:
    """Markdown table of one quantity against n: value, difference to the previous count, the
    order from the last three counts, wall time."""
    lines = [f"{a['quantity']} against n:", "",
             "| n | value | a_n - a_n/2 | order from n/4, n/2, n | wall (s) |", "|---|---|---|---|---|"]
    for i, (n, v, p, w) in enumerate(zip(a["ns"], a["values"], a["local_orders"], a["wall_s"])):
        diff = f"{v - a['values'][i - 1]:.3g}" if i > 0 else ""
        order = f"{p:.3f}" if math.isfinite(p) else ("" if i < 2 else "NaN")
        lines.append(f"| {n} | {v:.13g} | {diff} | {order} | {w:.3g} |")
    return lines + [""]


def fit_exponent(ns, costs) -> float:
    """Least-squares slope of log(cost) on log(n) (NaN with fewer than two positive points)."""
    pts = [(math.log(n), math.log(c)) for n, c in zip(ns, costs) if c is not None and math.isfinite(c) and c > 0]
    if len(pts) < 2:
        return math.nan
    mx = sum(x for x, _ in pts) / len(pts)
    my = sum(y for _, y in pts) / len(pts)
    sxx = sum((x - mx) ** 2 for x, _ in pts)
    return sum((x - mx) * (y - my) for x, y in pts) / sxx if sxx > 0 else math.nan


def cost_table(study, results, min_n: int = 8) -> list[str]:
    """Markdown: each case's run wall time (set-up, integration and summary in the worker) and
    integration steps against n, with the fitted exponent of the wall time over n >= min_n (below
    that the fixed set-up costs dominate)."""
    ns = sorted({r.params[ROD_KEY] for c in study.cases for r in results[c.id].records})
    lines = ["Cost of each run against the rod count (wall s, whole run in its worker: set-up with the "
             "equilibrium solve, integration, summary; steps in brackets), and the least-squares exponent "
             f"of wall time against n over n >= {min_n}:", "",
             "| case | " + " | ".join(f"n = {n}" for n in ns) + f" | wall ~ n^p (n >= {min_n}) |",
             "|---|" + "---|" * (len(ns) + 1)]
    for case in study.cases:
        recs = {r.params[ROD_KEY]: r for r in results[case.id].records}
        cells, fit_n, fit_w = [], [], []
        for n in ns:
            r = recs.get(n)
            if r is None:
                cells.append("")
            elif not r.ok:
                cells.append("failed")
            else:
                steps = r.summary.get("n_steps", math.nan)
                cells.append(f"{r.wall_s:.3g} ({steps:.0f})")
                if n >= min_n:
                    fit_n.append(n)
                    fit_w.append(r.wall_s)
        p = fit_exponent(fit_n, fit_w)
        lines.append(f"| {case.id} | " + " | ".join(cells) + f" | {p:.2f} |")
    return lines + [""]


def figure(case, analysis, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(5.5, 4))
    for a in analysis:
        if not math.isfinite(a["limit"]):
            continue
        pts = [(n, abs(v - a["limit"])) for n, v in zip(a["ns"], a["values"]) if abs(v - a["limit"]) > 0]
        if pts:
            ax.loglog(*zip(*pts), "o-", label=f"{a['quantity']} (p = {a['order']:.2f})")
    ax.set_xlabel("rods n")
    ax.set_ylabel("|value - Richardson estimate|")
    ax.set_title(case.id)
    ax.grid(True, which="both", alpha=0.3)
    if ax.lines:
        ax.legend(fontsize=8)
    from tetherlab.provenance import stamp_figure
    stamp_figure(fig, "studies/convergence.py, studies/convergence.toml; Richardson estimate (tetherlab/richardson.py)")
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv=None) -> int:
    import time

    from tetherlab.sweep import load_study, run_cases

    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out", help="output directory")
    ap.add_argument("--max-rods", type=int, help="largest rod count (default: [options] max_rods of the study)")
    ap.add_argument("--scheduler", help="Dask scheduler address; default: local processes")
    ap.add_argument("--workers", type=int)
    ap.add_argument("--quiet", action="store_true")
    args = ap.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    study = load_study(HERE / "convergence.toml")
    max_rods = args.max_rods or int(study.options.get("max_rods", 64))
    t0 = time.perf_counter()
    # Every case through one pool, largest rod counts first: the n = 64 libration run takes most
    # of the study's time, and the other runs fill the other workers meanwhile.
    results = run_cases(study, None, out, scheduler=args.scheduler, workers=args.workers, progress=not args.quiet,
                        filter_point=lambda case, p: p[ROD_KEY] <= max_rods, first=lambda case, p: p[ROD_KEY])
    wall = time.perf_counter() - t0
    md = [f"## Rod-count convergence (n <= {max_rods})", "", study.description, "",
          "Richardson estimate and observed order p from the three finest successful points "
          "(tetherlab/richardson.py); 'NaN' when those points do not converge monotonically.  The "
          "tables below give the order from every three consecutive counts.  Why each case runs as it "
          "does (start, tolerance, duration), with the measurements behind it: studies/convergence.toml.",
          "", "| case | quantity | finest n | Richardson estimate | p | error estimate of finest |",
          "|---|---|---|---|---|---|"]
    failures, table, sections = [], [], []
    for case in study.cases:
        res = results[case.id]
        analysis = analyse(case, res)
        figure(case, analysis, out / f"convergence-{case.id}.png")
        for r in res.failed:
            failures.append(f"- {case.id}, {r.label}: `{r.error}`")
        sections += [f"### {case.id}", "", case.description + ".", ""]
        for a in analysis:
            md.append(f"| {case.id} | {a['quantity']} | {', '.join(map(str, a['ns'][-3:]))} | "
                      f"{a['limit']:.13g} | {a['order']:.3f} | {a['error_estimate']:.3g} |")
            sections += quantity_table(case, a)
            for n, v, p, w in zip(a["ns"], a["values"], a["local_orders"], a["wall_s"]):
                table.append(f"{case.id},{a['quantity']},{n},{v!r},{p!r},{a['limit']!r},{a['order']!r},{w!r}")
    (out / "convergence.csv").write_text("case,quantity,rods,value,order_from_last_three,richardson_estimate,"
                                         "observed_order,wall_s\n" + "\n".join(table) + "\n")
    md += ["", *sections, *cost_table(study, results),
           f"Study wall time {wall:.0f} s (runs cached in the output's cache/ are not rerun).", "",
           "Figures (|value - Richardson estimate| against n):", "",
           *(f"![{c.id}](convergence-{c.id}.png)" for c in study.cases), ""]
    if failures:
        md += ["Failed runs (kept in the per-case CSV with their message):", ""] + failures + [""]
    (out / "convergence.md").write_text("\n".join(md))
    print("\n".join(md))
    return 0


if __name__ == "__main__":
    sys.exit(main())
