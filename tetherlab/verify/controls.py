"""The negative controls of verify: every deliberate defect (tetherlab.mutants) against the gates'
cheap probes, the mutation matrix and its two gates."""

from __future__ import annotations

import math
import time

from ..report import _fmt
from .checks import (
    check_de421,
    check_dop853,
    check_hanging_chain,
    check_heyoka_orbits,
    check_invariants,
    check_lateral_mode,
    check_libration,
    check_stiefel_probe,
)
from .hanging_chain_modes import ORDER_NS, check_hanging_chain_modes
from .inextensible import check_inextensible
from .studies import check_catenary_probe

#: (probe name, function(rows) -> {gate: value}, code paths it exercises)
PROBES = [
    ("libration", lambda rows: check_libration(rows, ns=(1, 4)), {"tether", "integrator"}),
    ("invariants", lambda rows: check_invariants(rows, quick=True), {"tether", "diagnostics", "integrator"}),
    ("lateral", lambda rows: check_lateral_mode(rows, kinds=("paper", "energy")), {"tether", "integrator"}),
    ("catenary", lambda rows: check_catenary_probe(rows), {"tether", "statics"}),
    ("hanging_chain", lambda rows: check_hanging_chain(rows, ns=(8,), models=("paper",)), {"tether", "integrator"}),
    ("hanging_chain_bessel", lambda rows: check_hanging_chain_modes(rows, ns=ORDER_NS), {"tether", "inextensible"}),
    ("inextensible", lambda rows: check_inextensible(rows, quick=True), {"tether", "integrator", "inextensible"}),
    ("heyoka_orbits", lambda rows: check_heyoka_orbits(rows), {"gravity", "integrator"}),
    ("stiefel", lambda rows: check_stiefel_probe(rows), {"gravity", "moon", "integrator", "dromo"}),
    ("de421", lambda rows: check_de421(rows), {"de421"}),
    ("dop853", lambda rows: check_dop853(rows), {"integrator"}),
]
#: the probes the CI test runs (tests/test_gates.py): the cheapest defect/gate pairs
FAST_PAIRS = (
    ("statics_holding_force_1pc", "catenary"),
    ("energy_without_elastic_term", "invariants"),
    ("de421_low_degree", "de421"),
    ("j2_sign", "heyoka_orbits"),
)

