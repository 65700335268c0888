"""studies/hard_cases.py: the pass criterion of the hard cases has teeth.

Synthetic run records (tetherlab.sweep.RunRecord) exercise each part of the criterion: invariants
against their round-off bounds, convergence as the tolerance tightens (a ladder that does not
converge, or does not resolve anything above round-off, fails), and the clear error expected
where a case leaves the model's validity.  The bounds' formulas are the derivation in the study's
docstring; the numbers below are worked by hand from them.  The study itself runs in make verify.
"""

from __future__ import annotations

import math

import pytest

from tests.helpers import SCENES, forget_study, import_study
from tetherlab.scene import load_scene
from tetherlab.summaries import event_code
from tetherlab.sweep import RunRecord

U = 2.0**-53


@pytest.fixture(scope="module")
def hc():
    yield import_study("hard_cases")
    forget_study("hard_cases")


@pytest.fixture(scope="module")
def scene():
    return load_scene(SCENES / "hard-massratio-one.toml")  # bodies m0, mf; paper model


def summary(x_mf, dh=1e-8, de=1e-8, steps=10_000.0, **extra):
    s = {"nonfinite": 0.0, "angmom_error_own": dh, "energy_error_own": de, "n_steps": steps,
         "angmom_sum_scale": 1e7, "energy_sum_scale": 5e7, "r_max_m": 7.4e6, "v_max_m_s": 7.3e3,
         "t_end_s": 6000.0, "wall_s": 0.1}  # fmt: skip
    for b in ("m0", "mf"):
        for a in "xyz":
            s[f"{b}.{a}_m"] = 0.0
    s["mf.x_m"] = x_mf
    s.update(extra)
    return s


def records(summaries, taus=(1e-9, 1e-10, 1e-11)):
    return [RunRecord("h", "l", {"case": "c", "tol": t}, True, s) for t, s in zip(taus, summaries)]


def test_bounds_follow_the_derivation(hc):
    s = summary(0.0, steps=10_000.0)
    b_h, b_e = hc.invariant_bounds(s)
    # B_H = 4 (2/sqrt3) u sqrt(N) S_H, B_E = 4 (1/sqrt3) u sqrt(N) S_E (studies/hard_cases.py, part 2)
    assert b_h == pytest.approx(4 * 2 / math.sqrt(3) * U * 100.0 * 1e7)
    assert b_e == pytest.approx(4 / math.sqrt(3) * U * 100.0 * 5e7)
    f = hc.position_floor_m(s, s)
    assert f == pytest.approx(4 / math.sqrt(3) * U * math.sqrt(20_000.0) * (7.4e6 + math.sqrt(3) * 7.3e3 * 6000.0))


def test_converging_ladder_passes_with_its_rate(hc, scene):
    out = hc.check("c", {}, {}, records([summary(1e-4), summary(1e-4 + 1e-5), summary(1e-4 + 1e-5 + 1e-6)]), scene)
    assert out["passed"], out["reasons"]
    assert out["rate"] == pytest.approx(1.0)


def test_non_converging_ladder_fails(hc, scene):
    # the differences do not shrink and stay far above the floor (~1e-6 m here): garbage
    out = hc.check("c", {}, {}, records([summary(0.0), summary(1e-3), summary(0.0)]), scene)
    assert not out["passed"] and "not converging" in out["reasons"][0]


def test_ladder_resolving_nothing_fails(hc, scene):
    # every run within round-off of the others: the check would be toothless, so it fails
    out = hc.check("c", {}, {}, records([summary(0.0), summary(1e-9), summary(0.0)]), scene)
    assert not out["passed"] and "round-off floor" in out["reasons"][0]


def test_tight_pair_at_the_floor_passes(hc, scene):
    f2 = hc.position_floor_m(summary(0.0), summary(0.0))
    out = hc.check("c", {}, {}, records([summary(0.0), summary(1e-4), summary(1e-4 + 0.9 * f2)]), scene)
    assert out["passed"], out["reasons"]


