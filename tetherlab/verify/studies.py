"""The studies verify runs (scripts of the checkout's studies/ package that write OUTDIR/<name>.md,
CSV and PNG) and the readers of their gates."""

from __future__ import annotations

import json
import math
import re
import time
from pathlib import Path

import numpy as np

from ..report import table as _table_md
from .checks import EXAMPLE1_TE_RUN
from .checkout import load_study


def catenary_values(df, rows_out=None) -> dict:
    """The catenary gates from the study's table (paper model): the n = 64 errors in units of
    their Richardson estimate |e(32) - e(64)| / (2^2 - 1) (order 2, docs/catenary.md), and the
    observed order."""
    mod = load_study("catenary")
    paper = df[df.model == "paper"].sort_values("n")
    last, prev = paper.iloc[-1], paper.iloc[-2]
    def worst(cols):
        w = 0.0
        for c in cols:
            est = abs(float(prev[c]) - float(last[c])) / 3.0
            ratio = float(last[c]) / est if est > 0 else math.inf
            if rows_out is not None:
                rows_out.append({"case": f"catenary {c}, n = {int(last.n)} (paper model)", "error": float(last[c]),
                                 "Richardson estimate |e(n/2) - e(n)|/3": est, "error / estimate": ratio})  # fmt: skip
            w = max(w, ratio)
        return w

    out = {
        "catenary_shape_n64": worst(("shape_joints_m",)),
        "catenary_tension_n64": worst(("tension_A_N", "tension_B_N", "holding_force_N", "nail_force_N")),
    }
    order = mod.observed_order(paper["n"], paper["shape_joints_m"])
    out["catenary_order_deviation"] = abs(order - 2.0)
    return out


def _catenary_gates(outdir: Path) -> dict:
    import pandas as pd

    return catenary_values(pd.read_csv(outdir / "catenary.csv"))


def check_catenary_probe(rows_out):
    """The catenary study's paper-model rows n = 4 ... 64 (its gates), without figures."""
    import pandas as pd

    mod = load_study("catenary")
    df = pd.DataFrame(mod.run(mod.load_reference(), ns=(4, 8, 16, 32, 64), models=("paper",)))
    return catenary_values(df, rows_out)


def _stiefel_gates(outdir: Path) -> dict:
    import pandas as pd

    df = pd.read_csv(outdir / "stiefel_table.csv")
    best = {who: float(g["final_position_error_m"].min()) for who, g in df.groupby("who")}
    form, method, tol = EXAMPLE1_TE_RUN
    ex1 = df[(df["who"] == f"ex1 tetherlab {form} {method}") & (np.isclose(df["tol"], tol, rtol=1e-9, atol=0.0))]
    return {
        "stiefel_cowell_best_error": min(v for k, v in best.items() if k.startswith("tetherlab cowell")),
        "stiefel_dromo_best_error": min(v for k, v in best.items() if k.startswith("tetherlab dromo")),
        # a missing row (the study did not run it) fails the gate
        "stiefel_example1_te_error": float(ex1["final_position_error_m"].iloc[0]) if len(ex1) else math.inf,
    }


def _deorbit_gates(outdir: Path) -> dict:
    runs = json.loads((outdir / "deorbit_summary.json").read_text())["runs"]
    n1 = runs[0]
    out = {"deorbit_n1_vs_paper": abs(n1["vs_paper_rel"]), "deorbit_n1_vs_closed_form": abs(n1["vs_closed_form_rel"])}
    n4 = [r for r in runs if r.get("label", "").startswith("n=4")]
    if n4:
        out["deorbit_n4_vs_n1"] = abs(n4[0]["deorbit_days"] / n1["deorbit_days"] - 1.0)
    return out


def _hard_cases_gates(outdir: Path) -> dict:
    s = json.loads((outdir / "hard_cases_summary.json").read_text())
    control = s.get("negative_control_over_bound")
    return {
        "hard_cases_failed": float(s["failed"]),
        "hard_cases_invariant_over_bound": s["invariant_over_bound"],
        "hard_cases_convergence_score": s["convergence_score"],
        "hard_cases_floor_over_loose_change": s["floor_over_loose_change"],
        "hard_cases_collapse_stop_spread": s["stop_time_spread_s"],
        # the control must exceed its bound; the gate reads bound / measured (<= 1 passes)
        "hard_cases_negative_control": (1.0 / control) if control else math.inf,
        # n = 512 over an orbit (docs/verification.md 5), and its anti-damped control (inverted likewise)
        "hard_cases_n512_stability": s["n512_stability"] if s.get("n512_stability") is not None else math.inf,
        "hard_cases_n512_negative_control": _inverse(s.get("n512_control_stability")),
    }