#: gates no defect of tetherlab.mutants can reach, and why (the report marks them toothless)
TOOTHLESS = {
    "vertical_equilibrium": "the start is the model's own relative equilibrium, solved with the same kernels, so a "
    "defect of the model moves the equilibrium with it; the gate checks the equilibrium solver and the "
    "integration's stability, not the physics",
    "reproducible_runs": "a deterministic defect is reproduced exactly; the gate guards non-determinism (chunking, "
    "threads, uninitialised memory), which no defect here introduces",
    "stiefel_reference_data_check": "a data check: it reads the builders' stored distance between two oracle "
    "references, so no simulator defect can move it",
    "catenary_order_deviation": "the statics' convergence order: the defects on the statics path are a constant "
    "offset (holding force: seen by catenary_tension_n64) or act on motion only (velocities are zero at rest)",
    "libration_outofplane_frequency": "held to the theory's leading order only (2e-3, gates.toml): the registry's "
    "defects of the distributed forces move 2 w by 1.3e-3 (F_TP dropped) and 1.7e-3 (one node) on this scene's "
    "10 kg tether between 1100 kg of end masses, inside the theory's own error; libration_rod_count_spread, "
    "which is exact to (L/r0)^2, catches both",
    "catenary_shape_n64": "the shape of a chain at rest in uniform gravity: the half-rod loads are uniform "
    "(exact for any node count) and at rest the defects of eqs. 19, 20 and F_TP change no equilibrium "
    "(measured: shape unchanged to 1e-9 under each); the statics defect in the registry is in the holding "
    "force, which catenary_tension_n64 catches",
    "deorbit_n1_vs_paper": "not probed: a de-orbit run takes minutes (the whole study in make verify); no defect of "
    "the electrodynamic or drag path is in the registry yet",
    "deorbit_n1_vs_closed_form": "not probed: as deorbit_n1_vs_paper",
    "deorbit_n4_vs_n1": "not probed: as deorbit_n1_vs_paper",
    "hard_cases_failed": "not probed: each hard case runs tens of seconds; the study runs its own eq. 20 control "
    "(hard_cases_negative_control)",
    "hard_cases_invariant_over_bound": "not probed: as hard_cases_failed (the control is the printed-model run)",
    "hard_cases_convergence_score": "not probed: as hard_cases_failed",
    "hard_cases_floor_over_loose_change": "not probed: a property of the tolerance ladders chosen, not of the code",
    "hard_cases_collapse_stop_spread": "not probed: as hard_cases_failed",
    "hub_spoke_centre_tip_over_bound": "not probed: the rigid-body study runs minutes; the registry has no defect "
    "on a point-mass hub's steady spin that the cheap probes miss, and the study's own control (a 1 % stiffer "
    "tether, hub_spoke_centre_negative_control) shows the order gate sees a stiffness error",
    "hub_spoke_centre_tension_over_bound": "not probed: as hub_spoke_centre_tip_over_bound",
    "hub_spoke_centre_order_deficit": "not probed by the registry: its own control is "
    "hub_spoke_centre_negative_control (a 1 % stiffer tether fails it)",
    "hub_spoke_centre_negative_control": "a control itself (must pass: the order gate fails a 1 % stiffer tether)",
    "hub_spoke_radius_tension_over_bound": "not probed: the rigid attachment defects are run and credited through "
    "hub_spoke_radius_tip_over_bound (the study's part B)",
    "hub_spoke_radius_order_deficit": "not probed: as hub_spoke_radius_tension_over_bound",
    "torque_free_over_bound": "not probed by the registry (no defect of the attitude kinematics in it yet): the "
    "study's own control perturbs the inertia by 1e-4 (torque_free_negative_control)",
    "torque_free_negative_control": "a control itself (a 1e-4 inertia error must fail torque_free_over_bound)",
    "torque_free_convergence": "not probed: the integrator's convergence on the torque-free body (a property of "
    "the tolerance ladder, as hard_cases_floor_over_loose_change)",
    "gg_libration_frequency": "not probed by the registry (no gravity-gradient-torque defect in it yet): the "
    "study's own control perturbs the inertia (gg_libration_negative_control)",
    "gg_libration_negative_control": "a control itself (a perturbed inertia must fail gg_libration_frequency)",
    "wheel_exchange_over_bound": "not probed: no wheel defect in the registry yet; an exact first integral "
    "(H, and energy minus motor work) within a derived round-off bound",
    "wheels_tumbling_over_bound": "not probed: as wheel_exchange_over_bound",
    "untethered_bodies_over_bound": "not probed: compares a forest against single-body runs of the same kernel; a "
    "model defect moves both alike (it guards the forest's bookkeeping)",
    "conservation_tree_over_bound": "not probed by the harness (the study runs minutes); tests/test_rigid.py runs "
    "the two attachment defects against the same first integrals and both fail them by > 1e6 x the bound",
    "uq_known_distribution_over_ci": "not probed by the registry (no defect of the uncertainty machinery in it): the "
    "section's own control, every current 3 % high, must fail it (counted by uq_machinery_negative_controls)",
    "uq_ci_coverage_floor_over_min": "not probed by the registry: its control is uq_ci_coverage_negative_control "
    "(4 workers sharing one seed must fail the floor)",
    "uq_ci_coverage_negative_control": "a control itself (the shared-seed sampler must fail the coverage floor)",
    "uq_sobol_indices_over_ci": "not probed by the registry: the section's own control, Ishigami with x1 and x2 "
    "swapped, must fail it (uq_machinery_negative_controls)",
    "uq_mc_slope_vs_half": "not probed by the registry: the section's own control, an MC stream that wraps after 64 "
    "points, must fail it (uq_machinery_negative_controls)",
    "uq_sobol_slope_steeper": "not probed by the registry: the section's own control, plain MC points in place of "
    "Sobol' ones, must fail it (uq_machinery_negative_controls)",
    "uq_machinery_negative_controls": "the count of the machinery's controls that missed itself",
    "uq_deorbit_mean_vs_closed_form": "not probed: 256 de-orbits take minutes; the study's own control, every current "
    "10 % high, must fail it (uq_deorbit_negative_controls)",
    "uq_deorbit_slope_vs_closed_form": "not probed: as uq_deorbit_mean_vs_closed_form; the study's own control, the "
    "prepared model reused without re-packing the sample's values, must fail it (uq_deorbit_negative_controls)",
    "uq_deorbit_failed": "not probed: a count of failed runs (a defect that makes runs fail is caught by the runs' "
    "own error reports, listed in failures.csv)",
    "uq_deorbit_negative_controls": "the count of the de-orbit study's controls that missed itself",
    "deployment_birth_remap": "the remap of a birth is Python (deployment.birth_state), which no defect of the "
    "kernel reaches; it is exact by construction (docs/deployment.md 6.1) and measured without integration",
    "inextensible_bessel_order": "not probed (24 runs up to 64 rods); its rod-count order is a property of the bars "
    "the model reduces to, which inextensible_rigid_chain measures exactly",
    "inextensible_drift_control": "a control itself: the stabilisation switched off must drift beyond the bound",
    "inextensible_drift_orbit_control": "a control itself: the 35-day run with the stabilisation switched off must "
    "drift beyond the bound",
    "inextensible_rigid_chain": "probed, but no registered defect gives it teeth: the one on its path that moves "
    "the chain (inextensible_centripetal_dropped) makes the probe refuse to run (the frequency fit finds one zero "
    "crossing: RAISED, the defect caught but no gate credited), and the Baumgarte rate set to 0 "
    "(inextensible_unstabilised) leaves the frequencies at 7.9e-12 (the drift gates catch it)",
    "inextensible_energy": "not probed: the drift gate catches the unstabilised constraint, and a defect of the "
    "distributed forces keeps them conservative",
    "inextensible_ea_slope": "not probed (8 elastic RADAU5 runs): the slope measures the elastic model's limit, "
    "whose defects the elastic gates catch",
    "mutation_uncaught_defects": "the mutation score itself",
    "mutation_toothless_unexplained": "the count of gates without teeth or reason itself",
}


