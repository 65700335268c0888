"""The reel as a dynamical system: spool, brake, friction, tension law (docs/deployment.md 10-11).

Each gate has its threshold from the error budget of docs/deployment.md 11 and a negative control
(a deliberate defect of kernel/layout.py it must fail):

* a frictionless drum in uniform gravity against the closed form of the inextensible line; the
  exit tension taken at L'' = 0 (the coupling dropped) fails it;
* the energy balance E + K_spool + W_brake + W_loss = const with a torque and both frictions, the
  works' quadrature on the outputs as the budget; the uncoupled solve fails it;
* the tension law's closed-loop modes against the roots of its characteristic polynomial;
  the sign of k2 flipped fails it;
* the bad keys of the spool laws are SceneErrors naming the key.
"""

from __future__ import annotations

import numpy as np
import pytest

from tetherlab.deployment import simulate_reel
from tetherlab.errors import SceneError
from tetherlab.model.params import DEFECT_SPOOL_UNCOUPLED, DEFECT_TENSION_K2_SIGN
from tetherlab.scene import Scene

from .helpers import import_study

_STUDY = import_study("reel_laws")
TORQUE_N_M = 10.0  # drum_scene's default


@pytest.fixture(scope="module")
def drum():
    return simulate_reel(_STUDY.drum_scene(), progress=False)


def test_drum_in_uniform_gravity_follows_the_closed_form(drum):
    err, budget = _STUDY.drum_error(drum, TORQUE_N_M)
    assert err <= budget, (err, budget)
    L = drum.reel["deployed_length_m"].to_numpy()
    assert L[-1] - L[0] > 50.0  # m: the drum pays out, with the torque holding back half the end mass's weight
    # the outputs of the spool: its torque, L'', the power the torque takes (tau/R) L'
    r = drum.reel
    assert np.allclose(r["torque_N_m"], TORQUE_N_M)
    assert np.allclose(r["brake_power_W"], TORQUE_N_M / _STUDY.DRUM["R"] * r["speed_m_s"], rtol=1e-12)
    # L'' rings with the line's axial mode (released unstretched, undamped) about the oracle's
    # a + b l > 0: only its mean over the run is positive
    assert float(r["accel_m_s2"].mean()) > 0.0


def test_drum_without_the_coupling_of_the_exit_tension_fails_the_oracle():
    run = simulate_reel(_STUDY.drum_scene(), defect=DEFECT_SPOOL_UNCOUPLED, progress=False, raise_on_failure=False)
    err, budget = _STUDY.drum_error(run, TORQUE_N_M) if run.ok else (np.inf, 0.0)
    assert err > 100.0 * budget, (err, budget)


def _friction_scene(count=401):
    # EA 1e6 N: the line's axial mode (released unstretched, ~40 rad/s) rings through the brake's
    # viscous power; ten outputs per period keep the works' trapezoid rule in its asymptotic range
    return _STUDY.drum_scene(torque="4 N m", friction=(2.0, 15.0), count=count, duration="6 s", ea_N=1e6)


def test_energy_balance_with_brake_and_friction():
    """E + K_spool + W_brake + W_loss = const (docs/deployment.md 10.3): exact for the flow; the
    integrator keeps it to rtol of the energies that move, the two works' trapezoid rule on the
    outputs to its Richardson estimate (x2)."""
    run = simulate_reel(_friction_scene(), progress=False)
    total, est = _STUDY.spool_energy(run)
    drift = float(np.abs(total - total[0]).max())
    brake = float(run.reel["brake_work_J"].iloc[-1])
    assert brake > 100.0  # J: the brake and the friction take a good part of the energy released
    scale = float(np.abs(run.invariants["energy_J"]).max()) + float(run.reel["spool_kinetic_J"].max())
    assert drift <= 2.0 * est + 100.0 * 1e-10 * scale, (drift, est)


def test_uncoupled_spool_fails_the_energy_balance():
    run = simulate_reel(_friction_scene(), defect=DEFECT_SPOOL_UNCOUPLED, progress=False, raise_on_failure=False)
    total, est = _STUDY.spool_energy(run)
    drift = float(np.abs(total - total[0]).max())
    assert drift > 100.0 * est, (drift, est)


@pytest.fixture(scope="module")
def tension():
    run, om = _STUDY.tension_run()
    assert run.ok, run.message
    return _STUDY.tension_measure(run, om)


def test_tension_law_modes_match_the_characteristic_polynomial(tension):
    m = tension
    assert m["worst"] <= m["budget"], (m["worst"], m["budget"], m["theta"], m["xi"], m["roots"])
    # both modes seen in both signals: two pairs each, the fast one near 2.69 Omega
    assert len(m["theta"]) == len(m["xi"]) == 2


def test_tension_law_with_k2_flipped_fails_the_polynomial_gate(tension):
    run, om = _STUDY.tension_run(DEFECT_TENSION_K2_SIGN)
    worst = _STUDY.tension_measure(run, om)["worst"] if run.ok else np.inf
    assert worst > 3.0 * tension["budget"], (worst, tension["budget"])


def test_scene_round_trip_keeps_the_spool_law():
    for scene in (_STUDY.drum_scene(friction=(2.0, 15.0)), _STUDY.tension_scene()[0]):
        again = Scene.from_dict(scene.to_dict())
        assert again.tethers[0].reel == scene.tethers[0].reel


