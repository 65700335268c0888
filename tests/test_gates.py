"""references/gates.toml is the single list of accuracy gates: every gate is well formed and
`make verify` measures every one of them (a gate nobody measures would pass silently... it does not:
verify reports it as "not measured" and fails, but CI should catch the typo first)."""

from __future__ import annotations

import ast
import math
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def _gates():
    return tomllib.loads((ROOT / "references" / "gates.toml").read_text())


def test_every_gate_has_quantity_threshold_unit_source():
    gates = _gates()
    assert len(gates) >= 10
    for gid, g in gates.items():
        # budget: the error budget or the stated reason behind the threshold (docs/verification.md 1)
        assert {"quantity", "threshold", "unit", "source", "budget"} <= set(g) <= {
            "quantity", "threshold", "unit", "source", "budget", "kind"}, gid
        assert isinstance(g["threshold"], (int, float)) and math.isfinite(g["threshold"]) and g["threshold"] >= 0, gid
        assert g["quantity"].strip() and g["source"].strip() and g["unit"].strip() and g["budget"].strip(), gid
        assert g.get("kind", "measurement") in ("measurement", "data check"), gid


def test_every_gate_is_measured_by_verify():
    # The gate ids verify produces are the string keys of the dicts its check functions return;
    # read them from the source (running every check is make verify's job, not CI's).
    trees = [ast.parse(f.read_text()) for f in sorted((ROOT / "tetherlab" / "verify").glob("*.py"))]
    assert len(trees) >= 5  # the verify package's modules
    produced = set()
    for node in (n for tree in trees for n in ast.walk(tree)):
        if isinstance(node, ast.Dict):
            produced |= {k.value for k in node.keys if isinstance(k, ast.Constant) and isinstance(k.value, str)}
        if isinstance(node, ast.Assign):  # out["gate"] = value
            for tgt in node.targets:
                if isinstance(tgt, ast.Subscript) and isinstance(tgt.slice, ast.Constant):
                    produced.add(tgt.slice.value)
    missing = set(_gates()) - produced
    assert not missing, f"gates that make verify never measures: {sorted(missing)}"


def test_every_gate_has_a_probe_or_a_reason_to_have_none():
    # The negative controls (make verify) run each deliberate defect against the probes of
    # tetherlab.verify.PROBES; a gate outside every probe must say in TOOTHLESS why it has no teeth
    # (docs/verification.md 2), or the mutation_toothless_unexplained gate fails at verify time.
    from tetherlab import verify

    probed = {g for gs in verify._PROBE_GATES.values() for g in gs}
    assert {p[0] for p in verify.PROBES} == set(verify._PROBE_GATES)
    gates = set(_gates())
    assert not (set(verify.TOOTHLESS) - gates), "reasons for gates that do not exist"
    # the hard-cases control runs eq. 20 inside its study; the rigid-body study runs the two
    # attachment defects and credits them to its tip gate (verify.mutation_summary)
    credited = {"hard_cases_negative_control", "hub_spoke_radius_tip_over_bound",
                "hub_spoke_radius_defects_negative_control",
                # the n = 512 hard case runs damping_sign itself (studies/hard_cases.py part 5)
                "hard_cases_n512_stability", "hard_cases_n512_negative_control",
                # the deployment study runs the reel kernel's defects itself (studies/deployment.py)
                "deployment_momentum_over_bound", "deployment_angular_momentum_over_bound",
                "deployment_energy_over_bound", "deployment_retirement_momentum_over_bound",
                "deployment_exponential_angle_over_budget", "deployment_exponential_tension_over_budget",
                "deployment_retrieval_invariant", "deployment_rescaled_negative_control",
                "deployment_no_ldot_negative_control", "deployment_frozen_negative_control",
                "deployment_retirement_angmom_over_bound", "deployment_retirement_linear_only_negative_control",
                # and the rigid hub's two (part H, studies/deployment_hub.py)
                "deployment_hub_angular_momentum_over_bound", "deployment_hub_momentum_over_bound",
                "deployment_hub_energy_over_bound", "deployment_hub_exit_torque_negative_control",
                "deployment_hub_centripetal_negative_control", "deployment_hub_axis_spin_over_bound",
                "deployment_hub_ring_negative_control",
                # and the hub-and-spoke's three (part P, studies/deployment_spoke.py)
                "deployment_spoke_axis_spin_over_bound", "deployment_spoke_ring_full_negative_control",
                "deployment_spoke_angular_momentum_over_bound", "deployment_spoke_wheels_negative_control",
                "deployment_spoke_momentum_over_bound", "deployment_spoke_one_stored_negative_control",
                # and the spool's two (part I)
                "deployment_spool_drum_over_budget", "deployment_spool_energy_over_bound",
                "deployment_tension_roots_over_budget", "deployment_spool_uncoupled_negative_control",
                "deployment_tension_k2_negative_control",
                # and the spool limits' three (part M)
                "deployment_limits_torque_over_budget", "deployment_limits_speed_over_budget",
                "deployment_limits_balance_over_bound", "deployment_limits_energy_over_bound",
                "deployment_limits_torque_unlimited_negative_control",
                "deployment_limits_no_speed_brake_negative_control", "deployment_limits_one_sided_negative_control",
                # and the retrieval against the reeled pendulum (part N)
                "deployment_retrieval_pendulum_over_budget", "deployment_retrieval_pendulum_frozen_negative_control",
                # and the YES2-like hold (part K)
                "deployment_yes2_hold_over_budget", "deployment_yes2_hold_3l_negative_control",
                # and the YES2-like two-stage run: its energy and its switch (part K)
                "deployment_yes2_energy_over_bound", "deployment_yes2_switch_over_tolerance",
                "deployment_yes2_turns_negative_control", "deployment_yes2_first_rod_negative_control",
                # and the staged retrieval's settling (part L)
                "deployment_retrieval_settle_over_budget", "deployment_retrieval_settle_3l_negative_control",
                # and the SEDS-like run against the reduced model and its energy (part J)
                "deployment_seds_reduced_over_budget", "deployment_seds_energy_over_bound",
                "deployment_seds_canister_negative_control",
                # and the drum under a spool law on the hub (part R)
                "deployment_hub_drum_angular_momentum_over_bound", "deployment_hub_drum_energy_over_bound",
                "deployment_hub_drum_negative_control",
                # and the rod-count convergence (part G)
                "deployment_convergence_ratio_over_bound", "deployment_convergence_cut_nominal_negative_control",
                "deployment_birth_bounds_over_budget", "deployment_birth_bounds_cut_nominal_negative_control",
                # and the rod levels against the continuum's limit (part G)
                "deployment_continuum_limit_over_budget", "deployment_continuum_transport_drop_negative_control",
                "deployment_continuum_no_ldot_negative_control"}
    assert not (gates - probed - set(verify.TOOTHLESS) - credited), "gates neither probed nor explained"