def run_negative_controls(rows_out, gates: dict, names=None, probes=None):
    """Each active defect (tetherlab.mutants) against every probe on its code path.

    Returns (cells, baseline): cells[(defect, gate)] = (value, "caught" / "missed" / "raised");
    baseline[gate] = the probe's value with no defect (a probe that fails with no defect cannot
    claim a catch).  "raised": the probe refused to run under the defect.  The defect is caught
    (a run that refuses is not silent garbage), but the refusal says nothing of what any one of
    the probe's gates measures, so it gives none of them teeth (mutation_summary).
    ``names``/``probes`` restrict the run (tests)."""
    from .. import mutants

    names = mutants.names() if names is None else names
    wanted = [p for p in PROBES if probes is None or p[0] in probes]
    baseline, cells = {}, {}
    t_all = time.perf_counter()
    for pname, fn, _paths in wanted:
        t0 = time.perf_counter()
        vals = fn([])
        baseline.update(vals)
        rows_out.append({"defect": "(none)", "probe": pname, "wall (s)": time.perf_counter() - t0,
                         **{g: v for g, v in vals.items()}})  # fmt: skip
    for name in names:
        m = mutants.MUTANTS[name]
        for pname, fn, paths in wanted:
            if m.path not in paths:
                continue
            if pname in m.skip:
                for g in _probe_gates(pname, baseline):
                    cells[name, g] = (None, "skipped: " + m.skip[pname])
                continue
            t0 = time.perf_counter()
            try:
                with mutants.active(name):
                    vals = fn([])
            except Exception as exc:  # the probe refused to run under the defect: see the docstring
                for g in _probe_gates(pname, baseline):
                    cells[name, g] = (None, RAISED)
                rows_out.append({"defect": name, "probe": pname, "error": f"{type(exc).__name__}: {exc}"[:200],
                                 "wall (s)": time.perf_counter() - t0})
                continue
            for g, v in vals.items():
                thr = gates.get(g, {}).get("threshold", math.inf)
                base_ok = not mutants.caught(baseline.get(g), thr)
                cells[name, g] = (v, "caught" if (base_ok and mutants.caught(v, thr)) else "missed")
            rows_out.append({"defect": name, "probe": pname, "wall (s)": time.perf_counter() - t0})
    rows_out.append({"defect": "(all)", "probe": "total", "wall (s)": time.perf_counter() - t_all})
    return cells, baseline


#: the verdict of a cell whose probe raised under the defect
RAISED = "raised"


def _probe_gates(pname, baseline):
    return _PROBE_GATES.get(pname, [])


_PROBE_GATES = {
    "libration": ["libration_inplane_frequency", "libration_outofplane_frequency", "libration_rod_count_spread"],
    "invariants": ["angular_momentum_internal", "energy_model_energy", "energy_model_power_balance"],
    "lateral": ["lateral_mode_two_rods"],
    "catenary": ["catenary_shape_n64", "catenary_tension_n64", "catenary_order_deviation"],
    "hanging_chain": ["hanging_chain_lateral_modes"],
    "hanging_chain_bessel": ["hanging_chain_bessel_order", "hanging_chain_bessel_n64"],
    "inextensible": ["inextensible_rigid_chain", "inextensible_drift", "inextensible_drift_orbit", "inextensible_libration"],
    "heyoka_orbits": ["heyoka_orbits_position"],
    "stiefel": ["stiefel_cowell_best_error", "stiefel_dromo_best_error", "stiefel_example1_te_error"],
    "de421": ["de421_fit_error"],
    "dop853": ["dop853_work_exponent"],
}


