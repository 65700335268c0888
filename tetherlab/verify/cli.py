"""``python -m tetherlab.verify``: run the sections, assemble the report, enforce the gates."""

from __future__ import annotations

import argparse
import math
import sys
import time
import tomllib
from pathlib import Path

from ..report import table as _table_md
from .checkout import ROOT, require_checkout
from .controls import TOOTHLESS, matrix_md, mutation_summary
from .runner import _cores, idle_machine_wall_s, run_tasks, section_tasks
from .sections import CHECKS, FIGURE_SECTION, RETIRED, gate_section
from .studies import STUDIES

def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m tetherlab.verify", description=__doc__)
    ap.add_argument("--out", default=str(ROOT / "reports"))
    ap.add_argument("--only", nargs="*", help="run only these studies (names of studies/*.py)")
    ap.add_argument("--no-controls", action="store_true", help="skip the negative controls (mutation matrix)")
    ap.add_argument("--jobs", type=int, default=min(2, _cores()),
                    help="worker processes for the sections (default: 2, or 1 on a one-core machine)")
    args = ap.parse_args(argv)
    if args.jobs < 1:
        ap.error(f"--jobs: expected a positive integer, got {args.jobs}")
    try:
        require_checkout()
    except RuntimeError as exc:  # an installed tetherlab has no studies/ or references/
        ap.error(str(exc))
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    gates = tomllib.loads((ROOT / "references" / "gates.toml").read_text())
    t0 = time.perf_counter()
    tasks = section_tasks(args.only, args.no_controls)
    results = run_tasks(tasks, out, args.jobs, log=lambda *a, **k: print(*a, **{"flush": True, **k}))
    sections = {}  # id -> (title, rows, wall)
    values = {}
    section_failures = []
    for sid, title, _fn in CHECKS:
        r = results[f"check:{sid}"]
        rows = list(r["rows"])
        if r["error"]:
            rows.append({"case": f"SECTION FAILED: {r['error']}"})
            section_failures.append(f"section {sid} ({r['error']})")
        values.update(r["values"])
        sections[sid] = (title, rows, r["wall_s"])
    r = results["figures"]
    fig_rows, figs = list(r["rows"]), r.get("figures", [])
    if r["error"]:
        fig_rows.append({"case": f"SECTION FAILED: {r['error']}"})
        section_failures.append(f"figures ({r['error']})")
    study_sections, study_values, study_failures = [], {}, []
    for t in tasks:
        if t.startswith("study:"):
            r = results[t]
            if r["error"]:  # run_studies catches a study's own failure; this is a lost worker
                name = t.split(":", 1)[1]
                title = next(tt for tt, nm, *_ in STUDIES if nm == name)
                study_sections.append((name, title, f"**Study failed:** `{r['error']}`", r["wall_s"]))
                study_failures.append(name)
                continue
            study_sections += r["studies"]
            study_values.update(r["values"])
            study_failures += r["failures"]
    values.update(study_values)

    control_rows, cells, by_defect, by_gate = [], {}, {}, {}
    if not args.no_controls:
        r = results["controls"]
        control_rows, cells = list(r["rows"]), r.get("cells", {})
        if r["error"]:
            control_rows.append({"defect": f"SECTION FAILED: {r['error']}"})
            section_failures.append(f"negative controls ({r['error']})")
        by_defect, by_gate, mvals = mutation_summary(cells, gates, study_values)
        if not r["error"]:
            values.update(mvals)

    gate_rows = []
    failed = []
    partial = args.only is not None or args.no_controls
    for gid, g in gates.items():
        val = values.get(gid)
        ok = val is not None and val <= g["threshold"]
        skipped = val is None and partial  # a partial run (--only, --no-controls) does not fail them
        if not ok and not skipped:
            failed.append(gid)
        gate_rows.append({"gate": gid, "value": val if val is not None else "not measured",
                          "threshold": g["threshold"], "unit": g["unit"],
                          "result": "PASS" if ok else ("SKIPPED" if skipped else "FAIL")})  # fmt: skip
    failed += [f"study {name} (crashed)" for name in study_failures] + section_failures
    with open(out / "gates.csv", "w") as f:
        f.write("gate,value,threshold,unit,result\n")
        for r in gate_rows:
            f.write(f"{r['gate']},{r['value']},{r['threshold']},{r['unit']},{r['result']}\n")
    with open(out / "sections.csv", "w") as f:  # where the time went (order and workers vary; results do not)
        f.write("section,wall_s,cpu_s,worker_pid,result\n")
        for t in tasks:
            r = results[t]
            f.write(f"{t},{r['wall_s']:.1f},{r.get('cpu_s', math.nan):.1f},{r.get('pid', '')},"
                    f"{'FAILED' if r['error'] else 'ok'}\n")
    wall = time.perf_counter() - t0
    cpu = sum(r.get("cpu_s", math.nan) for r in results.values())
    print(f"sections: {cpu:.0f} s of CPU; on {args.jobs} idle core(s), longest first: about "
          f"{idle_machine_wall_s(results, args.jobs):.0f} s (measured wall {wall:.0f} s; OUT/sections.csv)", flush=True)

    from .. import report
    from ..provenance import footer, git_commit

    doc = report.Document(
        gates=gates, gate_rows=gate_rows, sections=sections, figures=figs, figure_rows=fig_rows,
        figure_section=FIGURE_SECTION, studies=study_sections, controls=(control_rows, cells, by_defect, by_gate),
        toothless=TOOTHLESS, retired=RETIRED, gate_section=gate_section, wall_s=wall, commit=git_commit(),
        footer=footer(), matrix_md=matrix_md(cells, gates, by_defect, by_gate) if cells else "",
        descriptions={sid: fn.__doc__ for sid, _title, fn in CHECKS},
    )  # fmt: skip
    md = doc.markdown()
    (out / "index.md").write_text(md)
    (out / "index.html").write_text(report.render_html(md, title="tetherlab verification report"))
    print(_table_md([{k: r[k] for k in ("gate", "value", "threshold", "unit", "result")} for r in gate_rows]))
    print(f"\nreport: {out / 'index.html'}  ({wall:.0f} s)")
    if failed:
        print(f"FAILED gates: {', '.join(failed)}", file=sys.stderr)
        return 1
    return 0

