"""Catenary (paper section 4.2): the statics solver against Irvine's elastic catenary.

Expected values come from references/catenary/reference.json (Irvine, Cable Structures, 1981,
closed form; built by references/catenary/build_reference.py without tetherlab code).  Thresholds
are set from the measurements of studies/catenary.py (quoted in docs/catenary.md, section 5) with
a margin: the paper model's shape error at n = 64 is 2.37e-5 m, the end tension error 2.85e-5 N,
the observed order 2.00-2.02 for every quantity.
"""

from __future__ import annotations

import importlib.util
import math

import numpy as np
import pytest

from tests.helpers import ROOT

from tetherlab.errors import SceneError
from tetherlab.formulations.cowell import cowell_rhs_py
from tetherlab.scene import Scene, load_scene

_spec = importlib.util.spec_from_file_location("catenary_study", ROOT / "studies" / "catenary.py")
study = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(study)

REF = study.load_reference()
SCENE = ROOT / "studies" / "scenes" / "catenary.toml"


@pytest.fixture(scope="module")
def sweep():
    return {r["n"]: r for r in study.run(REF, ns=(4, 8, 16, 32, 64), models=("paper",))}


def test_reference_is_self_consistent():
    # The builder's two methods (closed form, ODE shooting) agree to 2.5e-14 m (reference.json);
    # the vertical support force of a symmetric span is half the weight (statics).
    assert REF["second_method"]["max_shape_distance_m"] < 1e-10
    c = REF["case"]
    assert math.isclose(REF["solution"]["V_A_N"], 0.5 * c["tether_mass_kg"] * c["g_m_s2"], rel_tol=1e-12)


@pytest.mark.parametrize("n", [1, 4, 16])
def test_statics_residual(n):
    eq = study.solve_case(REF, n)
    # Newton stops at 1e-12 EA (4e-11 N) of rod force imbalance; the end mass sits within
    # 1e-14 of the tether length of its required place (tetherlab/statics.py).
    assert eq.residual_N < 1e-12 * REF["case"]["EA_N"]
    assert eq.constraint_m < 1e-13
    # Independent check through the Cowell right-hand side: every acceleration vanishes.  The
    # holding force is applied by the model's applied_force slot, so re-evaluate with it.
    from tetherlab.statics import held_model
    from tetherlab.forces import uniform_gravity
    from tetherlab.system import TetherSpec

    c = REF["case"]
    spec = TetherSpec("main", n, c["L0_m"], c["EA_N"], c["tether_mass_kg"], tip_mass_kg=c["end_mass_kg"], tip_name="mf")
    model = held_model(spec, [(uniform_gravity.SPEC, {"g": c["g_m_s2"]})])
    from tetherlab.statics import _force_slot

    k = _force_slot(model)
    model.p[k : k + 3] = eq.holding_force_N
    dy = cowell_rhs_py(model, eq.y)
    h = eq.y.size // 2
    # rod forces m_i d''_i within the solver's tolerance 1e-12 EA; the root does not move
    assert np.all(dy[h : h + 3] == 0.0)
    m_rod = c["tether_mass_kg"] / n
    assert np.max(np.abs(m_rod * dy[h + 3 :])) < 1e-12 * c["EA_N"]
    # the end mass is at rest: m_f g + J_n + R_f = 0 (statics of the end mass)
    w = np.array([0.0, 0.0, -c["end_mass_kg"] * c["g_m_s2"]])
    assert np.linalg.norm(eq.tip_pull_N + w + eq.holding_force_N) < 1e-12


@pytest.mark.parametrize("quantity", study.ERRORS)
def test_error_falls_with_observed_order_two(sweep, quantity):
    ns = sorted(sweep)
    errors = [sweep[n][quantity] for n in ns]
    assert all(b < a for a, b in zip(errors, errors[1:])), errors
    # measured 1.99-2.02 (docs/catenary.md, section 5); a band of +-0.15 catches a change of
    # discretisation order without tripping on the pre-asymptotic n = 4
    assert 1.85 < study.observed_order(ns, errors) < 2.15


def test_n64_errors_below_thresholds(sweep):
    r = sweep[64]
    # measured 2.37e-5 m / 3.60e-5 m (joints / joints and centres): threshold 0.05 mm
    assert r["shape_joints_m"] < 5e-5
    assert r["shape_points_m"] < 5e-5
    # measured 2.85e-5 N at both ends, 3.97e-5 N for the end reactions: threshold 0.05 mN
    assert r["tension_A_N"] < 5e-5
    assert r["tension_B_N"] < 5e-5
    assert r["nail_force_N"] < 5e-5
    assert r["holding_force_N"] < 5e-5
    assert r["axial_force_N"] < 5e-5


