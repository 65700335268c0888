"""A table like the paper's Figure 3 for the Stiefel-Scheifele case (paper section 4.1).

    python studies/stiefel_table.py OUTDIR

For each formulation (Cowell, DROMO sigma form), integrator (dop853, vern9, radau5) and tolerance
1e-4 ... 1e-13 (rtol = atol): the final-position error against references/stiefel/reference.json
and the mean accepted steps per orbit (50 orbits; for DROMO the sigma pass, with the steps of the
final-time search in their own column), beside heyoka's double-precision rows stored in the same
JSON (built by references/stiefel/build_reference.py).  Writes stiefel_table.csv,
stiefel_table.md and stiefel_table.png (log-log error against steps per orbit).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from tetherlab.benchmarks.stiefel import N_ORBITS, REFERENCE, reference_position_m, runner  # noqa: E402

TOLS = tuple(10.0**-k for k in range(4, 14))
#: ("dromo", "abm"): the constant-step Adams-Bashforth-Moulton method (2 rhs calls a step, against
#: 12 for DOP853 and 16 for Vern9: compare its n_rhs, not its steps; docs/integrators.md section 8)
CASES = (("cowell", "dop853"), ("cowell", "vern9"), ("cowell", "radau5"), ("dromo", "dop853"),
         ("dromo", "vern9"), ("dromo", "radau5"), ("dromo", "abm"))
#: Example 1 (J2 only, references/stiefel/example1.json): the sigma form with tau and with the linear time
#: element ("dromo+te", docs/dromo.md section 11), rows "ex1 tetherlab ..."; the gate
#: stiefel_example1_te_error reads the dromo+te abm row at 1e-11 (tetherlab/verify/studies.py, _stiefel_gates)
EX1_CASES = (("dromo", "vern9"), ("dromo+te", "vern9"), ("dromo+te", "abm"))
EX1_TOLS = tuple(10.0**-k for k in range(8, 14))


def _row(case: str, form: str, method: str, tol: float, ref) -> dict:
    """One run's table row ("who" prefixed with "ex1 " for Example 1)."""
    try:
        r, st = runner(form, method, tol, case)()
        err = float(np.linalg.norm(r - ref))
    except Exception as exc:  # a failed run is a table entry, not a crash of the study
        st, err = {}, float("nan")
        print(f"{case} {form} {method} {tol:.0e}: failed: {exc}", file=sys.stderr)
    row = {
        "who": ("ex1 " if case == "ex1" else "") + f"tetherlab {form} {method}", "tol": tol,
        "final_position_error_m": err, "mean_steps_per_orbit": st.get("n_accepted", 0) / N_ORBITS,
        "search_steps": st.get("search_n_accepted", 0), "n_rhs": st.get("n_rhs", 0),
    }  # fmt: skip
    print(f"{case} {form:8s} {method:7s} {tol:.0e} err {err:.3e} m  steps/orbit {row['mean_steps_per_orbit']:.1f}  "
          f"rhs {row['n_rhs']}", flush=True)  # fmt: skip
    return row


def rows() -> list[dict]:
    ref = reference_position_m()
    out = [_row("ex2", form, method, tol, ref) for form, method in CASES for tol in TOLS]
    ref1 = reference_position_m("ex1")
    out += [_row("ex1", form, method, tol, ref1) for form, method in EX1_CASES for tol in EX1_TOLS]
    ref_json = json.loads(REFERENCE.read_text())
    for h in ref_json["heyoka_double"]["rows"]:
        out.append({"who": "heyoka double (stored)", "tol": h["tol"],
                    "final_position_error_m": h["final_position_error_m"],
                    "mean_steps_per_orbit": h["mean_steps_per_orbit"], "search_steps": 0,
                    "n_rhs": ""})  # fmt: skip
    return out


def footer() -> str:
    from tetherlab.provenance import footer as provenance

    return (f"{provenance()}; reference: references/stiefel/reference.json (heyoka binary128 + decimal "
            "Taylor); heyoka rows: the same file, heyoka_double")  # fmt: skip


def write(outdir: Path, table: list[dict]) -> None:
    import pandas as pd

    outdir.mkdir(parents=True, exist_ok=True)
    df = pd.DataFrame(table)
    df.to_csv(outdir / "stiefel_table.csv", index=False)
    wide_err = df.pivot(index="tol", columns="who", values="final_position_error_m").sort_index(ascending=False)
    wide_steps = df.pivot(index="tol", columns="who", values="mean_steps_per_orbit").sort_index(ascending=False)
    lines = ["# Stiefel-Scheifele: final-position error [m] / mean steps per orbit (paper Figure 3 analogue)", "",
             "| tol | " + " | ".join(wide_err.columns) + " |", "|---|" + "---|" * len(wide_err.columns)]  # fmt: skip
    for tol in wide_err.index:
        cells = [f"{wide_err.loc[tol, c]:.3g} / {wide_steps.loc[tol, c]:.0f}" for c in wide_err.columns]
        lines.append(f"| {tol:.0e} | " + " | ".join(cells) + " |")
    lines += ["", "![stiefel](stiefel_table.png)", "", "DROMO: sigma form; steps are the sigma pass.  The output search adds to it (column "
              "search_steps of the CSV): with DOP853 one landing step per output (an event on tau in the "
              "compiled loop), with RADAU5 a Newton search of a few dozen steps.  DROMO abm: constant-step "
              "Adams-Bashforth-Moulton, 2 rhs calls a step (12 for DOP853, 16 for Vern9): compare n_rhs in "
              "the CSV; docs/integrators.md section 8.  Columns \"ex1 ...\": Stiefel & Scheifele's Example 1 (J2 only, "
              "286.8 d) against references/stiefel/example1.json, tolerances 1e-8 ... 1e-13 only; dromo+te: the "
              "linear time element (docs/dromo.md section 11).", "", footer(), ""]  # fmt: skip
    (outdir / "stiefel_table.md").write_text("\n".join(lines))

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 5))
    for who, g in df.groupby("who"):
        g = g.sort_values("tol", ascending=False)
        ax.loglog(g["mean_steps_per_orbit"], g["final_position_error_m"], "o-", label=who)
    ax.axhline(1.0, color="gray", lw=0.5)
    ax.set_xlabel("mean steps per orbit")
    ax.set_ylabel("final position error [m]")
    ax.set_title("Stiefel-Scheifele, 50 orbits (tol 1e-4 ... 1e-13)")
    ax.legend(fontsize=8)
    from tetherlab.provenance import stamp_figure
    stamp_figure(fig, "studies/stiefel_table.py; references/stiefel/reference.json (heyoka binary128 + decimal Taylor)")
    fig.savefig(outdir / "stiefel_table.png", dpi=120)


def main(argv: list[str]) -> int:
    if len(argv) != 1:
        print("usage: python studies/stiefel_table.py OUTDIR", file=sys.stderr)
        return 2
    write(Path(argv[0]), rows())
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