def _inverse(v):
    """1 / a control's measurement (its gate passes when the control fails its bound); a control
    that did not run gives inf (fails), one that stopped (inf) gives 0."""
    return math.inf if v is None or v == 0 else 1.0 / v


def _rigid_bodies_gates(outdir: Path) -> dict:
    """Gates of studies/rigid_bodies.py (bounds in docs/rigid-oracles.md section 7).
    A part the build cannot run (no rigid bodies) leaves its gates None: "not measured"."""
    g = json.loads((outdir / "rigid_bodies_summary.json").read_text())["gates"]
    return {
        "hub_spoke_centre_tip_over_bound": g.get("hub_spoke_centre_tip_over_bound"),
        "hub_spoke_centre_tension_over_bound": g.get("hub_spoke_centre_tension_over_bound"),
        "hub_spoke_centre_order_deficit": g.get("hub_spoke_centre_order_deficit"),
        "hub_spoke_centre_negative_control": g.get("hub_spoke_centre_negative_control"),
        "hub_spoke_radius_tip_over_bound": g.get("hub_spoke_radius_tip_over_bound"),
        "hub_spoke_radius_tension_over_bound": g.get("hub_spoke_radius_tension_over_bound"),
        "hub_spoke_radius_order_deficit": g.get("hub_spoke_radius_order_deficit"),
        "hub_spoke_radius_defects_negative_control": g.get("hub_spoke_radius_defects_negative_control"),
        "torque_free_over_bound": g.get("torque_free_over_bound"),
        "torque_free_negative_control": g.get("torque_free_negative_control"),
        "torque_free_convergence": g.get("torque_free_convergence"),
        "gg_libration_frequency": g.get("gg_libration_frequency"),
        "gg_libration_negative_control": g.get("gg_libration_negative_control"),
        "wheel_exchange_over_bound": g.get("wheel_exchange_over_bound"),
        "wheels_tumbling_over_bound": g.get("wheels_tumbling_over_bound"),
        "untethered_bodies_over_bound": g.get("untethered_bodies_over_bound"),
        "conservation_tree_over_bound": g.get("conservation_tree_over_bound"),
    }


def _uncertainty_gates(outdir: Path) -> dict:
    """Gates of the uncertainty machinery (tetherlab/uncertainty/verification.py)."""
    g = json.loads((outdir / "uncertainty_gates.json").read_text())
    return {
        "uq_known_distribution_over_ci": g.get("uq_known_distribution_over_ci"),
        "uq_ci_coverage_floor_over_min": g.get("uq_ci_coverage_floor_over_min"),
        "uq_ci_coverage_negative_control": g.get("uq_ci_coverage_negative_control"),
        "uq_sobol_indices_over_ci": g.get("uq_sobol_indices_over_ci"),
        "uq_mc_slope_vs_half": g.get("uq_mc_slope_vs_half"),
        "uq_sobol_slope_steeper": g.get("uq_sobol_slope_steeper"),
        "uq_machinery_negative_controls": g.get("uq_machinery_negative_controls"),
    }


def _uncertainty_deorbit_gates(outdir: Path) -> dict:
    """Gates of the de-orbit study under uncertainty (tetherlab/uncertainty/verification_deorbit.py)."""
    g = json.loads((outdir / "uncertainty_deorbit_gates.json").read_text())
    return {
        "uq_deorbit_mean_vs_closed_form": g.get("uq_deorbit_mean_vs_closed_form"),
        "uq_deorbit_slope_vs_closed_form": g.get("uq_deorbit_slope_vs_closed_form"),
        "uq_deorbit_failed": g.get("uq_deorbit_failed"),
        "uq_deorbit_negative_controls": g.get("uq_deorbit_negative_controls"),
    }


