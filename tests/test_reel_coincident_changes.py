"""A tension law's stage switch at the instant of a birth or a retirement (docs/deployment.md 17.2).

A located event is a change of side of g (g < 0 against g >= 0).  When a stage's at_length is
reached at the instant the first rod reaches a bound, the phase ends on one of the two events,
and the other starts the next phase already on its new side: it never fires unless the end of
the phase takes it.  Three coincidences, on the staged retrieval of docs/deployment.md 14 (5 km
of line, rods of 1 km, 6 rods' worth of state at most, RADAU5 rtol = atol = 1e-9), half an orbit:

* hauled in about l_c = 2.5 km, a stage at 4050 m: L = 4 x 1000 m + 50 m is where the first rod
  reaches its retirement bound (0.05 rods);
* paid out towards l_c = 5.8 km, a stage at 5500 m: 4 x 1000 m + 1500 m, the birth bound (1.5 rods);
* the same with the stage 1e-11 m short of 5500 m: the stage is located first, and the birth is
  due at its end (L' ~ 0.2 m/s: 1e-11 m is 5e-11 s, inside the event bracket of 64 eps t ~ 3e-11 s
  only by a factor of two, so the two land within the tolerance of one stop).

Expected in each: both changes recorded at one instant, the switch's length within (10.7a) of
at_length, the birth or retirement's rod count, and the first rod within its bounds at the end.
"""

from __future__ import annotations

import math

import pytest

from tetherlab.deployment import simulate_reel
from tetherlab.integrators.common import EPS, event_time_tolerance
from tetherlab.scene import Scene

from .helpers import import_study

_STUDY = import_study("reel_retrieval")
ROD_M, RTOL = 1000.0, 1e-9  # the study's rods and its rtol = atol (studies/reel_retrieval.py RETRIEVAL)

CASES = {
    # name: (the law's commanded length, the stage's at_length, the stage's commanded length, change, rods after)
    "stage-at-retirement": (2500.0, 4050.0, 1250.0, "retire", 4),
    "stage-at-birth": (5800.0, 5500.0, 5900.0, "birth", 6),
    "birth-due-at-stage": (5800.0, 5500.0 - 1e-11, 5900.0, "birth", 6),
}


def _scene(lc0_m: float, at_m: float, lc1_m: float) -> Scene:
    data = _STUDY.retrieval_scene(controlled=True, orbits=0.5, count=41).to_dict()
    reel = data["tethers"]["main"]["reel"]
    reel["commanded_length"] = f"{lc0_m!r} m"
    reel["stages"] = [{"at_length": f"{at_m!r} m", "commanded_length": f"{lc1_m!r} m"}]
    return Scene.from_dict(data)


@pytest.fixture(scope="module", params=list(CASES))
def case(request):
    lc0, at, lc1, kind, rods = CASES[request.param]
    assert _STUDY.RETRIEVAL["rod"] == ROD_M and _STUDY.RETRIEVAL["retire"] == 50.0
    return request.param, at, kind, rods, simulate_reel(_scene(lc0, at, lc1), progress=False)


def test_a_stage_and_a_bound_at_one_instant_are_both_taken(case):
    """Both the switch and the birth (retirement) are in ``changes``, at one time t_b; the switch's
    length is at_length within (10.7a): |L'| 64 eps max(t_b, t_b - t_a) + 4 eps a + sqrt(n)
    (atol + rtol a), n = 6 (1 + 5) + 2 the state's size with the 5 rods the phase ended with, t_a = 0
    (no change before it); the rod count after it is the birth's (6) or the retirement's (4)."""
    name, at, kind, rods, run = case
    sw = [c for c in run.changes if c["change"] == "stage"]
    ch = [c for c in run.changes if c["change"] == kind]
    assert len(sw) == 1 and sw[0]["stage"] == 0, (name, run.changes)
    assert len(ch) >= 1 and ch[0]["rods"] == rods, (name, run.changes)
    t_b = sw[0]["t_s"]
    assert ch[0]["t_s"] == t_b, (name, run.changes)  # one instant: the same stop state
    r = run.reel
    speed = float(r.loc[r["t_s"] == t_b, "speed_m_s"].abs().max())
    n = 6 * (1 + 5) + 2
    tol = speed * event_time_tolerance(t_b, t_b) + 4.0 * EPS * at + math.sqrt(n) * (RTOL + RTOL * at)
    assert abs(sw[0]["length_m"] - at) <= tol, (name, sw[0]["length_m"] - at, tol)
    assert speed > 0.05, (name, speed)  # a crossing, not a graze


def test_the_first_rod_stays_within_its_bounds(case):
    """No change lost: at the end the first rod l = L - (n - 1) l_rod is between the retirement
    bound (50 m) and the birth bound (1500 m) of the study's reel, to 1e-6 m (a change taken at a
    located stop is within 1e-9 m of its bound; 1e-6 m leaves room for the outputs' rounding)."""
    name, at, kind, rods, run = case
    r = run.reel
    L = float(r["deployed_length_m"].iloc[-1])
    n = int(r["rods"].iloc[-1])
    l_first = L - (n - 1) * ROD_M
    assert 50.0 - 1e-6 <= l_first <= 1500.0 + 1e-6, (name, L, n, l_first)
