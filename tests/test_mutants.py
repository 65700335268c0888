"""The deliberate defects of tetherlab/mutants.py (negative controls of the gates, docs/verification.md 2).

What is checked here, fast: no user run can carry a defect (the switch is 0 / 1 as built from any
shipped scene), switching one on and off leaves nothing behind, and the cheapest defect/gate pairs
of tetherlab.verify.FAST_PAIRS are caught by the gate's own measurement while the same measurement
passes without the defect.  The whole matrix is `make verify`'s (report section "Negative
controls").  Thresholds come from references/gates.toml (each with its budget there).
"""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

import pytest

from tetherlab import mutants, verify
from tetherlab.forces import stiefel_moon
from tetherlab.model import params as L
from tetherlab.model.params import ParamView
from tetherlab.pipeline import prepare
from tetherlab.scene import load_scene
from tetherlab.system import Model

ROOT = Path(__file__).resolve().parent.parent
GATES = tomllib.loads((ROOT / "references" / "gates.toml").read_text())


@pytest.mark.parametrize("scene", sorted(p.name for p in (ROOT / "studies" / "scenes").glob("*.toml")
                                         if p.name != "rigid-example.toml"))
def test_no_shipped_scene_reaches_a_defect(scene):
    try:
        sc = load_scene(ROOT / "studies" / "scenes" / scene)
    except Exception as exc:  # a scene that cannot load is another test's business
        pytest.skip(f"{scene}: {exc}")
    p = prepare(sc).model.fresh_params()
    v = ParamView(p)
    assert v.defect == L.MUT_NONE
    for t in v.tethers:
        assert t.model in (L.MODEL_PAPER, L.MODEL_ENERGY)
    for par in v.effects_with_code(stiefel_moon.CODE):
        assert p[par + 3] == 1.0  # the indirect term's factor


def test_switching_a_defect_on_and_off_leaves_nothing_behind():
    original = Model.fresh_params
    model = prepare(load_scene(ROOT / "studies" / "scenes" / "lateral-two-rods.toml")).model
    before = model.fresh_params()
    for name in mutants.names():
        with mutants.active(name) as m:
            assert m.name == name
            after = model.fresh_params()
            if m.mutate is not None and m.path in ("tether", "diagnostics", "statics"):
                assert (after != before).any(), name  # the copy carries the defect ...
        assert (model.p == before).all(), name  # ... the model's own block never does
    assert Model.fresh_params is original
    assert (model.fresh_params() == before).all()


def test_every_active_defect_names_gates_that_exist_and_the_rigid_defects_are_active():
    for m in mutants.MUTANTS.values():
        assert set(m.gates) <= set(GATES), m.name
        if m.status == "active":
            assert m.gates and (m.mutate or m.patch), m.name
    # the rigid-body defects and the others share the block's one defect field (kernel/schema.py)
    assert {"rigid_attachment_not_rotated", "rigid_centripetal_dropped"} <= set(mutants.names())
    p = prepare(load_scene(ROOT / "studies" / "scenes" / "lateral-two-rods.toml")).model.fresh_params()
    mutants.MUTANTS["rigid_centripetal_dropped"].mutate(p)
    assert ParamView(p).defect == L.DEFECT_NO_CENTRIPETAL


def test_the_rigid_defects_are_credited_only_through_their_control_gate():
    # verify.mutation_summary: a passing hub_spoke_radius_defects_negative_control credits both
    # defects to hub_spoke_radius_tip_over_bound; a failing or missing one credits nothing
    thr = GATES["hub_spoke_radius_defects_negative_control"]["threshold"]
    for ctrl, expect in ((0.5 * thr, True), (2.0 * thr, False), (None, False)):
        by_defect, _by_gate, _ = verify.mutation_summary({}, GATES, {"hub_spoke_radius_defects_negative_control": ctrl})
        got = "hub_spoke_radius_tip_over_bound" in by_defect["rigid_centripetal_dropped"]
        assert got == expect, ctrl