def _deployment_gates(outdir: Path) -> dict:
    """Gates of studies/deployment.py (budgets in docs/deployment.md 8); a part that did not run
    leaves its gates None: "not measured"."""
    g = json.loads((outdir / "deployment_summary.json").read_text())["gates"]
    return {
        "deployment_momentum_over_bound": g.get("deployment_momentum_over_bound"),
        "deployment_angular_momentum_over_bound": g.get("deployment_angular_momentum_over_bound"),
        "deployment_energy_over_bound": g.get("deployment_energy_over_bound"),
        "deployment_birth_remap": g.get("deployment_birth_remap"),
        "deployment_retirement_momentum_over_bound": g.get("deployment_retirement_momentum_over_bound"),
        "deployment_retirement_angmom_over_bound": g.get("deployment_retirement_angmom_over_bound"),
        "deployment_retirement_linear_only_negative_control": g.get("deployment_retirement_linear_only_negative_control"),
        "deployment_exponential_angle_over_budget": g.get("deployment_exponential_angle_over_budget"),
        "deployment_exponential_tension_over_budget": g.get("deployment_exponential_tension_over_budget"),
        "deployment_retrieval_invariant": g.get("deployment_retrieval_invariant"),
        "deployment_rescaled_negative_control": g.get("deployment_rescaled_negative_control"),
        "deployment_no_ldot_negative_control": g.get("deployment_no_ldot_negative_control"),
        "deployment_frozen_negative_control": g.get("deployment_frozen_negative_control"),
        # part H: a reel on a spinning rigid hub (studies/deployment_hub.py, docs/deployment.md 9)
        "deployment_hub_angular_momentum_over_bound": g.get("deployment_hub_angular_momentum_over_bound"),
        "deployment_hub_momentum_over_bound": g.get("deployment_hub_momentum_over_bound"),
        "deployment_hub_energy_over_bound": g.get("deployment_hub_energy_over_bound"),
        "deployment_hub_exit_torque_negative_control": g.get("deployment_hub_exit_torque_negative_control"),
        "deployment_hub_centripetal_negative_control": g.get("deployment_hub_centripetal_negative_control"),
        "deployment_hub_axis_spin_over_bound": g.get("deployment_hub_axis_spin_over_bound"),
        "deployment_hub_ring_negative_control": g.get("deployment_hub_ring_negative_control"),
        # part P: hub-and-spoke under spool laws (studies/deployment_spoke.py, docs/deployment.md 9.5)
        "deployment_spoke_axis_spin_over_bound": g.get("deployment_spoke_axis_spin_over_bound"),
        "deployment_spoke_ring_full_negative_control": g.get("deployment_spoke_ring_full_negative_control"),
        "deployment_spoke_angular_momentum_over_bound": g.get("deployment_spoke_angular_momentum_over_bound"),
        "deployment_spoke_wheels_negative_control": g.get("deployment_spoke_wheels_negative_control"),
        "deployment_spoke_momentum_over_bound": g.get("deployment_spoke_momentum_over_bound"),
        "deployment_spoke_one_stored_negative_control": g.get("deployment_spoke_one_stored_negative_control"),
        # part R: a drum under a spool law on the hub (studies/deployment_hub.py, docs/deployment.md 9.7)
        "deployment_hub_drum_angular_momentum_over_bound": g.get("deployment_hub_drum_angular_momentum_over_bound"),
        "deployment_hub_drum_energy_over_bound": g.get("deployment_hub_drum_energy_over_bound"),
        "deployment_hub_drum_negative_control": g.get("deployment_hub_drum_negative_control"),
        "deployment_spool_drum_over_budget": g.get("deployment_spool_drum_over_budget"),
        "deployment_spool_energy_over_bound": g.get("deployment_spool_energy_over_bound"),
        "deployment_tension_roots_over_budget": g.get("deployment_tension_roots_over_budget"),
        "deployment_spool_uncoupled_negative_control": g.get("deployment_spool_uncoupled_negative_control"),
        "deployment_tension_k2_negative_control": g.get("deployment_tension_k2_negative_control"),
        # part M: the spool limits (studies/reel_limits.py, docs/deployment.md 10.4)
        "deployment_limits_torque_over_budget": g.get("deployment_limits_torque_over_budget"),
        "deployment_limits_speed_over_budget": g.get("deployment_limits_speed_over_budget"),
        "deployment_limits_balance_over_bound": g.get("deployment_limits_balance_over_bound"),
        "deployment_limits_energy_over_bound": g.get("deployment_limits_energy_over_bound"),
        "deployment_limits_torque_unlimited_negative_control": g.get("deployment_limits_torque_unlimited_negative_control"),
        "deployment_limits_no_speed_brake_negative_control": g.get("deployment_limits_no_speed_brake_negative_control"),
        "deployment_limits_one_sided_negative_control": g.get("deployment_limits_one_sided_negative_control"),
        # part N: the retrieval against the reeled pendulum (studies/reel_retrieval.py, docs/deployment.md 14.1)
        "deployment_retrieval_pendulum_over_budget": g.get("deployment_retrieval_pendulum_over_budget"),
        "deployment_retrieval_pendulum_frozen_negative_control": g.get("deployment_retrieval_pendulum_frozen_negative_control"),
        # part K: the YES2-like first stage held (studies/reel_yes2.py, docs/deployment.md 11.4)
        "deployment_yes2_hold_over_budget": g.get("deployment_yes2_hold_over_budget"),
        "deployment_yes2_hold_3l_negative_control": g.get("deployment_yes2_hold_3l_negative_control"),
        # part K: the two-stage run's energy across the switch and the births, and the switch's location (15.1)
        "deployment_yes2_energy_over_bound": g.get("deployment_yes2_energy_over_bound"),
        "deployment_yes2_switch_over_tolerance": g.get("deployment_yes2_switch_over_tolerance"),
        "deployment_yes2_turns_negative_control": g.get("deployment_yes2_turns_negative_control"),
        "deployment_yes2_first_rod_negative_control": g.get("deployment_yes2_first_rod_negative_control"),
        # part L: the staged retrieval's last stage settling (studies/reel_retrieval.py, docs/deployment.md 14.2)
        "deployment_retrieval_settle_over_budget": g.get("deployment_retrieval_settle_over_budget"),
        "deployment_retrieval_settle_3l_negative_control": g.get("deployment_retrieval_settle_3l_negative_control"),
        # part J: the SEDS-like deployment against the reduced model (studies/seds_reduced.py, docs/deployment.md 12.2)
        "deployment_seds_reduced_over_budget": g.get("deployment_seds_reduced_over_budget"),
        "deployment_seds_energy_over_bound": g.get("deployment_seds_energy_over_bound"),
        "deployment_seds_canister_negative_control": g.get("deployment_seds_canister_negative_control"),
        # part G: rod-count convergence and the birth bounds (studies/deployment.py, docs/deployment.md 8c)
        "deployment_convergence_ratio_over_bound": g.get("deployment_convergence_ratio_over_bound"),
        "deployment_convergence_cut_nominal_negative_control": g.get("deployment_convergence_cut_nominal_negative_control"),
        "deployment_birth_bounds_over_budget": g.get("deployment_birth_bounds_over_budget"),
        "deployment_birth_bounds_cut_nominal_negative_control": g.get("deployment_birth_bounds_cut_nominal_negative_control"),
        # part G: the rod levels against the continuum's limit (tetherlab/oracles/deploying_string.py, docs/deployment.md 8h)
        "deployment_continuum_limit_over_budget": g.get("deployment_continuum_limit_over_budget"),
        "deployment_continuum_transport_drop_negative_control": g.get("deployment_continuum_transport_drop_negative_control"),
        "deployment_continuum_no_ldot_negative_control": g.get("deployment_continuum_no_ldot_negative_control"),
    }


