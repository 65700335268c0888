"""A tension law's stage started on reaching a deployed length (docs/deployment.md 10.6, 10.7).

* the `at_length` key and the stage-wise gains and limits: bad input is a SceneError naming the
  key; a stage's gains and limits are its own where given and the law's otherwise; the stages
  survive a round trip through the scene's dictionary;
* the switch is a located event (`reel.<tether>.stage`): the phase ends where L crosses the
  length, within the locator's tolerance in length, and the next phase runs under the stage's
  commanded length and gains (the command at every output is the law's formula with the stage's
  parameters).

The scene is the staged retrieval of docs/deployment.md 14 (5 km hauled in from rest about
l_c = 2.5 km) with its time stages replaced by one started at 4 km, with its own gains.
"""

from __future__ import annotations

import math

import pytest

from tetherlab.deployment import simulate_reel
from tetherlab.errors import SceneError
from tetherlab.integrators.common import EPS, event_time_tolerance
from tetherlab.scene import Scene
from tetherlab.scene.reels import stage_parameters

from .helpers import import_study

_STUDY = import_study("reel_retrieval")
KEY = "tethers.main.reel.stages"
#: the stage: at 4 km (the law drives L from 5 km towards 2.5 km), then l_c = 1.25 km with k1 = 6, k2 = 2
AT_M, LC2_M, K1, K2 = 4000.0, 1250.0, 6.0, 2.0


def _data(stages, orbits: float = 1.0) -> dict:
    data = _STUDY.retrieval_scene(controlled=True, orbits=orbits, count=81).to_dict()
    data["tethers"]["main"]["reel"]["stages"] = stages
    return data


STAGE = {"at_length": f"{AT_M} m", "commanded_length": f"{LC2_M} m", "k1": K1, "k2": K2}

BAD = [
    ([{"commanded_length": "1 km"}], f"{KEY}[0]"),  # neither start nor at_length
    ([{"start": "1 h", "at_length": "4 km", "commanded_length": "1 km"}], f"{KEY}[0]"),  # both
    ([{"at_length": "-1 km", "commanded_length": "1 km"}], f"{KEY}[0].at_length"),  # not positive
    ([{"at_length": "7 km", "commanded_length": "1 km"}], f"{KEY}[0].at_length"),  # beyond the line (5 + 1 km)
    # the law drives L from 5 km down to 2.5 km: 5.5 km is never reached, nor 5 km itself
    ([{"at_length": "5.5 km", "commanded_length": "1 km"}], f"{KEY}[0].at_length"),
    ([{"at_length": "5 km", "commanded_length": "1 km"}], f"{KEY}[0].at_length"),
    # the second stage begins at 4 km and drives L down to 1 km: 4.5 km is on the wrong side
    ([STAGE, {"at_length": "4.5 km", "commanded_length": "1 km"}], f"{KEY}[1].at_length"),
    # a time stage after a length stage: the switch's time is not known ahead
    ([STAGE, {"start": "2 h", "commanded_length": "1 km"}], f"{KEY}[1].start"),
    ([dict(STAGE, k1="four")], f"{KEY}[0].k1"),
    ([dict(STAGE, min_tension="-1 N")], f"{KEY}[0].min_tension"),
    ([dict(STAGE, min_tension="2 N", max_tension="1 N")], f"{KEY}[0].max_tension"),
    ([dict(STAGE, limit_width="0.01 N")], f"{KEY}[0].limit_width"),  # the law has no limits to round
    ([dict(STAGE, max_speed="2 m/s")], f"{KEY}[0].speed_brake_gain"),  # the law has no brake gain
    ([dict(STAGE, speed_limit_width="0.01 m/s")], f"{KEY}[0].speed_limit_width"),  # no max_speed
    ([dict(STAGE, torque="1 N m")], f"{KEY}[0].torque"),  # not a stage's key
]


@pytest.mark.parametrize("stages,key", BAD)
def test_bad_length_stages_name_the_key(stages, key):
    with pytest.raises(SceneError) as err:
        Scene.from_dict(_data(stages))
    assert err.value.key == key


def test_a_length_stage_after_a_time_stage_is_checked_against_the_line_only():
    """After a time stage L at the switch is not known ahead: only the length's bounds apply."""
    sp = Scene.from_dict(_data([{"start": "1 h", "commanded_length": "4.5 km"},
                                {"at_length": "4.2 km", "commanded_length": "1 km"}])).tethers[0].reel.spool  # fmt: skip
    assert sp.stages[0].start_s == 3600.0 and sp.stages[1].at_length_m == 4200.0