def test_invariants_beyond_their_bound_fail_energy_only_for_the_energy_model(hc, scene):
    b_h, b_e = hc.invariant_bounds(summary(0.0))
    ok = [summary(1e-4), summary(1e-4 + 1e-5), summary(1e-4 + 1e-5 + 1e-6, dh=0.5 * b_h, de=10 * b_e)]
    assert hc.check("c", {}, {}, records(ok), scene)["passed"]  # paper model: E is not an invariant
    energy = scene.replace(**{"tethers.main.model": "energy"})
    out = hc.check("c", {}, {}, records(ok), energy)
    assert not out["passed"] and "|dE|" in out["reasons"][0]
    bad = ok[:2] + [summary(1e-4 + 1e-5 + 1e-6, dh=2 * b_h)]
    assert "|dH|" in hc.check("c", {}, {}, records(bad), scene)["reasons"][0]


def test_nan_fails(hc, scene):
    s = [summary(1e-4), summary(1e-4 + 1e-5, nonfinite=3.0), summary(1e-4 + 1e-5 + 1e-6)]
    out = hc.check("c", {}, {}, records(s), scene)
    assert not out["passed"] and "non-finite" in out["reasons"][0]


def _events(times, codes):
    s = {"n_events": float(len(times))}
    for k, (t, c) in enumerate(zip(times, codes)):
        s[f"event{k}_t_s"], s[f"event{k}_code"] = t, c
    return s


def test_switch_times_converge_and_sequences_must_match(hc, scene):
    n = hc.N_SWITCHES
    codes = [float(2 * (k % 4 + 1) + k % 2) for k in range(n)]
    base = [80.0 + k for k in range(n)]
    runs = [summary(0.0, **_events([t + e for t in base], codes)) for e in (1e-5, 1e-6, 1e-7)]
    crit = {"measure": "switch_times"}
    out = hc.check("c", {}, crit, records(runs), scene)
    assert out["passed"], out["reasons"]
    assert out["rate"] == pytest.approx(1.0, abs=1e-6)
    swapped = codes[:10] + [codes[11], codes[10]] + codes[12:]
    runs[2] = summary(0.0, **_events(base, swapped))
    out = hc.check("c", {}, crit, records(runs), scene)
    assert not out["passed"] and "switch sequences differ" in out["reasons"][0]


def test_event_code_names_rod_and_side():
    assert event_code({"event": "slack.main.rod3", "side": "taut"}) == 7.0
    assert event_code({"event": "slack.main.rod3", "side": "slack"}) == 6.0
    assert event_code({"event": "stop.altitude"}) == -1.0


def _failed(tol, t, rod=1):
    msg = (f"SimulationError: run stopped at t = {t!r} s: rod collapsed (its length went to zero or below the "
           f"minimum strain) in tether 'main', rod {rod} of 4 (strain -0.9); last failing evaluation at t = {t!r} s.")
    return RunRecord("h", "l", {"case": "c", "tol": tol}, False, {}, msg)


def test_collapse_must_be_a_clear_repeatable_error(hc, scene):
    crit = {"expect_error": ["rod collapsed", "rod "]}
    good = [_failed(1e-9, 1.5407427), _failed(1e-10, 1.54074271), _failed(1e-11, 1.54074271)]
    out = hc.check("c", {}, crit, good, scene)
    assert out["passed"], out["reasons"]
    assert out["stop_rod"] == "rod 1" and out["stop_time_spread_s"] == pytest.approx(1e-8)
    late = good[:2] + [_failed(1e-11, 1.6)]
    assert "stop times spread" in hc.check("c", {}, crit, late, scene)["reasons"][0]
    other_rod = good[:2] + [_failed(1e-11, 1.54074271, rod=2)]
    assert "different rods" in hc.check("c", {}, crit, other_rod, scene)["reasons"][0]
    ran = good[:2] + [RunRecord("h", "l", {"case": "c", "tol": 1e-11}, True, summary(0.0))]
    assert "expected a SimulationError" in hc.check("c", {}, crit, ran, scene)["reasons"][0]


# -- part 5: n = 512 over an orbit (docs/verification.md section 5) -----------------------------
MU_EARTH = 3.986004418e14  # the "earth" preset of tetherlab/scene/data.py


@pytest.fixture(scope="module")
def scene512():
    return load_scene(SCENES / "hard-n512.toml")


def test_n512_scene_is_a_damped_energy_model_tether(scene512):
    t = scene512.tethers[0]
    # "n = 512 rods stay stable over an orbit" (studies/hard_cases.py part 5); damped, energy model
    assert t.rods == 512 and t.damping_N_s == 2e4 and t.model == "energy"
    assert scene512.duration_orbits == 1.0 and scene512.orbit.motion == "corotating"  # no special start
    assert scene512.integrator.method == "radau5"


