"""The continuum string of a reel's deployment (tetherlab/oracles/deploying_string.py,
docs/deployment.md 8h): its case is part G's scene, its stored limit is the builder's, a line paid out
without any field is the exact straight uniform motion, and its grid refinement has the scheme's
second order."""

from __future__ import annotations

import importlib.util
import json
import math

import numpy as np
import pytest

from studies.deployment import convergence_scene
from tests.helpers import ROOT
from tetherlab.oracles.deploying_string import DeployingString, solve

_spec = importlib.util.spec_from_file_location("deploying_string_build", ROOT / "references" / "deploying_string" / "build_limit.py")
build_limit = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(build_limit)

LIMIT = json.loads((ROOT / "references" / "deploying_string" / "limit.json").read_text())


def test_the_case_is_part_g_scene():
    # source of every expected value: studies/deployment.py convergence_scene (part G), read back
    scene = convergence_scene(1000.0)
    t = scene.tethers[0]
    bodies = {b.name: b.mass_kg for b in scene.bodies}
    c = build_limit.CASE
    assert (c.station_kg, c.end_kg) == (bodies[t.from_body], bodies[t.to_body])
    assert c.rho_kg_m == pytest.approx(t.mass_kg / t.length_m, rel=1e-15)  # kg/m
    assert (c.ea_n, c.damping_n_s, c.length0_m) == (t.EA_N, t.damping_N_s, t.length_m)
    assert (t.model, t.tension_only, t.initial.shape, t.initial.side, t.initial.strain) == ("energy", False, "straight",
                                                                                          "up", 0.0)
    assert t.initial.theta_rad == 0.0 and t.initial.phi_rad == 0.0
    assert (t.reel.law, t.reel.exit) == ("constant", "canister")
    assert c.speed_m_s == pytest.approx(t.reel.speed_m_s, rel=1e-15)  # m/s
    assert c.stored0_m == t.reel.stored_length_m
    assert c.duration_s == pytest.approx(scene.duration_s, rel=1e-15)  # s
    assert (scene.orbit.reference, scene.orbit.motion, scene.orbit.elements.e) == ("center_of_mass", "corotating", 0.0)
    assert c.radius_m == scene.orbit.elements.a_m


def test_the_stored_limit_is_the_builders_case_with_its_provenance():
    c = build_limit.CASE
    assert LIMIT["case"] == {k: getattr(c, k) for k in c.__dataclass_fields__}
    grids = [r["grid"] for r in LIMIT["levels"]]
    assert len(grids) >= 3 and all(b == 2 * a for a, b in zip(grids, grids[1:]))
    assert LIMIT["tolerance_check"]["grid"] in grids
    assert LIMIT["rtol"] == build_limit.RTOL and LIMIT["method"] == build_limit.METHOD
    for key in ("oracle", "builder", "command", "date_utc", "scipy"):
        assert LIMIT["provenance"][key]


def test_a_line_paid_out_without_a_field_moves_straight_and_unstrained():
    # mu = 1e-12 m^3/s^2 on a 7000 km radius: frame rate 5e-17 rad/s (the Coriolis drift n L' t^2 ~ 1e-11 m); a 1e15 kg
    # station recoils by rho L'^2 / M ~ 1e-17 m/s^2.  The exact solution (docs/deployment.md 8h): the line
    # stays on its initial straight line, unstrained, the end mass L0 + L' t from the station and node j
    # at (1 - j/N) L(t) from it; the tolerance is the integrator's (rtol 1e-10 of ~1 km)
    case = DeployingString(station_kg=1e15, end_kg=25.0, rho_kg_m=5e-3, ea_n=1e5, damping_n_s=1e4, length0_m=500.0,
                           speed_m_s=2.0, stored0_m=1e4, mu_m3_s2=1e-12, radius_m=7e6, duration_s=300.0)  # fmt: skip
    n = 8
    s = solve(case, n, rtol=1e-10, atol_m=1e-10)
    L = 500.0 + 2.0 * 300.0
    rel = s.positions_m - s.positions_m[-1]
    expected = np.column_stack([(1.0 - np.arange(n + 1) / n) * L, np.zeros(n + 1)])
    assert np.max(np.abs(rel - expected)) < 1e-6  # m
    assert abs(s.theta_rad[-1]) < 1e-12 and s.offset_m[-1] < 1e-6  # rad, m


def test_bad_arguments_raise_naming_the_key():
    with pytest.raises(ValueError, match="DeployingString.ea_n: expected a positive finite number; got -1"):
        DeployingString(1000.0, 25.0, 5e-3, -1.0, 1e4, 500.0, 1.0, 1e4, 3.986e14, 7e6, 100.0)
    with pytest.raises(ValueError, match="grid: expected at least 4 segments; got 2"):
        solve(build_limit.CASE, 2)


@pytest.mark.slow
def test_grid_refinement_has_the_second_order_of_the_staggered_scheme():
    # the first quarter of part G's run on 8, 16, 32 segments: the ratio of successive differences of
    # the end angle is 4 for the staggered second-order scheme in its asymptotic range; +-0.3 in the
    # order allows the next term (the stored levels to 128 segments show 1.99-2.0)
    c = build_limit.CASE
    quarter = DeployingString(**{k: getattr(c, k) for k in c.__dataclass_fields__ if k != "duration_s"},
                              duration_s=c.duration_s / 4)  # fmt: skip
    v = [solve(quarter, n, rtol=1e-9, atol_m=1e-8, method="BDF").theta_rad[-1] for n in (8, 16, 32)]
    order = math.log2(abs((v[1] - v[0]) / (v[2] - v[1])))
    assert abs(order - 2.0) < 0.3, (v, order)


def test_the_simulators_start_is_the_oracles():
    # the oracle's start (docs/deployment.md 8h): the centre of mass of the station's dry mass, the end
    # mass and the line on the reference radius, the line straight up the vertical; the simulator's first
    # output row of part G's scene (tetherlab/initial/star.py lays it out) must agree to round-off of 7e6 m
    from tetherlab.deployment import simulate_reel

    c = build_limit.CASE
    run = simulate_reel(convergence_scene(1000.0))
    row = run.phases[0].timeseries.iloc[0]
    station = np.array([row["m0.x_m"], row["m0.y_m"]])
    tip = np.array([row["main.node1.x_m"], row["main.node1.y_m"]])
    m_line = c.rho_kg_m * c.length0_m
    offset = (c.end_kg * c.length0_m + m_line * c.length0_m / 2) / (c.station_kg + c.end_kg + m_line)
    assert abs(np.linalg.norm(station) - (c.radius_m - offset)) < 1e-8  # m
    assert np.max(np.abs(tip - station - np.array([c.length0_m, 0.0]))) < 1e-8  # m
