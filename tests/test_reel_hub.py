"""A reel on a rigid body (docs/deployment.md 9): the stored tether's share against a ring of point
masses, the balances of a spinning hub under every reel law with their negative controls, and every
bad key of such a reel a SceneError naming it.

The runs are the verify study's own scenes (studies/deployment_hub.py), shortened to 40 s (two
births at 2 m/s); their bounds are the study's (references/gates.toml, deployment_hub_*).
"""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest

from tetherlab.deployment import simulate_reel
from tetherlab.errors import SceneError
from tetherlab.model.params import DEFECT_NO_CENTRIPETAL, DEFECT_REEL_NO_EXIT_TORQUE, DEFECT_REEL_NO_RING, ParamView
from tetherlab.pipeline import prepare
from tetherlab.scene import Scene
from tetherlab.tether.reel_hub import reel_hub_share
from tetherlab.tether.solve import system_accelerations

from .helpers import import_study

_HUB = import_study("deployment_hub")
RTOL = _HUB.HUB_RTOL
MASS_KG = _HUB.HUB_KG + _HUB.END_KG + _HUB.RHO_KG_M * (150.0 + _HUB.STORED_M)  # hub, end mass, whole line


def _short(**kw):
    return _HUB.hub_scene(duration="40 s", count=81, **kw)


def _errors(run):
    """(|H - H0| max, its bound 100 rtol |H0|, |P - P0| max, its bound 100 rtol sqrt(2 M K_max))."""
    H, P = _HUB._vec(run.invariants, "H"), _HUB._vec(run.invariants, "P")
    p_scale = math.sqrt(2.0 * MASS_KG * float(run.invariants["kinetic_J"].max()))
    return (float(np.abs(H - H[0]).max()), 100.0 * RTOL * float(np.linalg.norm(H[0])),
            float(np.abs(P - P[0]).max()), 100.0 * RTOL * p_scale)  # fmt: skip


# -- the stored tether's share against a ring of point masses --------------------------------------
@pytest.mark.parametrize("exit_", ["canister", "drum"])
def test_stored_tether_share_is_that_of_a_ring_of_point_masses(exit_):
    # An independent sum over 3600 point masses of the thin ring (radius R_s about the spool axis,
    # centred at the exit) moving with the hub (and, on a drum, at L'/R_s about its axis): its
    # momentum, angular momentum about the origin and kinetic energy, against reel_hub_share's
    # closed forms (docs/deployment.md 9.1).  The sum is exact for the ring's second moments up to
    # round-off (a regular polygon of N > 2 points has the ring's inertia), so 1e-12 relative.
    scene = _HUB.hub_scene(law="constant", exit_=exit_)
    prep = prepare(scene)
    model = prep.model
    p = model.fresh_params()
    lay = model.state
    y = prep.y0
    acc = np.zeros(lay.n_qt)
    datt = np.zeros(lay.n_attitude + lay.n_wheels)
    assert system_accelerations(0.0, y[lay.q], y[lay.qd], y[lay.first_order], p, acc, datt) == 0
    got = np.array(reel_hub_share(p, 0)[:7])
    v = ParamView(p)
    bs = v.body_scratch[0]
    r_o, v_o = np.array(bs.r_m), np.array(bs.v_m_s)
    R = np.array(bs.rot).reshape(3, 3)
    w = np.array(bs.w_rad_s)
    e = R @ np.array(_HUB.EXIT_B)
    a = R @ (np.array([0.0, 0.0, 1.0]) if exit_ == "drum" else np.array([1.0, 0.0, 0.0]))
    b1 = np.cross(a, [0.0, 1.0, 0.0] if abs(a[1]) < 0.9 else [1.0, 0.0, 0.0])
    b1 /= np.linalg.norm(b1)
    b2 = np.cross(a, b1)
    n = 3600
    phi = 2.0 * np.pi * np.arange(n) / n
    rad = _HUB.SPOOL_R * (np.outer(np.cos(phi), b1) + np.outer(np.sin(phi), b2))
    x = e + rad  # from O
    ms = _HUB.RHO_KG_M * _HUB.STORED_M  # 2 km stored at t = 0
    dm = ms / n
    vel = v_o + np.cross(w, x)
    if exit_ == "drum":  # the turns at the rim speed L' = 2 m/s about +a (scene: spool_axis)
        vel = vel + np.cross((2.0 / _HUB.SPOOL_R) * a, rad)
    # the hub's share counts the stored mass at O with v_O (bodies/point.py): subtract it
    mom = dm * vel.sum(axis=0) - ms * v_o
    ang = dm * np.cross(r_o + x, vel).sum(axis=0) - ms * np.cross(r_o, v_o)
    ke = 0.5 * dm * (vel * vel).sum() - 0.5 * ms * (v_o @ v_o)
    want = np.concatenate([mom, ang, [ke]])
    scale = np.array([np.abs(mom).max() + ms * np.linalg.norm(w) * 1.0] * 3 + [np.abs(ang).max()] * 3 + [abs(ke)])
    assert np.all(np.abs(got - want) <= 1e-12 * scale), (got, want)