def test_strain_envelope_worked_by_hand(hc, scene512):
    # docs/verification.md 5: m0 = 1000, mf = 100, mt = 10 kg, L = 5000 m, EA = 5e4 N, r0 = 7400 km,
    # theta0 = 30 deg.  s_c = (100*5000 + 10*2500)/1110 = 472.973 m; n^2 = mu/r0^3 = 9.83672e-7 /s^2;
    # K_max = n^2 ((1 + sqrt3/2)^2 + 2) = 5.48205 n^2; T = K_max (1000 s_c + 0.002 s_c^2/2) = 2.55169 N
    env = hc.strain_envelope(scene512)
    assert env["eps_qs"] == pytest.approx(2.55169 / 5e4, rel=2e-5)
    # sudden start: 2 K(theta0)/K_max = 2 * 3 * 0.75 / 5.48205 = 0.82086 of eps_qs
    assert env["eps_start_overshoot"] == pytest.approx(0.82086 * env["eps_qs"], rel=1e-5)
    # beta = 10 (L/r0 + eps_qs + 3 n^2 / w_ax^2), w_ax^2 = EA/(L mf) = 0.1 /s^2
    n2 = MU_EARTH / 7.4e6**3
    assert env["beta"] == pytest.approx(10 * (5000 / 7.4e6 + env["eps_qs"] + 3 * n2 / 0.1), rel=1e-12)
    assert env["envelope"] == pytest.approx(env["eps_qs"] * (1 + env["beta"]), rel=1e-12)
    # the same field on the local vertical (K = 3 n^2) is the attachment tension 3 n^2 m0 s_c = 1.3957 N
    # (the convergence study's root tension is 1.39502 N: the rigid theory to 5e-4)
    assert 3 * n2 * 1000 * 472.973 == pytest.approx(1.3957, rel=1e-4)


def _summary512(**over):
    s = {"strain_min": 0.0, "strain_max": 5.1e-5, "angmom_error_own": 0.01, "energy_error_own": 0.01,
         "energy_rise_own": 0.01, "angmom_sum_scale": 2.6e7, "energy_sum_scale": 5.2e7, "n_steps": 2600.0,
         "nonfinite": 0.0, "wall_s": 10.0}
    return {**s, **over}


def test_n512_stable_run_passes_and_each_part_has_teeth(hc, scene512):
    ok = hc.n512_stability(_summary512(), None, scene512)
    assert ok["passed"] and ok["stability"] == pytest.approx(5.1e-5 / ok["envelope"])
    # budgets N rtol S: 2600 * 1e-9 * 2.6e7 = 67.6 (H), 2600 * 1e-9 * 5.2e7 = 135.2 (E)
    assert ok["B_H_int_own"] == pytest.approx(67.6) and ok["B_E_int_own"] == pytest.approx(135.2)
    over = hc.n512_stability(_summary512(strain_max=1.02 * ok["envelope"]), None, scene512)
    assert not over["passed"] and over["stability"] == pytest.approx(1.02)
    compressed = hc.n512_stability(_summary512(strain_min=-2 * ok["envelope"]), None, scene512)
    assert not compressed["passed"]
    assert not hc.n512_stability(_summary512(angmom_error_own=70.0), None, scene512)["passed"]
    assert not hc.n512_stability(_summary512(energy_rise_own=140.0), None, scene512)["passed"]
    # a falling energy (dissipation) is not a rise
    assert hc.n512_stability(_summary512(energy_rise_own=-5.0, energy_error_own=5.0), None, scene512)["passed"]
    nan = hc.n512_stability(_summary512(nonfinite=3.0), None, scene512)
    assert not nan["passed"] and nan["stability"] == math.inf
    stop = hc.n512_stability(None, "SimulationError: run stopped at t = 1 s: Newton failure", scene512)
    assert not stop["passed"] and stop["stability"] == math.inf and "Newton failure" in stop["reasons"][0]


@pytest.mark.slow
def test_n512_negative_control_is_caught(hc, scene512):
    # the anti-damped tether (mutants damping_sign) must fail the stability measure (it stops within
    # 0.02 s with a collapsed rod: docs/verification.md 5)
    c = hc.n512_negative_control(scene512)
    assert not c["passed"] and c["stability"] > 1.0