def test_the_reel_defects_are_credited_only_through_their_control_gates():
    # verify.mutation_summary: each passing deployment control gate credits its defect to the gates
    # it failed in studies/deployment.py; a failing or missing one credits nothing
    pairs = (("deployment_rescaled_negative_control", "reel_rescaled", "deployment_momentum_over_bound"),
             ("deployment_no_ldot_negative_control", "reel_strain_rate_without_ldot",
              "deployment_exponential_tension_over_budget"),
             ("deployment_continuum_no_ldot_negative_control", "reel_strain_rate_without_ldot",
              "deployment_continuum_limit_over_budget"),
             ("deployment_frozen_negative_control", "reel_law_frozen", "deployment_retrieval_invariant"),
             ("deployment_hub_exit_torque_negative_control", "reel_hub_exit_torque_dropped",
              "deployment_hub_angular_momentum_over_bound"),
             ("deployment_hub_ring_negative_control", "reel_hub_ring_dropped", "deployment_hub_axis_spin_over_bound"),
             ("deployment_limits_torque_unlimited_negative_control", "spool_torque_unlimited",
              "deployment_limits_energy_over_bound"),
             ("deployment_limits_no_speed_brake_negative_control", "spool_no_speed_brake",
              "deployment_limits_speed_over_budget"),
             ("deployment_limits_one_sided_negative_control", "spool_torque_one_sided",
              "deployment_limits_torque_over_budget"),
             ("deployment_retrieval_pendulum_frozen_negative_control", "reel_law_frozen",
              "deployment_retrieval_pendulum_over_budget"),
             ("deployment_spoke_ring_full_negative_control", "reel_hub_ring_full", "deployment_spoke_axis_spin_over_bound"),
             ("deployment_spoke_wheels_negative_control", "wheels_gyro_dropped",
              "deployment_spoke_angular_momentum_over_bound"),
             ("deployment_spoke_one_stored_negative_control", "reel_one_stored", "deployment_spoke_momentum_over_bound"),
             ("deployment_yes2_hold_3l_negative_control", "tension_3l", "deployment_yes2_hold_over_budget"),
             ("deployment_yes2_turns_negative_control", "drum_no_turns", "deployment_yes2_energy_over_bound"),
             ("deployment_yes2_first_rod_negative_control", "stage_first_rod", "deployment_yes2_switch_over_tolerance"),
             ("deployment_retrieval_settle_3l_negative_control", "tension_3l", "deployment_retrieval_settle_over_budget"),
             ("deployment_seds_canister_negative_control", "canister_as_drum", "deployment_seds_reduced_over_budget"),
             ("deployment_hub_drum_negative_control", "hub_drum_no_spin", "deployment_hub_drum_angular_momentum_over_bound"))
    for ctrl_gate, defect, gate in pairs:
        assert ParamView(_reel_params(defect)).defect == getattr(L, "DEFECT_" + {
            "reel_rescaled": "REEL_RESCALED", "reel_strain_rate_without_ldot": "REEL_NO_LDOT",
            "reel_law_frozen": "REEL_FROZEN", "reel_hub_exit_torque_dropped": "REEL_NO_EXIT_TORQUE",
            "reel_hub_ring_dropped": "REEL_NO_RING", "spool_torque_unlimited": "SPOOL_TORQUE_UNLIMITED",
            "spool_no_speed_brake": "SPOOL_NO_SPEED_BRAKE", "spool_torque_one_sided": "SPOOL_TORQUE_ONE_SIDED",
            "reel_hub_ring_full": "REEL_RING_FULL", "wheels_gyro_dropped": "WHEELS_NO_GYRO",
            "reel_one_stored": "REEL_ONE_STORED", "tension_3l": "TENSION_3L", "canister_as_drum": "CANISTER_AS_DRUM",
            "hub_drum_no_spin": "HUB_DRUM_NO_SPIN", "drum_no_turns": "DRUM_NO_TURNS",
            "stage_first_rod": "STAGE_FIRST_ROD"}[defect])
        thr = GATES[ctrl_gate]["threshold"]
        for ctrl, expect in ((0.5 * thr, True), (2.0 * thr, False), (None, False)):
            by_defect, _by_gate, _ = verify.mutation_summary({}, GATES, {ctrl_gate: ctrl})
            assert (gate in by_defect[defect]) == expect, (ctrl_gate, ctrl)


def test_the_birth_cut_defect_is_credited_only_through_part_g_control_gates():
    # the birth's cut against the nominal rod is Python (simulate_reel's remap_defect), run by
    # studies/deployment.py part G itself: each passing control credits it to its gate, a failing or
    # missing one credits nothing
    for ctrl_gate, gate in (("deployment_convergence_cut_nominal_negative_control", "deployment_convergence_ratio_over_bound"),
                            ("deployment_birth_bounds_cut_nominal_negative_control", "deployment_birth_bounds_over_budget")):  # fmt: skip
        thr = GATES[ctrl_gate]["threshold"]
        for ctrl, expect in ((0.5 * thr, True), (2.0 * thr, False), (None, False)):
            by_defect, by_gate, _ = verify.mutation_summary({}, GATES, {ctrl_gate: ctrl})
            assert (gate in by_defect.get("birth_cut_nominal", [])) == expect, (ctrl_gate, ctrl)
            assert ("birth_cut_nominal" in by_gate.get(ctrl_gate, [])) == expect, (ctrl_gate, ctrl)


def test_the_transport_drop_birth_is_credited_only_through_its_continuum_control_gate():
    # the births without the transport velocity are Python (studies/deployment.py
    # simulate_reel's remap_defect "transport-dropped"), run by part G itself: a passing control credits the defect to the
    # continuum gate, a failing or missing one credits nothing
    ctrl_gate, gate = "deployment_continuum_transport_drop_negative_control", "deployment_continuum_limit_over_budget"
    thr = GATES[ctrl_gate]["threshold"]
    for ctrl, expect in ((0.5 * thr, True), (2.0 * thr, False), (None, False)):
        by_defect, by_gate, _ = verify.mutation_summary({}, GATES, {ctrl_gate: ctrl})
        assert (gate in by_defect.get("birth_transport_dropped", [])) == expect, ctrl
        assert ("birth_transport_dropped" in by_gate.get(ctrl_gate, [])) == expect, ctrl


