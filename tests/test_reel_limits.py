"""The spool laws' smooth limits on the motor's torque and the pay-out speed (docs/deployment.md 10.4).

One run of studies/reel_limits.py (a drum in uniform gravity under the tension law, the motor's
torque limited and the regulating brake engaged, both limits active over most of the run) against
the bounds derived from the spool's balance, each with a deliberate defect it must fail; and the
limits' bad keys as SceneErrors naming the key.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from tetherlab.errors import SceneError
from tetherlab.model.params import (
    DEFECT_SPOOL_NO_SPEED_BRAKE,
    DEFECT_SPOOL_TORQUE_ONE_SIDED,
    DEFECT_SPOOL_TORQUE_UNLIMITED,
)
from tetherlab.scene import Scene

from .helpers import import_study

_STUDY = import_study("reel_limits")


@pytest.fixture(scope="module")
def limited():
    run = _STUDY.limits_run()
    assert run.ok
    return _STUDY.limits_measure(run)


def test_the_run_hits_both_limits(limited):
    m = limited
    active = m["active"]
    assert (active == 1).sum() > 50 and (active == 3).sum() > 50, np.unique(active, return_counts=True)
    assert m["torque_command"] > 1.5 * _STUDY.LIMITS["max_torque"]  # the command goes well beyond the limit


def test_applied_torque_within_its_limit(limited):
    assert limited["torque"] <= limited["torque_budget"], (limited["torque"], limited["torque_budget"])


def test_limited_torque_follows_the_command_inside_the_limit():
    """|tau - tau_c| <= w e^(-d/w) at a distance d inside the limit (the softplus corners, 10.4);
    measured on the kernel's function directly, with the corners of +-tau_max both counted."""
    from tetherlab.tether.reel_spool import limited_torque

    tmax, w = 32.0, 0.32
    for tau in np.linspace(-30.0, 30.0, 61):
        d = tmax - abs(tau)
        assert abs(limited_torque(tau, tmax, w) - tau) <= 2.0 * w * math.exp(-d / w) + 1e-12 * tmax
    for tau in (-1e3, -40.0, 40.0, 1e3):
        assert abs(limited_torque(tau, tmax, w)) <= tmax + w * math.log(2.0)


def test_speed_within_its_bound(limited):
    assert limited["speed"] <= limited["speed_budget"], (limited["speed"], limited["speed_budget"])
    assert limited["speed"] > _STUDY.LIMITS["max_speed"]  # the brake engaged: the bound is not idle


def test_spool_balance_closes_with_the_applied_limits(limited):
    assert limited["residual"] <= limited["residual_budget"], (limited["residual"], limited["residual_budget"])


def test_energy_balance_holds_with_the_limits(limited):
    """(10.3): the limited torque's and the regulating brake's work are in W_b."""
    assert limited["brake_work"] > 1e3  # J: the motor and the brake take a good part of the weight's work
    assert limited["energy_drift"] <= limited["energy_budget"], (limited["energy_drift"], limited["energy_budget"])


def test_unlimited_torque_in_the_balance_fails_residual_and_energy(limited):
    m = _STUDY.limits_measure(_STUDY.limits_run(DEFECT_SPOOL_TORQUE_UNLIMITED))
    assert m["residual"] > 100.0 * m["residual_budget"], (m["residual"], m["residual_budget"])
    assert m["energy_drift"] > 100.0 * m["energy_budget"], (m["energy_drift"], m["energy_budget"])


def test_brake_left_out_of_the_balance_fails_the_speed_bound():
    m = _STUDY.limits_measure(_STUDY.limits_run(DEFECT_SPOOL_NO_SPEED_BRAKE))
    assert m["speed"] > m["speed_budget"] + 1.0, (m["speed"], m["speed_budget"])
    assert m["energy_drift"] > 100.0 * m["energy_budget"], (m["energy_drift"], m["energy_budget"])


