"""Events with DROMO (docs/dromo.md section 10): ``[stop] altitude`` and tension-only switches, located in the
time form on the same event functions of the physical state as with Cowell
(formulations/dromo.py ``dromo_time_events``; docs/dromo.md section 8).

Expected values: Kepler's equation for the stop time of a point mass (analytic); for the
tether's slack/taut switches, the Cowell run at a 10x tighter tolerance (an independent
formulation: other variables, other step sequence; only the event function is shared).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import tetherlab
from tests.helpers import MU_EARTH, SCENES
from tetherlab.scene import Scene

A_M, ECC = 7.4e6, 0.1  # perigee 6660 km, apogee 8140 km


def _point_mass(formulation: str, stop_km: float, tol: float = 1e-11) -> Scene:
    """A point mass on a Kepler ellipse (a = 7400 km, e = 0.1), starting at apogee."""
    ra = A_M * (1 + ECC)
    va = math.sqrt(MU_EARTH / A_M * (1 - ECC) / (1 + ECC))  # vis-viva at apogee
    return Scene.from_dict({
        "name": "dromo-stop", "duration": "3 h",
        "central_body": {"name": "earth"},
        "effects": {"central_gravity": {}},
        "bodies": {"sat": {"mass": "1 kg", "position": [f"{ra} m", "0 m", "0 m"],
                           "velocity": ["0 m/s", f"{va} m/s", "0 m/s"]}},
        "integrator": {"method": "dop853", "rtol": tol, "atol": tol, "formulation": formulation},
        "output": {"count": 11},
        "stop": {"altitude": f"{stop_km} km"},
    })  # fmt: skip


@pytest.mark.parametrize("formulation", ["dromo", "dromo-time", "cowell"])
def test_stop_altitude_with_dromo_lands_on_kepler_time(formulation):
    sc = _point_mass(formulation, 500.0)
    res = tetherlab.simulate(sc, progress=False)
    assert res.stats["stopped_by"] == "stop.altitude"
    ts = res.timeseries
    radius = sc.central_body.radius_m + 500e3
    # Kepler: r = a(1 - e cos E) on the descending branch (E in (pi, 2 pi)), t = (M - pi)/n
    E = 2 * math.pi - math.acos((1 - radius / A_M) / ECC)
    t_kepler = (E - ECC * math.sin(E) - math.pi) / math.sqrt(MU_EARTH / A_M**3)
    # rtol 1e-11 over 1/3 orbit: ~1e-4 m of position error, ~1e-7 s at the ~1 km/s radial speed
    # there; 1e-4 s leaves room for the event bracket (event_time_tolerance).
    assert abs(ts["t_s"].iloc[-1] - t_kepler) < 1e-4, (ts["t_s"].iloc[-1], t_kepler)
    r = np.sqrt(ts["sat.x_m"] ** 2 + ts["sat.y_m"] ** 2 + ts["sat.z_m"] ** 2).to_numpy()
    assert abs(r[-1] - radius) < 1e-2 and np.all(r[:-1] > radius)


def test_dromo_runs_the_time_form_when_the_scene_has_events():
    from tetherlab.pipeline import prepare

    assert prepare(_point_mass("dromo", 500.0)).formulation == "dromo-time"
    no_stop = _point_mass("dromo", 500.0).to_dict()
    del no_stop["stop"]
    assert prepare(Scene.from_dict(no_stop)).formulation == "dromo-sigma"


def test_slack_and_taut_switches_with_dromo_match_cowell():
    sc = tetherlab.load_scene(SCENES / "hard-slack-snap.toml").replace(
        **{"duration": "300 s", "tethers.main.rods": 2})  # fmt: skip
    dro = tetherlab.simulate(sc.replace(**{"integrator.formulation": "dromo"}), progress=False)
    cow = tetherlab.simulate(sc.replace(**{"integrator.rtol": 1e-11, "integrator.atol": 1e-11}),
                             progress=False)  # fmt: skip
    ed, ec = dro.stats["events"], cow.stats["events"]
    assert len(ed) == len(ec) >= 8  # measured: 12 switches of the two rods in 300 s
    assert [(e["event"], e["side"]) for e in ed] == [(e["event"], e["side"]) for e in ec]
    # rtol 1e-10 against 1e-11: Cowell's own switch times move by 6e-7 s between these two
    # tolerances (measured); DROMO at 1e-10 must be as close to the tight run (16x margin).
    dt = max(abs(a["t_s"] - b["t_s"]) for a, b in zip(ed, ec))
    assert dt < 1e-5, dt


def test_abm_is_a_sigma_form_method_only():
    """'abm' (docs/integrators.md section 8) runs the DROMO sigma form; elsewhere it is refused
    naming integrator.method."""
    from tetherlab.errors import SceneError

    no_stop = _point_mass("dromo", 500.0).to_dict()
    del no_stop["stop"]
    sc = Scene.from_dict(no_stop).replace(**{"integrator.method": "abm", "duration": "1 h"})
    ref = tetherlab.simulate(sc.replace(**{"integrator.method": "vern9"}), progress=False)
    res = tetherlab.simulate(sc, progress=False)
    # the same Kepler arc by two methods at tol 1e-11: agreement far below a millimetre
    cols = ["sat.x_m", "sat.y_m", "sat.z_m"]
    d = np.linalg.norm(res.timeseries[cols].to_numpy() - ref.timeseries[cols].to_numpy(), axis=1)
    assert d.max() < 1e-4, d.max()
    for change in ({"integrator.formulation": "cowell"}, {"integrator.formulation": "dromo-time"}):
        with pytest.raises(SceneError) as info:
            tetherlab.simulate(sc.replace(**change), progress=False)
        assert info.value.key == "integrator.method"
    with pytest.raises(SceneError) as info:  # events: the time form, where abm does not apply
        tetherlab.simulate(_point_mass("dromo", 500.0).replace(**{"integrator.method": "abm"}), progress=False)
    assert info.value.key == "integrator.method"