def mutation_summary(cells, gates: dict, study_values: dict):
    """(defect -> gates that caught it, gate -> defects it caught, the two mutation gate values)."""
    from .. import mutants

    by_defect = {n: [] for n in mutants.names()}
    by_gate = {g: [] for g in gates}
    for (d, g), (_v, verdict) in cells.items():
        if verdict == "caught":
            by_defect.setdefault(d, []).append(g)
            by_gate.setdefault(g, []).append(d)
        elif verdict == RAISED:  # the defect is caught (the run refused), but no gate earns teeth by it
            by_defect.setdefault(d, []).append(f"{g} (raised)")
    # the hard-cases study runs eq. 20 as printed itself (its control gate must pass = it was seen)
    ctrl = study_values.get("hard_cases_negative_control")
    if ctrl is not None and ctrl <= gates["hard_cases_negative_control"]["threshold"]:
        by_defect.setdefault("eq20_printed_sign", []).append("hard_cases_invariant_over_bound")
        by_gate.setdefault("hard_cases_invariant_over_bound", []).append("eq20_printed_sign")
        by_gate.setdefault("hard_cases_negative_control", []).append("eq20_printed_sign")
    # the hard-cases study runs the n = 512 tether with the damping's sign flipped (part 5): its
    # control gate passes only if the stability measure fails under that defect
    ctrl = study_values.get("hard_cases_n512_negative_control")
    if ctrl is not None and ctrl <= gates["hard_cases_n512_negative_control"]["threshold"]:
        by_defect.setdefault("damping_sign", []).append("hard_cases_n512_stability")
        by_gate.setdefault("hard_cases_n512_stability", []).append("damping_sign")
        by_gate.setdefault("hard_cases_n512_negative_control", []).append("damping_sign")
    # the rigid-body study runs the kernel's two attachment defects itself (part B): its control
    # gate passes only if the tip-radius measure fails under both (studies/rigid_bodies.py)
    ctrl = study_values.get("hub_spoke_radius_defects_negative_control")
    if ctrl is not None and ctrl <= gates["hub_spoke_radius_defects_negative_control"]["threshold"]:
        for d in ("rigid_attachment_not_rotated", "rigid_centripetal_dropped"):
            by_defect.setdefault(d, []).append("hub_spoke_radius_tip_over_bound")
            by_gate.setdefault("hub_spoke_radius_tip_over_bound", []).append(d)
            by_gate.setdefault("hub_spoke_radius_defects_negative_control", []).append(d)
    # the deployment study runs the reel kernel's defects (and, on the rigid hub, the rigid bodies'
    # centripetal one) itself (studies/deployment.py): each control gate passes only if its defect
    # failed every gate listed here
    for ctrl_gate, defect, caught_by in (
        ("deployment_rescaled_negative_control", "reel_rescaled",
         ("deployment_momentum_over_bound", "deployment_angular_momentum_over_bound", "deployment_energy_over_bound",
          "deployment_retirement_momentum_over_bound")),
        ("deployment_no_ldot_negative_control", "reel_strain_rate_without_ldot",
         ("deployment_exponential_angle_over_budget", "deployment_exponential_tension_over_budget")),
        ("deployment_frozen_negative_control", "reel_law_frozen", ("deployment_retrieval_invariant",)),
        ("deployment_retrieval_pendulum_frozen_negative_control", "reel_law_frozen",
         ("deployment_retrieval_pendulum_over_budget",)),
        # (the remap is Python: deployment.retire_state's P-only correction, run by the study itself)
        ("deployment_retirement_linear_only_negative_control", "retire_remap_linear_only",
         ("deployment_retirement_angmom_over_bound",)),
        ("deployment_hub_exit_torque_negative_control", "reel_hub_exit_torque_dropped",
         ("deployment_hub_angular_momentum_over_bound",)),
        ("deployment_hub_centripetal_negative_control", "rigid_centripetal_dropped",
         ("deployment_hub_momentum_over_bound", "deployment_hub_energy_over_bound")),
        ("deployment_hub_ring_negative_control", "reel_hub_ring_dropped", ("deployment_hub_axis_spin_over_bound",)),
        ("deployment_spoke_ring_full_negative_control", "reel_hub_ring_full", ("deployment_spoke_axis_spin_over_bound",)),
        ("deployment_spoke_wheels_negative_control", "wheels_gyro_dropped",
         ("deployment_spoke_angular_momentum_over_bound",)),
        ("deployment_spoke_one_stored_negative_control", "reel_one_stored", ("deployment_spoke_momentum_over_bound",)),
        ("deployment_hub_drum_negative_control", "hub_drum_no_spin",
         ("deployment_hub_drum_angular_momentum_over_bound", "deployment_hub_drum_energy_over_bound")),
        ("deployment_spool_uncoupled_negative_control", "spool_uncoupled",
         ("deployment_spool_drum_over_budget", "deployment_spool_energy_over_bound")),
        ("deployment_tension_k2_negative_control", "tension_k2_flipped", ("deployment_tension_roots_over_budget",)),
        ("deployment_limits_torque_unlimited_negative_control", "spool_torque_unlimited",
         ("deployment_limits_balance_over_bound", "deployment_limits_energy_over_bound")),
        ("deployment_limits_no_speed_brake_negative_control", "spool_no_speed_brake",
         ("deployment_limits_speed_over_budget", "deployment_limits_balance_over_bound",
          "deployment_limits_energy_over_bound")),
        ("deployment_limits_one_sided_negative_control", "spool_torque_one_sided",
         ("deployment_limits_torque_over_budget",)),
        ("deployment_yes2_hold_3l_negative_control", "tension_3l", ("deployment_yes2_hold_over_budget",)),
        ("deployment_yes2_turns_negative_control", "drum_no_turns", ("deployment_yes2_energy_over_bound",)),
        ("deployment_yes2_first_rod_negative_control", "stage_first_rod", ("deployment_yes2_switch_over_tolerance",)),
        ("deployment_retrieval_settle_3l_negative_control", "tension_3l", ("deployment_retrieval_settle_over_budget",)),
        # (the birth's cut is Python: simulate_reel's remap_defect "cut-nominal", run by the study)
        ("deployment_convergence_cut_nominal_negative_control", "birth_cut_nominal",
         ("deployment_convergence_ratio_over_bound",)),
        ("deployment_birth_bounds_cut_nominal_negative_control", "birth_cut_nominal",
         ("deployment_birth_bounds_over_budget",)),
        # (the births without the transport velocity are Python too: remap_defect "transport-dropped")
        ("deployment_continuum_transport_drop_negative_control", "birth_transport_dropped",
         ("deployment_continuum_limit_over_budget",)),
        ("deployment_continuum_no_ldot_negative_control", "reel_strain_rate_without_ldot",
         ("deployment_continuum_limit_over_budget",)),
        ("deployment_seds_canister_negative_control", "canister_as_drum",
         ("deployment_seds_reduced_over_budget", "deployment_seds_energy_over_bound")),
    ):  # fmt: skip
        ctrl = study_values.get(ctrl_gate)
        if ctrl is not None and ctrl <= gates[ctrl_gate]["threshold"]:
            for g in caught_by:
                by_defect.setdefault(defect, []).append(g)
                by_gate.setdefault(g, []).append(defect)
            by_gate.setdefault(ctrl_gate, []).append(defect)
    uncaught = [d for d, gs in by_defect.items() if not gs]
    unexplained = [g for g, ds in by_gate.items() if not ds and g not in TOOTHLESS]
    return by_defect, by_gate, {"mutation_uncaught_defects": float(len(uncaught)),
                                "mutation_toothless_unexplained": float(len(unexplained))}


def matrix_md(cells, gates: dict, by_defect, by_gate) -> str:
    from .. import mutants

    gate_cols = [g for g in gates if any(g == gg for (_d, gg) in cells) or by_gate.get(g)]
    head = "| defect | " + " | ".join(f"[{g}](#gate-{g})" for g in gate_cols) + " | caught by |"
    lines = [head, "|---|" + "---|" * (len(gate_cols) + 1)]
    for name in mutants.names():
        row = []
        for g in gate_cols:
            v = cells.get((name, g))
            if v is None:
                row.append("CAUGHT (study)" if name in by_gate.get(g, []) else "·")
            elif v[1] == "caught":
                row.append(f"**CAUGHT** {_fmt(v[0])}")
            elif v[1] == RAISED:
                row.append("RAISED")
            elif v[1].startswith("skipped"):
                row.append("skipped")
            else:
                row.append(f"missed {_fmt(v[0])}")
        lines.append(f"| {name} | " + " | ".join(row) + f" | {len(by_defect.get(name, []))} |")
    return "\n".join(lines)