def test_one_sided_torque_limit_fails_the_torque_bound_alone():
    """The upper corner dropped (DEFECT_SPOOL_TORQUE_ONE_SIDED): the applied torque follows the
    command above tau_max (measured 55 N m against 32.2), while the balance and the energy, which
    carry the same torque, still close: only the torque bound sees it."""
    m = _STUDY.limits_measure(_STUDY.limits_run(DEFECT_SPOOL_TORQUE_ONE_SIDED))
    assert m["ok"]
    assert m["torque"] > 1.5 * m["torque_budget"], (m["torque"], m["torque_budget"])
    assert m["residual"] <= m["residual_budget"] and m["energy_drift"] <= m["energy_budget"]


def test_scene_round_trip_keeps_the_limits():
    scene = _STUDY.limits_scene()
    again = Scene.from_dict(scene.to_dict())
    assert again.tethers[0].reel == scene.tethers[0].reel
    assert again.tethers[0].reel.spool.max_torque_N_m == _STUDY.LIMITS["max_torque"]


P = "tethers.main.reel."
BAD_LIMITS = [
    ({"max_torque": "-1 N m"}, P + "max_torque"),
    ({"max_torque": "0 N m"}, P + "max_torque"),
    ({"max_speed": "-1 m/s"}, P + "max_speed"),
    ({"speed_brake_gain": "-5 N s/m"}, P + "speed_brake_gain"),
    ({"torque_limit_width": "10 N m"}, P + "torque_limit_width"),  # wider than a tenth of the limit
    ({"speed_limit_width": "0 m/s"}, P + "speed_limit_width"),
]


@pytest.mark.parametrize("change,key", BAD_LIMITS)
def test_bad_limit_keys_name_the_key(change, key):
    data = _STUDY.limits_scene().to_dict()
    data["tethers"]["main"]["reel"].update(change)
    with pytest.raises(SceneError) as err:
        Scene.from_dict(data)
    assert err.value.key == key


def test_limit_keys_without_their_limit_are_refused():
    data = _STUDY.limits_scene().to_dict()
    reel = data["tethers"]["main"]["reel"]
    for limit, dependent in (("max_speed", "speed_brake_gain"), ("max_torque", "torque_limit_width"),
                             ("max_speed", "speed_limit_width")):  # fmt: skip
        bad = {k: v for k, v in reel.items() if k != limit}
        if dependent not in bad:
            bad[dependent] = reel.get(dependent, "1 N s/m")
        d = dict(data, tethers={"main": dict(data["tethers"]["main"], reel=bad)})
        with pytest.raises(SceneError) as err:
            Scene.from_dict(d)
        assert err.value.key.startswith(P), err.value.key


def test_speed_limit_needs_its_brake_gain():
    data = _STUDY.limits_scene().to_dict()
    data["tethers"]["main"]["reel"].pop("speed_brake_gain")
    with pytest.raises(SceneError) as err:
        Scene.from_dict(data)
    assert err.value.key == P + "speed_brake_gain"


def test_constant_torque_beyond_its_limit_is_refused():
    data = import_study("reel_laws").drum_scene().to_dict()
    data["tethers"]["main"]["reel"]["max_torque"] = "5 N m"  # the drum's torque is 10 N m
    with pytest.raises(SceneError) as err:
        Scene.from_dict(data)
    assert err.value.key == P + "torque"


def test_limits_are_refused_under_a_prescribed_law():
    data = import_study("reel_laws").drum_scene().to_dict()
    reel = data["tethers"]["main"]["reel"]
    for k in ("spool_inertia", "drum_radius", "torque", "viscous_friction", "coulomb_friction", "friction_speed"):
        reel.pop(k, None)
    reel.update({"law": "constant", "speed": "1 m/s", "max_speed": "2 m/s"})
    with pytest.raises(SceneError) as err:
        Scene.from_dict(data)
    assert err.value.key == P + "max_speed"