# -- the balances of the spinning hub, every law -----------------------------------------------------
@pytest.mark.parametrize("law,exit_", [("constant", "canister"), ("exponential", "drum"), ("table", "canister"),
                                       ("constant", "drum")])  # fmt: skip
def test_spinning_hub_keeps_angular_and_linear_momentum(law, exit_):
    run = simulate_reel(_short(law=law, exit_=exit_))
    assert run.ok, run.message
    assert [c["change"] for c in run.changes] and all(c["change"] == "birth" for c in run.changes)
    h_err, h_bound, p_err, p_bound = _errors(run)
    assert h_err <= h_bound, (h_err, h_bound)
    assert p_err <= p_bound, (p_err, p_bound)


def test_without_the_exit_torque_angular_momentum_fails_its_bound():
    h_err, h_bound, _, _ = _errors(simulate_reel(_short(), defect=DEFECT_REEL_NO_EXIT_TORQUE, raise_on_failure=False))
    assert h_err > h_bound, (h_err, h_bound)


def test_without_the_centripetal_term_momentum_fails_its_bound():
    _, _, p_err, p_bound = _errors(simulate_reel(_short(), defect=DEFECT_NO_CENTRIPETAL, raise_on_failure=False))
    assert p_err > p_bound, (p_err, p_bound)


def test_hub_energy_plus_exit_work_is_constant_to_its_quadrature():
    # docs/deployment.md 9.3: E + W_exit = const exactly (free wheel, no external force); the only
    # error is the trapezoid rule of W_exit on the outputs, bounded by twice its Richardson estimate
    for exit_ in ("canister", "drum"):
        coarse = simulate_reel(_HUB.hub_scene(exit_=exit_, duration="40 s", count=81))
        fine = simulate_reel(_HUB.hub_scene(exit_=exit_, duration="40 s", count=161))
        drift, bound, _ = _HUB._energy_bound(coarse, fine)
        assert drift <= bound, (exit_, drift, bound)


def test_stored_tether_leaves_the_hub_mass():
    # the hub's mass is its own plus the stored tether: 200 kg + 10 g/m x (2000 m - 80 m paid out)
    run = simulate_reel(_short())
    stored = run.reel["stored_length_m"].to_numpy()
    assert stored[0] == pytest.approx(2000.0, abs=1e-9)
    assert stored[-1] == pytest.approx(2000.0 - 80.0, abs=1e-9)  # 2 m/s x 40 s


# -- scene keys ----------------------------------------------------------------------------------------
def _dict(**reel_changes):
    d = copy.deepcopy(_short().to_dict())
    d["tethers"]["main"].pop("from_point", None)  # the reel's point is the tether's attachment
    reel = d["tethers"]["main"]["reel"]
    for k, v in reel_changes.items():
        if v is None:
            reel.pop(k, None)
        else:
            reel[k] = v
    return d


def test_a_hub_scene_reads_back_the_same():
    scene = _short(exit_="drum")
    again = Scene.from_dict(scene.to_dict())
    assert again.tethers[0].reel == scene.tethers[0].reel
    assert again.tethers[0].from_point_m == pytest.approx(_HUB.EXIT_B)


@pytest.mark.parametrize("change,key,words", [
    ({"exit_direction": None}, "tethers.main.reel.exit_direction", "rigid body"),
    ({"exit_direction": [0, 0, 0]}, "tethers.main.reel.exit_direction", "non-zero length"),
    ({"exit_direction": ["1 m", 0, 0]}, "tethers.main.reel.exit_direction[0]", "a number"),
    ({"exit_direction": [1, 0]}, "tethers.main.reel.exit_direction", "3 numbers"),
    ({"point": None}, "tethers.main.reel.point", "exit point"),
    ({"point": ["50 m", "0 m", "0 m"]}, "tethers.main.reel.point", "within 10 times the body's size"),
    ({"point": [1, 0, 0]}, "tethers.main.reel.point[0]", "m"),
    ({"spool_radius": None}, "tethers.main.reel.spool_radius", "radius of the spool"),
    ({"spool_radius": "0 m"}, "tethers.main.reel.spool_radius", "> 0"),
    ({"spool_radius": "-0.3 m"}, "tethers.main.reel.spool_radius", "> 0"),
    ({"spool_radius": "40 m"}, "tethers.main.reel.spool_radius", "within 10 times the body's size"),
    ({"spool_axis": [0, 0, 1]}, "tethers.main.reel.spool_axis", "canister"),
    ({"exit": "drum"}, "tethers.main.reel.spool_axis", "drum's axis"),
    ({"exit": "drum", "spool_axis": [1, 0, 1]}, "tethers.main.reel.spool_axis", "perpendicular"),
    ({"exit": "drum", "spool_axis": [0, 0, 0]}, "tethers.main.reel.spool_axis", "non-zero length"),
])  # fmt: skip
def test_bad_hub_reel_keys_are_scene_errors_naming_the_key(change, key, words):
    with pytest.raises(SceneError) as e:
        Scene.from_dict(_dict(**change))
    assert e.value.key == key, str(e.value)
    assert words in str(e.value)