def test_scene_round_trip_of_a_canister_spool_law_without_a_drum_radius():
    # a canister under the spool law has no torque and no drum radius: the written scene must not
    # carry a torque, which would then ask for its arm
    data = _STUDY.drum_scene().to_dict()
    reel = data["tethers"]["main"]["reel"]
    for key in ("spool_inertia", "drum_radius", "torque"):
        del reel[key]
    reel["exit"] = "canister"
    scene = Scene.from_dict(data)
    written = scene.to_dict()["tethers"]["main"]["reel"]
    assert "torque" not in written and "drum_radius" not in written
    assert Scene.from_dict(scene.to_dict()).tethers[0].reel == scene.tethers[0].reel


BAD_SPOOLS = [
    ({"viscous_friction": "-1 N s/m"}, "tethers.main.reel.viscous_friction"),
    ({"coulomb_friction": "-2 N"}, "tethers.main.reel.coulomb_friction"),
    ({"friction_speed": "0 m/s"}, "tethers.main.reel.friction_speed"),
    ({"spool_inertia": "0 kg m2"}, "tethers.main.reel.spool_inertia"),
    ({"drum_radius": "-0.1 m"}, "tethers.main.reel.drum_radius"),
    ({"torque": "3 N"}, "tethers.main.reel.torque"),
    ({"rate": "1e-3 1/s"}, "tethers.main.reel.rate"),
    ({"k1": 4.0}, "tethers.main.reel.k1"),  # a gain of the tension law under the spool law
]


@pytest.mark.parametrize("change,key", BAD_SPOOLS)
def test_bad_spool_keys_name_the_key(change, key):
    data = _STUDY.drum_scene().to_dict()
    data["tethers"]["main"]["reel"].update(change)
    with pytest.raises(SceneError) as err:
        Scene.from_dict(data)
    assert err.value.key == key


def test_drum_without_inertia_or_radius_is_refused():
    for missing in ("spool_inertia", "drum_radius"):
        data = _STUDY.drum_scene().to_dict()
        data["tethers"]["main"]["reel"].pop(missing)
        with pytest.raises(SceneError) as err:
            Scene.from_dict(data)
        assert err.value.key == f"tethers.main.reel.{missing}"


def test_canister_has_no_spool_inertia():
    data = _STUDY.drum_scene().to_dict()
    data["tethers"]["main"]["reel"]["exit"] = "canister"
    with pytest.raises(SceneError) as err:
        Scene.from_dict(data)
    assert err.value.key == "tethers.main.reel.spool_inertia"


BAD_TENSION = [
    ({"k2": "fast"}, "tethers.main.reel.k2"),
    ({"orbit_rate": "0 rad/s"}, "tethers.main.reel.orbit_rate"),
    ({"reduced_mass": "-1 kg"}, "tethers.main.reel.reduced_mass"),
    ({"max_tension": "0.1 N", "min_tension": "0.2 N"}, "tethers.main.reel.max_tension"),
    ({"limit_width": "0.01 N"}, "tethers.main.reel.limit_width"),
    ({"torque": "1 N m"}, "tethers.main.reel.torque"),  # the law sets the torque
]


@pytest.mark.parametrize("change,key", BAD_TENSION)
def test_bad_tension_law_keys_name_the_key(change, key):
    data = _STUDY.tension_scene()[0].to_dict()
    data["tethers"]["main"]["reel"].update(change)
    with pytest.raises(SceneError) as err:
        Scene.from_dict(data)
    assert err.value.key == key


def test_tension_law_without_its_gains_is_refused():
    data = _STUDY.tension_scene()[0].to_dict()
    data["tethers"]["main"]["reel"].pop("k1")
    with pytest.raises(SceneError) as err:
        Scene.from_dict(data)
    assert err.value.key == "tethers.main.reel.k1"


def test_canister_with_brake_closes_the_energy_balance():
    """Through a canister the spool has no inertia: L'' comes from T(L'') = j + F_b alone (the line's
    own mass, S < 0), and the exit's loss is mostly the Carnot loss (docs/deployment.md 10.3)."""
    data = _friction_scene().to_dict()
    data["tethers"]["main"]["reel"]["exit"] = "canister"
    data["tethers"]["main"]["reel"].pop("spool_inertia")
    run = simulate_reel(Scene.from_dict(data), progress=False)
    total, est = _STUDY.spool_energy(run)
    drift = float(np.abs(total - total[0]).max())
    assert float(run.reel["exit_loss_J"].iloc[-1]) > 1e3  # J: the material jerked from rest
    assert float(run.reel["spool_kinetic_J"].abs().max()) == 0.0
    scale = float(np.abs(run.invariants["energy_J"]).max())
    assert drift <= 2.0 * est + 100.0 * 1e-10 * scale, (drift, est)


def test_births_under_a_spool_law_are_located_events():
    """L is state, so the births are located events of the run (docs/deployment.md 10.5): each
    happens where the first rod reaches its birth bound (30 m for rods of 20 m), and the drum
    still follows its closed form across them."""
    run = simulate_reel(_STUDY.drum_scene(rod_length="20 m"), progress=False)
    assert [c["change"] for c in run.changes] == ["birth"] * 3  # 10 -> 84 m
    r = run.reel
    for c in run.changes:
        row = r[(r["t_s"] == c["t_s"]) & (r["rods"] == c["rods"] - 1)]
        first = float(row["deployed_length_m"].iloc[-1]) - (c["rods"] - 2) * 20.0
        assert abs(first - 30.0) <= 1e-9 * 30.0, first
    err, budget = _STUDY.drum_error(run, TORQUE_N_M)
    assert err <= budget, (err, budget)
