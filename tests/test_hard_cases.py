"""studies/hard_cases.py: the pass criterion of the hard cases (issue 4) has teeth.

Synthetic run records (tetherlab.sweep.RunRecord) exercise each part of the criterion: invariants
against their round-off bounds, convergence as the tolerance tightens (a ladder that does not
converge, or does not resolve anything above round-off, fails), and the clear error expected
where a case leaves the model's validity.  The bounds' formulas are the derivation in the study's
docstring; the numbers below are worked by hand from them.  The study itself runs in make verify.
"""

from __future__ import annotations

import importlib.util
import math
import sys

import pytest

from tests.helpers import ROOT, SCENES
from tetherlab.scene import load_scene
from tetherlab.summaries import event_code
from tetherlab.sweep import RunRecord

U = 2.0**-53


@pytest.fixture(scope="module")
def hc():
    spec = importlib.util.spec_from_file_location("tetherlab_study_hard_cases", ROOT / "studies" / "hard_cases.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod
    spec.loader.exec_module(mod)
    yield mod
    sys.modules.pop(spec.name, None)


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