#: studies that live in the package rather than in the checkout's studies/ (name -> module with main)
PACKAGE_STUDIES = {
    "uncertainty": "tetherlab.uncertainty.verification",
    "uncertainty_deorbit": "tetherlab.uncertainty.verification_deorbit",
}


def _study_module(name: str):
    if name in PACKAGE_STUDIES:
        import importlib

        return importlib.import_module(PACKAGE_STUDIES[name])
    return load_study(name)


#: (title, study script in studies/ or PACKAGE_STUDIES, its arguments after OUTDIR, markdown it
#: writes, gate reader)
STUDIES = [
    ("Catenary against Irvine's elastic catenary (paper section 4.2)", "catenary", [], "catenary.md", _catenary_gates),
    ("Stiefel-Scheifele: Cowell and DROMO against the oracle (paper section 4.1, Figure 3)", "stiefel_table", [],
     "stiefel_table.md", _stiefel_gates),
    ("Electrodynamic de-orbit (paper section 5, Figure 7)", "deorbit", [], None, _deorbit_gates),
    ("Lumped-mass (bead) model against TMED", "bead_vs_tmed", [], "bead_vs_tmed.md", None),
    ("Rod-count convergence", "convergence", ["--quiet"], "convergence.md", None),
    ("What accuracy costs in time (work-precision)", "workprecision", ["--quiet"], "work_precision.md", None),
    ("Hard cases", "hard_cases", ["--quiet"], "hard_cases.md", _hard_cases_gates),
    ("Fidelity ladder: the de-orbit at each environment level (docs/environment.md)", "fidelity", ["--quiet"], "fidelity.md", None),
    ("Rigid bodies, wheels, attitude control and tether trees (docs/model.md 12)", "rigid_scenes", [], "rigid_scenes.md", None),
    ("Rigid bodies, wheels and hub-and-spoke against the oracles (docs/rigid-oracles.md)", "rigid_bodies", ["--quiet"],
     "rigid_bodies.md", _rigid_bodies_gates),
    ("Uncertainty machinery against known answers (docs/uncertainty.md 6)", "uncertainty", [], "uncertainty.md",
     _uncertainty_gates),
    ("Electrodynamic de-orbit under uncertainty: 256 samples against the closed form (docs/uncertainty.md 7)",
     "uncertainty_deorbit", [], "uncertainty_deorbit.md", _uncertainty_deorbit_gates),
    ("Deployment and retrieval from a reel: balances across births, exponential deployment, slow retrieval "
     "(docs/deployment.md 8)", "deployment", ["--quiet"], "deployment.md", _deployment_gates),
]