def test_a_from_point_other_than_the_reel_point_is_refused():
    d = _dict()
    d["tethers"]["main"]["from_point"] = ["0 m", "1 m", "0 m"]
    with pytest.raises(SceneError) as e:
        Scene.from_dict(d)
    assert e.value.key == "tethers.main.from_point" and "reel's point" in str(e.value)


def test_a_reel_at_the_end_that_is_not_its_body_attachment_is_refused():
    # the end mass fixed, so it is the root and the hub hangs from the tether by its `from` end:
    # the reel on the hub would sit at the end the hub hangs by, not the one it holds the tether by
    d = _dict()
    d["bodies"]["mf"]["fixed"] = True
    d["bodies"]["mf"].pop("velocity")
    with pytest.raises(SceneError) as e:
        Scene.from_dict(d)
    assert e.value.key == "tethers.main.reel" and "attachment" in str(e.value)


def test_hub_keys_on_a_point_mass_reel_are_refused():
    d = _dict()
    d["bodies"]["hub"].pop("rigid")
    d["bodies"]["hub"].pop("wheels")
    with pytest.raises(SceneError) as e:
        Scene.from_dict(d)
    assert e.value.key == "tethers.main.reel.point" and "point mass" in str(e.value)


def test_a_hub_that_hangs_from_another_tether_keeps_angular_momentum():
    # the hub is a child (its parent tether's end body, eliminated into the root's system through
    # its compliance with the stored tether's coupled 6x6 matrix): a 50 kg root holds it by a 39 m
    # line at (-1, 0, 0) m in body axes while it pays out from its reel; bound and control as above
    d = _short().to_dict()
    d["bodies"] = {"m0": {"mass": "50 kg", "position": ["-40 m", "0 m", "0 m"], "velocity": ["0 m/s", "-2 m/s", "0 m/s"]},
                   **d["bodies"]}  # fmt: skip
    d["tethers"] = {"hold": {"from": "m0", "to": "hub", "length": "39 m", "EA": "5e3 N", "linear_density": "0.01 kg/m",
                             "rods": 2, "model": "energy", "to_point": ["-1 m", "0 m", "0 m"]}, **d["tethers"]}  # fmt: skip
    for defect, fails in ((0, False), (DEFECT_REEL_NO_EXIT_TORQUE, True)):
        run = simulate_reel(Scene.from_dict(d), defect=defect, raise_on_failure=False)
        assert run.ok and len(run.changes) == 2, run.message
        H = _HUB._vec(run.invariants, "H")
        h_err, h_bound = float(np.abs(H - H[0]).max()), 100.0 * RTOL * float(np.linalg.norm(H[0]))
        assert (h_err > h_bound) == fails, (defect, h_err, h_bound)


def test_radau5_with_its_structured_newton_matrix_keeps_the_hub_balances():
    # RADAU5 (its Newton matrix from the structured solver with the attitude bordered on,
    # integrators/radau5/border.py) on a hub reel: a Newton matrix off the stored tether's terms
    # would cost iterations, not the balances; rtol 1e-9 here, so the bound is 100 rtol |H(0)|
    d = _short().to_dict()
    d["integrator"] = {"method": "radau5", "rtol": 1e-9, "atol": 1e-9}
    run = simulate_reel(Scene.from_dict(d))
    assert run.ok, run.message
    H = _HUB._vec(run.invariants, "H")
    assert float(np.abs(H - H[0]).max()) <= 100.0 * 1e-9 * float(np.linalg.norm(H[0]))


def test_on_axis_the_hub_spins_up_as_the_spool_empties():
    # docs/deployment.md 9.4: omega_z = omega_0 (J + m_s(0) R_s^2)/(J + m_s(t) R_s^2) on the axis (the
    # ring's term of eq. 9.3; the line, the end mass and the flux have no moment about z); bound the
    # integrator's error 100 rtol omega_0; control: the ring's term dropped (omega_z stays omega_0)
    bound = 100.0 * RTOL * _HUB.AXIS_SPIN_RAD_S
    _, _, err = _HUB.axis_errors(simulate_reel(_HUB.axis_scene(count=31)))
    assert err <= bound, (err, bound)
    _, _, c_err = _HUB.axis_errors(simulate_reel(_HUB.axis_scene(count=31), defect=DEFECT_REEL_NO_RING))
    assert c_err > bound, (c_err, bound)