def test_scene_nail_at_origin_and_equilibrium_start():
    scene = load_scene(SCENE)
    assert scene.body("nail").fixed and scene.body("nail").mass_kg == 0.0
    assert Scene.from_dict(scene.to_dict()) == scene  # the massless nail round-trips
    from tetherlab.pipeline import prepare

    prep = prepare(scene)
    eq = study.solve_case(REF, scene.tether("main").rods)
    # the scene's starting shape is the statics solution of the same case (same code path)
    assert np.max(np.abs(prep.y0 - eq.y)) < 1e-12
    assert np.linalg.norm(prep.holding_force_N - eq.holding_force_N) < 1e-9
    # with the holding force applied, a short run stays at rest (a consistent initial condition)
    fx, fy, fz = (float(v) for v in prep.holding_force_N)
    held = scene.replace(**{
        "effects.applied_force": {"body": 1, "fx": f"{fx!r} N", "fy": f"{fy!r} N", "fz": f"{fz!r} N"},
        "duration": "0.5 s",
    })
    from tetherlab.pipeline import simulate

    res = simulate(held, progress=False)
    ts = res.timeseries
    drift = np.hypot(ts["main.node4.x_m"] - ts["main.node4.x_m"].iloc[0], ts["main.node4.z_m"] - ts["main.node4.z_m"].iloc[0])
    # rtol = atol = 1e-9 of the scene: the middle joint moves by less than 1e-7 m in 0.5 s
    assert drift.max() < 1e-7


def _catenary_dict():
    return load_scene(SCENE).to_dict()


def test_scene_errors():
    data = _catenary_dict()
    # a fixed body at the centre of the central body is refused only with central gravity
    data["effects"]["central_gravity"] = {}
    with pytest.raises(SceneError, match="bodies.nail.position"):
        Scene.from_dict(data)
    # 'equilibrium' takes no angles
    data = _catenary_dict()
    data["tethers"]["main"]["initial"] = {"shape": "equilibrium", "theta": "0.1 rad"}
    with pytest.raises(SceneError, match="tethers.main.initial.theta"):
        Scene.from_dict(data)
    # the tip may not be fixed (the kernel holds only the root)
    data = _catenary_dict()
    data["bodies"]["mf"] = {"fixed": True, "position": ["0.9 m", "0 m", "0 m"]}
    from tetherlab.pipeline import prepare

    with pytest.raises(SceneError, match="bodies.mf.fixed"):
        prepare(Scene.from_dict(data))
    # a moving root cannot start in 'equilibrium'
    data = _catenary_dict()
    data["bodies"]["nail"] = {"mass": "1 kg", "position": ["0 m", "0 m", "0 m"], "velocity": ["0 m/s"] * 3}
    with pytest.raises(SceneError, match="bodies.nail.fixed"):
        prepare(Scene.from_dict(data))
    # a moving end mass cannot start in equilibrium
    data = _catenary_dict()
    data["bodies"]["mf"]["velocity"] = ["0.1 m/s", "0 m/s", "0 m/s"]
    with pytest.raises(SceneError, match="bodies.mf.velocity"):
        prepare(Scene.from_dict(data))
    # applied_force body index out of range
    data = _catenary_dict()
    data["effects"]["applied_force"] = {"body": 5}
    with pytest.raises(SceneError, match="effects.applied_force.body"):
        prepare(Scene.from_dict(data))


def test_uniform_gravity_potential_matches_force():
    # U = g z per unit mass: the diagnostics' potential energy of a mass at rest at height z
    # is m g z (definition), checked through the kernel's potential dispatch.
    from tetherlab.kernel.effects import potential_per_mass
    from tetherlab.statics import held_model
    from tetherlab.forces import uniform_gravity
    from tetherlab.system import TetherSpec

    spec = TetherSpec("main", 1, 1.0, 40.06, 0.1, tip_mass_kg=0.1, tip_name="mf")
    model = held_model(spec, [(uniform_gravity.SPEC, {"g": 9.80665})])
    p = model.fresh_params()
    assert potential_per_mass(p, 0.0, 0.3, -0.2, 2.0) == pytest.approx(9.80665 * 2.0, rel=1e-15)
