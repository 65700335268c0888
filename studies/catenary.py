"""Catenary (paper section 4.2): TMED statics against Irvine's elastic catenary, n = 1 ... 64 rods.

For every rod count n the static equilibrium of the tether between the fixed nail and the held end
mass is solved on the compiled model (tetherlab.statics) and compared with the analytic elastic
catenary of references/catenary/reference.json (built by references/catenary/build_reference.py,
no tetherlab code):

* shape: the largest distance of the joints from the analytic curve (the primary measure; the two
  end joints lie on it by construction, so n = 1 has zero error), the same over joints and rod
  centres, and the largest distance of joint k from the material point s_k = k L0 / n;
* tension at both ends (|J_0|, |J_n| against T(0), T(L0)) and the largest error of the rods'
  axial forces F_e against T at the rod midpoints;
* end reactions: the nail's force on the tether (J_0) and the holding force R_f on the end mass,
  as vector errors.

The observed order is the slope of a least-squares fit of log(error) on log(n) over n = 4 ... 64.
Writes OUTDIR/catenary.csv, catenary.png, catenary.md.  Run (about 15 s after compilation):

    PYTHONPATH=. python studies/catenary.py reports/catenary
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

import numpy as np

from tetherlab.forces import uniform_gravity
from tetherlab.statics import held_model, solve
from tetherlab.system import TetherSpec

ROOT = Path(__file__).resolve().parent.parent
REFERENCE = ROOT / "references" / "catenary" / "reference.json"
ROD_COUNTS = (1, 2, 4, 8, 16, 32, 64)
FIT_FROM = 4  # smallest n in the slope fit (n = 1, 2 are pre-asymptotic: one and two straight rods)
ERRORS = (
    "shape_joints_m",
    "shape_points_m",
    "material_m",
    "tension_A_N",
    "tension_B_N",
    "axial_force_N",
    "nail_force_N",
    "holding_force_N",
)


def load_reference(path: Path = REFERENCE) -> dict:
    return json.loads(Path(path).read_text())


def distance_to_curve(points: np.ndarray, curve: np.ndarray) -> np.ndarray:
    """Distance of each point (k, 3) from the polyline through ``curve`` (m, 3)."""
    a = curve[:-1]
    ab = curve[1:] - a
    ab2 = np.einsum("ij,ij->i", ab, ab)
    out = np.empty(len(points))
    for k, pt in enumerate(points):
        t = np.clip(np.einsum("ij,ij->i", pt - a, ab) / ab2, 0.0, 1.0)
        out[k] = np.sqrt(np.min(np.sum((a + t[:, None] * ab - pt) ** 2, axis=1)))
    return out


def solve_case(ref: dict, n: int, model: str = "paper"):
    c = ref["case"]
    spec = TetherSpec(
        "main", n, c["L0_m"], c["EA_N"], c["tether_mass_kg"], model=model,
        tip_mass_kg=c["end_mass_kg"], tip_name="mf",
    )
    held = held_model(spec, [(uniform_gravity.SPEC, {"g": c["g_m_s2"]})])
    return solve(held, [0.0, 0.0, 0.0], [c["span_m"], 0.0, c["height_m"]])


def compare(ref: dict, eq) -> dict:
    """Errors of one TMED equilibrium against the analytic catenary (absolute, SI units)."""
    smp = ref["samples"]
    sol = ref["solution"]
    s = np.asarray(smp["s_m"])
    x = np.asarray(smp["x_m"])
    z = np.asarray(smp["z_m"])
    tension = np.asarray(smp["tension_N"])
    curve = np.column_stack([x, np.zeros_like(x), z])
    n = len(eq.axial_force_N)
    L0 = ref["case"]["L0_m"]
    sk = np.linspace(0.0, L0, n + 1)
    material = np.column_stack([np.interp(sk, s, x), np.zeros(n + 1), np.interp(sk, s, z)])
    smid = (np.arange(n) + 0.5) * L0 / n
    tn = eq.tension_N
    return {
        "shape_joints_m": float(distance_to_curve(eq.joints_m, curve).max()),
        "shape_points_m": float(distance_to_curve(np.vstack([eq.joints_m, eq.centres_m]), curve).max()),
        "material_m": float(np.linalg.norm(eq.joints_m - material, axis=1).max()),
        "tension_A_N": float(abs(tn[0] - sol["tension_A_N"])),
        "tension_B_N": float(abs(tn[-1] - sol["tension_B_N"])),
        "axial_force_N": float(np.abs(eq.axial_force_N - np.interp(smid, s, tension)).max()),
        "nail_force_N": float(np.linalg.norm(eq.nail_force_N - np.asarray(sol["nail_force_on_tether_N"]))),
        "holding_force_N": float(np.linalg.norm(eq.holding_force_N - np.asarray(sol["holding_force_on_end_mass_N"]))),
    }


def observed_order(ns, errors, n_min: int = FIT_FROM) -> float:
    """Minus the slope of log(error) against log(n), least squares over n >= n_min."""
    ns = np.asarray(ns, float)
    err = np.asarray(errors, float)
    keep = (ns >= n_min) & (err > 0)
    slope = np.polyfit(np.log(ns[keep]), np.log(err[keep]), 1)[0]
    return float(-slope)


def run(ref: dict, ns=ROD_COUNTS, models=("paper", "energy")) -> list[dict]:
    rows = []
    for model in models:
        for n in ns:
            eq = solve_case(ref, n, model)
            rows.append({
                "model": model, "n": n, **compare(ref, eq),
                "residual_N": eq.residual_N, "iterations": eq.iterations,
                "tension_A_value_N": float(eq.tension_N[0]), "H_value_N": float(-eq.nail_force_N[0]),
            })
    return rows


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("outdir", type=Path)
    args = ap.parse_args(argv)
    out = args.outdir
    out.mkdir(parents=True, exist_ok=True)
    ref = load_reference()
    rows = run(ref)
    import pandas as pd

    df = pd.DataFrame(rows)
    df.to_csv(out / "catenary.csv", index=False)
    orders = {
        m: {e: observed_order(g["n"], g[e]) for e in ERRORS} for m, g in df.groupby("model", sort=False)
    }

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(15, 4.5))
    smp = ref["samples"]
    ax = axes[0]
    ax.plot(smp["x_m"], smp["z_m"], "k-", lw=1, label="Irvine (analytic)")
    for n, mk in ((1, "s--"), (2, "^--"), (4, "o--")):
        eq = solve_case(ref, n)
        ax.plot(eq.joints_m[:, 0], eq.joints_m[:, 2], mk, ms=4, lw=0.8, label=f"TMED n = {n} (joints)")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("z (m)")
    ax.set_aspect("equal")
    ax.legend(fontsize=8)
    ax.set_title("Shape")
    ax = axes[1]
    eq = solve_case(ref, 8)
    ax.plot(smp["s_m"], smp["tension_N"], "k-", lw=1, label="Irvine T(s)")
    L0 = ref["case"]["L0_m"]
    ax.plot(np.linspace(0, L0, 9), eq.tension_N, "o", label="TMED n = 8 |J_k| (joints)")
    ax.plot((np.arange(8) + 0.5) * L0 / 8, eq.axial_force_N, "x", label="TMED n = 8 F_e (rods)")
    ax.set_xlabel("unstretched arc s (m)")
    ax.set_ylabel("tension (N)")
    ax.legend(fontsize=8)
    ax.set_title("Tension along the tether")
    ax = axes[2]
    g = df[(df.model == "paper") & (df.n >= 2)]  # n = 1: the end joints only, on the curve exactly
    for e, mk in zip(ERRORS, "osd^v<>p"):
        unit = "m" if e.endswith("_m") else "N"
        ax.loglog(g["n"], g[e].where(g[e] > 0), mk + "-", ms=4, label=f"{e} ({unit})")
    nn = np.array([4, 64])
    ax.loglog(nn, 0.5 * g[g.n == 4]["shape_joints_m"].iloc[0] * (nn / 4.0) ** -2, "k:", label="slope -2")
    ax.set_xlabel("rods n")
    ax.set_ylabel("error")
    ax.legend(fontsize=7)
    ax.set_title("Error against Irvine (paper model)")
    from tetherlab.provenance import stamp_figure
    stamp_figure(fig, "studies/catenary.py; references/catenary (Irvine's elastic catenary)")
    fig.savefig(out / "catenary.png", dpi=120)

    sol = ref["solution"]
    c = ref["case"]
    lines = [
        "## Catenary (paper section 4.2)",
        "",
        f"Nail at the origin, end mass held at ({c['span_m']} m, 0, {c['height_m']} m); L0 = {c['L0_m']} m, "
        f"EA = {c['EA_N']} N, tether mass {c['tether_mass_kg']} kg, end mass {c['end_mass_kg']} kg, "
        f"g = {c['g_m_s2']} m/s2 along -z.  Oracle: Irvine's elastic catenary "
        f"(references/catenary/reference.json): H = {sol['H_N']:.9f} N, T(0) = T(L0) = {sol['tension_A_N']:.9f} N, "
        f"sag {-sol['lowest_point_m'][2]:.6f} m.  TMED: tetherlab.statics (Newton on the compiled accelerations).",
        "",
        "Errors (absolute; m or N):",
        "",
        "| model | n | " + " | ".join(ERRORS) + " | residual_N |",
        "|---|---|" + "---|" * (len(ERRORS) + 1),
    ]
    for r in rows:
        lines.append(f"| {r['model']} | {r['n']} | " + " | ".join(f"{r[e]:.3e}" for e in ERRORS) + f" | {r['residual_N']:.1e} |")
    lines += ["", f"Observed order (slope fit, n = {FIT_FROM} ... 64):", "", "| model | " + " | ".join(ERRORS) + " |",
              "|---|" + "---|" * len(ERRORS)]
    for m, o in orders.items():
        lines.append(f"| {m} | " + " | ".join(f"{o[e]:.2f}" for e in ERRORS) + " |")
    lines += ["", "![catenary](catenary.png)", ""]
    (out / "catenary.md").write_text("\n".join(lines))
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