def test_stage_parameters_inherit_the_law_and_override_their_own():
    data = _data([dict(STAGE, min_tension="0.5 N", max_tension="20 N"),
                  {"at_length": "2 km", "commanded_length": "1 km", "max_speed": "2 m/s", "speed_brake_gain": "50 N s/m"}])  # fmt: skip
    sp = Scene.from_dict(data).tethers[0].reel.spool
    law = stage_parameters(sp, -1)
    one, two = stage_parameters(sp, 0), stage_parameters(sp, 1)
    assert (law["lc_m"], law["k1"], law["k2"], law["twidth_N"], law["speed_width_m_s"]) == (2500.0, 4.0, 1.0, 0.0, 0.0)
    assert (one["lc_m"], one["k1"], one["k2"], one["tmin_N"], one["tmax_N"]) == (LC2_M, K1, K2, 0.5, 20.0)
    # the law's default corner, 1 % of the stage's band (scene/reels.py)
    assert one["twidth_N"] == pytest.approx(0.01 * 19.5, rel=1e-15)
    # the second stage gives no gains or tension limits: the law's (none), not the first stage's
    assert (two["k1"], two["k2"], two["tmin_N"], two["tmax_N"], two["twidth_N"]) == (4.0, 1.0, 0.0, 0.0, 0.0)
    assert (two["max_speed_m_s"], two["speed_gain_N_s_m"]) == (2.0, 50.0)
    assert two["speed_width_m_s"] == pytest.approx(0.02, rel=1e-15)  # LIMIT_WIDTH_DEFAULT of max_speed
    again = Scene.from_dict(Scene.from_dict(data).to_dict()).tethers[0].reel.spool
    assert again.stages == sp.stages


@pytest.fixture(scope="module")
def switched():
    return simulate_reel(Scene.from_dict(_data([STAGE])), progress=False)


def test_the_switch_is_located_at_the_length(switched):
    """The phase ends where L crosses 4 km: |L - 4 km| within the located stop's tolerance in
    length (docs/deployment.md 10.7a): |L'| times the event bracket's width (the step at most the
    phase), the round-off of L, and the integration to the bracket's end against the polynomial the
    bracket was found on, sqrt(n) (atol + rtol L) with n = 6 (1 + rods) + 2 the state's size
    (rtol = atol = 1e-9; the rods and the phase's start from the last retirement before the
    switch).  Measured 2.7e-10 m, above the bracket's share (< 2e-11 m): the integrator's term is
    the one that holds it."""
    sw = [c for c in switched.changes if c["change"] == "stage"]
    assert len(sw) == 1 and sw[0]["stage"] == 0, switched.changes
    t_b, L = sw[0]["t_s"], sw[0]["length_m"]
    before = [c for c in switched.changes if c["t_s"] < t_b]
    rods, t_a = (before[-1]["rods"], before[-1]["t_s"]) if before else (5, 0.0)
    r = switched.reel
    speed = float(r.loc[r["t_s"] == t_b, "speed_m_s"].abs().max())
    n = 6 * (1 + rods) + 2
    tol = speed * event_time_tolerance(t_b, t_b - t_a) + 4.0 * EPS * AT_M + math.sqrt(n) * (1e-9 + 1e-9 * AT_M)
    assert abs(L - AT_M) <= tol, (L - AT_M, tol)
    assert tol < 1e-3 * speed  # far below the travel of a second at |L'|, let alone a step's or an output's
    assert speed > 0.1  # a crossing, not a graze: the law hauls in there
    starts = [float(ph.timeseries["t_s"].iloc[0]) for ph in switched.phases]
    assert t_b in starts  # the switch ends a phase, the next starts there
    assert float(r["deployed_length_m"].iloc[-1]) < AT_M  # the run went on past it


def test_each_stage_runs_with_its_own_command_and_gains(switched):
    """command_N = m* Omega^2 [3 l_c + k1 (L - l_c) + k2 L'/Omega] at every output, with the law's
    l_c = 2.5 km, k1 = 4, k2 = 1 before the switch and the stage's 1.25 km, 6, 2 after it (the
    switch's own time has both rows), to round-off of the command."""
    c = _STUDY.RETRIEVAL
    om, mred = _STUDY.omega(), _STUDY.reduced_mass()
    r = switched.reel
    t_b = next(c["t_s"] for c in switched.changes if c["change"] == "stage")
    worst, after = 0.0, 0
    for ph, t, L, v, cmd in zip(r["phase"], r["t_s"], r["deployed_length_m"], r["speed_m_s"], r["command_N"]):
        stage = t > t_b or (t == t_b and ph == r.loc[r["t_s"] == t_b, "phase"].max())
        lc, k1, k2 = (LC2_M, K1, K2) if stage else (2500.0, c["k1"], c["k2"])
        after += stage
        want = mred * om**2 * (3.0 * lc + k1 * (L - lc) + k2 * v / om)
        worst = max(worst, abs(cmd - want) / abs(want))
    assert worst < 1e-12, worst
    assert after > 10  # the stage holds over many outputs
    # the command jumps at the switch by m* Omega^2 [(3 - k1') l_c' - (3 - k1) l_c + (k1' - k1) L + (k2' - k2) L'/Omega]
    at = r[r["t_s"] == t_b]
    L, v = float(at["deployed_length_m"].iloc[0]), float(at["speed_m_s"].iloc[0])
    jump = mred * om**2 * ((3.0 - K1) * LC2_M - (3.0 - c["k1"]) * 2500.0 + (K1 - c["k1"]) * L + (K2 - c["k2"]) * v / om)
    got = float(at["command_N"].iloc[-1] - at["command_N"].iloc[0])
    assert math.isclose(got, jump, rel_tol=1e-9), (got, jump)