#: the studies that run their scenes through tetherlab.sweep (they take ``--workers N``)
SWEEPING_STUDIES = ("convergence", "workprecision", "hard_cases")


def _summary_md(name: str, sdir: Path) -> str:
    """A section for a study that writes JSON/CSV and figures but no Markdown of its own: what it
    checks, against what (the study's own docstring, its first paragraphs up to the command line),
    then its tables and figures."""
    lines = []
    doc = (load_study(name).__doc__ or "").strip()
    intro = []
    for para in doc.split("\n\n"):
        if para.lstrip().startswith(("PYTHONPATH", "python ", "Writes into", "``--")):
            continue  # how to run the script, not what it checks
        text = " ".join(para.split())
        text = re.sub(r":[a-z]+:`~?([^`]+)`", r"`\1`", text).replace("``", "`")  # reST -> Markdown
        intro.append(text)
    if intro:
        lines += ["**What this study checks, against what:** " + intro[0], ""] + [p + "\n" for p in intro[1:]]
    for csv in sorted(sdir.glob("*.csv")):
        import pandas as pd

        df = pd.read_csv(csv)
        keep = [c for c in df.columns if df[c].dtype != object or c in ("label", "case", "method")][:12]
        lines += [f"`{csv.name}`:", "", _table_md(df[keep].to_dict("records")), ""]
    lines += [f"![{png.stem}]({png.name})" for png in sorted(sdir.glob("*.png"))]
    return "\n".join(lines)


def run_studies(out: Path, only=None, study_workers: int | None = None):
    """Run every study into out/<name>/; a study that fails is reported (its gates then fail),
    the others still run.  ``study_workers``: the worker processes of the studies that sweep
    (``--workers``; None: their default, all cores)."""
    sections, values, failures = [], {}, []
    for title, name, extra, md_name, gates_fn in STUDIES:
        if only is not None and name not in only:
            continue
        sdir = out / name
        sdir.mkdir(parents=True, exist_ok=True)
        t0 = time.perf_counter()
        try:
            pool = ["--workers", str(study_workers)] if study_workers and name in SWEEPING_STUDIES else []
            _study_module(name).main([str(sdir), *extra, *pool])
            values.update(gates_fn(sdir) if gates_fn else {})
            md = (sdir / md_name).read_text() if md_name else _summary_md(name, sdir)
            # images and links in the study's Markdown are relative to its own directory
            md = re.sub(r"\]\((?!https?:|#)([^)]+)\)", lambda m: f"]({name}/{m.group(1)})", md)
            md = _nest_headings(md)
            sections.append((name, title, md, time.perf_counter() - t0))
        except Exception as exc:  # report and go on: one broken study must not hide the rest
            failures.append(name)
            sections.append((name, title, f"**Study failed:** `{type(exc).__name__}: {exc}`", time.perf_counter() - t0))
    return sections, values, failures


def _nest_headings(md: str) -> str:
    """A study's Markdown under the report's own section heading: its leading title (which the
    report's heading replaces) is dropped and its other headings go one level down."""
    lines = md.lstrip("\n").split("\n")
    if lines and re.match(r"#{1,2} ", lines[0]):
        lines = lines[1:]
    return re.sub(r"^(#{1,5}) ", r"#\1 ", "\n".join(lines), flags=re.M)