def _reel_params(name):
    p = prepare(load_scene(ROOT / "studies" / "scenes" / "lateral-two-rods.toml")).model.fresh_params()
    mutants.MUTANTS[name].mutate(p)
    return p


def _gate(values, gid):
    return values[gid], GATES[gid]["threshold"]


def test_holding_force_off_by_one_percent_fails_the_catenary_tension_gate():
    # catenary_tension_n64: errors against Irvine in units of their Richardson estimate (gates.toml)
    v, thr = _gate(verify.check_catenary_probe([]), "catenary_tension_n64")
    assert v <= thr
    with mutants.active("statics_holding_force_1pc"):
        v_bad, _ = _gate(verify.check_catenary_probe([]), "catenary_tension_n64")
    assert v_bad > thr


def test_energy_without_elastic_term_fails_the_energy_gate():
    # energy_model_energy: max|dE| / max V_e of the energy model in free space (gates.toml budget)
    thr = GATES["energy_model_energy"]["threshold"]
    assert verify._energy_free_space([], quick=True) <= thr
    with mutants.active("energy_without_elastic_term"):
        bad = verify._energy_free_space([], quick=True)
    assert not (bad <= thr)  # inf (no elastic energy to divide by) or far above


def test_de421_low_degree_fails_the_fit_gate():
    v, thr = _gate(verify.check_de421([]), "de421_fit_error")
    assert v <= thr
    with mutants.active("de421_low_degree"):
        v_bad, _ = _gate(verify.check_de421([]), "de421_fit_error")
    assert v_bad > thr


def test_j2_sign_fails_the_heyoka_orbit_gate():
    v, thr = _gate(verify.check_heyoka_orbits([]), "heyoka_orbits_position")
    assert v <= thr
    with mutants.active("j2_sign"):
        v_bad, _ = _gate(verify.check_heyoka_orbits([]), "heyoka_orbits_position")
    assert v_bad > 1e3 * thr and math.isfinite(v_bad)  # J2's along-track drift in 1 day: kilometres


def test_the_harness_fills_the_matrix_for_a_fast_pair():
    rows = []
    cells, baseline = verify.run_negative_controls(rows, GATES, names=["de421_low_degree"], probes=["de421"])
    assert cells[("de421_low_degree", "de421_fit_error")][1] == "caught"
    assert baseline["de421_fit_error"] <= GATES["de421_fit_error"]["threshold"]
    by_defect, by_gate, vals = verify.mutation_summary(cells, GATES, {})
    assert by_defect["de421_low_degree"] == ["de421_fit_error"]
    # the other defects were not run here, so they count as uncaught
    assert vals["mutation_uncaught_defects"] == len(mutants.names()) - 1
    assert "de421_fit_error" in verify.matrix_md(cells, GATES, by_defect, by_gate)


def test_a_probe_that_raises_catches_the_defect_but_gives_no_gate_teeth(monkeypatch):
    # verify.run_negative_controls: a probe that refuses to run under a defect marks its cells
    # "raised" (RAISED in the matrix); mutation_summary counts the defect caught and credits no gate
    from tetherlab import ephemeris
    from tetherlab.verify import controls

    def probe(rows):
        if ephemeris.DEGREE == 5:  # the defect de421_low_degree is on
            raise ValueError("deliberate refusal")
        return {"de421_fit_error": 0.0}

    monkeypatch.setattr(controls, "PROBES", [("fake", probe, {"de421"})])
    monkeypatch.setitem(controls._PROBE_GATES, "fake", ["de421_fit_error"])
    rows = []
    cells, baseline = controls.run_negative_controls(rows, GATES, names=["de421_low_degree"])
    assert baseline == {"de421_fit_error": 0.0}
    assert cells == {("de421_low_degree", "de421_fit_error"): (None, controls.RAISED)}
    assert any("deliberate refusal" in r.get("error", "") for r in rows)
    by_defect, by_gate, _ = verify.mutation_summary(cells, GATES, {})
    assert by_defect["de421_low_degree"] == ["de421_fit_error (raised)"]
    assert by_gate["de421_fit_error"] == []
    assert "RAISED" in verify.matrix_md(cells, GATES, by_defect, by_gate)
    # a measured failure, by contrast, gives the gate its teeth
    cells = {("de421_low_degree", "de421_fit_error"): (1e9, "caught")}
    _by_defect, by_gate, _ = verify.mutation_summary(cells, GATES, {})
    assert by_gate["de421_fit_error"] == ["de421_low_degree"]
